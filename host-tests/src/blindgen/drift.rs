//! Drift: the bias changes with time (zero at t = 0). Shapes: linear, quadratic, a warm-up with two
//! time constants, and a slow smooth random wander (a sum of slow sinusoids).

use serde_json::{Value, json};

use super::noise::Rng;
use super::session::{Ctx, G_MPS2};
use super::vec3::{V3, add, scale};
use super::{Effect, EffectModel, Injector, LogSpec, Magnitude};

/// The time course of the bias change.
#[derive(Debug, Clone, PartialEq)]
pub enum DriftShape {
    /// `b(t) = c1 t + c2 t^2` (m/s^2 per s, per s^2); linear when `c2 = 0`.
    Polynomial {
        /// Linear coefficient.
        c1: V3,
        /// Quadratic coefficient.
        c2: V3,
    },
    /// `b(t) = a1 (1 - exp(-t / tau1)) + a2 (1 - exp(-t / tau2))`.
    WarmUp {
        /// Fast amplitude (m/s^2).
        a1: V3,
        /// Fast time constant (s).
        tau1_s: f64,
        /// Slow amplitude (m/s^2).
        a2: V3,
        /// Slow time constant (s).
        tau2_s: f64,
    },
    /// `b(t) = sum_k amp_k (sin(2 pi t / period_k + phase_k) - sin(phase_k))`.
    Wander {
        /// Amplitudes per component (m/s^2).
        amp: Vec<V3>,
        /// Periods (s).
        period_s: Vec<f64>,
        /// Phases (rad), the same on every axis of a component.
        phase_rad: Vec<f64>,
    },
}

/// A drift effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Drift {
    /// Its time course.
    pub shape: DriftShape,
    /// Largest bias change over the session (mg), as drawn.
    pub peak_mg: f64,
}

/// Sets a random drift on `spec`.
pub fn randomise(rng: &mut Rng, spec: &mut LogSpec) {
    super::temperature::TempProfile::hold_steady(&mut spec.session.temperature);
    let total_s = spec.session.total_s();
    let peak_mg = rng.log_uniform(0.5, 50.0);
    let peak = peak_mg * 1e-3 * G_MPS2;
    let shape = match rng.index(4) {
        0 => DriftShape::Polynomial { c1: scale(rng.unit_vector(), peak / total_s), c2: [0.0; 3] },
        1 => quadratic(rng, peak, total_s),
        2 => warm_up(rng, peak, total_s),
        _ => wander(rng, peak, total_s),
    };
    spec.set_effect(Effect::Drift(Drift { shape, peak_mg }));
}

/// A quadratic drift reaching about `peak` at the end.
fn quadratic(rng: &mut Rng, peak: f64, total_s: f64) -> DriftShape {
    let w = rng.range(0.0, 0.5);
    DriftShape::Polynomial {
        c1: scale(rng.unit_vector(), w * peak / total_s),
        c2: scale(rng.unit_vector(), (1.0 - w) * peak / (total_s * total_s)),
    }
}

/// A two-time-constant warm-up of total amplitude about `peak`.
fn warm_up(rng: &mut Rng, peak: f64, total_s: f64) -> DriftShape {
    let w = rng.range(0.3, 0.7);
    DriftShape::WarmUp {
        a1: scale(rng.unit_vector(), w * peak),
        tau1_s: rng.range(0.03, 0.15) * total_s,
        a2: scale(rng.unit_vector(), (1.0 - w) * peak),
        tau2_s: rng.range(0.3, 1.5) * total_s,
    }
}

/// Three slow sinusoids, periods from a third of the session to three sessions.
fn wander(rng: &mut Rng, peak: f64, total_s: f64) -> DriftShape {
    let amp = (0..3).map(|_| scale(rng.normal3(), 0.4 * peak)).collect();
    let period_s = (0..3).map(|_| rng.log_uniform(0.33, 3.0) * total_s).collect();
    let phase_rad = (0..3).map(|_| rng.range(0.0, core::f64::consts::TAU)).collect();
    DriftShape::Wander { amp, period_s, phase_rad }
}

impl DriftShape {
    /// The bias change at `t_s` (m/s^2).
    pub fn at(&self, t_s: f64) -> V3 {
        match self {
            Self::Polynomial { c1, c2 } => add(scale(*c1, t_s), scale(*c2, t_s * t_s)),
            Self::WarmUp { a1, tau1_s, a2, tau2_s } => {
                add(scale(*a1, 1.0 - (-t_s / tau1_s).exp()), scale(*a2, 1.0 - (-t_s / tau2_s).exp()))
            }
            Self::Wander { amp, period_s, phase_rad } => {
                let mut b = [0.0; 3];
                for ((a, p), ph) in amp.iter().zip(period_s).zip(phase_rad) {
                    let w = (core::f64::consts::TAU * t_s / p + ph).sin() - ph.sin();
                    b = add(b, scale(*a, w));
                }
                b
            }
        }
    }

    /// The shape's name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Polynomial { c2, .. } if *c2 == [0.0; 3] => "linear",
            Self::Polynomial { .. } => "quadratic",
            Self::WarmUp { .. } => "warm_up",
            Self::Wander { .. } => "wander",
        }
    }
}

impl EffectModel for Drift {
    fn shape(&self) -> String {
        self.shape.name().into()
    }

    fn params(&self) -> Value {
        match &self.shape {
            DriftShape::Polynomial { c1, c2 } => json!({"c1_mps2_per_s": c1, "c2_mps2_per_s2": c2}),
            DriftShape::WarmUp { a1, tau1_s, a2, tau2_s } => {
                json!({"a1_mps2": a1, "tau1_s": tau1_s, "a2_mps2": a2, "tau2_s": tau2_s})
            }
            DriftShape::Wander { amp, period_s, phase_rad } => {
                json!({"amp_mps2": amp, "period_s": period_s, "phase_rad": phase_rad})
            }
        }
    }

    fn magnitude(&self) -> Magnitude {
        Magnitude { value: self.peak_mg, unit: "mg", what: "bias change over the session" }
    }

    fn injector(&self, _rng: Rng) -> Box<dyn Injector + '_> {
        Box::new(self)
    }
}

impl Injector for &Drift {
    fn bias_mps2(&mut self, ctx: &Ctx) -> V3 {
        self.shape.at(ctx.t_s)
    }
}
