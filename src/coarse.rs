//! Six-position coarse calibration (the paper's eq. 6) and the GA search intervals it sets.
//!
//! For each axis the poses that point it up and down are found by their dominant axis; per axis
//! `k = (V_up - V_down) / (2 g0)` and `b = (V_up + V_down) / 2` (poses of the same face are averaged).
//! The sensor reads `Ka^-1 (g_b + B)`, so the coarse model is `S = 1/k`, `B = b/k`, `M = 0`. The
//! intervals are centred there: scale relative, non-orthogonality around 0, bias with an *absolute*
//! width (the coarse bias can miss by ~10 % of the bias itself).
//!
//! ```
//! use accelcal::accumulator::Pose;
//! use accelcal::coarse::{CoarseCalibration, SearchWidths};
//! let g = 9.80665;
//! let means = [[g + 0.1, 0.0, 0.0], [-g + 0.1, 0.0, 0.0], [0.0, g, 0.0], [0.0, -g, 0.0],
//!     [0.0, 0.0, g - 0.2], [0.0, 0.0, -g - 0.2]];
//! let coarse = CoarseCalibration::from_poses(&means.map(|m| Pose::from_mean(m, 100)), g).unwrap();
//! assert!((coarse.params().bias[0] - 0.1).abs() < 1e-5);
//! let intervals = coarse.intervals(&SearchWidths::DEFAULT);
//! assert!(intervals[3].0 < 1.0 && intervals[3].1 > 1.0); // Sxx
//! ```

use crate::accumulator::Pose;
use crate::ellipsoid::{EllipsoidError, check_input, half_axes_near_of, mid_range};
use crate::frame::{Deviation, Frame, FrameError};
use crate::ga::{GaError, SearchBox};
use crate::model::{PARAM_COUNT, Params};

/// Why a coarse calibration could not be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CoarseError {
    /// No pose points this axis up (`up == true`) or down.
    MissingAxisPair {
        /// Axis index 0..3 (x, y, z).
        axis: u8,
        /// Which half of the pair is missing.
        up: bool,
    },
    /// Gravity must be finite and positive.
    InvalidGravity,
    /// A pose mean is not finite.
    NonFinitePose,
    /// The readings of this axis span much less than those of the widest axis: it was never pointed
    /// both up and down (which side is missing cannot be told before calibration).
    NotReversed {
        /// Axis index 0..3 (x, y, z).
        axis: u8,
        /// Its span as a percentage of the widest axis' span.
        span_pct: u8,
    },
    /// The up and down readings of an axis coincide or are reversed.
    DegenerateAxis {
        /// Axis index.
        axis: u8,
    },
}

impl core::fmt::Display for CoarseError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::MissingAxisPair { axis, up } => write!(
                f,
                "no pose with the {} axis pointing {} was recognised: each axis must be pointed straight up \
                 and straight down (within 25 deg) once",
                crate::axis_name(*axis),
                if *up { "up" } else { "down" }
            ),
            Self::NotReversed { axis, span_pct } => write!(
                f,
                "the {} axis was never pointed both up and down (its readings span {span_pct} % of the widest axis'): \
                 capture {} up and {} down",
                crate::axis_name(*axis),
                crate::axis_name(*axis),
                crate::axis_name(*axis)
            ),
            Self::InvalidGravity => f.write_str("gravity must be finite and positive"),
            Self::NonFinitePose => f.write_str("a pose mean is not finite"),
            Self::DegenerateAxis { axis } => {
                write!(f, "the up and down readings of the {} axis do not differ", crate::axis_name(*axis))
            }
        }
    }
}

impl core::error::Error for CoarseError {}

/// The coarse calibration's name for an input error.
impl From<EllipsoidError> for CoarseError {
    fn from(e: EllipsoidError) -> Self {
        if e == EllipsoidError::InvalidGravity { Self::InvalidGravity } else { Self::NonFinitePose }
    }
}

impl From<FrameError> for CoarseError {
    fn from(e: FrameError) -> Self {
        match e {
            FrameError::InvalidGravity => Self::InvalidGravity,
            FrameError::DegenerateGain { axis } => Self::DegenerateAxis { axis },
            FrameError::NonFiniteOffset => Self::NonFinitePose,
        }
    }
}

/// Half-widths of the GA search intervals around the coarse estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SearchWidths {
    /// Bias half-width as a fraction of gravity (absolute, not relative to the bias). Defaults to 0.01
    /// (10 mg).
    pub bias_g: f32,
    /// Scale half-width, relative. Defaults to 0.01 (1 %).
    pub scale_rel: f32,
    /// Non-orthogonality half-width, dimensionless (rad). Defaults to 0.03.
    pub nonorth: f32,
}

impl SearchWidths {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { bias_g: 0.01, scale_rel: 0.01, nonorth: 0.03 };

    /// The half-widths per parameter, in the deviation coordinates of [`crate::frame`].
    pub fn half_widths(&self) -> [f32; PARAM_COUNT] {
        let [b, s, n] = [self.bias_g, self.scale_rel, self.nonorth];
        [b, b, b, s, s, s, n, n, n]
    }

    /// The box in the deviation coordinates of [`crate::frame`], centred on `center`.
    pub fn search_box(&self, center: &Deviation) -> Result<SearchBox<PARAM_COUNT>, GaError> {
        SearchBox::around(center, &self.half_widths())
    }
}

impl Default for SearchWidths {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The coarse (six-position) calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CoarseCalibration {
    frame: Frame,
    /// Poses averaged into `V_up` / `V_down` per axis.
    pub poses_used: [[u16; 2]; 3],
}

/// Smallest span of an axis' readings, as a fraction of the widest axis' span, for it to count as
/// pointed both up and down (an axis seen only from one side spans at most about half).
const MIN_SPAN_FRACTION: f32 = 0.75;

/// Fraction of a pose's normalised reading on its dominant axis for it to count as up or down
/// (cos 25 deg).
const DOMINANCE: f32 = 0.906;

impl CoarseCalibration {
    /// Coarse calibration from the means (input unit) of the poses against `gravity` (output unit).
    pub fn from_poses(poses: &[Pose], gravity: f32) -> Result<Self, CoarseError> {
        let means = poses.iter().map(|p| &p.mean);
        check_input(means.clone(), gravity).map_err(CoarseError::from)?;
        let (mut offset, mut gain) = ([0.0; 3], [0.0; 3]);
        let poses_used = face_means(means, gravity, &mut offset, &mut gain)?;
        Ok(Self { frame: Frame::new(offset, gain, gravity)?, poses_used })
    }

    /// The normalising frame (offset `b`, gain `k`, gravity).
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The coarse model in the paper's convention: `S = 1/k`, `B = b/k`, `M = 0`.
    pub fn params(&self) -> Params {
        self.frame.to_params(&[0.0; PARAM_COUNT])
    }

    /// The search intervals `(lower, upper)` per parameter in the paper's convention
    /// ([`Params::to_array`] order): centre +- half-width, the bias half-width being `bias_g * g`.
    pub fn intervals(&self, widths: &SearchWidths) -> [(f32, f32); PARAM_COUNT] {
        let center = self.params().to_array();
        let k = self.frame.gain;
        let g = self.frame.gravity;
        let half = [
            widths.bias_g * g,
            widths.bias_g * g,
            widths.bias_g * g,
            widths.scale_rel * center[3].abs(),
            widths.scale_rel * center[4].abs(),
            widths.scale_rel * center[5].abs(),
            widths.nonorth / k[0].abs(),
            widths.nonorth / k[0].abs(),
            widths.nonorth / k[1].abs(),
        ];
        let mut out = [(0.0, 0.0); PARAM_COUNT];
        for i in 0..PARAM_COUNT {
            out[i] = (center[i] - half[i], center[i] + half[i]);
        }
        out
    }
}

/// Whether every axis, by the half-range `half` of its readings (the largest `widest`), was pointed
/// both up and down: it then spans about twice gravity, like the widest one; one that spans much less
/// was never reversed, and its centre (hence its dominant poses) is unknown.
fn check_reversed(half: [f32; 3], widest: f32) -> Result<(), CoarseError> {
    for a in 0..3 {
        // Never true when all are 0.
        if half[a] < MIN_SPAN_FRACTION * widest {
            // In [0, 75): the cast to `u8` needs no clamp (`u32` is one instruction).
            let span_pct = (100.0 * half[a] / widest) as u32 as u8;
            return Err(CoarseError::NotReversed { axis: a as u8, span_pct });
        }
    }
    Ok(())
}

/// The six-position offset `b` and gain `k` per axis from pose means [`check_input`] has accepted,
/// written into `offset` and `gain` (where they stay: no copies), and how many poses were averaged
/// into `V_up` / `V_down` per axis.
pub(crate) fn face_means<'a>(
    means: impl Iterator<Item = &'a [f32; 3]> + Clone,
    gravity: f32,
    offset: &mut [f32; 3],
    gain: &mut [f32; 3],
) -> Result<[[u16; 2]; 3], CoarseError> {
    // Centre and half-range per axis from the extremes: removes the large offsets of raw counts.
    // Read in place (destructured, the centre and half-ranges were copied).
    let range = mid_range(means.clone());
    let (mid, half) = (&range.0, &range.1);
    check_reversed(*half, range.2)?;
    let mut sums = [[0.0f32; 2]; 3];
    let mut counts = [[0u16; 2]; 3];
    for m in means {
        // Every half-range is positive here, or all are 0 (all means equal): then `u` is NaN, near
        // no half-axis.
        let near = half_axes_near_of(m, mid, half, DOMINANCE);
        // At most one half-axis is within 25 deg (all six only for u = 0, which points nowhere).
        if near != 0 && near != 0x3f {
            // Half-axis `bit`: axis `bit / 2`, up (even) or down (odd).
            let bit = near.trailing_zeros() as usize;
            if let (Some(sum), Some(count), Some(v)) =
                (sums.as_flattened_mut().get_mut(bit), counts.as_flattened_mut().get_mut(bit), m.get(bit / 2))
            {
                *sum += v;
                *count = count.saturating_add(1);
            }
        }
    }
    for a in 0..3 {
        let [up, down] = counts[a];
        if up == 0 || down == 0 {
            return Err(CoarseError::MissingAxisPair { axis: a as u8, up: up == 0 });
        }
        let v_up = sums[a][0] / f32::from(up);
        let v_down = sums[a][1] / f32::from(down);
        if !(v_up > v_down) {
            return Err(CoarseError::DegenerateAxis { axis: a as u8 });
        }
        gain[a] = (v_up - v_down) / (2.0 * gravity);
        offset[a] = 0.5 * (v_up + v_down);
    }
    Ok(counts)
}
