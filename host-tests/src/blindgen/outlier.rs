//! Effects outside the diagnosis catalogue: one bad pose (a gross offset during one hold), mains
//! pickup (50/60 Hz with its third harmonic, aliased by the sample rate), hysteresis (the bias of each
//! axis depends on whether its input rose or fell in the last rotation), and a non-linear cross-axis
//! coupling (`a_x += kx a_y a_z`, and cyclically; a linear coupling would be absorbed by the model).

use serde_json::{Value, json};

use super::noise::Rng;
use super::session::{Ctx, G_MPS2};
use super::vec3::{V3, scale};
use super::{Effect, EffectModel, Injector, LogSpec, Magnitude};

/// An out-of-catalogue effect.
#[derive(Debug, Clone, PartialEq)]
pub enum Outlier {
    /// A constant offset during hold `pose` only.
    BadPose {
        /// The hold.
        pose: usize,
        /// Offset (m/s^2, added to the bias).
        offset_mps2: V3,
    },
    /// Mains pickup `amp (sin(2 pi f t + phase) + third sin(6 pi f t + 3 phase))` along `amp`.
    Mains {
        /// Mains frequency, near 50 or 60 Hz (Hz).
        freq_hz: f64,
        /// Amplitude vector (m/s^2).
        amp_mps2: V3,
        /// Relative amplitude of the third harmonic.
        third: f64,
        /// Phase (rad).
        phase_rad: f64,
    },
    /// Bias `h_k tanh(change_k / width)`, `change_k` the change of axis `k`'s gravity component
    /// (in g) during the last rotation; held from the start of each hold.
    Hysteresis {
        /// Half-width of the hysteresis loop per axis (m/s^2).
        h_mps2: V3,
        /// Input change that saturates the loop (g).
        width_g: f64,
    },
    /// `a_x += k_x a_y a_z`, `a_y += k_y a_z a_x`, `a_z += k_z a_x a_y` (g).
    CrossAxis {
        /// Coefficients (1/g).
        k_per_g: V3,
    },
}

/// Sets a random out-of-catalogue effect on `spec`.
pub fn randomise(rng: &mut Rng, spec: &mut LogSpec) {
    let poses = spec.session.poses.len();
    let effect = match rng.index(4) {
        0 => Outlier::BadPose {
            pose: 1 + rng.index(poses - 1),
            offset_mps2: scale(rng.unit_vector(), rng.log_uniform(3.0, 300.0) * 1e-3 * G_MPS2),
        },
        1 => Outlier::Mains {
            freq_hz: if rng.chance(0.5) { 50.0 } else { 60.0 } + rng.range(-0.05, 0.05),
            amp_mps2: scale(rng.unit_vector(), rng.log_uniform(0.3, 20.0) * 1e-3 * G_MPS2),
            third: rng.range(0.0, 0.4),
            phase_rad: rng.range(0.0, core::f64::consts::TAU),
        },
        2 => Outlier::Hysteresis {
            h_mps2: scale(rng.normal3(), rng.log_uniform(0.3, 30.0) * 1e-3 * G_MPS2),
            width_g: rng.range(0.05, 0.3),
        },
        _ => Outlier::CrossAxis {
            k_per_g: core::array::from_fn(|_| rng.sign() * rng.range(0.3, 1.0) * rng.log_uniform(0.3, 30.0) * 1e-3),
        },
    };
    spec.set_effect(Effect::Outlier(effect));
}

impl EffectModel for Outlier {
    fn shape(&self) -> String {
        match self {
            Self::BadPose { .. } => "bad_pose",
            Self::Mains { .. } => "mains",
            Self::Hysteresis { .. } => "hysteresis",
            Self::CrossAxis { .. } => "cross_axis",
        }
        .into()
    }

    fn params(&self) -> Value {
        match self {
            Self::BadPose { pose, offset_mps2 } => json!({"pose": pose, "offset_mps2": offset_mps2}),
            Self::Mains { freq_hz, amp_mps2, third, phase_rad } => {
                json!({"freq_hz": freq_hz, "amp_mps2": amp_mps2, "third": third, "phase_rad": phase_rad})
            }
            Self::Hysteresis { h_mps2, width_g } => json!({"h_mps2": h_mps2, "width_g": width_g}),
            Self::CrossAxis { k_per_g } => json!({"k_per_g": k_per_g}),
        }
    }

    fn magnitude(&self) -> Magnitude {
        let largest = |v: &V3| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let (value, what) = match self {
            Self::BadPose { offset_mps2, .. } => (super::vec3::norm(*offset_mps2) / G_MPS2, "offset of the bad pose"),
            Self::Mains { amp_mps2, .. } => (super::vec3::norm(*amp_mps2) / G_MPS2, "pickup amplitude"),
            Self::Hysteresis { h_mps2, .. } => (largest(h_mps2) / G_MPS2, "largest loop half-width"),
            Self::CrossAxis { k_per_g } => (largest(k_per_g), "largest product coefficient at 1 g x 1 g"),
        };
        Magnitude { value: value * 1e3, unit: "mg", what }
    }

    fn injector(&self, _rng: Rng) -> Box<dyn Injector + '_> {
        Box::new(OutlierInjector { effect: self, hysteresis: [0.0; 3] })
    }
}

/// The hysteresis state (the bias set at the last hold start).
struct OutlierInjector<'a> {
    effect: &'a Outlier,
    hysteresis: V3,
}

impl Injector for OutlierInjector<'_> {
    fn advance(&mut self, ctx: &Ctx) {
        if let Outlier::Hysteresis { h_mps2, width_g } = *self.effect
            && ctx.in_hold
            && ctx.pose > 0
        {
            self.hysteresis =
                core::array::from_fn(|k| h_mps2[k] * ((ctx.up_body[k] - ctx.prev_up_body[k]) / width_g).tanh());
        }
    }

    fn response_g(&mut self, _ctx: &Ctx, a: V3) -> V3 {
        let Outlier::CrossAxis { k_per_g: k } = *self.effect else { return a };
        [a[0] + k[0] * a[1] * a[2], a[1] + k[1] * a[2] * a[0], a[2] + k[2] * a[0] * a[1]]
    }

    fn bias_mps2(&mut self, ctx: &Ctx) -> V3 {
        match *self.effect {
            Outlier::BadPose { pose, offset_mps2 } if ctx.in_hold && ctx.pose == pose => offset_mps2,
            Outlier::Mains { freq_hz, amp_mps2, third, phase_rad } => {
                let x = core::f64::consts::TAU * freq_hz * ctx.t_s + phase_rad;
                scale(amp_mps2, x.sin() + third * (3.0 * x).sin())
            }
            Outlier::Hysteresis { .. } => self.hysteresis,
            _ => [0.0; 3],
        }
    }
}
