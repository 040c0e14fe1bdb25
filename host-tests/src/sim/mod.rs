//! The accelerometer simulator, the host's only one: a sensor with known 9-parameter errors (Zou et
//! al. 2020, eq. 2) held in a sequence of static orientations, with realistic moves between them,
//! white noise and, as options, unmodelled effects injected as physics, the Monte Carlo fast path
//! that draws pose means directly, and an MPU-6050 answering on a simulated I2C bus.
//!
//! | module | job |
//! |---|---|
//! | [`config`] | [`SimConfig`] and its checks, the paper's truth, random truths |
//! | [`plan`] | the orientations ([`Plan`]) and each pose's rotation (`glam` quaternions) |
//! | [`units`] | the output unit ([`OutputUnits`]) |
//! | `model`, `motion` | the sensor model in `f64`; the hand's carry between poses |
//! | [`record`] | every sample: [`simulate`], [`simulate_with`], [`write_csv`] |
//! | [`pose_means`] | the fast path: [`simulate_pose_means`] |
//! | [`effects`] | [`Effect`] and the catalogue of effects the diagnosis knows |
//! | [`scenario`] | random logs with one effect and a temperature column, for `diagnose` |
//! | [`i2c`] | [`SimMpu6050`](i2c::SimMpu6050): a recording replayed through MPU-6050 registers |
//! | [`random`] | seeded streams and the `rand_distr` distributions every module draws from |
//!
//! [`crate::blindgen`] is a second, deliberately separate generator: written from the physics by
//! someone who had not seen the diagnosis, it is the blind test's data source and must stay
//! independent of this simulator (sharing code would let a simulator bug hide a detector bug).
//!
//! # Model
//!
//! The sensor model is `f_b = Ka f_s - B` with `Ka = [[Sxx, 0, 0], [Mxx, Syy, 0], [Myy, Mzz, Szz]]`.
//! The sensor therefore *reads* `f_s = Ka^-1 (f_b + B)`, where `f_b` is the true specific force in the
//! orthogonal body frame (m/s^2). At rest `f_b` is the reaction to gravity, pointing up, `|f_b| = g`.
//! All arithmetic is done in `f64` (the [`Params`](accelcal::model::Params) are converted from `f32`).
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

pub mod config;
pub mod effects;
pub mod i2c;
#[cfg(test)]
pub(crate) mod knocked;
mod model;
mod motion;
pub mod plan;
pub mod pose_means;
pub mod random;
pub mod record;
pub mod scenario;
pub mod units;

pub use config::{
    DEFAULT_FLIP_DEG, DEFAULT_TILT_DEG, LANDING_JOLT_MPS2, MAX_SAMPLES, MOVE_SHAKE_MPS2, PAPER_TRUTH, SHAKE_ONSET_S,
    STANDARD_GRAVITY_MPS2, SimConfig, SimConfigError, random_truth,
};
pub use effects::Effect;
pub use model::equivalent_params;
pub use plan::{ParsePlanError, Plan, plan_directions, plan_directions_with};
pub use pose_means::simulate_pose_means;
pub use record::{Recording, SimPose, simulate, simulate_with, write_csv};
pub use units::{OutputUnits, ParseUnitsError};
