//! Accelerometer simulator: a sensor with known 9-parameter errors (Zou et al. 2020, eq. 2) held in a
//! sequence of static orientations, with realistic moves between them and white noise.
//!
//! # Model
//!
//! The sensor model is `f_b = Ka f_s - B` with `Ka = [[Sxx, 0, 0], [Mxx, Syy, 0], [Myy, Mzz, Szz]]`.
//! The sensor therefore *reads* `f_s = Ka^-1 (f_b + B)`, where `f_b` is the true specific force in the
//! orthogonal body frame (m/s^2). At rest `f_b` is the reaction to gravity, pointing up, `|f_b| = g`.
//! All arithmetic is done in `f64` (the [`Params`] are converted from `f32`).
//!
//! Per sample, in this order: the true `f_b` (rest or move) gives the noise-free reading `f_s`
//! (m/s^2, sensor axes); every [`Effect`] is applied to it; white Gaussian noise is added
//! (`noise_mg` per axis, converted with `1 g = gravity`); the result is converted to the
//! [`OutputUnits`] (rounded and clamped for counts).
//!
//! # Orientations
//!
//! The world frame has `z` up. Each pose is a rotation `R_wb` taking body coordinates to world
//! coordinates; the body-frame direction of the specific force at rest is `d = R_wbᵀ e_z`
//! (returned by [`plan_directions`]). For the `paper24` and `cube26` plans
//!
//! `R_wb = T · Rz(ψ) · E · N`, applied right to left to a body vector:
//!
//! - `N`: the nominal placement, the shortest rotation taking the body direction that should point
//!   up (a face, edge or vertex direction) onto `e_z` (180° about `x` for `-z`);
//! - `E = Rx(α) · Ry(β)`: the flip (placement) error, `α, β` uniform in `±flip_deg`, one draw per
//!   placement (the four turns of one face share it);
//! - `Rz(ψ)`: the turn of the platform about its own vertical, `ψ = 0°, 90°, 180°, 270°` for the four
//!   turns of a `paper24` face, `ψ = 0` for `cube26`;
//! - `T = Rx(tilt_deg)`: the fixed tilt of the platform about the world `x` axis. Since `T` is applied
//!   after the turn, the four turns see the tilt from four sides.
//!
//! The four turns of a `paper24` face therefore give (nearly) the same direction in the body frame,
//! within a cone of half-angle `tilt_deg` around `NᵀEᵀe_z`: only six distinct directions, as in the
//! paper. `random:N` draws `R_wb` uniformly on SO(3) (the directions are uniform on the sphere);
//! `tilt_deg` and `flip_deg` are ignored there.
//!
//! # Moves
//!
//! Between two poses the sensor is carried for `move_seconds`: `R_wb` is slerped with a minimum-jerk
//! profile and the hand adds a linear acceleration (three sinusoids of 1.5..6 Hz per world axis,
//! amplitude set by [`MOVE_SHAKE_MPS2`]) that ramps up within [`SHAKE_ONSET_S`] of the lift-off and
//! lasts until the sensor is set down. The set-down is a contact: the shake stops abruptly and the
//! last moving sample carries the landing jolt (an upward acceleration of 0.5..1.5 times
//! [`LANDING_JOLT_MPS2`], the deceleration of the lowering), so a static detector sees the motion up
//! to the last moving sample. The lift-off is gentle (the shake ramps up, the rotation starts with zero
//! velocity and acceleration). Lever-arm and rotation-rate effects are not modelled.
//!
//! ```
//! use accelcal_host::sim::{simulate, SimConfig};
//! let rec = simulate(&SimConfig::paper(7));
//! assert_eq!(rec.poses.len(), 24);
//! assert_eq!(rec.samples.len(), 24 * 1000 + 23 * 400);
//! ```

use std::fmt;
use std::io::{self, Write};
use std::str::FromStr;

use accelcal::accumulator::Pose;
use accelcal::model::Params;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

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

/// Largest recording [`simulate`] accepts, samples (a guard against typos like `rate_hz = 1e9`).
pub const MAX_SAMPLES: usize = 100_000_000;

/// The paper's Table 1 truth: `B = 0.124886392` m/s^2 on every axis,
/// `S = 0.97, 0.970119681, 0.970239377`, `M = -0.01523798, -0.01500048, -0.01523986`.
#[allow(clippy::excessive_precision)] // the paper's digits, rounded to f32 by the compiler
pub const PAPER_TRUTH: Params = Params {
    bias: [0.124_886_392; 3],
    scale: [0.97, 0.970_119_681, 0.970_239_377],
    nonorth: [-0.015_237_98, -0.015_000_48, -0.015_239_86],
};

// ---------------------------------------------------------------------------------------------
// Plans
// ---------------------------------------------------------------------------------------------

/// Which orientations the sensor is held in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Plan {
    /// The paper's 24 positions: faces `+z, +y, -z, +x, -x, -y` up (the paper's order), each turned
    /// four times by 90° about the vertical on a tilted platform, with a flip error per face.
    Paper24,
    /// 26 directions: 6 faces, 12 edges, 8 vertices of a cube, with the same tilt/flip model
    /// (one placement each, no turn).
    Cube26,
    /// `N >= 1` hand-placed orientations drawn uniformly on SO(3).
    Random(usize),
    /// A free-hand session: `N >= 1` orientations drawn uniformly on SO(3), held by hand for a few
    /// seconds each ([`SimConfig::for_plan`]: 4 s holds, 1.5 s rotations with the hand's shake, no long
    /// initial rest). No face is ever aligned.
    FreeHand(usize),
}

impl Plan {
    /// Number of poses.
    pub fn pose_count(&self) -> usize {
        match self {
            Self::Paper24 => 24,
            Self::Cube26 => 26,
            Self::Random(n) | Self::FreeHand(n) => *n,
        }
    }

    /// Default [`SimConfig::initial_rest_s`]: 0 s on a platform, 10 s for hand-placed poses.
    pub fn default_initial_rest_s(&self) -> f64 {
        match self {
            Self::Paper24 | Self::Cube26 => 0.0,
            Self::Random(_) => 10.0,
            Self::FreeHand(_) => 0.0,
        }
    }
}

impl fmt::Display for Plan {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Paper24 => f.write_str("paper24"),
            Self::Cube26 => f.write_str("cube26"),
            Self::Random(n) => write!(f, "random:{n}"),
            Self::FreeHand(n) => write!(f, "freehand:{n}"),
        }
    }
}

/// Why a plan name did not parse.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ParsePlanError {
    /// Not `paper24`, `cube26`, `random:N` or `freehand:N`.
    UnknownPlan(String),
    /// `random:N` with `N` not a whole number `>= 1`.
    InvalidCount(String),
}

impl fmt::Display for ParsePlanError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::UnknownPlan(s) => {
                write!(f, "unknown plan `{s}` (expected paper24, cube26, random:N or freehand:N)")
            }
            Self::InvalidCount(s) => {
                write!(f, "invalid pose count `{s}` in random:N (expected N >= 1)")
            }
        }
    }
}

impl std::error::Error for ParsePlanError {}

impl FromStr for Plan {
    type Err = ParsePlanError;

    /// Parses `paper24`, `cube26` or `random:N` (case-insensitive, surrounding spaces ignored).
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let text = s.trim().to_ascii_lowercase();
        match text.as_str() {
            "paper24" => Ok(Self::Paper24),
            "cube26" => Ok(Self::Cube26),
            _ => {
                let (make, count): (fn(usize) -> Self, _) = if let Some(c) = text.strip_prefix("random:") {
                    (Self::Random, c)
                } else if let Some(c) = text.strip_prefix("freehand:") {
                    (Self::FreeHand, c)
                } else {
                    return Err(ParsePlanError::UnknownPlan(s.to_string()));
                };
                match count.trim().parse::<usize>() {
                    Ok(n) if n >= 1 => Ok(make(n)),
                    _ => Err(ParsePlanError::InvalidCount(count.to_string())),
                }
            }
        }
    }
}

/// Unit specific-force directions in the body frame (what `f_b / g` is at rest) for each pose, with
/// the default tilt (1.5°) and flip error (±2°). See [`plan_directions_with`].
pub fn plan_directions(plan: &Plan, seed: u64) -> Vec<[f64; 3]> {
    plan_directions_with(plan, seed, DEFAULT_TILT_DEG, DEFAULT_FLIP_DEG)
}

/// Unit specific-force directions in the body frame for each pose, with the given platform tilt and
/// flip-error bound in degrees (ignored by [`Plan::Random`]). Deterministic by `seed`; these are the
/// directions [`simulate`] uses for the same plan, seed, tilt and flip.
pub fn plan_directions_with(plan: &Plan, seed: u64, tilt_deg: f64, flip_deg: f64) -> Vec<[f64; 3]> {
    placement_rotations(plan, seed, tilt_deg, flip_deg).iter().map(up_in_body).collect()
}

/// Body-to-world rotations `R_wb` of every pose (see the module documentation).
fn placement_rotations(plan: &Plan, seed: u64, tilt_deg: f64, flip_deg: f64) -> Vec<Mat3> {
    let mut rng = stream_rng(seed, Stream::Geometry);
    let tilt = rot_x(tilt_deg.to_radians());
    let flip_rad = flip_deg.to_radians();
    let flip = |rng: &mut Xoshiro256PlusPlus| {
        let alpha = uniform_in(rng, -flip_rad, flip_rad);
        let beta = uniform_in(rng, -flip_rad, flip_rad);
        mat_mul(&rot_x(alpha), &rot_y(beta))
    };
    match plan {
        Plan::Paper24 => {
            let faces = [
                [0.0, 0.0, 1.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, -1.0],
                [1.0, 0.0, 0.0],
                [-1.0, 0.0, 0.0],
                [0.0, -1.0, 0.0],
            ];
            let mut rotations = Vec::with_capacity(24);
            for face in faces {
                let placed = mat_mul(&flip(&mut rng), &rotation_onto_up(face));
                for turn in 0..4 {
                    let turned = mat_mul(&rot_z(f64::from(turn) * std::f64::consts::FRAC_PI_2), &placed);
                    rotations.push(mat_mul(&tilt, &turned));
                }
            }
            rotations
        }
        Plan::Cube26 => cube26_nominal()
            .into_iter()
            .map(|dir| {
                let placed = mat_mul(&flip(&mut rng), &rotation_onto_up(dir));
                mat_mul(&tilt, &placed)
            })
            .collect(),
        Plan::Random(n) | Plan::FreeHand(n) => (0..*n).map(|_| quat_to_mat(&random_quat(&mut rng))).collect(),
    }
}

/// The 26 nominal cube directions: faces (paper order), then edges, then vertices; unit length.
fn cube26_nominal() -> Vec<Vec3> {
    let mut dirs: Vec<Vec3> =
        vec![[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];
    let mut edges = Vec::new();
    let mut vertices = Vec::new();
    for x in [-1.0, 0.0, 1.0] {
        for y in [-1.0, 0.0, 1.0] {
            for z in [-1.0, 0.0, 1.0] {
                let v: Vec3 = [x, y, z];
                match v.iter().filter(|c| **c != 0.0).count() {
                    2 => edges.push(normalize(v)),
                    3 => vertices.push(normalize(v)),
                    _ => {}
                }
            }
        }
    }
    dirs.extend(edges);
    dirs.extend(vertices);
    dirs
}

// ---------------------------------------------------------------------------------------------
// Output units
// ---------------------------------------------------------------------------------------------

/// The unit of the simulated readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OutputUnits {
    /// Raw ADC counts of a 16-bit converter: `reading = round(f_s_in_g * lsb_per_g + offset)`,
    /// clamped into `[offset - 32768, offset + 32767]`: the `i16` range for `offset = 0` (e.g. an
    /// MPU-6050 at ±2 g: 16384 LSB/g), the `u16` range for `offset = 32768` (offset-binary output).
    Counts {
        /// Counts per g (`1 g = SimConfig::gravity`).
        lsb_per_g: f64,
        /// Reading at zero specific force, counts.
        offset: f64,
    },
    /// Units of g (`1 g = SimConfig::gravity`).
    G,
    /// m/s^2.
    Mps2,
}

impl OutputUnits {
    /// An MPU-6050 at ±2 g: 16384 LSB/g, signed.
    pub const MPU6050_2G: Self = Self::Counts { lsb_per_g: 16384.0, offset: 0.0 };

    /// Converts a reading in m/s^2 to this unit, unrounded and unclamped.
    pub fn from_mps2(&self, value_mps2: f64, gravity_mps2: f64) -> f64 {
        match *self {
            Self::Counts { lsb_per_g, offset } => value_mps2 / gravity_mps2 * lsb_per_g + offset,
            Self::G => value_mps2 / gravity_mps2,
            Self::Mps2 => value_mps2,
        }
    }

    /// What the converter outputs for `value` (this unit): rounded and clamped for counts,
    /// unchanged otherwise.
    pub fn quantize(&self, value: f64) -> f64 {
        match self.count_range() {
            Some((low, high)) => value.round().clamp(low, high),
            None => value,
        }
    }

    /// The `[lowest, highest]` output for counts, `None` for the other units.
    pub fn count_range(&self) -> Option<(f64, f64)> {
        match *self {
            Self::Counts { offset, .. } => {
                let offset = offset.round();
                Some((offset - 32768.0, offset + 32767.0))
            }
            Self::G | Self::Mps2 => None,
        }
    }

    /// A white-noise standard deviation of `noise_mg` milli-g in this unit.
    pub fn noise_std(&self, noise_mg: f64, gravity_mps2: f64) -> f64 {
        let noise_g = noise_mg * 1e-3;
        match *self {
            Self::Counts { lsb_per_g, .. } => noise_g * lsb_per_g,
            Self::G => noise_g,
            Self::Mps2 => noise_g * gravity_mps2,
        }
    }

    /// `true` for [`OutputUnits::Counts`].
    pub fn is_counts(&self) -> bool {
        matches!(self, Self::Counts { .. })
    }

    /// `true` when the unit is usable: counts need a finite, non-zero `lsb_per_g` and a finite offset.
    pub fn is_valid(&self) -> bool {
        match *self {
            Self::Counts { lsb_per_g, offset } => lsb_per_g.is_finite() && lsb_per_g > 0.0 && offset.is_finite(),
            Self::G | Self::Mps2 => true,
        }
    }
}

impl fmt::Display for OutputUnits {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Counts { lsb_per_g, offset } => write!(f, "counts:{lsb_per_g}:{offset}"),
            Self::G => f.write_str("g"),
            Self::Mps2 => f.write_str("mps2"),
        }
    }
}

/// Why an output unit did not parse.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseUnitsError(pub String);

impl fmt::Display for ParseUnitsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "invalid output unit `{}` (expected mps2, g, counts, counts:LSB_PER_G or counts:LSB_PER_G:OFFSET)",
            self.0
        )
    }
}

impl std::error::Error for ParseUnitsError {}

impl FromStr for OutputUnits {
    type Err = ParseUnitsError;

    /// Parses `mps2` (also `m/s2`, `m/s^2`), `g`, `counts` (16384 LSB/g, offset 0),
    /// `counts:LSB_PER_G` or `counts:LSB_PER_G:OFFSET`; case-insensitive.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let error = || ParseUnitsError(s.to_string());
        let text = s.trim().to_ascii_lowercase();
        let units = match text.as_str() {
            "mps2" | "m/s2" | "m/s^2" => Self::Mps2,
            "g" => Self::G,
            "counts" => Self::MPU6050_2G,
            _ => {
                let rest = text.strip_prefix("counts:").ok_or_else(error)?;
                let mut parts = rest.split(':');
                let lsb_per_g = parts.next().and_then(|p| p.trim().parse::<f64>().ok()).ok_or_else(error)?;
                let offset = match parts.next() {
                    Some(p) => p.trim().parse::<f64>().map_err(|_| error())?,
                    None => 0.0,
                };
                if parts.next().is_some() {
                    return Err(error());
                }
                Self::Counts { lsb_per_g, offset }
            }
        };
        if units.is_valid() { Ok(units) } else { Err(error()) }
    }
}

/// The parameters a perfect calibration of readings in `units` finds when it calibrates against
/// `|f_b| = target_gravity` (e.g. 9.80665 for m/s^2 out, 1.0 for g out), given the `truth` in m/s^2
/// and `1 g = gravity_mps2`. With `f_s[m/s^2] = c (r - offset)` (`c = g / lsb_per_g`, `g` or 1) and
/// `k = target_gravity / g`: `Ka' = k c Ka`, `B' = k (B + c Ka offset)`.
pub fn equivalent_params(truth: &Params, units: OutputUnits, gravity_mps2: f64, target_gravity: f64) -> Params {
    let model = Model64::from(truth);
    let (c, offset) = match units {
        OutputUnits::Counts { lsb_per_g, offset } => (gravity_mps2 / lsb_per_g, offset),
        OutputUnits::G => (gravity_mps2, 0.0),
        OutputUnits::Mps2 => (1.0, 0.0),
    };
    let k = target_gravity / gravity_mps2;
    let ka_offset = model.ka_times([offset; 3]);
    Params {
        bias: std::array::from_fn(|a| (k * (model.bias[a] + c * ka_offset[a])) as f32),
        scale: std::array::from_fn(|a| (k * c * model.scale[a]) as f32),
        nonorth: std::array::from_fn(|a| (k * c * model.nonorth[a]) as f32),
    }
}

// ---------------------------------------------------------------------------------------------
// Configuration
// ---------------------------------------------------------------------------------------------

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

// ---------------------------------------------------------------------------------------------
// Recording
// ---------------------------------------------------------------------------------------------

/// One simulated static interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimPose {
    /// Index of the first sample of the static interval.
    pub start: usize,
    /// Index one past the last sample of the static interval.
    pub end: usize,
    /// True `f_b / g`, body frame (unit vector).
    pub direction: [f64; 3],
    /// The noise-free reading the 9-parameter model predicts, output unit (unrounded, without
    /// [`Effect`]s).
    pub true_reading: [f64; 3],
}

/// A simulated recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Sample times, s (`index / rate_hz`).
    pub times_s: Vec<f64>,
    /// Readings `[x, y, z]`, output unit (whole numbers for counts).
    pub samples: Vec<[f64; 3]>,
    /// The unit of `samples`.
    pub units: OutputUnits,
    /// The static intervals, in time order.
    pub poses: Vec<SimPose>,
}

/// An unmodelled effect (drift, temperature, nonlinearity, settling, colored noise, ...) applied to
/// every noise-free reading before the white noise and the unit conversion.
///
/// Closures `FnMut(f64, Option<usize>, &mut [f64; 3])` implement it.
pub trait Effect {
    /// Modifies `reading_mps2` (sensor axes, m/s^2) of the sample at `t_s` seconds; `pose_index` is
    /// the static pose the sample belongs to, `None` during a move.
    fn apply(&mut self, t_s: f64, pose_index: Option<usize>, reading_mps2: &mut [f64; 3]);
}

impl<F: FnMut(f64, Option<usize>, &mut [f64; 3])> Effect for F {
    fn apply(&mut self, t_s: f64, pose_index: Option<usize>, reading_mps2: &mut [f64; 3]) {
        self(t_s, pose_index, reading_mps2);
    }
}

/// Simulates a recording (no extra effects). Deterministic by `cfg.seed`. An invalid configuration
/// (see [`SimConfig::validate`]) gives an empty recording.
pub fn simulate(cfg: &SimConfig) -> Recording {
    simulate_with(cfg, &mut [])
}

/// Simulates a recording with `effects` applied in order to every noise-free reading. Deterministic
/// by `cfg.seed` (given deterministic effects). An invalid configuration gives an empty recording.
pub fn simulate_with(cfg: &SimConfig, effects: &mut [&mut dyn Effect]) -> Recording {
    let mut recording = Recording { times_s: Vec::new(), samples: Vec::new(), units: cfg.units, poses: Vec::new() };
    if cfg.validate().is_err() {
        return recording;
    }
    let rotations = placement_rotations(&cfg.plan, cfg.seed, cfg.tilt_deg, cfg.flip_deg);
    let layout = Layout::new(cfg, rotations.len());
    let model = Model64::from(&cfg.truth);
    let mut motion_rng = stream_rng(cfg.seed, Stream::Motion);
    let mut noise = Gaussian::new(stream_rng(cfg.seed, Stream::Noise));
    let sigma_mps2 = cfg.noise_mg * 1e-3 * cfg.gravity;
    recording.times_s.reserve_exact(layout.total_samples);
    recording.samples.reserve_exact(layout.total_samples);

    let mut push = |recording: &mut Recording, f_s: Vec3, pose_index: Option<usize>| {
        let index = recording.samples.len();
        let t_s = index as f64 / cfg.rate_hz;
        let mut reading = f_s;
        for effect in effects.iter_mut() {
            effect.apply(t_s, pose_index, &mut reading);
        }
        let sample = std::array::from_fn(|a| {
            let noisy = reading[a] + sigma_mps2 * noise.sample();
            cfg.units.quantize(cfg.units.from_mps2(noisy, cfg.gravity))
        });
        recording.times_s.push(t_s);
        recording.samples.push(sample);
    };

    for (i, rotation) in rotations.iter().enumerate() {
        if i > 0 {
            let hand_move = HandMove::new(&rotations[i - 1], rotation, &mut motion_rng);
            let steps = layout.move_samples;
            for step in 0..steps {
                let elapsed_s = (step + 1) as f64 / cfg.rate_hz;
                let progress = (step + 1) as f64 / (steps + 1) as f64;
                let landing = step + 1 == steps;
                let f_b = hand_move.specific_force(progress, elapsed_s, cfg.gravity, landing);
                push(&mut recording, model.reading(f_b), None);
            }
        }
        let direction = up_in_body(rotation);
        let f_s = model.reading(scale(direction, cfg.gravity));
        let start = recording.samples.len();
        debug_assert_eq!(start, layout.pose_ranges[i].0);
        for _ in 0..layout.pose_ranges[i].1 - start {
            push(&mut recording, f_s, Some(i));
        }
        let true_reading = f_s.map(|v| cfg.units.from_mps2(v, cfg.gravity));
        recording.poses.push(SimPose { start, end: recording.samples.len(), direction, true_reading });
    }
    recording
}

/// Writes `t,ax,ay,az` CSV: times with 6 decimals, counts as integers, other units with 9
/// significant digits.
pub fn write_csv(rec: &Recording, w: impl Write) -> io::Result<()> {
    let mut w = io::BufWriter::new(w);
    writeln!(w, "t,ax,ay,az")?;
    for (t, s) in rec.times_s.iter().zip(&rec.samples) {
        if rec.units.is_counts() {
            writeln!(w, "{t:.6},{},{},{}", s[0] as i64, s[1] as i64, s[2] as i64)?;
        } else {
            writeln!(w, "{t:.6},{},{},{}", significant(s[0], 9), significant(s[1], 9), significant(s[2], 9))?;
        }
    }
    w.flush()
}

/// `value` with `digits` significant digits in plain decimal notation (at most 15 decimals).
fn significant(value: f64, digits: i32) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let magnitude = value.abs().log10().floor() as i32;
    let decimals = (digits - 1 - magnitude).clamp(0, 15) as usize;
    format!("{value:.decimals$}")
}

/// The Monte Carlo fast path: for each pose, the exact distribution of the mean of its
/// `n = round(rate_hz * seconds)` white-noise samples, drawn directly as `N(true_reading, σ²/n)` per
/// axis, with `variance = σ²` and `n`, `start_index`, `end_index` as [`simulate`] lays them out.
///
/// `σ` is the noise in the output unit; for counts the rounding is added as independent uniform
/// noise (`σ² + 1/12` LSB²), which holds when the noise is at least about 0.5 LSB (1 mg is 16 LSB at
/// 16384 LSB/g). Moves, clamping and effects are not simulated. Deterministic by `cfg.seed` (its own
/// noise stream; the directions are those of [`simulate`]). An invalid configuration gives no poses.
pub fn simulate_pose_means(cfg: &SimConfig) -> Vec<Pose> {
    if cfg.validate().is_err() {
        return Vec::new();
    }
    let rotations = placement_rotations(&cfg.plan, cfg.seed, cfg.tilt_deg, cfg.flip_deg);
    let layout = Layout::new(cfg, rotations.len());
    let model = Model64::from(&cfg.truth);
    let mut noise = Gaussian::new(stream_rng(cfg.seed, Stream::PoseMeans));
    let sigma = cfg.units.noise_std(cfg.noise_mg, cfg.gravity);
    let variance = sigma * sigma + if cfg.units.is_counts() { 1.0 / 12.0 } else { 0.0 };
    rotations
        .iter()
        .zip(&layout.pose_ranges)
        .map(|(rotation, &(start, end))| {
            let n = end - start;
            let std_of_mean = (variance / n as f64).sqrt();
            let f_s = model.reading(scale(up_in_body(rotation), cfg.gravity));
            Pose {
                mean: f_s.map(|v| (cfg.units.from_mps2(v, cfg.gravity) + std_of_mean * noise.sample()) as f32),
                variance: [variance as f32; 3],
                n: n as u32,
                start_index: start as u32,
                end_index: end as u32,
            }
        })
        .collect()
}

/// Sample layout: pose 0 at index 0, then (move, pose) pairs.
struct Layout {
    /// `[start, end)` of every static interval.
    pose_ranges: Vec<(usize, usize)>,
    /// Samples per move.
    move_samples: usize,
    /// All samples.
    total_samples: usize,
}

impl Layout {
    fn new(cfg: &SimConfig, pose_count: usize) -> Self {
        let samples = |seconds: f64| (seconds * cfg.rate_hz).round().max(0.0) as usize;
        let first = samples(cfg.initial_rest_s + cfg.seconds_per_pose);
        let per_pose = samples(cfg.seconds_per_pose);
        let move_samples = samples(cfg.move_seconds);
        let mut pose_ranges = Vec::with_capacity(pose_count);
        let mut next = 0usize;
        for i in 0..pose_count {
            let (start, len) = if i == 0 { (0, first) } else { (next.saturating_add(move_samples), per_pose) };
            let end = start.saturating_add(len);
            pose_ranges.push((start, end));
            next = end;
        }
        Self { pose_ranges, move_samples, total_samples: next }
    }
}

// ---------------------------------------------------------------------------------------------
// Moves
// ---------------------------------------------------------------------------------------------

/// Sinusoids of the hand's shake per world axis.
const SHAKE_TONES: usize = 3;

/// One carry between two poses: a minimum-jerk slerp plus the hand's linear acceleration.
struct HandMove {
    from: Quat,
    to: Quat,
    /// `(amplitude m/s^2, frequency Hz, phase rad)` per world axis and tone.
    shake: [[(f64, f64, f64); SHAKE_TONES]; 3],
    /// Upward acceleration on the last moving sample, m/s^2.
    landing_jolt_mps2: f64,
}

impl HandMove {
    fn new(from: &Mat3, to: &Mat3, rng: &mut Xoshiro256PlusPlus) -> Self {
        let shake = std::array::from_fn(|_| {
            std::array::from_fn(|_| {
                let amplitude = MOVE_SHAKE_MPS2 * uniform_in(rng, 0.25, 0.5);
                let frequency = uniform_in(rng, 1.5, 6.0);
                let phase = uniform_in(rng, 0.0, std::f64::consts::TAU);
                (amplitude, frequency, phase)
            })
        });
        Self {
            from: quat_from_mat(from),
            to: quat_from_mat(to),
            shake,
            landing_jolt_mps2: LANDING_JOLT_MPS2 * uniform_in(rng, 0.5, 1.5),
        }
    }

    /// True specific force in the body frame, m/s^2, at `progress` in (0, 1), `elapsed_s` after
    /// lift-off; `landing` on the last moving sample.
    fn specific_force(&self, progress: f64, elapsed_s: f64, gravity: f64, landing: bool) -> Vec3 {
        let u = progress.clamp(0.0, 1.0);
        let eased = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
        let rotation = quat_to_mat(&slerp(&self.from, &self.to, eased));
        let onset = (elapsed_s / SHAKE_ONSET_S).min(1.0);
        let window = (onset * std::f64::consts::FRAC_PI_2).sin();
        let mut world: Vec3 = [0.0, 0.0, gravity];
        for (axis, tones) in self.shake.iter().enumerate() {
            let acceleration: f64 = tones
                .iter()
                .map(|&(amp, freq, phase)| amp * (std::f64::consts::TAU * freq * elapsed_s + phase).sin())
                .sum();
            world[axis] += window * acceleration;
        }
        if landing {
            world[2] += self.landing_jolt_mps2;
        }
        mat_t_vec(&rotation, world)
    }
}

// ---------------------------------------------------------------------------------------------
// f64 sensor model
// ---------------------------------------------------------------------------------------------

/// The 9-parameter model in `f64`.
#[derive(Debug, Clone, Copy)]
struct Model64 {
    bias: Vec3,
    scale: Vec3,
    nonorth: Vec3,
}

impl From<&Params> for Model64 {
    fn from(p: &Params) -> Self {
        Self { bias: p.bias.map(f64::from), scale: p.scale.map(f64::from), nonorth: p.nonorth.map(f64::from) }
    }
}

impl Model64 {
    /// `Ka f_s`.
    fn ka_times(&self, f_s: Vec3) -> Vec3 {
        let (s, m) = (self.scale, self.nonorth);
        [s[0] * f_s[0], m[0] * f_s[0] + s[1] * f_s[1], m[1] * f_s[0] + m[2] * f_s[1] + s[2] * f_s[2]]
    }

    /// The reading for true specific force `f_b`: `f_s = Ka^-1 (f_b + B)` (forward substitution).
    fn reading(&self, f_b: Vec3) -> Vec3 {
        let (s, m) = (self.scale, self.nonorth);
        let y = [f_b[0] + self.bias[0], f_b[1] + self.bias[1], f_b[2] + self.bias[2]];
        let x0 = y[0] / s[0];
        let x1 = (y[1] - m[0] * x0) / s[1];
        let x2 = (y[2] - m[1] * x0 - m[2] * x1) / s[2];
        [x0, x1, x2]
    }

    /// Calibrated specific force `f_b = Ka f_s - B`.
    #[cfg(test)]
    fn apply(&self, f_s: Vec3) -> Vec3 {
        let k = self.ka_times(f_s);
        [k[0] - self.bias[0], k[1] - self.bias[1], k[2] - self.bias[2]]
    }
}

// ---------------------------------------------------------------------------------------------
// Random numbers
// ---------------------------------------------------------------------------------------------

/// Independent random streams derived from one seed.
#[derive(Clone, Copy)]
enum Stream {
    Geometry = 1,
    Motion = 2,
    Noise = 3,
    PoseMeans = 4,
    Truth = 5,
}

/// SplitMix64 finaliser.
fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

fn stream_rng(seed: u64, stream: Stream) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(mix64(seed ^ mix64(stream as u64)))
}

/// Uniform in `[0, 1)` with 53 random bits.
fn uniform01(rng: &mut impl Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

fn uniform_in(rng: &mut impl Rng, low: f64, high: f64) -> f64 {
    low + (high - low) * uniform01(rng)
}

/// Standard normal draws (Box-Muller, both outputs used).
struct Gaussian {
    rng: Xoshiro256PlusPlus,
    spare: Option<f64>,
}

impl Gaussian {
    fn new(rng: Xoshiro256PlusPlus) -> Self {
        Self { rng, spare: None }
    }

    fn sample(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        let radius = (-2.0 * (1.0 - uniform01(&mut self.rng)).ln()).sqrt(); // 1 - u is in (0, 1]
        let angle = std::f64::consts::TAU * uniform01(&mut self.rng);
        self.spare = Some(radius * angle.sin());
        radius * angle.cos()
    }
}

/// A rotation uniform on SO(3) (Shoemake's method).
fn random_quat(rng: &mut impl Rng) -> Quat {
    let (u1, u2, u3) = (uniform01(rng), uniform01(rng), uniform01(rng));
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (t2, t3) = (std::f64::consts::TAU * u2, std::f64::consts::TAU * u3);
    [b * t3.cos(), a * t2.sin(), a * t2.cos(), b * t3.sin()]
}

// ---------------------------------------------------------------------------------------------
// Small rotation algebra
// ---------------------------------------------------------------------------------------------

type Vec3 = [f64; 3];
type Mat3 = [[f64; 3]; 3];
/// Unit quaternion `[w, x, y, z]`.
type Quat = [f64; 4];

fn scale(v: Vec3, k: f64) -> Vec3 {
    v.map(|c| c * k)
}

fn dot(a: Vec3, b: Vec3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: Vec3, b: Vec3) -> Vec3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}

fn normalize(v: Vec3) -> Vec3 {
    scale(v, 1.0 / dot(v, v).sqrt())
}

fn mat_mul(a: &Mat3, b: &Mat3) -> Mat3 {
    std::array::from_fn(|i| std::array::from_fn(|j| (0..3).map(|k| a[i][k] * b[k][j]).sum()))
}

/// `mᵀ v`.
fn mat_t_vec(m: &Mat3, v: Vec3) -> Vec3 {
    std::array::from_fn(|j| (0..3).map(|i| m[i][j] * v[i]).sum())
}

/// World up in body coordinates, `R_wbᵀ e_z` (the third row of `R_wb`).
fn up_in_body(r_wb: &Mat3) -> Vec3 {
    r_wb[2]
}

fn rot_x(angle: f64) -> Mat3 {
    let (s, c) = angle.sin_cos();
    [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]]
}

fn rot_y(angle: f64) -> Mat3 {
    let (s, c) = angle.sin_cos();
    [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]]
}

fn rot_z(angle: f64) -> Mat3 {
    let (s, c) = angle.sin_cos();
    [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]
}

/// The shortest rotation taking the unit vector `from` onto `e_z` (180° about `x` for `-e_z`).
fn rotation_onto_up(from: Vec3) -> Mat3 {
    let up = [0.0, 0.0, 1.0];
    let axis = cross(from, up);
    let sin = dot(axis, axis).sqrt();
    let cos = dot(from, up);
    if sin < 1e-12 {
        return if cos > 0.0 { rot_x(0.0) } else { rot_x(std::f64::consts::PI) };
    }
    let k = scale(axis, 1.0 / sin);
    let kx: Mat3 = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    let kx2 = mat_mul(&kx, &kx);
    std::array::from_fn(|i| {
        std::array::from_fn(|j| f64::from(u8::from(i == j)) + sin * kx[i][j] + (1.0 - cos) * kx2[i][j])
    })
}

fn quat_to_mat(q: &Quat) -> Mat3 {
    let [w, x, y, z] = *q;
    [
        [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - w * z), 2.0 * (x * z + w * y)],
        [2.0 * (x * y + w * z), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - w * x)],
        [2.0 * (x * z - w * y), 2.0 * (y * z + w * x), 1.0 - 2.0 * (x * x + y * y)],
    ]
}

/// Quaternion of a rotation matrix (Shepperd's method), normalised.
fn quat_from_mat(m: &Mat3) -> Quat {
    let trace = m[0][0] + m[1][1] + m[2][2];
    let q = if trace > 0.0 {
        let s = (trace + 1.0).sqrt() * 2.0;
        [0.25 * s, (m[2][1] - m[1][2]) / s, (m[0][2] - m[2][0]) / s, (m[1][0] - m[0][1]) / s]
    } else if m[0][0] > m[1][1] && m[0][0] > m[2][2] {
        let s = (1.0 + m[0][0] - m[1][1] - m[2][2]).sqrt() * 2.0;
        [(m[2][1] - m[1][2]) / s, 0.25 * s, (m[0][1] + m[1][0]) / s, (m[0][2] + m[2][0]) / s]
    } else if m[1][1] > m[2][2] {
        let s = (1.0 + m[1][1] - m[0][0] - m[2][2]).sqrt() * 2.0;
        [(m[0][2] - m[2][0]) / s, (m[0][1] + m[1][0]) / s, 0.25 * s, (m[1][2] + m[2][1]) / s]
    } else {
        let s = (1.0 + m[2][2] - m[0][0] - m[1][1]).sqrt() * 2.0;
        [(m[1][0] - m[0][1]) / s, (m[0][2] + m[2][0]) / s, (m[1][2] + m[2][1]) / s, 0.25 * s]
    };
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / norm)
}

/// Spherical interpolation along the shorter arc, `t` in `[0, 1]`.
fn slerp(a: &Quat, b: &Quat, t: f64) -> Quat {
    let mut cos = (0..4).map(|i| a[i] * b[i]).sum::<f64>();
    let mut b = *b;
    if cos < 0.0 {
        cos = -cos;
        b = b.map(|c| -c);
    }
    let (wa, wb) = if cos > 0.9995 {
        (1.0 - t, t)
    } else {
        let angle = cos.acos();
        let sin = angle.sin();
        (((1.0 - t) * angle).sin() / sin, (t * angle).sin() / sin)
    };
    let q: Quat = std::array::from_fn(|i| wa * a[i] + wb * b[i]);
    let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
    q.map(|c| c / norm)
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // per-axis loops over several arrays read best indexed
mod tests {
    use super::*;
    use accelcal::accumulator::{Accumulator, AccumulatorConfig};

    fn angle_deg(a: Vec3, b: Vec3) -> f64 {
        dot(a, b).clamp(-1.0, 1.0).acos().to_degrees()
    }

    #[test]
    fn plans_parse_and_display() {
        for plan in [Plan::Paper24, Plan::Cube26, Plan::Random(1), Plan::Random(500)] {
            assert_eq!(plan.to_string().parse::<Plan>(), Ok(plan));
        }
        assert_eq!(" Paper24 ".parse::<Plan>(), Ok(Plan::Paper24));
        assert_eq!("random:0".parse::<Plan>(), Err(ParsePlanError::InvalidCount("0".into())));
        assert_eq!("random:x".parse::<Plan>(), Err(ParsePlanError::InvalidCount("x".into())));
        assert_eq!("random:-3".parse::<Plan>(), Err(ParsePlanError::InvalidCount("-3".into())));
        assert_eq!("cube27".parse::<Plan>(), Err(ParsePlanError::UnknownPlan("cube27".into())));
        assert!(ParsePlanError::UnknownPlan("x".into()).to_string().contains("paper24"));
    }

    #[test]
    fn units_parse_and_display() {
        for units in [
            OutputUnits::Mps2,
            OutputUnits::G,
            OutputUnits::MPU6050_2G,
            OutputUnits::Counts { lsb_per_g: 1024.0, offset: 32768.0 },
        ] {
            assert_eq!(units.to_string().parse::<OutputUnits>(), Ok(units));
        }
        assert_eq!("counts".parse::<OutputUnits>(), Ok(OutputUnits::MPU6050_2G));
        assert_eq!("m/s^2".parse::<OutputUnits>(), Ok(OutputUnits::Mps2));
        assert!("counts:0".parse::<OutputUnits>().is_err());
        assert!("counts:16384:1:2".parse::<OutputUnits>().is_err());
        assert!("furlongs".parse::<OutputUnits>().is_err());
    }

    #[test]
    fn directions_are_unit_vectors() {
        for plan in [Plan::Paper24, Plan::Cube26, Plan::Random(100)] {
            let dirs = plan_directions(&plan, 3);
            assert_eq!(dirs.len(), plan.pose_count());
            for d in dirs {
                assert!((dot(d, d).sqrt() - 1.0).abs() < 1e-12, "{plan}: {d:?}");
            }
        }
    }

    #[test]
    fn paper24_clusters_into_six_directions() {
        let faces =
            [[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0], [1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, -1.0, 0.0]];
        for seed in 0..20 {
            let dirs = plan_directions(&Plan::Paper24, seed);
            assert_eq!(dirs.len(), 24);
            for (f, face) in faces.iter().enumerate() {
                let group = &dirs[4 * f..4 * f + 4];
                for a in group {
                    // Flip error (up to ~2.8°) plus tilt (1.5°) from the nominal face.
                    assert!(angle_deg(*a, *face) < 4.5, "seed {seed} face {f}: {a:?}");
                    for b in group {
                        assert!(angle_deg(*a, *b) <= 2.0 * DEFAULT_TILT_DEG + 1e-9, "seed {seed} face {f}");
                    }
                }
                // The tilt is seen from four sides: the turns are not identical.
                assert!(angle_deg(group[0], group[2]) > 2.9, "seed {seed} face {f}");
            }
            for i in 0..24 {
                for j in 0..24 {
                    if i / 4 != j / 4 {
                        assert!(angle_deg(dirs[i], dirs[j]) > 80.0);
                    }
                }
            }
        }
    }

    #[test]
    fn cube26_has_26_distinct_directions() {
        let nominal = cube26_nominal();
        for seed in 0..20 {
            let dirs = plan_directions(&Plan::Cube26, seed);
            assert_eq!(dirs.len(), 26);
            for (d, n) in dirs.iter().zip(&nominal) {
                assert!(angle_deg(*d, *n) < 4.5);
            }
            for i in 0..26 {
                for j in i + 1..26 {
                    assert!(angle_deg(dirs[i], dirs[j]) > 25.0, "seed {seed}: {i} and {j}");
                }
            }
        }
    }

    #[test]
    fn random_directions_cover_the_sphere() {
        let dirs = plan_directions(&Plan::Random(4000), 11);
        let n = dirs.len() as f64;
        let mean = dirs.iter().fold([0.0; 3], |acc, d| [acc[0] + d[0] / n, acc[1] + d[1] / n, acc[2] + d[2] / n]);
        assert!(dot(mean, mean).sqrt() < 0.05, "{mean:?}");
        for axis in 0..3 {
            let upper = dirs.iter().filter(|d| d[axis] > 0.5).count() as f64 / n;
            assert!((upper - 0.25).abs() < 0.03, "axis {axis}: {upper}"); // a cap of height 1/2
        }
    }

    #[test]
    fn zero_tilt_and_flip_give_exact_faces() {
        let dirs = plan_directions_with(&Plan::Paper24, 5, 0.0, 0.0);
        assert!(dirs[0..4].iter().all(|d| angle_deg(*d, [0.0, 0.0, 1.0]) < 1e-6));
        assert!(dirs[8..12].iter().all(|d| angle_deg(*d, [0.0, 0.0, -1.0]) < 1e-6));
        assert!(dirs[20..24].iter().all(|d| angle_deg(*d, [0.0, -1.0, 0.0]) < 1e-6));
    }

    #[test]
    fn quaternions_round_trip() {
        let mut rng = stream_rng(9, Stream::Geometry);
        for _ in 0..200 {
            let m = quat_to_mat(&random_quat(&mut rng));
            let back = quat_to_mat(&quat_from_mat(&m));
            for i in 0..3 {
                for j in 0..3 {
                    assert!((m[i][j] - back[i][j]).abs() < 1e-12);
                }
            }
        }
        let a = quat_from_mat(&rot_x(0.0));
        let b = quat_from_mat(&rot_z(1.0));
        let half = quat_to_mat(&slerp(&a, &b, 0.5));
        let expected = rot_z(0.5);
        assert!((0..3).all(|i| (0..3).all(|j| (half[i][j] - expected[i][j]).abs() < 1e-12)));
    }

    #[test]
    fn layout_matches_config() {
        let cfg = SimConfig { initial_rest_s: 10.0, ..SimConfig::for_plan(Plan::Random(3), 1) };
        assert_eq!(cfg.initial_rest_s, 10.0);
        let rec = simulate(&cfg);
        let ranges: Vec<_> = rec.poses.iter().map(|p| (p.start, p.end)).collect();
        assert_eq!(ranges, vec![(0, 3000), (3400, 4400), (4800, 5800)]);
        assert_eq!(rec.samples.len(), 5800);
        assert_eq!(rec.times_s.len(), 5800);
        assert!((rec.times_s[200] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn same_seed_same_output_different_seed_different() {
        let cfg = SimConfig { plan: Plan::Cube26, ..SimConfig::paper(42) };
        let a = simulate(&cfg);
        assert_eq!(a, simulate(&cfg));
        let b = simulate(&SimConfig { seed: 43, ..cfg.clone() });
        assert_eq!(a.samples.len(), b.samples.len());
        assert_ne!(a.samples, b.samples);
        assert_ne!(a.poses[0].direction, b.poses[0].direction);
        assert_eq!(simulate_pose_means(&cfg), simulate_pose_means(&cfg));
        assert_ne!(simulate_pose_means(&cfg), simulate_pose_means(&SimConfig { seed: 43, ..cfg }));
        assert_eq!(random_truth(5), random_truth(5));
        assert_ne!(random_truth(5), random_truth(6));
    }

    #[test]
    fn noise_does_not_change_geometry_or_motion() {
        let quiet = simulate(&SimConfig { noise_mg: 0.0, ..SimConfig::paper(8) });
        let noisy = simulate(&SimConfig::paper(8));
        assert_eq!(
            quiet.poses.iter().map(|p| p.direction).collect::<Vec<_>>(),
            noisy.poses.iter().map(|p| p.direction).collect::<Vec<_>>()
        );
        let i = quiet.poses[0].end + 10; // inside the first move
        for a in 0..3 {
            assert!((quiet.samples[i][a] - noisy.samples[i][a]).abs() < 0.1);
        }
    }

    #[test]
    fn noiseless_static_readings_are_the_inverted_truth() {
        for (plan, units) in
            [(Plan::Paper24, OutputUnits::Mps2), (Plan::Cube26, OutputUnits::G), (Plan::Random(10), OutputUnits::Mps2)]
        {
            let cfg = SimConfig { noise_mg: 0.0, units, truth: random_truth(3), ..SimConfig::for_plan(plan, 4) };
            let rec = simulate(&cfg);
            let model = Model64::from(&cfg.truth);
            let to_mps2 = if units == OutputUnits::G { cfg.gravity } else { 1.0 };
            assert_eq!(rec.poses.len(), plan.pose_count());
            for pose in &rec.poses {
                let f_b = model.apply(scale(pose.true_reading, to_mps2));
                assert!((dot(f_b, f_b).sqrt() - cfg.gravity).abs() < 1e-9, "{f_b:?}");
                for a in 0..3 {
                    assert!((f_b[a] - cfg.gravity * pose.direction[a]).abs() < 1e-9);
                }
                for sample in &rec.samples[pose.start..pose.end] {
                    assert_eq!(*sample, pose.true_reading);
                }
            }
        }
    }

    #[test]
    fn moves_differ_from_the_poses_around_them() {
        let rec = simulate(&SimConfig { noise_mg: 0.0, ..SimConfig::paper(2) });
        for pair in rec.poses.windows(2) {
            let (before, after) = (&pair[0], &pair[1]);
            // The samples right next to each static interval are moving (abrupt start and stop).
            for (index, pose) in [(before.end, before), (after.start - 1, after)] {
                let d = (0..3).map(|a| (rec.samples[index][a] - pose.true_reading[a]).abs()).fold(0.0, f64::max);
                assert!(d > 1e-4, "sample {index}: {d}");
            }
            let mid = (before.end + after.start) / 2;
            let d = (0..3).map(|a| (rec.samples[mid][a] - before.true_reading[a]).abs()).fold(0.0, f64::max);
            assert!(d > 0.05, "mid-move sample {mid}: {d}");
        }
    }

    #[test]
    fn counts_are_rounded_and_clamped() {
        let signed = SimConfig { units: OutputUnits::MPU6050_2G, ..SimConfig::paper(1) };
        let unsigned =
            SimConfig { units: OutputUnits::Counts { lsb_per_g: 16384.0, offset: 32768.0 }, ..signed.clone() };
        let tiny_range = SimConfig { units: OutputUnits::Counts { lsb_per_g: 40000.0, offset: 0.0 }, ..signed.clone() };
        for (cfg, low, high) in
            [(&signed, -32768.0, 32767.0), (&unsigned, 0.0, 65535.0), (&tiny_range, -32768.0, 32767.0)]
        {
            let rec = simulate(cfg);
            for s in &rec.samples {
                for v in s {
                    assert_eq!(v.fract(), 0.0);
                    assert!((low..=high).contains(v));
                }
            }
            if cfg == &tiny_range {
                assert!(rec.samples.iter().any(|s| s.contains(&32767.0)), "1 g = 40000 LSB must clip");
            }
        }
        let a = simulate(&signed);
        let b = simulate(&unsigned);
        assert!(a.samples.iter().zip(&b.samples).all(|(x, y)| (0..3).all(|i| y[i] - x[i] == 32768.0)));
    }

    #[test]
    fn equivalent_params_calibrate_the_output_units() {
        let truth = random_truth(9);
        for (units, target) in [
            (OutputUnits::Mps2, 9.80665),
            (OutputUnits::G, 1.0),
            (OutputUnits::Counts { lsb_per_g: 4096.0, offset: 2048.0 }, 1.0),
        ] {
            let cfg = SimConfig { noise_mg: 0.0, units, truth, plan: Plan::Cube26, ..SimConfig::paper(1) };
            let rec = simulate(&cfg);
            let model = Model64::from(&equivalent_params(&truth, units, cfg.gravity, target));
            for pose in &rec.poses {
                let f_b = model.apply(pose.true_reading);
                for a in 0..3 {
                    // f32 parameters: relative precision ~1e-7.
                    assert!((f_b[a] - target * pose.direction[a]).abs() < 1e-5 * target, "{units}: {f_b:?}");
                }
            }
        }
    }

    #[test]
    fn effects_are_applied_before_noise_and_units() {
        let cfg = SimConfig { noise_mg: 0.0, units: OutputUnits::G, ..SimConfig::paper(3) };
        let mut calls = 0usize;
        let mut drift = |t_s: f64, pose: Option<usize>, reading: &mut [f64; 3]| {
            calls += 1;
            if pose.is_some() {
                reading[0] += 0.01 * t_s; // 10 mm/s^2 per second
            }
        };
        let rec = simulate_with(&cfg, &mut [&mut drift]);
        assert_eq!(calls, rec.samples.len());
        let pose = rec.poses[3];
        let i = pose.start + 17;
        let expected = pose.true_reading[0] + 0.01 * rec.times_s[i] / cfg.gravity;
        assert!((rec.samples[i][0] - expected).abs() < 1e-12);
        assert_eq!(rec.samples[i][1], pose.true_reading[1]);
    }

    #[test]
    fn static_noise_has_the_configured_std() {
        for units in [OutputUnits::Mps2, OutputUnits::MPU6050_2G] {
            let cfg = SimConfig { noise_mg: 2.0, units, ..SimConfig::paper(12) };
            let rec = simulate(&cfg);
            let sigma = units.noise_std(cfg.noise_mg, cfg.gravity);
            let expected = sigma * sigma + if units.is_counts() { 1.0 / 12.0 } else { 0.0 };
            let (mut sum_sq, mut count) = (0.0, 0.0);
            for pose in &rec.poses {
                for s in &rec.samples[pose.start..pose.end] {
                    for a in 0..3 {
                        sum_sq += (s[a] - pose.true_reading[a]).powi(2);
                        count += 1.0;
                    }
                }
            }
            let variance = sum_sq / count; // 72000 values: relative std 0.5 %
            assert!((variance / expected - 1.0).abs() < 0.03, "{units}: {variance} vs {expected}");
        }
    }

    #[test]
    fn pose_means_have_the_right_statistics() {
        let base = SimConfig { noise_mg: 3.0, ..SimConfig::paper(0) };
        let sigma = base.units.noise_std(base.noise_mg, base.gravity);
        let n: f64 = 1000.0;
        let draws = 2000;
        let reference = simulate_pose_means(&base);
        let truth: Vec<_> = simulate(&SimConfig { noise_mg: 0.0, ..base.clone() }).poses;
        let (mut sum, mut sum_sq, mut count) = (0.0, 0.0, 0.0);
        for seed in 0..draws {
            let means = simulate_pose_means(&SimConfig { seed, ..base.clone() });
            assert_eq!(means.len(), 24);
            for (p, mean) in means.iter().enumerate() {
                assert_eq!((mean.n, mean.variance), (1000, [(sigma * sigma) as f32; 3]));
                let expected = simulate_pose_means(&SimConfig { noise_mg: 0.0, seed, ..base.clone() })[p].mean;
                for a in 0..3 {
                    let z = (f64::from(mean.mean[a]) - f64::from(expected[a])) / (sigma / n.sqrt());
                    sum += z;
                    sum_sq += z * z;
                    count += 1.0;
                }
            }
        }
        let mean_z = sum / count;
        let var_z = sum_sq / count - mean_z * mean_z;
        // 144000 standard-normal values (up to f32 rounding of the means: ~1e-6 / 3e-4 of a sigma).
        assert!(mean_z.abs() < 0.02, "{mean_z}");
        assert!((var_z - 1.0).abs() < 0.03, "{var_z}");
        // Same layout and true readings as simulate.
        for (pose, sim_pose) in reference.iter().zip(&truth) {
            assert_eq!((pose.start_index as usize, pose.end_index as usize), (sim_pose.start, sim_pose.end));
            for a in 0..3 {
                let z = (f64::from(pose.mean[a]) - sim_pose.true_reading[a]) / (sigma / n.sqrt());
                assert!(z.abs() < 6.0);
            }
        }
    }

    #[test]
    fn invalid_configs_are_rejected_without_panicking() {
        let bad = [
            SimConfig { rate_hz: 0.0, ..SimConfig::default() },
            SimConfig { rate_hz: f64::NAN, ..SimConfig::default() },
            SimConfig { seconds_per_pose: 0.0, ..SimConfig::default() },
            SimConfig { move_seconds: -1.0, ..SimConfig::default() },
            SimConfig { noise_mg: f64::INFINITY, ..SimConfig::default() },
            SimConfig { gravity: 0.0, ..SimConfig::default() },
            SimConfig { truth: Params { scale: [1.0, 0.0, 1.0], ..Params::IDENTITY }, ..SimConfig::default() },
            SimConfig { units: OutputUnits::Counts { lsb_per_g: 0.0, offset: 0.0 }, ..SimConfig::default() },
            SimConfig { plan: Plan::Random(0), ..SimConfig::default() },
            SimConfig { rate_hz: 1e12, ..SimConfig::default() },
        ];
        for cfg in bad {
            assert!(cfg.validate().is_err(), "{cfg:?}");
            assert!(simulate(&cfg).samples.is_empty());
            assert!(simulate_pose_means(&cfg).is_empty());
        }
        assert_eq!(SimConfig::default().validate(), Ok(()));
        let error = SimConfig { rate_hz: -1.0, ..SimConfig::default() }.validate().unwrap_err();
        assert!(error.to_string().contains("rate_hz"));
    }

    #[test]
    fn csv_has_header_and_formats() {
        let cfg =
            SimConfig { plan: Plan::Random(1), initial_rest_s: 0.0, seconds_per_pose: 0.02, ..SimConfig::default() };
        let rec = simulate(&cfg);
        let mut out = Vec::new();
        write_csv(&rec, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<_> = text.lines().collect();
        assert_eq!(lines.len(), 5);
        assert_eq!(lines[0], "t,ax,ay,az");
        assert!(lines[2].starts_with("0.005000,"), "{}", lines[2]);
        let values: Vec<f64> = lines[1].split(',').map(|v| v.parse().unwrap()).collect();
        for a in 0..3 {
            let digits = lines[1].split(',').nth(a + 1).unwrap().chars().filter(char::is_ascii_digit).count();
            assert!((9..=10).contains(&digits) || values[a + 1].abs() < 1e-3, "{}", lines[1]);
            assert!((values[a + 1] - rec.samples[0][a]).abs() <= 1e-8 * rec.samples[0][a].abs().max(1.0));
        }
        let counts = simulate(&SimConfig { units: OutputUnits::MPU6050_2G, ..cfg });
        let mut out = Vec::new();
        write_csv(&counts, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let row: Vec<i64> = text.lines().nth(1).unwrap().split(',').skip(1).map(|v| v.parse().unwrap()).collect();
        assert_eq!(row, counts.samples[0].map(|v| v as i64).to_vec());
        assert_eq!(significant(0.000123456789123, 9), "0.000123456789");
        assert_eq!(significant(-9.80665, 9), "-9.80665000");
    }

    #[test]
    fn accumulator_finds_every_paper24_pose() {
        for seed in 0..8 {
            let rec = simulate(&SimConfig::paper(seed));
            let mut acc: Accumulator<f32, 64, 32> = Accumulator::new(AccumulatorConfig::default()).unwrap();
            for s in &rec.samples {
                acc.push(s.map(|v| v as f32)).unwrap();
            }
            acc.finish().unwrap();
            let found = acc.poses();
            assert_eq!(
                found.len(),
                24,
                "seed {seed}: rejections {:?}, noise variance {}",
                acc.rejections(),
                acc.noise_variance()
            );
            for (pose, sim_pose) in found.iter().zip(&rec.poses) {
                let (start, end) = (pose.start_index as usize, pose.end_index as usize);
                assert!(
                    sim_pose.start <= start && end <= sim_pose.end,
                    "seed {seed}: found {start}..{end} in {}..{}",
                    sim_pose.start,
                    sim_pose.end
                );
                assert!(end - start >= 800, "seed {seed}: only {} samples", end - start);
            }
        }
    }

    #[test]
    fn pose_means_are_fast() {
        let start = std::time::Instant::now();
        let mut checksum = 0.0f64;
        for seed in 0..500 {
            let means = simulate_pose_means(&SimConfig::paper(seed));
            checksum += f64::from(means[23].mean[2]);
        }
        let elapsed = start.elapsed();
        println!("500 paper24 pose-mean simulations: {elapsed:?} (checksum {checksum})");
        assert!(checksum.is_finite());
        #[cfg(not(debug_assertions))]
        assert!(elapsed.as_secs_f64() < 0.5, "{elapsed:?}");
    }
}
