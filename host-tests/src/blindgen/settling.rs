//! Settling after each rotation: an exponential creep per axis (a fraction of each axis' input
//! follows it through a first-order lag, so after a rotation the reading relaxes exponentially with
//! a time constant well inside the hold), a damped oscillation
//! of the mount (ringing at 2-30 Hz decaying in 0.1-1 s along a fixed body direction), or both.

use serde_json::{Value, json};

use super::noise::Rng;
use super::session::{Ctx, G_MPS2};
use super::vec3::{V3, scale};
use super::{Effect, EffectModel, Injector, LogSpec, Magnitude};

/// Exponential (anelastic) creep: axis `k` reads `a + lag_k (lowpass_k(a) - a)`, `lowpass_k` a
/// first-order lag of time constant `tau_k`; after a step change `D` of its input the reading is
/// `a - lag_k D exp(-t / tau_k)`.
#[derive(Debug, Clone, PartialEq)]
pub struct Creep {
    /// Fraction of the input change still missing at the end of the rotation, per axis (signed).
    pub lag_fraction: V3,
    /// Time constants per axis (s).
    pub tau_s: V3,
}

/// Mount ringing: `amp_i exp(-t / decay) sin(2 pi f t + phase_i)` along `dir_body` from the end of
/// rotation `i` (an abrupt stop excites the mode; the phase is small).
#[derive(Debug, Clone, PartialEq)]
pub struct Ringing {
    /// Mode direction in the body frame (unit).
    pub dir_body: V3,
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// Decay time constant (s).
    pub decay_s: f64,
    /// Initial amplitude per pose (m/s^2; pose 0 has no preceding rotation).
    pub amp_mps2: Vec<f64>,
    /// Phase per pose (rad).
    pub phase_rad: Vec<f64>,
}

/// A settling effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Settling {
    /// Exponential creep, if any.
    pub creep: Option<Creep>,
    /// Ringing, if any.
    pub ringing: Option<Ringing>,
    /// Strength as drawn: creep in mg per g of input change, or ringing amplitude in mg.
    pub magnitude: Magnitude,
}

/// Sets a random settling effect on `spec`.
pub fn randomise(rng: &mut Rng, spec: &mut LogSpec) {
    let poses = spec.session.poses.len();
    let kind = rng.index(3);
    let creep_mg_per_g = rng.log_uniform(2.0, 100.0);
    let ring_mg = rng.log_uniform(2.0, 200.0);
    let creep = (kind != 1).then(|| Creep {
        lag_fraction: core::array::from_fn(|_| rng.sign() * rng.range(0.5, 1.0) * creep_mg_per_g * 1e-3),
        tau_s: core::array::from_fn(|_| rng.log_uniform(0.2, 0.8)),
    });
    let ringing = (kind != 0).then(|| random_ringing(rng, poses, ring_mg));
    let magnitude = if kind == 1 {
        Magnitude { value: ring_mg, unit: "mg", what: "ringing amplitude after a rotation" }
    } else {
        Magnitude {
            value: creep_mg_per_g,
            unit: "mg/g",
            what: "creep fraction per g of input change (a hold start sees part of it)",
        }
    };
    spec.set_effect(Effect::Settling(Settling { creep, ringing, magnitude }));
}

/// Ringing with an initial amplitude around `amp_mg`.
fn random_ringing(rng: &mut Rng, poses: usize, amp_mg: f64) -> Ringing {
    Ringing {
        dir_body: rng.unit_vector(),
        freq_hz: rng.log_uniform(2.0, 30.0),
        decay_s: rng.log_uniform(0.1, 1.0),
        amp_mps2: (0..poses).map(|_| rng.range(0.5, 1.5) * amp_mg * 1e-3 * G_MPS2).collect(),
        phase_rad: (0..poses).map(|_| rng.range(-0.3, 0.3)).collect(),
    }
}

impl EffectModel for Settling {
    fn shape(&self) -> String {
        match (&self.creep, &self.ringing) {
            (Some(_), None) => "exponential",
            (None, Some(_)) => "ringing",
            _ => "exponential_and_ringing",
        }
        .into()
    }

    fn params(&self) -> Value {
        let creep = self.creep.as_ref().map(|c| json!({"lag_fraction": c.lag_fraction, "tau_s": c.tau_s}));
        let ringing = self.ringing.as_ref().map(|r| {
            json!({"dir_body": r.dir_body, "freq_hz": r.freq_hz, "decay_s": r.decay_s,
                   "amp_mps2": r.amp_mps2, "phase_rad": r.phase_rad})
        });
        json!({"creep": creep, "ringing": ringing})
    }

    fn magnitude(&self) -> Magnitude {
        self.magnitude
    }

    fn injector(&self, _rng: Rng) -> Box<dyn Injector + '_> {
        Box::new(SettlingInjector { effect: self, lowpass_g: None })
    }
}

/// `true` in a hold that follows a rotation.
fn after_rotation(ctx: &Ctx) -> bool {
    ctx.in_hold && ctx.pose > 0
}

/// The creep's low-pass state (g), started at the first input.
struct SettlingInjector<'a> {
    effect: &'a Settling,
    lowpass_g: Option<V3>,
}

impl Injector for SettlingInjector<'_> {
    fn body_force_mps2(&mut self, ctx: &Ctx) -> V3 {
        let Some(r) = self.effect.ringing.as_ref().filter(|_| after_rotation(ctx)) else { return [0.0; 3] };
        let t = ctx.elapsed_s;
        let wave = (core::f64::consts::TAU * r.freq_hz * t + r.phase_rad[ctx.pose]).sin();
        scale(r.dir_body, r.amp_mps2[ctx.pose] * (-t / r.decay_s).exp() * wave)
    }

    fn response_g(&mut self, ctx: &Ctx, a_g: V3) -> V3 {
        let Some(c) = self.effect.creep.as_ref() else { return a_g };
        let previous = self.lowpass_g.unwrap_or(a_g);
        let lowpass: V3 = core::array::from_fn(|k| a_g[k] + (previous[k] - a_g[k]) * (-ctx.dt_s / c.tau_s[k]).exp());
        self.lowpass_g = Some(lowpass);
        core::array::from_fn(|k| a_g[k] + c.lag_fraction[k] * (lowpass[k] - a_g[k]))
    }
}
