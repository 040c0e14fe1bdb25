//! A guided calibration session for firmware: feed samples, tell the person holding the board what to
//! do next, calibrate when there is enough.
//!
//! A [`Session`] wraps an [`Accumulator`] and runs a small state machine on its events:
//!
//! ```text
//! WaitingForStillness -> Capturing -> MoveOn -> PoseCaptured -> WaitingForStillness -> ...
//!                                 \-> PoseRejected (moved too early, saturated) -/
//! any -> Interrupted (sensor error; poses kept) -> WaitingForStillness
//! finish() -> Done (verdict passed: blob) | Failed (no fit, or a failed verdict: no blob; poses kept:
//!             capture more, or remove_pose() a bad one, and finish again)
//! ```
//!
//! Every [`Session::push`] returns a [`Progress`]: the state, poses captured, rejections, duplicates,
//! and a [`Guidance`] computed once per captured pose (the per-sample path is the accumulator's plus a
//! few comparisons; the guidance is some ten thousand `f32` operations, done while the person is
//! already turning the board):
//!
//! - the poses are normalised in the frame of the initial estimate ([`crate::init`]: the ellipsoid fit,
//!   or the six faces), or, before one can be made (fewer than 9 poses, too narrow a spread), in a
//!   provisional frame (zero offset, the mean reading as 1 g): guidance works from the first pose, in
//!   any order, with no face required;
//! - each of the 26 cube directions ([`CubeDirection`]: faces, edges, vertices) is scored by the
//!   parameter standard deviations the information matrix predicts if that orientation were added
//!   next (with the noise measured so far). The standard deviations are normalised by the [`VerdictBounds`](crate::verdict::VerdictBounds) of the
//!   calibration (1 = at the bound); the best candidate minimises the worst one, ties broken by the
//!   sum of squares (A-optimal); while some parameter is still above its bound, the candidate that adds
//!   the most information wins instead (D-optimal), which asks for new directions first. A weak prior (standard deviation 0.5 in every deviation coordinate
//!   of [`crate::frame`]) keeps the matrix invertible while some terms are not determined at all:
//!   such a term shows the prior's standard deviation (e.g. 50 for a non-orthogonality term under
//!   the default bounds), which no sensible bound accepts.
//!
//! [`Progress::ready`] says when the done criterion is met: at least
//! [`SessionConfig::min_poses`] poses and every predicted standard deviation within its bound.
//! [`Session::finish`] then runs [`calibrate`] (initial estimate, TAGA, LM, verdict) and, when the
//! verdict passes, returns the parameters, the verdict and the [`blob`](crate::blob) for flash.
//!
//! A new pose within [`SessionConfig::duplicate_angle_deg`] of an earlier one is *kept* and reported
//! ([`State::PoseCaptured`]'s `duplicate_of`, [`Progress::duplicates`]): a repeated orientation still
//! averages noise down (the paper's own plan holds each face four times) and after a sensor error the
//! second half of an interrupted pose is exactly such a repeat; the report lets the user interface say
//! that another orientation would help more.
//!
//! ```
//! use accelcal::calibrate::DefaultRng;
//! use accelcal::model::Params;
//! use accelcal::session::{Session, SessionConfig, State};
//! use rand_core::SeedableRng;
//!
//! let truth = Params { bias: [0.12; 3], scale: [0.97, 0.98, 0.99], nonorth: [-0.015, 0.01, 0.02] };
//! let g = 9.80665;
//! let config = SessionConfig { hold_samples: 300, ..SessionConfig::DEFAULT };
//! let mut session: Session<f32, 16, 32, 40> = Session::new(config).unwrap();
//! let mut noise = 0u32;
//! // The person follows the guidance: each time, hold the suggested direction up, then move.
//! while !session.progress().ready {
//!     let d = session.progress().guidance.next.unit();
//!     let reading = truth.invert([d[0] * g, d[1] * g, d[2] * g]).unwrap();
//!     for _ in 0..400 {
//!         noise = noise.wrapping_mul(1664525).wrapping_add(1013904223);
//!         let n = (noise >> 16) as f32 / 65536.0 - 0.5;
//!         session.push([reading[0] + 1e-3 * n, reading[1] - 1e-3 * n, reading[2] + 1e-3 * n]).unwrap();
//!     }
//!     for i in 0..50 {
//!         session.push([reading[0] + i as f32 * 0.3, reading[1], reading[2] - i as f32 * 0.2]).unwrap();
//!     }
//! }
//! let result = session.finish(DefaultRng::seed_from_u64(1)).unwrap(); // print the seed with results
//! assert_eq!(session.state(), State::Done);
//! assert!(result.calibration.verdict.pass());
//! assert!((result.calibration.params.nonorth[2] - 0.02).abs() < 1e-3);
//! assert_eq!(accelcal::blob::decode(&result.blob).unwrap().0, result.calibration.params);
//! ```

use core::ops::ControlFlow;

use rand_core::Rng;

use crate::accumulator::{
    Accumulator, AccumulatorConfig, AccumulatorError, Event, Pose, Reading, Rejection, Rejections,
};
use crate::blob::{BLOB_LEN, encode};
use crate::calibrate::{Calibration, CalibrationConfig, CalibrationError, Calibrator, calibrate};
use crate::frame::Frame;
use crate::init::{Init, NormalizedPoses};
use crate::model::PARAM_COUNT;
use crate::sensor::AccelSensor;
use crate::verdict::{Failures, Warnings};

mod guidance;
use guidance::information_guidance;

// ---------------------------------------------------------------------------------------------
// Orientations
// ---------------------------------------------------------------------------------------------

/// Whether a [`CubeDirection`] is a face, an edge or a vertex of the cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DirectionKind {
    /// One axis up or down (the board on a face).
    Face,
    /// Two axes at 45 degrees (the board on an edge).
    Edge,
    /// All three axes at 35.3 degrees from the horizontal (the board on a corner).
    Vertex,
}

/// One of the 26 cube directions in the sensor axes: the direction to turn *up* (away from the
/// ground). At rest the accelerometer then reads `+g` along it. Signs are `-1`, `0` or `+1` per axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CubeDirection {
    signs: [i8; 3],
}

const fn all_directions() -> [CubeDirection; 26] {
    let mut out = [CubeDirection { signs: [0, 0, 1] }; 26];
    let mut k = 0;
    let mut nonzero = 1;
    while nonzero <= 3 {
        let mut code = 0;
        while code < 27 {
            let s = [(code / 9) as i8 - 1, ((code / 3) % 3) as i8 - 1, (code % 3) as i8 - 1];
            let count = (s[0] != 0) as usize + (s[1] != 0) as usize + (s[2] != 0) as usize;
            if count == nonzero {
                out[k] = CubeDirection { signs: s };
                k += 1;
            }
            code += 1;
        }
        nonzero += 1;
    }
    out
}

impl CubeDirection {
    /// All 26: the 6 faces, then the 12 edges, then the 8 vertices.
    pub const ALL: [Self; 26] = all_directions();

    /// A direction from per-axis signs; `None` unless each is -1, 0 or 1 and one at least is not 0.
    pub const fn new(signs: [i8; 3]) -> Option<Self> {
        let valid =
            signs[0] >= -1 && signs[0] <= 1 && signs[1] >= -1 && signs[1] <= 1 && signs[2] >= -1 && signs[2] <= 1;
        if valid && !(signs[0] == 0 && signs[1] == 0 && signs[2] == 0) { Some(Self { signs }) } else { None }
    }

    /// The face with `axis` (0, 1, 2 for x, y, z; larger values mean z) pointing up (`up`) or down.
    pub const fn face(axis: u8, up: bool) -> Self {
        let mut signs = [0; 3];
        let a = if axis > 2 { 2 } else { axis as usize };
        signs[a] = if up { 1 } else { -1 };
        Self { signs }
    }

    /// Per-axis signs.
    pub const fn signs(&self) -> [i8; 3] {
        self.signs
    }

    /// Face, edge or vertex.
    pub const fn kind(&self) -> DirectionKind {
        let s = self.signs;
        match (s[0] != 0) as u8 + (s[1] != 0) as u8 + (s[2] != 0) as u8 {
            1 => DirectionKind::Face,
            2 => DirectionKind::Edge,
            _ => DirectionKind::Vertex,
        }
    }

    /// For a face, its name in vehicle terms, with the sensor in a vehicle's NED body axes (x forward,
    /// y right, z down): `level`, `upside down`, `nose up`, `nose down`, `left side down`,
    /// `right side down`; `None` for edges and vertices.
    pub const fn vehicle_name(&self) -> Option<&'static str> {
        match self.signs {
            [0, 0, -1] => Some("level"),
            [0, 0, 1] => Some("upside down"),
            [1, 0, 0] => Some("nose up"),
            [-1, 0, 0] => Some("nose down"),
            [0, 1, 0] => Some("left side down"),
            [0, -1, 0] => Some("right side down"),
            _ => None,
        }
    }

    /// The unit vector in the sensor axes.
    pub fn unit(&self) -> [f32; 3] {
        let c = match self.kind() {
            DirectionKind::Face => 1.0,
            DirectionKind::Edge => core::f32::consts::FRAC_1_SQRT_2,
            DirectionKind::Vertex => 0.577_350_27,
        };
        self.signs.map(|s| f32::from(s) * c)
    }
}

impl core::fmt::Display for CubeDirection {
    /// `face +z`, `edge +x-y`, `vertex -x+y+z`: the sensor axes to turn up.
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self.kind() {
            DirectionKind::Face => "face ",
            DirectionKind::Edge => "edge ",
            DirectionKind::Vertex => "vertex ",
        })?;
        for (axis, &s) in self.signs.iter().enumerate() {
            if s != 0 {
                write!(f, "{}{}", if s > 0 { '+' } else { '-' }, crate::axis_name(axis as u8))?;
            }
        }
        Ok(())
    }
}

// ---------------------------------------------------------------------------------------------
// Configuration, errors, progress
// ---------------------------------------------------------------------------------------------

/// How the session guides the person and what it accepts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mode {
    /// The full 9-parameter calibration: the next orientation is the most informative one (any
    /// start, any order); [`Session::finish`] accepts only a fit of every parameter.
    #[default]
    Guided,
    /// The six faces, as ArduPilot and PX4 ask for them ([`CubeDirection::vehicle_name`]): level,
    /// upside down, nose up, nose down, left side down, right side down. Fits the biases and scale
    /// factors (six directions cannot see the non-orthogonality, which is held at 0 and said so);
    /// ready when the six faces are captured.
    SixFace,
}

/// The six faces in the order [`Mode::SixFace`] asks for them, in the vehicle's NED body axes
/// (x forward, y right, z down): level (-z up), upside down, nose up, nose down, left side down (the
/// right side, +y, up), right side down.
pub const SIX_FACES: [CubeDirection; 6] = [
    CubeDirection::face(2, false),
    CubeDirection::face(2, true),
    CubeDirection::face(0, true),
    CubeDirection::face(0, false),
    CubeDirection::face(1, true),
    CubeDirection::face(1, false),
];

/// Session settings.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SessionConfig {
    /// Guidance and acceptance. Defaults to [`Mode::Guided`].
    pub mode: Mode,
    /// Static detection. Defaults to [`AccumulatorConfig::DEFAULT`].
    pub accumulator: AccumulatorConfig,
    /// The calibration run by [`Session::finish`]; its `gravity` (output unit) is the blob's and its
    /// `bounds` are also the done criterion. Defaults to [`CalibrationConfig::DEFAULT`].
    pub calibration: CalibrationConfig,
    /// Fewest poses before [`Progress::ready`] can be set; at least 9 (one per parameter) and at most
    /// the session's pose capacity. Defaults to 12.
    pub min_poses: usize,
    /// Samples a pose is held (counted from the start of the still interval) before the session says
    /// [`State::MoveOn`]; at least the accumulator's `min_pose_samples` plus two blocks, so the pose
    /// is long enough when the motion closes it. Defaults to 1000 (5 s at 200 Hz, as in the paper).
    pub hold_samples: u32,
    /// A new pose closer than this to an earlier one counts as a duplicate, degrees, in `[0, 90)`.
    /// Defaults to 10.
    pub duplicate_angle_deg: f32,
}

impl SessionConfig {
    /// The documented defaults.
    pub const DEFAULT: Self = Self {
        mode: Mode::Guided,
        accumulator: AccumulatorConfig::DEFAULT,
        calibration: CalibrationConfig::DEFAULT,
        min_poses: 12,
        hold_samples: 1000,
        duplicate_angle_deg: 10.0,
    };

    /// The defaults for a sensor read at `sample_rate_hz`: a pose held `hold_s` seconds before the
    /// session says [`State::MoveOn`], and still intervals shorter than `min_still_s` seconds not kept
    /// (both rounded to samples, at least one). The defaults are 5 s and 0.5 s at 200 Hz.
    pub fn at_rate(sample_rate_hz: f32, hold_s: f32, min_still_s: f32) -> Self {
        let samples = |s: f32| {
            let n = libm::roundf(s * sample_rate_hz);
            if n >= 1.0 && n < u32::MAX as f32 {
                n as u32
            } else if n >= 1.0 {
                u32::MAX
            } else {
                1
            }
        };
        let accumulator = AccumulatorConfig { min_pose_samples: samples(min_still_s), ..AccumulatorConfig::DEFAULT };
        Self { accumulator, hold_samples: samples(hold_s), ..Self::DEFAULT }
    }

    /// The six-face quick mode ([`Mode::SixFace`]) with the other defaults (6 poses at least).
    pub const SIX_FACE: Self = Self { mode: Mode::SixFace, min_poses: 6, ..Self::DEFAULT };

    /// Checks the accumulator settings, `min_poses >= 9`, `hold_samples >= min_pose_samples`, the
    /// duplicate angle, a finite positive gravity and positive (possibly infinite) parameter bounds.
    /// The checks that depend on the capacities are made by [`Session::new`].
    pub fn validate(&self) -> Result<(), SessionError> {
        self.accumulator.validate()?;
        let g = self.calibration.gravity;
        let b = &self.calibration.bounds;
        let positive = |v: f32| v > 0.0;
        let fewest = if self.mode == Mode::SixFace { 6 } else { PARAM_COUNT };
        let ok = self.min_poses >= fewest
            && self.hold_samples >= self.accumulator.min_pose_samples
            && (0.0..90.0).contains(&self.duplicate_angle_deg)
            && g.is_finite()
            && g > 0.0
            && positive(b.max_bias_std_mg)
            && positive(b.max_scale_std_rel)
            && positive(b.max_nonorth_std);
        if ok { Ok(()) } else { Err(SessionError::InvalidConfig) }
    }
}

impl Default for SessionConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Session errors. A session refusing a sample or a calibration keeps every pose captured so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SessionError {
    /// A configuration value is out of range (see [`SessionConfig::validate`] and [`Session::new`]).
    InvalidConfig,
    /// The accumulator refused the sample (non-finite: skipped) or had no room for a pose (dropped).
    Accumulator(AccumulatorError),
    /// The calibration failed; capture more poses (see the guidance) and finish again.
    Calibration(CalibrationError),
    /// The calibration ran but failed its verdict (what failed; the calibration is in
    /// [`Session::last_calibration`]); no blob is made. Capture more poses, or remove a bad one, and
    /// finish again.
    Verdict(Failures),
    /// The fit passed its verdict but could not determine every parameter (held at nominal) or left
    /// poses out; [`Mode::Guided`] wants them all: capture the orientations the guidance asks for
    /// (the calibration is in [`Session::last_calibration`]).
    Incomplete(Warnings),
    /// No pose has this index.
    NoSuchPose,
    /// The session is [`State::Done`]; start a new one.
    Finished,
}

impl core::fmt::Display for SessionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::InvalidConfig => f.write_str("session configuration out of range"),
            Self::Accumulator(e) => write!(f, "accumulator: {e}"),
            Self::Calibration(e) => write!(f, "calibration: {e}"),
            Self::Verdict(_) => f.write_str("the calibration failed its verdict: capture more orientations"),
            Self::Incomplete(_) => f.write_str(
                "the poses do not determine every parameter: capture the orientations the guidance asks for",
            ),
            Self::NoSuchPose => f.write_str("no pose has this index"),
            Self::Finished => f.write_str("the session is finished; start a new one"),
        }
    }
}

impl core::error::Error for SessionError {}

impl From<AccumulatorError> for SessionError {
    fn from(e: AccumulatorError) -> Self {
        match e {
            AccumulatorError::InvalidConfig => Self::InvalidConfig,
            other => Self::Accumulator(other),
        }
    }
}

impl From<CalibrationError> for SessionError {
    fn from(e: CalibrationError) -> Self {
        Self::Calibration(e)
    }
}

/// Where the session is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// No still interval: hold the board still in the suggested orientation.
    WaitingForStillness,
    /// A pose is being averaged: keep still.
    Capturing {
        /// Samples held so far (from the start of the still interval).
        held: u32,
    },
    /// The pose has been held for [`SessionConfig::hold_samples`]: turn the board to the suggested
    /// orientation (the motion closes the pose).
    MoveOn,
    /// This sample (or sensor error) closed a still interval and it was kept as pose `index`.
    PoseCaptured {
        /// Index into [`Session::poses`].
        index: usize,
        /// An earlier pose within [`SessionConfig::duplicate_angle_deg`] (the closest), if any. The
        /// new pose is kept either way.
        duplicate_of: Option<usize>,
    },
    /// This sample closed a still interval that was not kept.
    PoseRejected(Rejection),
    /// A sensor error was reported and no pose was open; hold still to resume.
    Interrupted,
    /// [`Session::finish`] succeeded; see [`Session::result`].
    Done,
    /// [`Session::finish`] failed; the poses are kept, pushing more samples resumes the capture.
    Failed(SessionError),
}

/// What the next orientation suggestion is based on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GuidanceBasis {
    /// The predicted parameter standard deviations in a provisional frame (zero offset, the mean
    /// reading as 1 g on every axis): too few poses, or too narrow a spread, for an initial estimate.
    Provisional,
    /// The predicted parameter standard deviations in the frame of the initial estimate (see the
    /// [module docs](self)).
    Information,
    /// [`Mode::SixFace`]: the next face not yet captured, in the order of [`SIX_FACES`].
    Faces,
}

/// What to do next, updated at every captured pose.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Guidance {
    /// The orientation that would help most next.
    pub next: CubeDirection,
    /// Why.
    pub basis: GuidanceBasis,
    /// Per parameter ([`crate::model::PARAM_NAMES`] order): predicted standard deviation above its
    /// bound.
    pub poorly_determined: [bool; PARAM_COUNT],
    /// Largest predicted standard deviation over its bound (1 = at the bound).
    pub worst_std: f32,
    /// The same after adding `next` (a prediction with the current noise).
    pub worst_std_after_next: f32,
}

impl Guidance {
    /// No information yet (or none that can be inverted): ask for +z, every parameter poorly determined.
    pub const UNKNOWN: Self = Self {
        next: CubeDirection::face(2, true),
        basis: GuidanceBasis::Provisional,
        poorly_determined: [true; PARAM_COUNT],
        worst_std: f32::INFINITY,
        worst_std_after_next: f32::INFINITY,
    };
}

/// The session's report after every sample.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Progress {
    /// The state.
    pub state: State,
    /// Poses captured.
    pub poses: usize,
    /// Poses flagged as duplicates (included in `poses`).
    pub duplicates: usize,
    /// Still intervals not kept, by reason.
    pub rejections: Rejections,
    /// Sensor errors reported.
    pub sensor_errors: u32,
    /// What to do next.
    pub guidance: Guidance,
    /// How many of the six faces have a pose (the raw mean within 25 deg of the face).
    pub faces_done: u8,
    /// The done criterion is met: at least [`SessionConfig::min_poses`] poses and every predicted
    /// standard deviation within its bound. A prediction: [`Session::finish`] judges the fit itself
    /// (a misfit or a bad pose can still fail it, after which this is `false` until a new pose).
    pub ready: bool,
}

/// A finished session.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SessionResult {
    /// Parameters, initial estimate, verdict, optimiser statistics.
    pub calibration: Calibration,
    /// [`crate::blob::encode`] of the parameters and the gravity: the bytes to store in flash.
    pub blob: [u8; BLOB_LEN],
    /// Poses used.
    pub poses: usize,
    /// Of which flagged as duplicates.
    pub duplicates: usize,
}

/// Limits of [`Session::run_with_sensor`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunLimits {
    /// Sensor reads (successful or not) before the capture stops and the session is finished.
    /// Defaults to `u32::MAX`.
    pub max_samples: u32,
    /// Consecutive sensor errors after which the run gives up with [`RunError::Sensor`] (the poses
    /// are kept: [`Session::finish`] can still be called). Defaults to 10.
    pub max_consecutive_errors: u32,
    /// Failed reads in all after which the run gives up with [`RunError::ReadErrorBudget`] (poses
    /// kept). Defaults to 10 000. A single failed read is a skipped sample (the pose being held goes
    /// on); two or more in a row are a gap ([`Session::sensor_error`]: an open pose is closed).
    pub max_read_errors: u32,
}

impl RunLimits {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { max_samples: u32::MAX, max_consecutive_errors: 10, max_read_errors: 10_000 };
}

impl Default for RunLimits {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Errors of [`Session::run_with_sensor`]: the sensor's, or the session's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RunError<E> {
    /// More than [`RunLimits::max_consecutive_errors`] reads in a row failed; the last error.
    Sensor(E),
    /// More than [`RunLimits::max_read_errors`] reads failed in all; the last error.
    ReadErrorBudget(E),
    /// The session failed (e.g. the calibration).
    Session(SessionError),
}

impl<E> From<SessionError> for RunError<E> {
    fn from(e: SessionError) -> Self {
        Self::Session(e)
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for RunError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Sensor(e) => write!(f, "sensor error: {e:?}"),
            Self::ReadErrorBudget(e) => write!(f, "too many failed sensor reads (last: {e:?})"),
            Self::Session(e) => write!(f, "{e}"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for RunError<E> {}

// ---------------------------------------------------------------------------------------------
// The session
// ---------------------------------------------------------------------------------------------

/// A guided calibration session: readings of type `R`, room for `POSES` poses, static detection on
/// blocks of `BLOCK` samples, a GA population of `POP` for [`Session::finish`].
pub struct Session<R: Reading, const POSES: usize, const BLOCK: usize, const POP: usize> {
    config: SessionConfig,
    acc: Accumulator<R, POSES, BLOCK>,
    state: State,
    /// `samples_seen` at the first sample of the open still interval.
    pose_start: u32,
    guidance: Guidance,
    duplicates: usize,
    sensor_errors: u32,
    ready: bool,
    duplicate_cos: f32,
    result: Option<SessionResult>,
    last: Option<Calibration>,
}

impl<R: Reading, const POSES: usize, const BLOCK: usize, const POP: usize> Session<R, POSES, BLOCK, POP> {
    const VALID: () = {
        assert!(POSES >= PARAM_COUNT, "a session needs room for at least 9 poses (one per parameter)");
        assert!(POP >= 4, "a GA population needs at least 4 individuals");
    };

    /// A session waiting for the first pose.
    pub fn new(config: SessionConfig) -> Result<Self, SessionError> {
        let () = Self::VALID;
        config.validate()?;
        let two_blocks = u32::try_from(BLOCK.saturating_mul(2)).unwrap_or(u32::MAX);
        if config.min_poses > POSES
            || config.hold_samples < config.accumulator.min_pose_samples.saturating_add(two_blocks)
        {
            return Err(SessionError::InvalidConfig);
        }
        let acc = Accumulator::new(config.accumulator)?;
        let duplicate_cos = libm::cosf(config.duplicate_angle_deg.to_radians());
        let mut session = Self {
            config,
            acc,
            state: State::WaitingForStillness,
            pose_start: 0,
            guidance: guidance_for::<POSES>(&[], &config.calibration),
            duplicates: 0,
            sensor_errors: 0,
            ready: false,
            duplicate_cos,
            result: None,
            last: None,
        };
        session.refresh_guidance();
        Ok(session)
    }

    /// Feeds one sample (x, y, z, input unit). An `Err` leaves the session as it was except that a
    /// non-finite sample is skipped and a pose completed with no room left is dropped.
    #[inline]
    pub fn push(&mut self, sample: [R; 3]) -> Result<Progress, SessionError> {
        if self.state == State::Done {
            return Err(SessionError::Finished);
        }
        let event = self.acc.push(sample);
        self.advance(event, false)
    }

    /// [`Session::push`] for micromath's vector types (`I16x3`, `F32x3`).
    #[cfg(feature = "micromath")]
    #[inline]
    pub fn push_vector(&mut self, v: micromath::vector::Vector3d<R>) -> Result<Progress, SessionError>
    where
        R: micromath::vector::Component,
    {
        self.push([v.x, v.y, v.z])
    }

    /// Reports a failed sensor read: the stream has a gap. An open pose is closed as if motion had
    /// started (kept if long enough); every pose captured so far is kept and the capture resumes with
    /// the next [`Session::push`].
    pub fn sensor_error(&mut self) -> Result<Progress, SessionError> {
        if self.state == State::Done {
            return Err(SessionError::Finished);
        }
        self.sensor_errors = self.sensor_errors.saturating_add(1);
        #[cfg(feature = "defmt")]
        defmt::warn!("session: sensor error {}, poses kept: {}", self.sensor_errors, self.acc.poses().len());
        let event = self.acc.interrupt();
        self.advance(event, true)
    }

    /// A failed read in [`Session::run_with_sensor`], counted: the first of a run is a skipped sample,
    /// the second in a row a gap (an open pose is closed, as by [`Session::sensor_error`]).
    fn read_failed(&mut self, consecutive: u32) -> Result<Progress, SessionError> {
        self.sensor_errors = self.sensor_errors.saturating_add(1);
        if consecutive < 2 {
            return Ok(self.progress());
        }
        let event = self.acc.interrupt();
        self.advance(event, true)
    }

    /// Closes an open pose and calibrates with every pose captured ([`calibrate`]: initial estimate,
    /// then the configured optimiser, TAGA + LM by default, then the verdict), seeded by `rng`. When
    /// the verdict passes the session is [`State::Done`] with the blob; otherwise (no fit, or a fit
    /// that failed its verdict: no blob) [`State::Failed`] with every pose kept: push more samples
    /// (the guidance says which orientation helps), or [`Session::remove_pose`] a bad one, and finish
    /// again.
    pub fn finish<G: Rng>(&mut self, rng: G) -> Result<SessionResult, SessionError> {
        self.close()?;
        #[cfg(feature = "defmt")]
        defmt::info!("session: solving with {} poses", self.acc.poses().len());
        let calibration = calibrate::<G, POP, POSES>(self.acc.poses(), &self.config.calibration, rng);
        self.conclude(calibration)
    }

    /// [`Session::finish`] in bounded steps: closes an open pose and returns a [`Calibrator`] over the
    /// session's poses. Step it with [`Session::poses`] (one GA generation per step) between other
    /// work, then hand its result to [`Session::conclude`].
    ///
    /// ```
    /// # use accelcal::session::{Session, SessionConfig};
    /// # use accelcal::calibrate::{DefaultRng, Step};
    /// # use rand_core::SeedableRng;
    /// # fn run(session: &mut Session<i16, 24, 32, 40>) -> Result<(), accelcal::session::SessionError> {
    /// let mut calibrator = session.begin_finish(DefaultRng::seed_from_u64(1))?;
    /// let calibration = loop {
    ///     match calibrator.step(session.poses()) {
    ///         Ok(accelcal::calibrate::Step::Running { .. }) => { /* run the control loop */ }
    ///         Ok(accelcal::calibrate::Step::Finished(c)) => break Ok(c),
    ///         Err(e) => break Err(e),
    ///     }
    /// };
    /// let result = session.conclude(calibration)?; // Done with the blob, or Failed with the poses kept
    /// # Ok(()) }
    /// ```
    pub fn begin_finish<G: Rng>(&mut self, rng: G) -> Result<Calibrator<G, POP, POSES>, SessionError> {
        self.close()?;
        Calibrator::new(self.acc.poses(), &self.config.calibration, rng).map_err(|e| self.fail(e.into()))
    }

    /// Closes an open pose before a solve; refuses a finished session.
    fn close(&mut self) -> Result<(), SessionError> {
        if self.state == State::Done {
            return Err(SessionError::Finished);
        }
        if let Ok(Some(Event::PoseCaptured(index))) = self.acc.finish() {
            let state = self.captured(usize::from(index));
            self.set_state(state);
        }
        Ok(())
    }

    /// Takes a calibration of the session's poses (from [`Session::begin_finish`]'s calibrator): when
    /// its verdict passes (and, in [`Mode::Guided`], every parameter was fitted) the session is
    /// [`State::Done`] with the blob; otherwise [`State::Failed`] with the poses kept.
    pub fn conclude(
        &mut self,
        calibration: Result<Calibration, CalibrationError>,
    ) -> Result<SessionResult, SessionError> {
        if self.state == State::Done {
            return Err(SessionError::Finished);
        }
        let calibration = calibration.map_err(|e| self.fail(SessionError::Calibration(e)))?;
        self.last = Some(calibration);
        #[cfg(feature = "defmt")]
        defmt::info!("session: pass {}, RMSE {} mg", calibration.verdict.pass(), calibration.verdict.rmse_after_mg);
        let verdict = &calibration.verdict;
        if !verdict.pass() {
            return Err(self.fail(SessionError::Verdict(verdict.failures)));
        }
        // Left-out poses are named but accepted; held parameters only in the six-face mode.
        if self.config.mode == Mode::Guided && verdict.warnings.held.iter().any(|&h| h) {
            return Err(self.fail(SessionError::Incomplete(verdict.warnings)));
        }
        let result = SessionResult {
            calibration,
            blob: encode(&calibration.params, self.config.calibration.gravity),
            poses: self.acc.poses().len(),
            duplicates: self.duplicates,
        };
        self.result = Some(result);
        self.set_state(State::Done);
        Ok(result)
    }

    /// [`State::Failed`] with the poses kept; `ready` waits for a new pose.
    fn fail(&mut self, error: SessionError) -> SessionError {
        self.ready = false;
        self.set_state(State::Failed(error));
        error
    }

    /// The current report (as the last [`Session::push`] returned it).
    pub fn progress(&self) -> Progress {
        Progress {
            state: self.state,
            poses: self.acc.poses().len(),
            duplicates: self.duplicates,
            rejections: self.acc.rejections(),
            sensor_errors: self.sensor_errors,
            guidance: self.guidance,
            faces_done: faces_done(self.acc.poses()).count_ones() as u8,
            ready: self.ready,
        }
    }

    /// The state.
    pub fn state(&self) -> State {
        self.state
    }

    /// The guidance computed at the last captured pose.
    pub fn guidance(&self) -> &Guidance {
        &self.guidance
    }

    /// The poses captured so far.
    pub fn poses(&self) -> &[Pose] {
        self.acc.poses()
    }

    /// The result, once [`State::Done`].
    pub fn result(&self) -> Option<&SessionResult> {
        self.result.as_ref()
    }

    /// The configuration.
    pub fn config(&self) -> &SessionConfig {
        &self.config
    }

    /// The accumulator (noise estimate, samples seen).
    pub fn accumulator(&self) -> &Accumulator<R, POSES, BLOCK> {
        &self.acc
    }

    fn advance(
        &mut self,
        event: Result<Option<Event>, AccumulatorError>,
        interrupted: bool,
    ) -> Result<Progress, SessionError> {
        let event = match event {
            Ok(event) => event,
            Err(e) => {
                let state = self.idle_state();
                self.set_state(state);
                return Err(e.into());
            }
        };
        let state = match event {
            Some(Event::StillnessDetected) => {
                let two_blocks = u32::try_from(BLOCK.saturating_mul(2)).unwrap_or(u32::MAX);
                self.pose_start = self.acc.samples_seen().saturating_sub(two_blocks);
                self.idle_state()
            }
            Some(Event::PoseCaptured(index)) => self.captured(usize::from(index)),
            Some(Event::PoseRejected(reason)) => State::PoseRejected(reason),
            None if interrupted => State::Interrupted,
            None => self.idle_state(),
        };
        self.set_state(state);
        Ok(self.progress())
    }

    /// The state between events: capturing (held long enough or not) or waiting.
    fn idle_state(&self) -> State {
        if self.acc.is_capturing() {
            let held = self.acc.samples_seen().saturating_sub(self.pose_start);
            if held >= self.config.hold_samples { State::MoveOn } else { State::Capturing { held } }
        } else {
            State::WaitingForStillness
        }
    }

    fn set_state(&mut self, state: State) {
        #[cfg(feature = "defmt")]
        if core::mem::discriminant(&self.state) != core::mem::discriminant(&state) {
            defmt::info!("session: {}", state);
        }
        self.state = state;
    }

    /// Pose `index` was captured: duplicate check, new guidance, done criterion.
    fn captured(&mut self, index: usize) -> State {
        let duplicate_of = find_duplicate(self.acc.poses(), index, self.duplicate_cos);
        if duplicate_of.is_some() {
            self.duplicates = self.duplicates.saturating_add(1);
        }
        self.refresh_guidance();
        #[cfg(feature = "defmt")]
        {
            defmt::info!(
                "session: pose {} captured (duplicate of {}), next: {}, worst std/bound {}, ready {}",
                index,
                duplicate_of,
                self.guidance.next,
                self.guidance.worst_std,
                self.ready
            );
        }
        State::PoseCaptured { index, duplicate_of }
    }

    /// New guidance and done criterion for the poses as they are.
    fn refresh_guidance(&mut self) {
        let poses = self.acc.poses();
        self.guidance = guidance_for::<POSES>(poses, &self.config.calibration);
        let enough = poses.len() >= self.config.min_poses;
        self.ready = match self.config.mode {
            Mode::Guided => {
                enough && self.guidance.basis == GuidanceBasis::Information && self.guidance.worst_std <= 1.0
            }
            Mode::SixFace => {
                let done = faces_done(poses);
                if let Some(next) = SIX_FACES.iter().enumerate().find(|(i, _)| done & (1 << i) == 0) {
                    self.guidance.next = *next.1;
                }
                self.guidance.basis = GuidanceBasis::Faces;
                enough && done == 0x3f
            }
        };
    }

    /// Removes pose `index` (a bad pose, or one to capture again: remove it, then hold the board in
    /// that orientation once more); the later poses move down by one. The guidance is updated.
    pub fn remove_pose(&mut self, index: usize) -> Result<Pose, SessionError> {
        if self.state == State::Done {
            return Err(SessionError::Finished);
        }
        let pose = self.acc.remove_pose(index).ok_or(SessionError::NoSuchPose)?;
        self.refresh_guidance();
        Ok(pose)
    }

    /// The last calibration [`Session::finish`] ran, passed or failed (a failed verdict says why).
    pub fn last_calibration(&self) -> Option<&Calibration> {
        self.last.as_ref()
    }
}

impl<const POSES: usize, const BLOCK: usize, const POP: usize> Session<i16, POSES, BLOCK, POP> {
    /// Runs the whole session on a sensor: reads samples, pushes them (a failed read is a
    /// [`Session::sensor_error`]), calls `on_progress` after each, and finishes with `rng` when
    /// `on_progress` breaks, the pose capacity is full or `limits.max_samples` reads were made.
    ///
    /// Pace the loop in `on_progress` (e.g. wait for the next sample tick) unless `read_raw` itself
    /// blocks until new data. After [`RunLimits::max_consecutive_errors`] failed reads in a row it
    /// returns [`RunError::Sensor`] with the poses kept.
    pub fn run_with_sensor<S: AccelSensor, G: Rng>(
        &mut self,
        sensor: &mut S,
        rng: G,
        limits: &RunLimits,
        mut on_progress: impl FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<SessionResult, RunError<S::Error>> {
        let mut consecutive_errors = 0u32;
        for _ in 0..limits.max_samples {
            let Some(progress) = self.take_read(sensor.read_raw(), &mut consecutive_errors, limits)? else { break };
            if on_progress(&progress).is_break() {
                break;
            }
        }
        Ok(self.finish(rng)?)
    }

    /// One read of a run: pushed (a failed read counted, see [`RunLimits`]); `None` when the pose
    /// capacity is full (the run finishes).
    pub(crate) fn take_read<E>(
        &mut self,
        read: Result<[i16; 3], E>,
        consecutive_errors: &mut u32,
        limits: &RunLimits,
    ) -> Result<Option<Progress>, RunError<E>> {
        match read {
            Ok(sample) => {
                *consecutive_errors = 0;
                match self.push(sample) {
                    Ok(progress) => Ok(Some(progress)),
                    Err(SessionError::Accumulator(AccumulatorError::Full)) => Ok(None),
                    Err(e) => Err(e.into()),
                }
            }
            Err(e) => {
                *consecutive_errors = consecutive_errors.saturating_add(1);
                let progress = self.read_failed(*consecutive_errors)?;
                if *consecutive_errors > limits.max_consecutive_errors {
                    return Err(RunError::Sensor(e));
                }
                if self.sensor_errors > limits.max_read_errors {
                    return Err(RunError::ReadErrorBudget(e));
                }
                Ok(Some(progress))
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Guidance
// ---------------------------------------------------------------------------------------------

/// The guidance for `poses`: in the frame of the initial estimate ([`Init::Auto`]: ellipsoid, or the
/// six faces) when one can be made, else in a provisional frame (zero offset, the mean reading
/// magnitude as 1 g on every axis), so that it works from the first pose, in any order.
fn guidance_for<const POSES: usize>(poses: &[Pose], calibration: &CalibrationConfig) -> Guidance {
    let (frame, basis) = guidance_frame::<POSES>(poses, calibration);
    Guidance { basis, ..information_guidance(&frame, poses, &calibration.bounds) }
}

/// The frame the guidance works in, and which one it is (see [`guidance_for`]).
fn guidance_frame<const POSES: usize>(poses: &[Pose], calibration: &CalibrationConfig) -> (Frame, GuidanceBasis) {
    let g = calibration.gravity;
    match NormalizedPoses::<POSES>::prepare(poses, Init::Auto, g, &calibration.outliers) {
        Ok(n) => (*n.frame(), GuidanceBasis::Information),
        Err(_) => (provisional_frame(poses, g), GuidanceBasis::Provisional),
    }
}

/// Cosine of the largest angle between a raw pose mean and a face for the pose to count as that face
/// (25 deg).
const FACE_COS: f32 = 0.906;

/// Bit `i` set when some pose lies within 25 deg of [`SIX_FACES`]`[i]` (raw means: the offsets are
/// small against 1 g on the sensors the session serves).
fn faces_done(poses: &[Pose]) -> u8 {
    let mut done = 0u8;
    for p in poses {
        let norm = crate::linalg::sqrt_f32(dot3(p.mean, p.mean));
        for (i, face) in SIX_FACES.iter().enumerate() {
            if dot3(p.mean, face.unit()) >= FACE_COS * norm && norm > 0.0 {
                done |= 1 << i;
            }
        }
    }
    done
}

/// Zero offset and the mean reading magnitude (1 when there is none) as `g` on every axis.
fn provisional_frame(poses: &[Pose], gravity: f32) -> Frame {
    let sum: f32 = poses.iter().map(|p| crate::linalg::sqrt_f32(dot3(p.mean, p.mean))).sum();
    let magnitude =
        if poses.is_empty() || !(sum > 0.0 && sum.is_finite()) { gravity } else { sum / poses.len() as f32 };
    let gain = magnitude / gravity;
    Frame::new([0.0; 3], [gain; 3], gravity).unwrap_or(Frame { offset: [0.0; 3], gain: [1.0; 3], gravity: 1.0 })
}

/// The earlier pose closest in direction to pose `index` within the duplicate angle (raw means: the
/// offsets are small against 1 g on the sensors the session serves).
fn find_duplicate(poses: &[Pose], index: usize, min_cos: f32) -> Option<usize> {
    let new = poses.get(index)?.mean;
    let new_norm = crate::linalg::sqrt_f32(dot3(new, new));
    let mut best: Option<(usize, f32)> = None;
    for (j, p) in poses.iter().enumerate() {
        if j == index {
            continue;
        }
        let d = p.mean;
        let cos = dot3(new, d) / (new_norm * crate::linalg::sqrt_f32(dot3(d, d)));
        if cos >= min_cos && best.is_none_or(|(_, c)| cos > c) {
            best = Some((j, cos));
        }
    }
    best.map(|(j, _)| j)
}

fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use super::*;
    use crate::model::Params;
    use crate::verdict::VerdictBounds;
    use rand_core::SeedableRng;

    const G: f32 = 9.80665;
    const TRUTH: Params = Params { bias: [0.12, -0.08, 0.1], scale: [0.97, 0.98, 0.99], nonorth: [-0.015, 0.01, 0.02] };

    type TestSession = Session<f32, 32, 32, 40>;

    fn config() -> SessionConfig {
        SessionConfig { hold_samples: 300, ..SessionConfig::DEFAULT }
    }

    /// A deterministic stream: `hold` still samples along `d` (+-0.5 mm/s^2 noise), then a move.
    struct Stream {
        state: u32,
    }

    impl Stream {
        fn noise(&mut self) -> f32 {
            self.state = self.state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (self.state >> 8) as f32 / 16_777_216.0 - 0.5
        }

        fn still(&mut self, d: [f32; 3], samples: usize) -> impl Iterator<Item = [f32; 3]> + '_ {
            let r = TRUTH.invert([d[0] * G, d[1] * G, d[2] * G]).unwrap();
            (0..samples).map(move |_| {
                let n = [self.noise(), self.noise(), self.noise()];
                [r[0] + 1e-3 * n[0], r[1] + 1e-3 * n[1], r[2] + 1e-3 * n[2]]
            })
        }

        fn moving(d: [f32; 3]) -> impl Iterator<Item = [f32; 3]> {
            (0..50).map(move |i| [d[0] * G + i as f32 * 0.3, d[1] * G - i as f32 * 0.1, d[2] * G - i as f32 * 0.2])
        }
    }

    /// Holds `d` for 400 samples then moves; returns the last progress.
    fn pose(session: &mut TestSession, stream: &mut Stream, d: [f32; 3]) -> Progress {
        for s in stream.still(d, 400) {
            session.push(s).unwrap();
        }
        let mut last = session.progress();
        for s in Stream::moving(d) {
            let p = session.push(s).unwrap();
            if matches!(p.state, State::PoseCaptured { .. }) {
                last = p;
            }
        }
        last
    }

    fn faces() -> [[f32; 3]; 6] {
        [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]]
    }

    #[test]
    fn cube_directions_are_the_26_distinct_unit_vectors() {
        let all = CubeDirection::ALL;
        for (i, a) in all.iter().enumerate() {
            let u = a.unit();
            assert!((dot3(u, u) - 1.0).abs() < 1e-6, "{a}");
            assert!(all[i + 1..].iter().all(|b| b != a));
        }
        let count = |k| all.iter().filter(|d| d.kind() == k).count();
        assert_eq!((count(DirectionKind::Face), count(DirectionKind::Edge), count(DirectionKind::Vertex)), (6, 12, 8));
        assert!(all[..6].iter().all(|d| d.kind() == DirectionKind::Face));
        assert_eq!(CubeDirection::face(2, true).to_string(), "face +z");
        assert_eq!(CubeDirection::new([-1, 1, -1]).unwrap().to_string(), "vertex -x+y-z");
        assert_eq!(CubeDirection::new([1, 0, -1]).unwrap().to_string(), "edge +x-z");
        assert_eq!(CubeDirection::new([0, 0, 0]), None);
        assert_eq!(CubeDirection::new([2, 0, 0]), None);
    }

    #[test]
    fn configuration_in_seconds_at_a_sample_rate() {
        let c = SessionConfig::at_rate(200.0, 5.0, 0.5);
        assert_eq!((c.hold_samples, c.accumulator.min_pose_samples), (1000, 100));
        assert_eq!(c, SessionConfig::DEFAULT);
        let c = SessionConfig::at_rate(1000.0, 2.0, 0.25);
        assert_eq!((c.hold_samples, c.accumulator.min_pose_samples), (2000, 250));
        // Nonsense rounds to a valid count or is refused by `new`.
        let c = SessionConfig::at_rate(f32::NAN, 2.0, 0.25);
        assert_eq!((c.hold_samples, c.accumulator.min_pose_samples), (1, 1));
        assert_eq!(TestSession::new(c).err(), Some(SessionError::InvalidConfig));
    }

    #[test]
    fn invalid_configurations_are_refused() {
        let bad = [
            SessionConfig { min_poses: 8, ..config() },
            SessionConfig { min_poses: 33, ..config() },
            SessionConfig { hold_samples: 150, ..config() }, // < 100 + 2 blocks of 32
            SessionConfig { duplicate_angle_deg: 90.0, ..config() },
            SessionConfig { duplicate_angle_deg: f32::NAN, ..config() },
            SessionConfig { calibration: CalibrationConfig { gravity: 0.0, ..CalibrationConfig::DEFAULT }, ..config() },
            SessionConfig {
                accumulator: AccumulatorConfig { enter_factor: -1.0, ..AccumulatorConfig::DEFAULT },
                ..config()
            },
        ];
        for c in bad {
            assert_eq!(TestSession::new(c).err(), Some(SessionError::InvalidConfig), "{c:?}");
        }
        assert!(TestSession::new(config()).is_ok());
        assert_eq!(SessionError::InvalidConfig.to_string(), "session configuration out of range");
    }

    /// Directions no cube face, edge or vertex is near: a free-hand start.
    fn free_directions() -> [[f32; 3]; 9] {
        let raw = [
            [0.3, 0.9, 0.3],
            [-0.8, 0.5, 0.33],
            [0.1, -0.7, 0.7],
            [0.6, 0.1, -0.8],
            [-0.2, -0.3, -0.93],
            [0.9, -0.4, 0.17],
            [-0.5, -0.8, 0.33],
            [0.05, 0.6, -0.8],
            [-0.7, 0.15, -0.7],
        ];
        raw.map(|d| {
            let n = libm::sqrtf(dot3(d, d));
            d.map(|v| v / n)
        })
    }

    #[test]
    fn guidance_works_from_any_start_and_order() {
        let mut session = TestSession::new(config()).unwrap();
        let mut stream = Stream { state: 1 };
        assert_eq!(session.progress().guidance.basis, GuidanceBasis::Provisional);
        let mut worst = f32::INFINITY;
        for (i, d) in free_directions().into_iter().enumerate() {
            let p = pose(&mut session, &mut stream, d);
            assert_eq!(p.state, State::PoseCaptured { index: i, duplicate_of: None });
            let expected = if i + 1 < PARAM_COUNT { GuidanceBasis::Provisional } else { GuidanceBasis::Information };
            assert_eq!(p.guidance.basis, expected, "after {} poses", i + 1);
            assert!(p.guidance.worst_std_after_next <= p.guidance.worst_std, "{:?}", p.guidance);
            worst = p.guidance.worst_std;
        }
        // Nine free directions: every parameter is determined, the suggestion improves on it.
        let g = *session.guidance();
        std::println!("after nine free poses: {g:?}");
        assert!(worst.is_finite() && g.worst_std_after_next < g.worst_std);
        let p = pose(&mut session, &mut stream, g.next.unit());
        assert!(p.guidance.worst_std < g.worst_std);
        assert!(!p.ready, "10 poses < min_poses");
    }

    #[test]
    fn a_failed_verdict_keeps_the_session_then_more_poses_pass() {
        // A strict bias bound nine poses cannot meet: the fit runs, fails its verdict, gives no blob.
        let strict = VerdictBounds { max_bias_std_mg: 0.002, ..VerdictBounds::DEFAULT };
        let cfg = SessionConfig {
            calibration: CalibrationConfig { bounds: strict, ..CalibrationConfig::DEFAULT },
            min_poses: 9,
            ..config()
        };
        let mut session = TestSession::new(cfg).unwrap();
        let mut stream = Stream { state: 11 };
        for d in free_directions() {
            pose(&mut session, &mut stream, d);
        }
        let e = session.finish(rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1)).unwrap_err();
        let SessionError::Verdict(failures) = e else { panic!("{e:?}") };
        assert!(failures.undetermined[..3].iter().any(|&u| u), "{failures:?}");
        assert_eq!((session.state(), session.result(), session.poses().len()), (State::Failed(e), None, 9));
        assert!(!session.progress().ready);
        assert!(!session.last_calibration().unwrap().verdict.pass());
        // Follow the guidance until ready, then finish again: the same session passes.
        let mut added = 0;
        while !session.progress().ready {
            let next = session.guidance().next;
            pose(&mut session, &mut stream, next.unit());
            added += 1;
            assert!(added <= 23, "not ready: {:?}", session.guidance());
        }
        let result = session.finish(rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1)).unwrap();
        std::println!("passed after {added} more poses: {:?}", result.calibration.verdict);
        assert!(result.calibration.verdict.pass() && session.state() == State::Done);
        assert_eq!(result.poses, 9 + added);
    }

    #[test]
    fn the_six_face_quick_mode_asks_for_the_faces_in_vehicle_terms() {
        let mut session = TestSession::new(SessionConfig { hold_samples: 300, ..SessionConfig::SIX_FACE }).unwrap();
        let mut stream = Stream { state: 19 };
        let mut asked = heapless::Vec::<&str, 6>::new();
        while !session.progress().ready {
            let next = session.guidance().next;
            assert_eq!(session.guidance().basis, GuidanceBasis::Faces);
            let _ = asked.push(next.vehicle_name().unwrap());
            let p = pose(&mut session, &mut stream, next.unit());
            assert_eq!(usize::from(p.faces_done), asked.len());
            assert!(asked.len() <= 6);
        }
        let expected = ["level", "upside down", "nose up", "nose down", "left side down", "right side down"];
        assert_eq!(asked.as_slice(), &expected);
        let result = session.finish(rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1)).unwrap();
        let v = result.calibration.verdict;
        assert!(v.pass(), "{v:?}");
        assert_eq!(v.warnings.held, [false, false, false, false, false, false, true, true, true]);
        assert_eq!(result.calibration.params.nonorth, [0.0; 3]);
    }

    #[test]
    fn a_stepped_finish_equals_the_one_call_finish() {
        let run = |stepped: bool| {
            let mut session = TestSession::new(config()).unwrap();
            let mut stream = Stream { state: 23 };
            while !session.progress().ready {
                let next = session.guidance().next;
                pose(&mut session, &mut stream, next.unit());
            }
            let rng = rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(5);
            if !stepped {
                return (session.finish(rng).unwrap(), 0);
            }
            let mut calibrator = session.begin_finish(rng).unwrap();
            let mut steps = 0;
            let calibration = loop {
                steps += 1;
                match calibrator.step(session.poses()) {
                    Ok(crate::calibrate::Step::Running { generation }) => assert_eq!(generation, steps),
                    Ok(crate::calibrate::Step::Finished(c)) => break Ok(c),
                    Err(e) => break Err(e),
                }
            };
            (session.conclude(calibration).unwrap(), steps)
        };
        let ((at_once, _), (stepped, steps)) = (run(false), run(true));
        assert_eq!(at_once, stepped);
        assert_eq!(steps, stepped.calibration.generations + 1);
    }

    #[test]
    fn a_bad_pose_can_be_removed() {
        let mut session = TestSession::new(config()).unwrap();
        let mut stream = Stream { state: 13 };
        for d in free_directions() {
            pose(&mut session, &mut stream, d);
        }
        let third = session.poses()[2];
        assert_eq!(session.remove_pose(2), Ok(third));
        assert_eq!(session.poses().len(), 8);
        assert_eq!(session.progress().guidance.basis, GuidanceBasis::Provisional, "8 poses: no fit yet");
        assert_eq!(session.remove_pose(8), Err(SessionError::NoSuchPose));
        // Captured again: back to nine.
        let p = pose(&mut session, &mut stream, free_directions()[2]);
        assert_eq!(p.state, State::PoseCaptured { index: 8, duplicate_of: None });
        assert_eq!(p.guidance.basis, GuidanceBasis::Information);
    }

    #[test]
    fn following_the_guidance_gets_ready_and_calibrates() {
        let mut session = TestSession::new(config()).unwrap();
        let mut stream = Stream { state: 7 };
        let mut poses = 0;
        while !session.progress().ready {
            let next = session.guidance().next;
            let p = pose(&mut session, &mut stream, next.unit());
            poses += 1;
            assert_eq!(p.poses, poses);
            assert!(poses <= 20, "not ready after 20 poses: {:?}", p.guidance);
        }
        std::println!("ready after {poses} poses: {:?}", session.guidance());
        assert!(poses >= 12);
        assert!(session.guidance().worst_std <= 1.0);
        let result = session.finish(rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(3)).unwrap();
        assert!(result.calibration.verdict.pass(), "{:?}", result.calibration.verdict);
        assert_eq!(session.state(), State::Done);
        assert_eq!(session.result(), Some(&result));
        let (params, gravity) = crate::blob::decode(&result.blob).unwrap();
        assert_eq!((params, gravity), (result.calibration.params, G));
        for (got, want) in params.to_array().iter().zip(TRUTH.to_array()) {
            assert!((got - want).abs() < 1e-3, "{params:?}");
        }
        assert_eq!(session.push([0.0; 3]), Err(SessionError::Finished));
        assert_eq!(session.sensor_error(), Err(SessionError::Finished));
        assert!(session.finish(rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(3)).is_err());
    }

    #[test]
    fn states_follow_the_pose_cycle_and_duplicates_are_kept_and_reported() {
        let mut session = TestSession::new(config()).unwrap();
        let mut stream = Stream { state: 3 };
        let d = [0.0, 0.0, 1.0];
        let mut seen_capturing = false;
        let mut seen_move_on = false;
        for s in stream.still(d, 400) {
            match session.push(s).unwrap().state {
                State::Capturing { .. } => seen_capturing = true,
                State::MoveOn => {
                    assert!(seen_capturing);
                    seen_move_on = true;
                }
                State::WaitingForStillness => assert!(!seen_capturing),
                other => panic!("unexpected {other:?}"),
            }
        }
        assert!(seen_move_on);
        let states: heapless::Vec<State, 64> = Stream::moving(d).map(|s| session.push(s).unwrap().state).collect();
        assert!(states.contains(&State::PoseCaptured { index: 0, duplicate_of: None }));
        assert_eq!(states.last(), Some(&State::WaitingForStillness));
        // Tilted by 5 degrees: a duplicate of pose 0, kept.
        let t = 5f32.to_radians();
        let p = pose(&mut session, &mut stream, [libm::sinf(t), 0.0, libm::cosf(t)]);
        assert_eq!(p.state, State::PoseCaptured { index: 1, duplicate_of: Some(0) });
        assert_eq!((p.poses, p.duplicates), (2, 1));
        // 20 degrees away: not a duplicate.
        let t = 20f32.to_radians();
        let p = pose(&mut session, &mut stream, [0.0, libm::sinf(t), libm::cosf(t)]);
        assert_eq!(p.state, State::PoseCaptured { index: 2, duplicate_of: None });
    }

    #[test]
    fn a_sensor_error_keeps_the_poses_and_the_capture_resumes() {
        let mut session = TestSession::new(config()).unwrap();
        let mut stream = Stream { state: 5 };
        pose(&mut session, &mut stream, [0.0, 0.0, 1.0]);
        let before = *session.poses().first().unwrap();
        // Half a pose, then the sensor fails: the half is long enough and is kept.
        for s in stream.still([1.0, 0.0, 0.0], 250) {
            session.push(s).unwrap();
        }
        let p = session.sensor_error().unwrap();
        assert_eq!(p.state, State::PoseCaptured { index: 1, duplicate_of: None });
        assert_eq!((p.poses, p.sensor_errors), (2, 1));
        // A second error with nothing open.
        assert_eq!(session.sensor_error().unwrap().state, State::Interrupted);
        // The sensor is back, still in the same orientation: a duplicate of the first half.
        let p = pose(&mut session, &mut stream, [1.0, 0.0, 0.0]);
        assert_eq!(p.state, State::PoseCaptured { index: 2, duplicate_of: Some(1) });
        assert_eq!(session.poses()[0], before);
        assert_eq!(session.progress().sensor_errors, 2);
    }

    #[test]
    fn bad_samples_and_early_finish_are_typed_errors_and_recoverable() {
        let mut session = TestSession::new(config()).unwrap();
        let mut stream = Stream { state: 9 };
        assert_eq!(
            session.push_vector(micromath::vector::F32x3 { x: f32::NAN, y: 0.0, z: 0.0 }),
            Err(SessionError::Accumulator(AccumulatorError::NonFiniteSample))
        );
        for d in faces() {
            pose(&mut session, &mut stream, d);
        }
        // Six faces fit the biases and scale factors only: the guided mode wants them all.
        let e = session.finish(rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1)).unwrap_err();
        let SessionError::Incomplete(warnings) = e else { panic!("{e:?}") };
        assert_eq!(warnings.held, [false, false, false, false, false, false, true, true, true]);
        assert_eq!(session.result(), None);
        assert_eq!(session.state(), State::Failed(e));
        assert_eq!(session.poses().len(), 6);
        // Capture resumes after a failed finish.
        let p = pose(&mut session, &mut stream, [0.577_350_27; 3]);
        assert_eq!(p.poses, 7);
    }

    #[test]
    fn a_sensor_failing_one_read_in_100_still_completes() {
        /// Free-hand poses in raw counts (16384 LSB/g), each 500 reads then 50 of motion; every 100th
        /// read fails.
        struct Flaky {
            stream: Stream,
            read: u32,
        }
        impl AccelSensor for Flaky {
            type Error = u32;
            fn read_raw(&mut self) -> Result<[i16; 3], u32> {
                self.read += 1;
                if self.read.is_multiple_of(100) {
                    return Err(self.read);
                }
                let dirs = free_directions();
                let (pose, at) = ((self.read / 550) as usize, self.read % 550);
                let d = dirs[pose % dirs.len()];
                let turn = if pose % 2 == 0 { 1.0 } else { -1.0 };
                let d = if pose >= dirs.len() { [d[1], d[2] * turn, d[0]] } else { d };
                let r = TRUTH.invert(d.map(|v| v * G)).unwrap_or([0.0; 3]);
                let moving = if at >= 500 { (at - 500) as f32 * 60.0 } else { 0.0 };
                let n = self.stream.noise() * 4.0;
                Ok(core::array::from_fn(|a| (r[a] * 16384.0 / G + n + moving) as i16))
            }
        }
        let mut sensor = Flaky { stream: Stream { state: 17 }, read: 0 };
        let config = SessionConfig { min_poses: 14, hold_samples: 400, ..config() };
        let mut session: Session<i16, 32, 32, 40> = Session::new(config).unwrap();
        let limits = RunLimits { max_samples: 20 * 550, ..RunLimits::DEFAULT };
        let rng = rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(2);
        let result = session.run_with_sensor(&mut sensor, rng, &limits, |p| {
            if p.ready { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
        let result = result.unwrap_or_else(|e| panic!("{e:?}: {:?}", session.progress()));
        assert!(result.calibration.verdict.pass(), "{:?}", result.calibration.verdict);
        assert!(result.poses >= 14, "{result:?}");
        assert!(session.progress().sensor_errors >= 70, "{:?}", session.progress());
    }

    #[test]
    fn run_with_sensor_gives_up_past_the_read_error_budget() {
        struct Broken;
        impl AccelSensor for Broken {
            type Error = ();
            fn read_raw(&mut self) -> Result<[i16; 3], ()> {
                Err(())
            }
        }
        let mut session: Session<i16, 16, 32, 8> = Session::new(config()).unwrap();
        let limits = RunLimits { max_consecutive_errors: u32::MAX, max_read_errors: 50, ..RunLimits::DEFAULT };
        let rng = rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1);
        let r = session.run_with_sensor(&mut Broken, rng, &limits, |_| ControlFlow::Continue(()));
        assert_eq!(r.err(), Some(RunError::ReadErrorBudget(())));
        assert_eq!(session.progress().sensor_errors, 51);
    }

    #[test]
    fn run_with_sensor_reads_until_told_to_stop() {
        struct Scripted {
            samples: heapless::Vec<[i16; 3], 4096>,
            at: usize,
        }
        impl AccelSensor for Scripted {
            type Error = ();
            fn read_raw(&mut self) -> Result<[i16; 3], ()> {
                self.at += 1;
                self.samples.get(self.at - 1).copied().ok_or(())
            }
        }
        let mut sensor = Scripted { samples: heapless::Vec::new(), at: 0 };
        for i in 0..600 {
            let _ = sensor.samples.push([(i % 3) as i16, 0, 16384]);
        }
        let mut session: Session<i16, 16, 32, 8> = Session::new(config()).unwrap();
        let mut calls = 0;
        let r = session.run_with_sensor(
            &mut sensor,
            rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1),
            &RunLimits::DEFAULT,
            |_| {
                calls += 1;
                ControlFlow::Continue(())
            },
        );
        // The stream ends: the open pose is closed by the first error, then the run gives up.
        assert_eq!(r.err(), Some(RunError::Sensor(())));
        assert_eq!(calls, 600 + RunLimits::DEFAULT.max_consecutive_errors);
        assert_eq!(session.poses().len(), 1);
        assert_eq!(session.progress().sensor_errors, 11);
    }
}
