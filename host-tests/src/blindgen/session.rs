//! The calibration session: static poses in random orientations, held for a few seconds, joined by
//! hand rotations (a minimum-jerk turn plus hand shake and a modest translation), with an optional
//! initial rest. Gives, at any time, the attitude, the linear acceleration and where in the session
//! the sample falls ([`Ctx`]).

use super::noise::Rng;
use super::orientation::Quat;
use super::temperature::TempProfile;
use super::vec3::{V3, add, scale};

/// Standard gravity (m/s^2).
pub const G_MPS2: f64 = 9.806_65;

/// Hand shake during a rotation: a small wobble of the attitude and of the position, faded in and
/// out with the rotation (zero at both ends).
#[derive(Debug, Clone, PartialEq)]
pub struct Shake {
    /// Attitude wobble amplitude per world axis (rad).
    pub angle_rad: V3,
    /// Linear acceleration wobble amplitude per world axis (m/s^2).
    pub accel_mps2: V3,
    /// Wobble frequency (Hz).
    pub freq_hz: f64,
    /// Phases per axis (rad).
    pub phase_rad: V3,
}

/// One static pose and the rotation that leads to it.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseSpec {
    /// Attitude during the hold (body to world).
    pub attitude: Quat,
    /// Length of the hold (s).
    pub hold_s: f64,
    /// Length of the rotation before the hold (s); ignored for the first pose.
    pub rotation_s: f64,
    /// Net displacement of the hand during that rotation (m, world frame).
    pub travel_m: V3,
    /// Hand shake during that rotation.
    pub shake: Shake,
}

/// A session: sample rate, poses, initial rest and thermometer profile.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionSpec {
    /// Sample rate (Hz).
    pub rate_hz: f64,
    /// Rest before the first hold, in the first pose's attitude (s).
    pub rest_s: f64,
    /// The poses, in the order visited.
    pub poses: Vec<PoseSpec>,
    /// Ambient (thermometer) temperature over time, if the log carries one.
    pub temperature: Option<TempProfile>,
}

/// Where a sample falls in the session, as effects see it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ctx {
    /// Time since the start (s).
    pub t_s: f64,
    /// Sample interval (s).
    pub dt_s: f64,
    /// Index of the current hold, or of the hold a rotation leads to.
    pub pose: usize,
    /// `true` in a hold (or the initial rest), `false` during a rotation.
    pub in_hold: bool,
    /// Time since the current hold started (s); during a rotation, time since it started.
    pub elapsed_s: f64,
    /// Length of the current hold or rotation (s).
    pub length_s: f64,
    /// Gravity direction (up) in the body frame at the current pose.
    pub up_body: V3,
    /// Gravity direction (up) in the body frame at the previous pose (the current one for pose 0).
    pub prev_up_body: V3,
    /// Thermometer temperature (deg C), if the session has one.
    pub thermometer_c: Option<f64>,
    /// Length of the whole session (s).
    pub total_s: f64,
}

/// A hold's time window and nominal attitude.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoldWindow {
    /// Start (s).
    pub start_s: f64,
    /// End (s).
    pub end_s: f64,
    /// Gravity direction (up) in the body frame.
    pub up_body: V3,
}

impl SessionSpec {
    /// A random session: 12-40 poses uniform on SO(3), holds 3-10 s, rotations 1-3 s, rest 0-10 s.
    pub fn random(rng: &mut Rng, rate_hz: f64) -> Self {
        let count = 12 + rng.index(29);
        let poses = (0..count).map(|_| random_pose(rng)).collect();
        let rest_s = if rng.chance(0.5) { rng.range(2.0, 10.0) } else { 0.0 };
        Self { rate_hz, rest_s, poses, temperature: None }
    }

    /// Re-orients the poses to the six faces (some body axis up or down), turned by multiples of
    /// 90 deg about the vertical, each tilted by 0.5-2 deg, in random order: a deliberately
    /// face-aligned session of 12, 18 or 24 poses.
    pub fn align_to_faces(&mut self, rng: &mut Rng) {
        let turns = (2 + rng.index(3)).min(self.poses.len() / 6);
        self.poses.truncate(6 * turns);
        let mut order: Vec<usize> = (0..self.poses.len()).collect();
        for i in (1..order.len()).rev() {
            order.swap(i, rng.index(i + 1));
        }
        for (pose, slot) in self.poses.iter_mut().zip(order) {
            let turn = Quat::from_rotvec([0.0, 0.0, (slot / 6) as f64 * core::f64::consts::FRAC_PI_2]);
            let tilt_axis = rng.range(0.0, core::f64::consts::TAU);
            let tilt = rng.range(0.5, 2.0).to_radians();
            let tilt = Quat::from_rotvec([tilt * tilt_axis.cos(), tilt * tilt_axis.sin(), 0.0]);
            pose.attitude = tilt.then_after(turn.then_after(face_up(slot % 6)));
        }
    }

    /// The hold windows, in order (the first includes the rest).
    pub fn holds(&self) -> Vec<HoldWindow> {
        let mut t = 0.0;
        let mut out = Vec::with_capacity(self.poses.len());
        for (i, p) in self.poses.iter().enumerate() {
            let (rotation, extra) = if i == 0 { (0.0, self.rest_s) } else { (p.rotation_s, 0.0) };
            let start_s = t + rotation;
            t = start_s + p.hold_s + extra;
            out.push(HoldWindow { start_s, end_s: t, up_body: up_in_body(p.attitude) });
        }
        out
    }

    /// Length of the session (s).
    pub fn total_s(&self) -> f64 {
        self.holds().last().map_or(0.0, |h| h.end_s)
    }

    /// Number of samples.
    pub fn sample_count(&self) -> usize {
        (self.total_s() * self.rate_hz).floor() as usize
    }
}

/// A random pose with its lead-in rotation.
fn random_pose(rng: &mut Rng) -> PoseSpec {
    let shake = Shake {
        angle_rad: scale(rng.normal3(), rng.range(0.3, 2.0).to_radians()),
        accel_mps2: scale(rng.normal3(), rng.range(0.05, 0.4)),
        freq_hz: rng.range(3.0, 9.0),
        phase_rad: scale([rng.uniform(), rng.uniform(), rng.uniform()], core::f64::consts::TAU),
    };
    PoseSpec {
        attitude: Quat::random(rng),
        hold_s: rng.range(3.0, 10.0),
        rotation_s: rng.range(1.0, 3.0),
        travel_m: scale(rng.unit_vector(), rng.range(0.0, 0.15)),
        shake,
    }
}

/// The attitude that puts body axis `+z, -z, +x, -x, +y, -y` (for `face` 0..5) up.
fn face_up(face: usize) -> Quat {
    let h = core::f64::consts::FRAC_PI_2;
    let rotvec = match face {
        0 => [0.0; 3],
        1 => [2.0 * h, 0.0, 0.0],
        2 => [0.0, -h, 0.0],
        3 => [0.0, h, 0.0],
        4 => [h, 0.0, 0.0],
        _ => [-h, 0.0, 0.0],
    };
    Quat::from_rotvec(rotvec)
}

/// The world's up direction seen in the body frame of `attitude`.
pub fn up_in_body(attitude: Quat) -> V3 {
    attitude.rotate_inv([0.0, 0.0, 1.0])
}

/// Minimum-jerk position profile and its second derivative, for progress `x` in `[0, 1]`.
fn min_jerk(x: f64) -> (f64, f64) {
    let s = x * x * x * (10.0 - 15.0 * x + 6.0 * x * x);
    let s2 = 60.0 * x - 180.0 * x * x + 120.0 * x * x * x;
    (s, s2)
}

/// Steps through a session sample by sample: context, attitude and linear acceleration.
#[derive(Debug, Clone)]
pub struct Timeline<'a> {
    spec: &'a SessionSpec,
    holds: Vec<HoldWindow>,
    total_s: f64,
}

impl<'a> Timeline<'a> {
    /// The timeline of `spec`.
    pub fn new(spec: &'a SessionSpec) -> Self {
        let holds = spec.holds();
        let total_s = holds.last().map_or(0.0, |h| h.end_s);
        Self { spec, holds, total_s }
    }

    /// The hold windows.
    pub fn holds(&self) -> &[HoldWindow] {
        &self.holds
    }

    /// Context at time `t_s`.
    pub fn ctx(&self, t_s: f64) -> Ctx {
        let i = self.holds.partition_point(|h| h.end_s <= t_s).min(self.holds.len() - 1);
        let h = self.holds[i];
        let in_hold = t_s >= h.start_s;
        let rot_start = if i == 0 { 0.0 } else { self.holds[i - 1].end_s };
        let (elapsed_s, length_s) =
            if in_hold { (t_s - h.start_s, h.end_s - h.start_s) } else { (t_s - rot_start, h.start_s - rot_start) };
        Ctx {
            t_s,
            dt_s: 1.0 / self.spec.rate_hz,
            pose: i,
            in_hold,
            elapsed_s,
            length_s,
            up_body: h.up_body,
            prev_up_body: self.holds[i.saturating_sub(1)].up_body,
            thermometer_c: self.spec.temperature.as_ref().map(|p| p.at(t_s)),
            total_s: self.total_s,
        }
    }

    /// Attitude (body to world) and linear acceleration (world, m/s^2) at `ctx`.
    pub fn kinematics(&self, ctx: &Ctx) -> (Quat, V3) {
        let pose = &self.spec.poses[ctx.pose];
        if ctx.in_hold || ctx.pose == 0 {
            return (pose.attitude, [0.0; 3]);
        }
        let from = self.spec.poses[ctx.pose - 1].attitude;
        let x = (ctx.elapsed_s / ctx.length_s).clamp(0.0, 1.0);
        let (s, s2) = min_jerk(x);
        let window = (core::f64::consts::PI * x).sin().powi(2);
        let sh = &pose.shake;
        let wobble: V3 =
            core::array::from_fn(|k| window * (core::f64::consts::TAU * sh.freq_hz * ctx.t_s + sh.phase_rad[k]).sin());
        let shake_rot = Quat::from_rotvec(core::array::from_fn(|k| sh.angle_rad[k] * wobble[k]));
        let attitude = shake_rot.then_after(from.slerp(pose.attitude, s));
        let travel = scale(pose.travel_m, s2 / (ctx.length_s * ctx.length_s));
        let accel = add(travel, core::array::from_fn(|k| sh.accel_mps2[k] * wobble[k]));
        (attitude, accel)
    }
}
