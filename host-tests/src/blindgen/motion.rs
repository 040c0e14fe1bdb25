//! Motion within holds: short taps (one-cycle sine pulses of 10-50 ms, no net velocity), slow sway of
//! a hand-held board (a small tilt oscillation about a horizontal axis through a wrist a lever arm
//! away), or bumps that shift the pose mid-hold (kept to the end of the hold, undone during the next
//! rotation).

use serde_json::{Value, json};

use super::noise::Rng;
use super::session::{Ctx, G_MPS2};
use super::vec3::{V3, add, cross, scale};
use super::{Effect, EffectModel, Injector, LogSpec, Magnitude};

/// A tap: `accel sin(2 pi (t - at) / width)` for `t` in `[at, at + width]` of hold `pose`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tap {
    /// The hold.
    pub pose: usize,
    /// Start, from the hold start (s).
    pub at_s: f64,
    /// Duration (s).
    pub width_s: f64,
    /// Peak acceleration (world, m/s^2).
    pub accel_mps2: V3,
}

/// A bump: the attitude turns by `rotvec_rad` (world) over `rise_s` starting at `at_s` of hold `pose`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bump {
    /// The hold.
    pub pose: usize,
    /// Start, from the hold start (s).
    pub at_s: f64,
    /// Rise time (s).
    pub rise_s: f64,
    /// The turn (world rotation vector, rad).
    pub rotvec_rad: V3,
}

/// The motion effect's shapes.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// Taps in some holds.
    Taps(Vec<Tap>),
    /// Sway in every hold: tilt `amp sin(2 pi f t + phase)` about a horizontal world axis per hold.
    Sway {
        /// Frequency (Hz).
        freq_hz: f64,
        /// Tilt amplitude (rad).
        amp_rad: f64,
        /// Distance from the pivot (wrist) to the sensor (m).
        lever_m: f64,
        /// Azimuth of the tilt axis per hold (rad).
        azimuth_rad: Vec<f64>,
    },
    /// Bumps in one to three holds.
    Bumps(Vec<Bump>),
}

/// Sets a random motion effect on `spec`.
pub fn randomise(rng: &mut Rng, spec: &mut LogSpec) {
    let holds: Vec<f64> = spec.session.holds().iter().map(|h| h.end_s - h.start_s).collect();
    let motion = match rng.index(3) {
        0 => random_taps(rng, &holds),
        1 => Motion::Sway {
            freq_hz: rng.log_uniform(0.2, 2.0),
            amp_rad: rng.log_uniform(0.05, 3.0).to_radians(),
            lever_m: rng.range(0.05, 0.3),
            azimuth_rad: holds.iter().map(|_| rng.range(0.0, core::f64::consts::TAU)).collect(),
        },
        _ => random_bumps(rng, &holds),
    };
    spec.set_effect(Effect::Motion(motion));
}

/// One to a third of the holds get a tap each; peak 20 mg to 2 g.
fn random_taps(rng: &mut Rng, holds: &[f64]) -> Motion {
    let peak_mg = rng.log_uniform(20.0, 2000.0);
    let count = 1 + rng.index(holds.len() / 3);
    let taps = (0..count)
        .map(|_| {
            let pose = 1 + rng.index(holds.len() - 1);
            Tap {
                pose,
                at_s: rng.range(0.5, holds[pose] - 0.6),
                width_s: rng.range(0.01, 0.05),
                accel_mps2: scale(rng.unit_vector(), rng.range(0.5, 1.0) * peak_mg * 1e-3 * G_MPS2),
            }
        })
        .collect();
    Motion::Taps(taps)
}

/// One to three holds get a bump of 0.2-10 deg about a horizontal axis.
fn random_bumps(rng: &mut Rng, holds: &[f64]) -> Motion {
    let angle_deg = rng.log_uniform(0.2, 10.0);
    let bumps = (0..1 + rng.index(3))
        .map(|_| {
            let pose = 1 + rng.index(holds.len() - 1);
            let azimuth = rng.range(0.0, core::f64::consts::TAU);
            let angle = rng.range(0.5, 1.0) * angle_deg.to_radians();
            Bump {
                pose,
                at_s: rng.range(0.3, 0.7) * holds[pose],
                rise_s: rng.range(0.05, 0.3),
                rotvec_rad: [angle * azimuth.cos(), angle * azimuth.sin(), 0.0],
            }
        })
        .collect();
    Motion::Bumps(bumps)
}

impl EffectModel for Motion {
    fn shape(&self) -> String {
        match self {
            Self::Taps(_) => "taps",
            Self::Sway { .. } => "sway",
            Self::Bumps(_) => "bump",
        }
        .into()
    }

    fn params(&self) -> Value {
        match self {
            Self::Taps(taps) => json!({"taps": taps.iter().map(|t| json!({"pose": t.pose, "at_s": t.at_s,
                "width_s": t.width_s, "accel_mps2": t.accel_mps2})).collect::<Vec<_>>()}),
            Self::Sway { freq_hz, amp_rad, lever_m, azimuth_rad } => json!({"freq_hz": freq_hz,
                "amp_rad": amp_rad, "lever_m": lever_m, "azimuth_rad": azimuth_rad}),
            Self::Bumps(bumps) => json!({"bumps": bumps.iter().map(|b| json!({"pose": b.pose, "at_s": b.at_s,
                "rise_s": b.rise_s, "rotvec_rad": b.rotvec_rad})).collect::<Vec<_>>()}),
        }
    }

    fn magnitude(&self) -> Magnitude {
        let (value, what) = match self {
            Self::Taps(taps) => {
                (taps.iter().map(|t| super::vec3::norm(t.accel_mps2)).fold(0.0, f64::max), "largest tap peak")
            }
            Self::Sway { amp_rad, .. } => (amp_rad * G_MPS2, "gravity change at the tilt amplitude"),
            Self::Bumps(b) => (
                b.iter().map(|b| super::vec3::norm(b.rotvec_rad)).fold(0.0, f64::max) * G_MPS2,
                "gravity change of the largest bump",
            ),
        };
        Magnitude { value: value / G_MPS2 * 1e3, unit: "mg", what }
    }

    fn injector(&self, _rng: Rng) -> Box<dyn Injector + '_> {
        Box::new(self)
    }
}

/// Minimum-jerk step from 0 to 1 over `[0, 1]`.
fn smooth_step(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * x * (10.0 - 15.0 * x + 6.0 * x * x)
}

/// The tap acceleration at `ctx` (world, m/s^2).
fn tap_accel(taps: &[Tap], ctx: &Ctx) -> V3 {
    let active = taps.iter().filter(|t| ctx.in_hold && t.pose == ctx.pose);
    active.fold([0.0; 3], |sum, t| {
        let x = (ctx.elapsed_s - t.at_s) / t.width_s;
        let pulse = if (0.0..=1.0).contains(&x) { (core::f64::consts::TAU * x).sin() } else { 0.0 };
        add(sum, scale(t.accel_mps2, pulse))
    })
}

/// The bump turn at `ctx` (world rotation vector): rises in its hold, undone during the next rotation.
fn bump_rotvec(bumps: &[Bump], ctx: &Ctx) -> V3 {
    bumps.iter().fold([0.0; 3], |sum, b| {
        let weight = if ctx.in_hold && ctx.pose == b.pose {
            smooth_step((ctx.elapsed_s - b.at_s) / b.rise_s)
        } else if !ctx.in_hold && ctx.pose == b.pose + 1 {
            1.0 - smooth_step(ctx.elapsed_s / ctx.length_s)
        } else {
            0.0
        };
        add(sum, scale(b.rotvec_rad, weight))
    })
}

/// Sway tilt (world rotation vector) and the lever arm's tangential acceleration in a hold.
fn sway(freq_hz: f64, amp_rad: f64, lever_m: f64, azimuth_rad: f64, ctx: &Ctx) -> (V3, V3) {
    if !ctx.in_hold {
        return ([0.0; 3], [0.0; 3]);
    }
    let w = core::f64::consts::TAU * freq_hz;
    let fade = smooth_step(ctx.elapsed_s / 0.5) * smooth_step((ctx.length_s - ctx.elapsed_s) / 0.5);
    let axis = [azimuth_rad.cos(), azimuth_rad.sin(), 0.0];
    let theta = fade * amp_rad * (w * ctx.t_s).sin();
    let theta_dd = -fade * amp_rad * w * w * (w * ctx.t_s).sin();
    let tangent = cross(axis, [0.0, 0.0, 1.0]);
    (scale(axis, theta), scale(tangent, -lever_m * theta_dd))
}

impl Injector for &Motion {
    fn motion(&mut self, ctx: &Ctx) -> (V3, V3) {
        match self {
            Motion::Taps(taps) => ([0.0; 3], tap_accel(taps, ctx)),
            Motion::Sway { freq_hz, amp_rad, lever_m, azimuth_rad } => {
                sway(*freq_hz, *amp_rad, *lever_m, azimuth_rad[ctx.pose], ctx)
            }
            Motion::Bumps(bumps) => (bump_rotvec(bumps, ctx), [0.0; 3]),
        }
    }
}
