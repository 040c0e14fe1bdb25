//! A guided calibration session for firmware: feed samples, tell the person holding the board what to
//! do next, calibrate when there is enough.
//!
//! A [`Session`] wraps an [`Accumulator`] and runs a small state machine on its events:
//!
//! ```text
//! WaitingForStillness -> Capturing -> MoveOn -> PoseCaptured -> WaitingForStillness -> ...
//!                                 \-> PoseRejected (moved too early, saturated) -/
//! any -> Interrupted (sensor error; poses kept) -> WaitingForStillness
//! finish() -> Done | Failed (poses kept: capture more and finish again)
//! ```
//!
//! Every [`Session::push`] returns a [`Progress`]: the state, poses captured, rejections, duplicates,
//! and a [`Guidance`] computed once per captured pose (the per-sample path is the accumulator's plus a
//! few comparisons; the guidance is some ten thousand `f64` operations, software-emulated on a
//! Cortex-M4F, done while the person is already turning the board):
//!
//! - until every axis has been seen pointing up and down, the guidance names the missing face;
//! - then the poses are normalised with the coarse (six-position) frame and each of the 26 cube
//!   directions ([`CubeDirection`]: faces, edges, vertices) is scored by the parameter standard
//!   deviations the information matrix predicts if that orientation were added next (with the noise
//!   measured so far). The standard deviations are normalised by the [`VerdictBounds`] of the
//!   calibration (1 = at the bound); the best candidate minimises the worst one, ties broken by the
//!   sum of squares (A-optimal). A weak prior (standard deviation 0.5 in every deviation coordinate
//!   of [`crate::frame`]) keeps the matrix invertible while some terms are not determined at all:
//!   such a term shows the prior's standard deviation (e.g. 50 for a non-orthogonality term under
//!   the default bounds), which no sensible bound accepts.
//!
//! [`Progress::ready`] says when the done criterion is met: at least
//! [`SessionConfig::min_poses`] poses and every predicted standard deviation within its bound.
//! [`Session::finish`] then runs [`calibrate`] (coarse, TAGA, LM, verdict) and returns the
//! parameters, the verdict and the [`blob`](crate::blob) for flash.
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
use crate::calibrate::{Calibration, CalibrationConfig, CalibrationError, calibrate};
use crate::coarse::{CoarseCalibration, CoarseError};
use crate::frame::{Frame, NormPose, modulus_error_gradient};
use crate::model::PARAM_COUNT;
use crate::sensor::AccelSensor;
use crate::verdict::VerdictBounds;

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

/// Session settings.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SessionConfig {
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
        accumulator: AccumulatorConfig::DEFAULT,
        calibration: CalibrationConfig::DEFAULT,
        min_poses: 12,
        hold_samples: 1000,
        duplicate_angle_deg: 10.0,
    };

    /// Checks the accumulator settings, `min_poses >= 9`, `hold_samples >= min_pose_samples`, the
    /// duplicate angle, a finite positive gravity and positive (possibly infinite) parameter bounds.
    /// The checks that depend on the capacities are made by [`Session::new`].
    pub fn validate(&self) -> Result<(), SessionError> {
        self.accumulator.validate()?;
        let g = self.calibration.gravity;
        let b = &self.calibration.bounds;
        let positive = |v: f32| v > 0.0;
        let ok = self.min_poses >= PARAM_COUNT
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
    /// The session is [`State::Done`]; start a new one.
    Finished,
}

impl core::fmt::Display for SessionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::InvalidConfig => f.write_str("session configuration out of range"),
            Self::Accumulator(e) => write!(f, "accumulator: {e}"),
            Self::Calibration(e) => write!(f, "calibration: {e}"),
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
    /// Some axis has not been seen pointing up or down yet: the suggestion is that face.
    MissingFace,
    /// The predicted parameter standard deviations (see the [module docs](self)).
    Information,
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
    /// bound (all `true` before the six faces exist).
    pub poorly_determined: [bool; PARAM_COUNT],
    /// Largest predicted standard deviation over its bound (1 = at the bound); infinite before the
    /// six faces exist.
    pub worst_std: f32,
    /// The same after adding `next` (a prediction with the current noise).
    pub worst_std_after_next: f32,
}

impl Guidance {
    fn missing_face(next: CubeDirection) -> Self {
        Self {
            next,
            basis: GuidanceBasis::MissingFace,
            poorly_determined: [true; PARAM_COUNT],
            worst_std: f32::INFINITY,
            worst_std_after_next: f32::INFINITY,
        }
    }
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
    /// The done criterion is met: [`Session::finish`] is expected to pass the verdict.
    pub ready: bool,
}

/// A finished session.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SessionResult {
    /// Parameters, coarse estimate, verdict, optimiser statistics.
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
}

impl RunLimits {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { max_samples: u32::MAX, max_consecutive_errors: 10 };
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
        Ok(Self {
            config,
            acc,
            state: State::WaitingForStillness,
            pose_start: 0,
            guidance: missing_face_guidance(&[], None),
            duplicates: 0,
            sensor_errors: 0,
            ready: false,
            duplicate_cos,
            result: None,
        })
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

    /// Closes an open pose and calibrates with every pose captured ([`calibrate`]: coarse, then the
    /// configured optimiser, TAGA + LM by default, then the verdict), seeded by `rng`. On success the
    /// session is [`State::Done`]; on failure [`State::Failed`] with the poses kept.
    pub fn finish<G: Rng>(&mut self, rng: G) -> Result<SessionResult, SessionError> {
        if self.state == State::Done {
            return Err(SessionError::Finished);
        }
        if let Ok(Some(Event::PoseCaptured(index))) = self.acc.finish() {
            let state = self.captured(index);
            self.set_state(state);
        }
        #[cfg(feature = "defmt")]
        defmt::info!("session: solving with {} poses", self.acc.poses().len());
        match calibrate::<G, POP, POSES>(self.acc.poses(), &self.config.calibration, rng) {
            Ok(calibration) => {
                let result = SessionResult {
                    calibration,
                    blob: encode(&calibration.params, self.config.calibration.gravity),
                    poses: self.acc.poses().len(),
                    duplicates: self.duplicates,
                };
                self.result = Some(result);
                self.set_state(State::Done);
                #[cfg(feature = "defmt")]
                defmt::info!(
                    "session: done, pass {}, RMSE {} mg",
                    calibration.verdict.pass(),
                    calibration.verdict.rmse_after_mg
                );
                Ok(result)
            }
            Err(e) => {
                let error = SessionError::Calibration(e);
                self.set_state(State::Failed(error));
                Err(error)
            }
        }
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
            Some(Event::PoseCaptured(index)) => self.captured(index),
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
        let poses = self.acc.poses();
        let mut means: heapless::Vec<[f32; 3], POSES> = heapless::Vec::new();
        for p in poses {
            // Same capacity as the accumulator's pose list.
            let _ = means.push(p.mean);
        }
        let coarse = CoarseCalibration::from_means(&means, self.config.calibration.gravity);
        let frame = coarse.as_ref().ok().map(|c| *c.frame());
        let duplicate_of = find_duplicate(poses, index, frame.as_ref(), self.duplicate_cos);
        self.guidance = match (frame, coarse) {
            (Some(frame), _) => information_guidance(&frame, poses, &self.config.calibration.bounds),
            (None, Err(e)) => missing_face_guidance(poses, Some(e)),
            (None, Ok(_)) => missing_face_guidance(poses, None),
        };
        if duplicate_of.is_some() {
            self.duplicates = self.duplicates.saturating_add(1);
        }
        self.ready = poses.len() >= self.config.min_poses
            && self.guidance.basis == GuidanceBasis::Information
            && self.guidance.worst_std <= 1.0;
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
            let progress = match sensor.read_raw() {
                Ok(sample) => {
                    consecutive_errors = 0;
                    match self.push(sample) {
                        Ok(progress) => progress,
                        Err(SessionError::Accumulator(AccumulatorError::Full)) => break,
                        Err(e) => return Err(e.into()),
                    }
                }
                Err(e) => {
                    consecutive_errors = consecutive_errors.saturating_add(1);
                    let progress = self.sensor_error()?;
                    if consecutive_errors > limits.max_consecutive_errors {
                        return Err(RunError::Sensor(e));
                    }
                    progress
                }
            };
            if on_progress(&progress).is_break() {
                break;
            }
        }
        Ok(self.finish(rng)?)
    }
}

// ---------------------------------------------------------------------------------------------
// Guidance
// ---------------------------------------------------------------------------------------------

/// Fraction of a raw pose mean on its dominant axis for it to count as a face (cos 25 deg, as the
/// coarse calibration uses).
const FACE_DOMINANCE: f32 = 0.906;

/// The order in which missing faces are asked for: `(axis, up)`, board flat first.
const FACE_ORDER: [(u8, bool); 6] = [(2, true), (2, false), (0, true), (0, false), (1, true), (1, false)];

/// Prior standard deviation of every deviation coordinate (bias 0.5 g, scale 50 %, non-orthogonality
/// 0.5 rad): keeps the information matrix invertible before every term is determined.
const PRIOR_STD: f64 = 0.5;

/// Smallest per-axis noise variance assumed, relative to `(k g)^2` (a standard deviation of 1e-7 g,
/// the resolution of the normalised `f32` pose).
const NOISE_FLOOR: f64 = 1e-14;

/// Relative tolerance under which two candidates' worst variances tie.
const TIE: f64 = 1e-6;

/// Before the six faces: the first face in [`FACE_ORDER`] no pose points along. Faces are recognised
/// by the dominant axis of the raw mean, which assumes the zero-g offset is small compared with 1 g
/// (true of signed outputs such as the MPU-6050's); if every face seems present the coarse error names
/// the axis.
fn missing_face_guidance(poses: &[Pose], error: Option<CoarseError>) -> Guidance {
    let mut present = [[false; 2]; 3];
    for p in poses {
        let m = p.mean;
        let norm = libm::sqrtf(m[0] * m[0] + m[1] * m[1] + m[2] * m[2]);
        for (a, seen) in present.iter_mut().enumerate() {
            if norm > 0.0 && m[a].abs() >= FACE_DOMINANCE * norm {
                seen[usize::from(m[a] < 0.0)] = true;
            }
        }
    }
    let missing = FACE_ORDER
        .iter()
        .copied()
        .find(|&(axis, up)| !present[usize::from(axis)][usize::from(!up)])
        .or(match error {
            Some(CoarseError::MissingAxisPair { axis, up }) => Some((axis, up)),
            _ => None,
        })
        .unwrap_or((2, true));
    Guidance::missing_face(CubeDirection::face(missing.0, missing.1))
}

/// The earlier pose closest in direction to pose `index` within the duplicate angle. Directions are
/// the normalised means when the coarse frame exists, else the raw means.
fn find_duplicate(poses: &[Pose], index: usize, frame: Option<&Frame>, min_cos: f32) -> Option<usize> {
    let direction = |p: &Pose| match frame {
        Some(f) => f.normalize(p.mean).u,
        None => p.mean,
    };
    let new = direction(poses.get(index)?);
    let new_norm = libm::sqrtf(dot3(new, new));
    let mut best: Option<(usize, f32)> = None;
    for (j, p) in poses.iter().enumerate() {
        if j == index {
            continue;
        }
        let d = direction(p);
        let cos = dot3(new, d) / (new_norm * libm::sqrtf(dot3(d, d)));
        if cos >= min_cos && best.is_none_or(|(_, c)| cos > c) {
            best = Some((j, cos));
        }
    }
    best.map(|(j, _)| j)
}

fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

type Matrix64 = [[f64; PARAM_COUNT]; PARAM_COUNT];
type Vector64 = [f64; PARAM_COUNT];

/// Variance of the normalised modulus error `E / g^2` of a pose along `u` at the coarse estimate:
/// `4 sum u_a^2 sigma_a^2 / (n (k_a g)^2)`; `relative` holds `sigma_a^2 / (n (k_a g)^2)`.
fn error_variance(u: [f32; 3], relative: [f64; 3]) -> f64 {
    let mut v = 0.0;
    for a in 0..3 {
        v += 4.0 * f64::from(u[a]) * f64::from(u[a]) * relative[a];
    }
    v.max(4.0 * NOISE_FLOOR)
}

/// Gradient of `E / g^2` with respect to the deviation vector at the coarse estimate.
fn gradient(u: [f32; 3]) -> Vector64 {
    let q = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] - 1.0;
    modulus_error_gradient(&[0.0; PARAM_COUNT], &NormPose { u, q }).1.map(f64::from)
}

/// One paper-convention parameter divided by its verdict bound, as a sparse combination of the
/// deviation coordinates (at most four terms: the bias couples to `Ka c`).
#[derive(Clone, Copy)]
struct SparseRow {
    index: [u8; PARAM_COUNT],
    value: [f64; PARAM_COUNT],
    len: usize,
}

impl SparseRow {
    fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.index.iter().zip(&self.value).take(self.len).map(|(&i, &v)| (usize::from(i), v))
    }

    fn dot(&self, v: &Vector64) -> f64 {
        self.terms().map(|(i, r)| r * v.get(i).copied().unwrap_or(0.0)).sum()
    }

    /// `r^T m r`.
    fn quadratic(&self, m: &Matrix64) -> f64 {
        let at = |i: usize, j: usize| m.get(i).and_then(|row| row.get(j)).copied().unwrap_or(0.0);
        self.terms().map(|(i, r)| r * self.terms().map(|(j, q)| at(i, j) * q).sum::<f64>()).sum()
    }
}

/// The parameters divided by their verdict bounds (as [`crate::verdict::judge`] sets them), at the
/// coarse estimate.
fn normalised_rows(frame: &Frame, bounds: &VerdictBounds) -> [SparseRow; PARAM_COUNT] {
    let x0 = [0.0; PARAM_COUNT];
    let t = frame.params_jacobian();
    let params = frame.to_params(&x0);
    let g = frame.gravity;
    let mut rows = [SparseRow { index: [0; PARAM_COUNT], value: [0.0; PARAM_COUNT], len: 0 }; PARAM_COUNT];
    for (i, row) in rows.iter_mut().enumerate() {
        let limit = match i {
            0..=2 => bounds.max_bias_std_mg * g / 1000.0,
            3..=5 => bounds.max_scale_std_rel * params.scale[i - 3].abs(),
            _ => bounds.max_nonorth_std * params.scale[if i == 8 { 1 } else { 0 }].abs(),
        };
        for j in 0..PARAM_COUNT {
            if t[i][j] == 0.0 {
                continue;
            }
            let v = f64::from(t[i][j]) / f64::from(limit);
            if let (true, Some(index), Some(value)) =
                (v.is_finite() && v != 0.0, row.index.get_mut(row.len), row.value.get_mut(row.len))
            {
                *index = j as u8;
                *value = v;
                row.len += 1;
            }
        }
    }
    rows
}

/// Scores the 26 cube directions by the predicted normalised parameter variances after adding each
/// (rank-one update of the covariance) and returns the best with the current state.
fn information_guidance(frame: &Frame, poses: &[Pose], bounds: &VerdictBounds) -> Guidance {
    let mut scale_sq = [0.0f64; 3];
    for a in 0..3 {
        let s = f64::from(frame.gain[a]) * f64::from(frame.gravity);
        scale_sq[a] = s * s;
    }
    // Lower triangle only (all `spd_inverse_f64` reads).
    let mut info = [[0.0f64; PARAM_COUNT]; PARAM_COUNT];
    for (i, row) in info.iter_mut().enumerate() {
        row[i] = 1.0 / (PRIOR_STD * PRIOR_STD);
    }
    let mut noise_sum = [0.0f64; 3];
    let mut n_sum = 0.0f64;
    for p in poses {
        let n = f64::from(p.n.max(1));
        let mut relative = [0.0; 3];
        for a in 0..3 {
            let v = (f64::from(p.variance[a]) / scale_sq[a]).max(NOISE_FLOOR);
            noise_sum[a] += v;
            relative[a] = v / n;
        }
        n_sum += n;
        let u = frame.normalize(p.mean).u;
        let g = gradient(u);
        let w = 1.0 / error_variance(u, relative);
        for i in 0..PARAM_COUNT {
            let gi = g[i] * w;
            for j in 0..=i {
                info[i][j] += gi * g[j];
            }
        }
    }
    let count = poses.len().max(1) as f64;
    let n_mean = (n_sum / count).max(1.0);
    let candidate_noise = noise_sum.map(|v| (v / count).max(NOISE_FLOOR) / n_mean);

    let Some(cov) = spd_inverse_f64(&info) else {
        return missing_face_guidance(poses, None);
    };
    let rows = normalised_rows(frame, bounds);
    let current = rows.map(|r| r.quadratic(&cov));
    let mut best = (CubeDirection::face(2, true), f64::INFINITY, f64::INFINITY);
    for d in CubeDirection::ALL {
        let u = d.unit();
        let g = gradient(u);
        let w = mat_vec(&cov, &g);
        let denominator = error_variance(u, candidate_noise) + dot(&g, &w);
        let (mut worst, mut sum) = (0.0f64, 0.0f64);
        for (row, now) in rows.iter().zip(current) {
            let tw = row.dot(&w);
            let v = now - tw * tw / denominator;
            if v > worst {
                worst = v;
            }
            sum += v;
        }
        let (_, best_worst, best_sum) = best;
        if worst < best_worst * (1.0 - TIE) || (worst <= best_worst * (1.0 + TIE) && sum < best_sum) {
            best = (d, worst, sum);
        }
    }
    let worst_now = current.iter().fold(0.0f64, |m, &v| if v > m { v } else { m });
    Guidance {
        next: best.0,
        basis: GuidanceBasis::Information,
        poorly_determined: current.map(|v| !(v <= 1.0)),
        worst_std: libm::sqrt(worst_now) as f32,
        worst_std_after_next: libm::sqrt(best.1) as f32,
    }
}

fn dot(a: &Vector64, b: &Vector64) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn mat_vec(m: &Matrix64, v: &Vector64) -> Vector64 {
    let mut out = [0.0; PARAM_COUNT];
    for (o, row) in out.iter_mut().zip(m) {
        *o = dot(row, v);
    }
    out
}

/// Inverse of a symmetric positive definite matrix in `f64` (Jacobi-scaled Cholesky): the information
/// matrix spans about ten decades between determined terms and the prior, too many for `f32`.
fn spd_inverse_f64(a: &Matrix64) -> Option<Matrix64> {
    const N: usize = PARAM_COUNT;
    let mut d = [0.0; N];
    for i in 0..N {
        if !(a[i][i] > 0.0 && a[i][i].is_finite()) {
            return None;
        }
        d[i] = 1.0 / libm::sqrt(a[i][i]);
    }
    let mut l = [[0.0f64; N]; N];
    for i in 0..N {
        for j in 0..=i {
            let mut s = a[i][j] * d[i] * d[j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return None;
                }
                l[i][i] = libm::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut inv = [[0.0; N]; N];
    for col in 0..N {
        // Solve L L^T x = e_col.
        let mut y = [0.0; N];
        for i in 0..N {
            let mut s = if i == col { 1.0 } else { 0.0 };
            for k in 0..i {
                s -= l[i][k] * y[k];
            }
            y[i] = s / l[i][i];
        }
        let mut x = [0.0; N];
        for i in (0..N).rev() {
            let mut s = y[i];
            for k in i + 1..N {
                s -= l[k][i] * x[k];
            }
            x[i] = s / l[i][i];
        }
        for i in 0..N {
            inv[i][col] = x[i] * d[i] * d[col];
        }
    }
    Some(inv)
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::string::ToString;

    use super::*;
    use crate::model::Params;
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

    #[test]
    fn asks_for_the_missing_faces_then_for_edges_or_vertices() {
        let mut session = TestSession::new(config()).unwrap();
        let mut stream = Stream { state: 1 };
        assert_eq!(session.progress().guidance.next, CubeDirection::face(2, true));
        let expected_next = ["face -z", "face +x", "face -x", "face +y", "face -y"];
        for (i, d) in faces().into_iter().enumerate() {
            let p = pose(&mut session, &mut stream, d);
            assert_eq!(p.state, State::PoseCaptured { index: i, duplicate_of: None });
            if i < 5 {
                assert_eq!(p.guidance.basis, GuidanceBasis::MissingFace);
                assert_eq!(p.guidance.next.to_string(), expected_next[i]);
            }
        }
        let g = *session.guidance();
        assert_eq!(g.basis, GuidanceBasis::Information);
        assert_ne!(g.next.kind(), DirectionKind::Face, "{}", g.next);
        // Six poses cannot determine nine parameters; the non-orthogonality is the part the faces do
        // not see at all.
        std::println!("after the faces: {g:?}");
        assert_eq!(&g.poorly_determined[6..], &[true; 3]);
        assert!(g.worst_std_after_next < g.worst_std);
        // Capture the suggestion: the next one is another direction.
        let p = pose(&mut session, &mut stream, g.next.unit());
        assert_eq!(p.state, State::PoseCaptured { index: 6, duplicate_of: None });
        std::println!("after {}: {:?}", g.next, p.guidance);
        assert_ne!(p.guidance.next, g.next);
        assert!(p.guidance.worst_std < g.worst_std);
        assert!(!p.ready);
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
        let e = session.finish(rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1)).unwrap_err();
        assert!(matches!(e, SessionError::Calibration(_)), "{e:?}");
        assert_eq!(session.state(), State::Failed(e));
        assert_eq!(session.poses().len(), 6);
        // Capture resumes after a failed finish.
        let p = pose(&mut session, &mut stream, [0.577_350_27; 3]);
        assert_eq!(p.poses, 7);
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
