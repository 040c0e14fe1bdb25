//! The initial estimate and the normalised problem built on it.
//!
//! Two initialisations: the paper's six-position coarse calibration ([`crate::coarse`]), which needs
//! each axis pointed straight up and down, and the closed-form ellipsoid fit ([`crate::ellipsoid`]),
//! which needs only a spread of directions and leaves out poses far off the ellipsoid. [`Init::Auto`]
//! (the default) uses the ellipsoid fit and falls back to the six faces when the ellipsoid cannot be
//! fitted. The initial model defines the [`Frame`] the optimisers work in (centre and per-axis gain)
//! and their start (its non-orthogonality).
//!
//! ```
//! use accelcal::accumulator::Pose;
//! use accelcal::init::{Init, NormalizedPoses};
//! use accelcal::model::Params;
//! let truth = Params { bias: [0.1, 0.2, -0.1], scale: [0.99, 1.01, 1.0], nonorth: [0.01, 0.0, -0.01] };
//! let dirs = [[0.3f32, 0.9, 0.3], [-0.8, 0.5, 0.33], [0.1, -0.7, 0.7], [0.6, 0.0, -0.8], [-0.2, -0.3, -0.93],
//!     [0.9, -0.4, 0.17], [-0.5, -0.8, 0.33], [0.0, 0.6, -0.8], [-0.7, 0.1, -0.7], [0.57, 0.57, 0.57]];
//! let poses = dirs.map(|d| {
//!     let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
//!     Pose::from_mean(truth.invert(d.map(|v| v / n * 9.80665)).unwrap(), 500)
//! });
//! let norm = NormalizedPoses::<16>::prepare(&poses, Init::Auto, 9.80665, &Default::default()).unwrap();
//! assert_eq!(norm.initial().kind, Init::Ellipsoid);
//! assert_eq!(norm.poses().len(), 10);
//! ```

use crate::accumulator::Pose;
use crate::coarse::{CoarseError, face_means};
use crate::ellipsoid::{EllipsoidError, Fitting, OutlierRule, PoseList, check_input, held_parameters, kept};
use crate::frame::{Deviation, Frame, NormPose};
use crate::model::{PARAM_COUNT, Params};
use crate::verdict::PoseSet;

/// Which initial estimate to start from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Init {
    /// The ellipsoid fit; the six faces when no ellipsoid can be fitted.
    #[default]
    Auto,
    /// The paper's six-position coarse calibration (each axis pointed up and down).
    SixPosition,
    /// The closed-form ellipsoid fit (any orientations with a spread of directions).
    Ellipsoid,
}

/// Why no initial estimate could be made.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum InitError {
    /// More poses than the buffer holds.
    TooManyPoses {
        /// Poses given.
        got: usize,
        /// Capacity.
        capacity: usize,
    },
    /// The six-position coarse calibration failed.
    Coarse(CoarseError),
    /// The ellipsoid fit failed.
    Ellipsoid(EllipsoidError),
}

impl core::fmt::Display for InitError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooManyPoses { got, capacity } => write!(f, "{got} poses given, capacity is {capacity}"),
            Self::Coarse(e) => write!(f, "six-position coarse calibration: {e}"),
            Self::Ellipsoid(e) => write!(f, "ellipsoid fit: {e}"),
        }
    }
}

impl core::error::Error for InitError {}

/// The initial estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Initial {
    /// Which initialisation made it ([`Init::SixPosition`] or [`Init::Ellipsoid`]).
    pub kind: Init,
    /// The initial model (paper convention).
    pub params: Params,
    /// Poses left out as far off the ellipsoid (indices into the poses given).
    pub excluded: PoseList,
    /// Parameters the initialisation could not determine ([`crate::model::PARAM_NAMES`] order).
    pub held: [bool; PARAM_COUNT],
}

/// Poses normalised into the frame of the initial estimate, in a fixed buffer of `MAX_POSES`.
pub struct NormalizedPoses<const MAX_POSES: usize> {
    frame: Frame,
    initial: Initial,
    start: Deviation,
    poses: heapless::Vec<NormPose, MAX_POSES>,
    source: heapless::Vec<u16, MAX_POSES>,
}

impl<const MAX_POSES: usize> NormalizedPoses<MAX_POSES> {
    /// The paper's path: six-position coarse calibration against `gravity`, every pose normalised.
    pub fn new(poses: &[Pose], gravity: f32) -> Result<Self, InitError> {
        Self::prepare(poses, Init::SixPosition, gravity, &OutlierRule::KEEP_ALL)
    }

    /// The initial estimate chosen by `init`, and the poses it keeps normalised in its frame.
    pub fn prepare(poses: &[Pose], init: Init, gravity: f32, rule: &OutlierRule) -> Result<Self, InitError> {
        let mut out = Self::EMPTY;
        out.refill(poses, init, gravity, rule)?;
        Ok(out)
    }

    /// A placeholder to [`NormalizedPoses::refill`], which writes every field: no poses, all zeros (a
    /// placeholder with ones in it was a 608-byte `memcpy` from flash where it was placed).
    pub(crate) const EMPTY: Self = Self {
        frame: Frame { offset: [0.0; 3], gain: [0.0; 3], gravity: 0.0 },
        initial: Initial {
            kind: Init::Auto,
            params: Params { bias: [0.0; 3], scale: [0.0; 3], nonorth: [0.0; 3] },
            excluded: PoseList::EMPTY,
            held: [false; PARAM_COUNT],
        },
        start: [0.0; PARAM_COUNT],
        poses: heapless::Vec::new(),
        source: heapless::Vec::new(),
    };

    /// [`NormalizedPoses::prepare`] into `self`, so that the pose buffer is written where it stays
    /// (no copy of it on the stack). On an error `self` is unusable.
    pub(crate) fn refill(
        &mut self,
        poses: &[Pose],
        init: Init,
        gravity: f32,
        rule: &OutlierRule,
    ) -> Result<(), InitError> {
        if poses.len() > MAX_POSES {
            return Err(InitError::TooManyPoses { got: poses.len(), capacity: MAX_POSES });
        }
        // A list of the poses by index (capacity checked above); the estimate fills and reorders it, its
        // first `used` entries are the poses it kept.
        self.source.clear();
        let _ = self.source.resize_default(poses.len());
        let used = initial_estimate(&mut self.initial, &mut self.frame, poses, &mut self.source, init, gravity, rule)?;
        self.source.truncate(used);
        start_deviation(&self.initial, &self.frame, &mut self.start);
        let frame = &self.frame;
        self.poses.clear();
        for m in kept(poses, &self.source) {
            // As many as the indices.
            let _ = self.poses.push(frame.normalize(*m));
        }
        Ok(())
    }

    /// The frame the deviation vectors live in.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// The initial estimate.
    pub fn initial(&self) -> &Initial {
        &self.initial
    }

    /// The initial estimate as a deviation vector (held parameters at 0).
    pub fn start(&self) -> Deviation {
        self.start
    }

    /// The normalised poses kept.
    pub fn poses(&self) -> &[NormPose] {
        &self.poses
    }

    /// For each normalised pose, the index of the pose it came from.
    pub fn source(&self) -> &[u16] {
        &self.source
    }

    /// The poses used, with `poses` the poses this was prepared from. Out of line: the calibration's
    /// calls share one copy.
    #[inline(never)]
    pub fn pose_set<'a>(&'a self, poses: &'a [Pose]) -> PoseSet<'a> {
        PoseSet { poses, norm: &self.poses, source: &self.source }
    }
}

/// The estimate `init` asks for (see [`Init`]) and its frame, written into `initial` and `frame`;
/// `list`, as long as `poses`, is filled with the indices of the poses it uses first; returns how
/// many it uses.
#[inline(always)]
fn initial_estimate(
    initial: &mut Initial,
    frame: &mut Frame,
    poses: &[Pose],
    list: &mut [u16],
    init: Init,
    gravity: f32,
    rule: &OutlierRule,
) -> Result<usize, InitError> {
    // The same checks for both (as the six faces' error when they are asked for).
    if let Err(e) = check_input(poses.iter().map(|p| &p.mean), gravity) {
        return Err(if init == Init::SixPosition { InitError::Coarse(e.into()) } else { InitError::Ellipsoid(e) });
    }
    // The ellipsoid's model and the poses it leaves out are written in place, its centre and gains
    // `1 / S` into the frame; its held terms kept here.
    let mut held = None;
    let mut ellipsoid_error = None;
    every_pose(list);
    frame.gravity = gravity;
    if init != Init::SixPosition {
        let mut fitting = Fitting::new(poses, gravity, &mut initial.params, &mut initial.excluded, &mut frame.offset);
        match fitting.robust(list, rule) {
            Ok(()) => {
                held = Some(fitting.held);
                let s = &initial.params.scale;
                frame.gain = [1.0 / s[0], 1.0 / s[1], 1.0 / s[2]];
            }
            Err(e) if init == Init::Ellipsoid => return Err(InitError::Ellipsoid(e)),
            Err(e) => {
                every_pose(list);
                ellipsoid_error = Some(e);
            }
        }
    }
    // The six faces' own frame (exactly: the paper's path), then the checks of either frame (gravity
    // checked above).
    let checked = match held {
        None => face_means(kept(poses, list), gravity, &mut frame.offset, &mut frame.gain).map(|_| ()),
        Some(_) => Ok(()),
    }
    .and_then(|()| Ok(frame.validate_axes()?));
    // When the six faces are the fallback, the ellipsoid's error is the one reported.
    if let Err(e) = checked {
        return Err(ellipsoid_error.map_or(InitError::Coarse(e), InitError::Ellipsoid));
    }
    let (kind, held) = match held {
        Some(held) => (Init::Ellipsoid, held),
        None => {
            initial.params = frame.to_params(&[0.0; PARAM_COUNT]);
            initial.excluded = PoseList::EMPTY;
            (Init::SixPosition, [false; 3])
        }
    };
    initial.kind = kind;
    initial.held = held_parameters(&held);
    Ok(list.len() - initial.excluded.count())
}

/// Every pose, in order: `list[i] = i`.
fn every_pose(list: &mut [u16]) {
    for (i, entry) in list.iter_mut().enumerate() {
        *entry = i as u16;
    }
}

/// [`Frame::to_deviation`] of `initial`'s model in `frame`, its frame, bit for bit, held parameters
/// at 0, written into `start`: the frame's offset is the model's centre, whose image `Ka c` is the
/// model's bias (the ellipsoid computes `B` so, and [`Frame::to_params`] the six faces' model), so the
/// bias deviations are exactly 0; only non-orthogonality terms are ever held.
#[inline(always)] // one caller
fn start_deviation(initial: &Initial, frame: &Frame, start: &mut Deviation) {
    let (p, k) = (&initial.params, frame.gain);
    for a in 0..3 {
        start[a] = 0.0;
        start[3 + a] = p.scale[a] * k[a] - 1.0;
        // Mxx and Myy are relative to the x gain, Mzz to the y gain.
        start[6 + a] = if initial.held[6 + a] { 0.0 } else { p.nonorth[a] * k[a / 2] };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Poses on a known model: the six faces (two turns each) and four diagonals.
    fn poses() -> [Pose; 16] {
        let truth = Params { bias: [0.3, -0.2, 0.1], scale: [1.02, 0.97, 1.01], nonorth: [0.01, -0.02, 0.015] };
        let d = 0.577_350_3 * 9.80665;
        let dirs: [[f32; 3]; 16] = [
            [9.80665, 0.1, 0.0],
            [9.80665, 0.0, 0.1],
            [-9.80665, 0.1, 0.0],
            [-9.80665, 0.0, -0.1],
            [0.1, 9.80665, 0.0],
            [0.0, 9.80665, 0.1],
            [0.1, -9.80665, 0.0],
            [0.0, -9.80665, -0.1],
            [0.1, 0.0, 9.80665],
            [0.0, 0.1, 9.80665],
            [0.1, 0.0, -9.80665],
            [0.0, -0.1, -9.80665],
            [d, d, d],
            [-d, d, -d],
            [d, -d, -d],
            [-d, -d, d],
        ];
        dirs.map(|g| Pose::from_mean(truth.invert(g).unwrap(), 100))
    }

    #[test]
    fn the_start_is_the_deviation_of_the_initial_model_bit_for_bit() {
        for init in [Init::Ellipsoid, Init::SixPosition] {
            let norm = NormalizedPoses::<16>::prepare(&poses(), init, 9.80665, &OutlierRule::DEFAULT).unwrap();
            assert_eq!(norm.initial().kind, init);
            let mut expected = norm.frame().to_deviation(&norm.initial().params);
            for (x, &held) in expected.iter_mut().zip(&norm.initial().held) {
                if held {
                    *x = 0.0;
                }
            }
            assert_eq!(norm.start().map(f32::to_bits), expected.map(f32::to_bits), "{init:?}");
        }
    }
}
