//! The simulator's settings ([`SimConfig`]) with their checks, the paper's truth and random truths.

use std::fmt;

use accelcal::model::Params;

use super::plan::Plan;
use super::random::{Stream, stream_rng, uniform_in};
use super::record::Layout;
use super::units::OutputUnits;

/// Standard gravity, m/s^2.
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;

/// Default platform tilt, degrees (the paper's 1.5°).
pub const DEFAULT_TILT_DEG: f64 = 1.5;

/// Default flip (placement) error bound, degrees: each placement is off by up to this much about
/// each horizontal axis.
pub const DEFAULT_FLIP_DEG: f64 = 2.0;

/// Scale of the hand's linear acceleration during a move, m/s^2 (each of the three sinusoids per
/// world axis has an amplitude of 0.25..0.5 times this).
pub const MOVE_SHAKE_MPS2: f64 = 0.5;

/// Scale of the set-down jolt on the last sample of a move, m/s^2 upward (drawn in 0.5..1.5 times
/// this).
pub const LANDING_JOLT_MPS2: f64 = 1.0;

/// Time over which the hand's shake ramps up after lift-off, s.
pub const SHAKE_ONSET_S: f64 = 0.1;

/// Largest recording [`simulate`](super::simulate) accepts, samples (a guard against typos like `rate_hz = 1e9`).
pub const MAX_SAMPLES: usize = 100_000_000;

/// The paper's Table 1 truth: `B = 0.124886392` m/s^2 on every axis,
/// `S = 0.97, 0.970119681, 0.970239377`, `M = -0.01523798, -0.01500048, -0.01523986`.
#[allow(clippy::excessive_precision)] // the paper's digits, rounded to f32 by the compiler
pub const PAPER_TRUTH: Params = Params {
    bias: [0.124_886_392; 3],
    scale: [0.97, 0.970_119_681, 0.970_239_377],
    nonorth: [-0.015_237_98, -0.015_000_48, -0.015_239_86],
};

/// Everything the simulator needs. Build with [`SimConfig::paper`], [`SimConfig::for_plan`] or
/// [`Default`] (the paper's setup, seed 0) and change fields with struct update syntax.
#[derive(Debug, Clone, PartialEq)]
pub struct SimConfig {
    /// The orientations.
    pub plan: Plan,
    /// Seed of every random draw (geometry, motion, noise, pose means; independent streams).
    pub seed: u64,
    /// Sample rate, Hz. Default 200.
    pub rate_hz: f64,
    /// Static time per pose, s. Default 5.
    pub seconds_per_pose: f64,
    /// Duration of each move between poses, s. Default 2.
    pub move_seconds: f64,
    /// Extra rest in the first orientation before its pose time, s: the recording starts with the
    /// sensor lying still for `initial_rest_s + seconds_per_pose` (it stays one pose). Default 0 on a
    /// platform, 10 for [`Plan::Random`].
    pub initial_rest_s: f64,
    /// White-noise standard deviation per sample and axis, milli-g. Default 1.
    pub noise_mg: f64,
    /// The sensor's true errors, m/s^2 convention (`f_b` in m/s^2, `f_s` in m/s^2).
    pub truth: Params,
    /// Magnitude of gravity, m/s^2; also the size of 1 g for the output units. Default 9.80665.
    pub gravity: f64,
    /// The unit of the readings. Default m/s^2.
    pub units: OutputUnits,
    /// Platform tilt, degrees. Default 1.5.
    pub tilt_deg: f64,
    /// Flip-error bound, degrees. Default 2.
    pub flip_deg: f64,
}

impl SimConfig {
    /// The paper's setup: 24 positions, 5 s each at 200 Hz, 2 s moves, 1 mg noise, Table 1 truth,
    /// m/s^2 output, 1.5° tilt, ±2° flip error.
    pub fn paper(seed: u64) -> Self {
        Self {
            plan: Plan::Paper24,
            seed,
            rate_hz: 200.0,
            seconds_per_pose: 5.0,
            move_seconds: 2.0,
            initial_rest_s: 0.0,
            noise_mg: 1.0,
            truth: PAPER_TRUTH,
            gravity: STANDARD_GRAVITY_MPS2,
            units: OutputUnits::Mps2,
            tilt_deg: DEFAULT_TILT_DEG,
            flip_deg: DEFAULT_FLIP_DEG,
        }
    }

    /// The paper's setup with another plan (and that plan's default initial rest); a free-hand plan
    /// also gets 4 s holds and 1.5 s rotations.
    pub fn for_plan(plan: Plan, seed: u64) -> Self {
        let base = Self { plan, initial_rest_s: plan.default_initial_rest_s(), ..Self::paper(seed) };
        match plan {
            Plan::FreeHand(_) => Self { seconds_per_pose: 4.0, move_seconds: 1.5, ..base },
            _ => base,
        }
    }

    /// Checks every field: positive finite rate, gravity and pose time (at least one sample per
    /// pose), non-negative finite move, rest and noise, finite angles, finite truth with non-zero
    /// scales, valid units, at least one pose and at most [`MAX_SAMPLES`] samples.
    pub fn validate(&self) -> Result<(), SimConfigError> {
        let fail = |field: &'static str, reason: &'static str| Err(SimConfigError { field, reason });
        let non_negative = |v: f64| v.is_finite() && v >= 0.0;
        if !(self.rate_hz.is_finite() && self.rate_hz > 0.0) {
            return fail("rate_hz", "must be finite and > 0");
        }
        if !(self.seconds_per_pose.is_finite() && (self.seconds_per_pose * self.rate_hz).round() >= 1.0) {
            return fail("seconds_per_pose", "must be finite and give at least one sample");
        }
        if !non_negative(self.move_seconds) {
            return fail("move_seconds", "must be finite and >= 0");
        }
        if !non_negative(self.initial_rest_s) {
            return fail("initial_rest_s", "must be finite and >= 0");
        }
        if !non_negative(self.noise_mg) {
            return fail("noise_mg", "must be finite and >= 0");
        }
        if !(self.gravity.is_finite() && self.gravity > 0.0) {
            return fail("gravity", "must be finite and > 0");
        }
        if !(self.truth.is_finite() && self.truth.scale.iter().all(|&s| s != 0.0)) {
            return fail("truth", "must be finite with non-zero scale factors");
        }
        if !self.units.is_valid() {
            return fail("units", "counts need a finite lsb_per_g > 0 and a finite offset");
        }
        if !(self.tilt_deg.is_finite() && self.flip_deg.is_finite()) {
            return fail("tilt_deg/flip_deg", "must be finite");
        }
        if self.plan.pose_count() == 0 {
            return fail("plan", "needs at least one pose");
        }
        let layout = Layout::new(self, self.plan.pose_count());
        if !(layout.total_samples as f64).is_finite() || layout.total_samples > MAX_SAMPLES {
            return fail("rate_hz/seconds", "the recording would exceed MAX_SAMPLES samples");
        }
        Ok(())
    }
}

impl Default for SimConfig {
    /// [`SimConfig::paper`] with seed 0.
    fn default() -> Self {
        Self::paper(0)
    }
}

/// An out-of-range [`SimConfig`] field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SimConfigError {
    /// The field's name.
    pub field: &'static str,
    /// What it must be.
    pub reason: &'static str,
}

impl fmt::Display for SimConfigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "invalid simulator setting `{}`: {}", self.field, self.reason)
    }
}

impl std::error::Error for SimConfigError {}

/// Plausible MEMS errors in the m/s^2 convention, deterministic by `seed`: bias uniform in
/// ±0.3 m/s^2, scale uniform in 0.95..1.05, non-orthogonality uniform in ±0.02.
pub fn random_truth(seed: u64) -> Params {
    let mut rng = stream_rng(seed, Stream::Truth);
    let mut draw = |low: f64, high: f64| uniform_in(&mut rng, low, high) as f32;
    Params {
        bias: [draw(-0.3, 0.3), draw(-0.3, 0.3), draw(-0.3, 0.3)],
        scale: [draw(0.95, 1.05), draw(0.95, 1.05), draw(0.95, 1.05)],
        nonorth: [draw(-0.02, 0.02), draw(-0.02, 0.02), draw(-0.02, 0.02)],
    }
}
