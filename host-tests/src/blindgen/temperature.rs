//! Temperature: the thermometer profile of a session (constant, warm-up, ramp, cycling) and the
//! sensor's bias and scale sensitivity to its own temperature, which may lag the thermometer by a
//! first-order lag.

use serde_json::{Value, json};

use super::noise::Rng;
use super::session::{Ctx, G_MPS2};
use super::vec3::{V3, scale};
use super::{Effect, EffectModel, Injector, LogSpec, Magnitude};

/// Thermometer noise (deg C, 1 sigma).
pub const THERMOMETER_NOISE_C: f64 = 0.02;

/// Ambient temperature over a session.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TempProfile {
    /// Constant.
    Constant {
        /// Temperature (deg C).
        c: f64,
    },
    /// `start + rise (1 - exp(-t / tau))`: a board warming up.
    WarmUp {
        /// At t = 0 (deg C).
        start_c: f64,
        /// Final rise (deg C).
        rise_c: f64,
        /// Time constant (s).
        tau_s: f64,
    },
    /// `start + rate t`.
    Ramp {
        /// At t = 0 (deg C).
        start_c: f64,
        /// Rate (deg C per s).
        rate_c_per_s: f64,
    },
    /// `mean + amp sin(2 pi t / period)`: a thermostat cycling.
    Cycling {
        /// Mean (deg C).
        mean_c: f64,
        /// Amplitude (deg C).
        amp_c: f64,
        /// Period (s).
        period_s: f64,
    },
}

impl TempProfile {
    /// The temperature at `t_s`.
    pub fn at(&self, t_s: f64) -> f64 {
        match *self {
            Self::Constant { c } => c,
            Self::WarmUp { start_c, rise_c, tau_s } => start_c + rise_c * (1.0 - (-t_s / tau_s).exp()),
            Self::Ramp { start_c, rate_c_per_s } => start_c + rate_c_per_s * t_s,
            Self::Cycling { mean_c, amp_c, period_s } => {
                mean_c + amp_c * (core::f64::consts::TAU * t_s / period_s).sin()
            }
        }
    }

    /// A room thermometer for logs without a temperature effect: constant or drifting by at most
    /// a couple of degrees.
    pub fn random_ambient(rng: &mut Rng) -> Self {
        let start_c = rng.range(18.0, 30.0);
        match rng.index(3) {
            0 => Self::Constant { c: start_c },
            1 => Self::Ramp { start_c, rate_c_per_s: rng.range(-2.0, 2.0) / 600.0 },
            _ => Self::WarmUp { start_c, rise_c: rng.range(0.5, 2.0), tau_s: rng.range(60.0, 600.0) },
        }
    }

    /// A clearly varying profile over a session of `total_s`: warm-up, ramp or cycling.
    pub fn random_varying(rng: &mut Rng, total_s: f64) -> Self {
        let start_c = rng.range(5.0, 35.0);
        match rng.index(3) {
            0 => Self::WarmUp { start_c, rise_c: rng.range(3.0, 15.0), tau_s: rng.range(0.1, 0.5) * total_s },
            1 => Self::Ramp { start_c, rate_c_per_s: rng.sign() * rng.range(3.0, 20.0) / total_s },
            _ => Self::Cycling { mean_c: start_c, amp_c: rng.range(2.0, 8.0), period_s: rng.range(0.3, 1.0) * total_s },
        }
    }

    /// Holds the thermometer `profile` (if any) at its starting value: logs whose effect is a slow
    /// bias change keep the temperature steady, so that the effect cannot equally be read as a
    /// temperature sensitivity.
    pub fn hold_steady(profile: &mut Option<Self>) {
        if let Some(p) = profile.as_mut() {
            *p = Self::Constant { c: p.at(0.0) };
        }
    }

    /// The largest departure from the temperature at t = 0 over `[0, total_s]` (deg C).
    pub fn span_c(&self, total_s: f64) -> f64 {
        let t0 = self.at(0.0);
        (0..=200).map(|k| (self.at(total_s * k as f64 / 200.0) - t0).abs()).fold(0.0, f64::max)
    }

    /// The profile as JSON.
    pub fn to_json(&self) -> Value {
        match *self {
            Self::Constant { c } => json!({"profile": "constant", "c": c}),
            Self::WarmUp { start_c, rise_c, tau_s } => {
                json!({"profile": "warm_up", "start_c": start_c, "rise_c": rise_c, "tau_s": tau_s})
            }
            Self::Ramp { start_c, rate_c_per_s } => {
                json!({"profile": "ramp", "start_c": start_c, "rate_c_per_s": rate_c_per_s})
            }
            Self::Cycling { mean_c, amp_c, period_s } => {
                json!({"profile": "cycling", "mean_c": mean_c, "amp_c": amp_c, "period_s": period_s})
            }
        }
    }
}

/// The sensor's temperature sensitivity, relative to its temperature at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct TempEffect {
    /// Shape name (`bias_linear`, `bias_quadratic`, `scale_linear`, `bias_and_scale`, with
    /// `_lagged` when the sensor lags the thermometer).
    pub shape: String,
    /// Bias per deg C (m/s^2 / C).
    pub bias_per_c: V3,
    /// Bias per deg C squared (m/s^2 / C^2).
    pub bias_per_c2: V3,
    /// Relative scale change per deg C (1 / C).
    pub scale_per_c: V3,
    /// Relative scale change per deg C squared (1 / C^2).
    pub scale_per_c2: V3,
    /// First-order lag of the sensor behind the thermometer (s), if any.
    pub lag_tau_s: Option<f64>,
    /// The drawn strength.
    pub magnitude: Magnitude,
}

/// Sets a temperature effect (and a varying thermometer) on `spec`.
pub fn randomise(rng: &mut Rng, spec: &mut LogSpec) {
    let total_s = spec.session.total_s();
    let profile = TempProfile::random_varying(rng, total_s);
    spec.session.temperature = Some(profile);
    let span_c = profile.span_c(total_s).max(0.5);
    let lag_tau_s = rng.chance(0.4).then(|| rng.log_uniform(30.0, 300.0));
    spec.set_effect(Effect::Temperature(TempEffect::random(rng, span_c, lag_tau_s)));
}

/// The shapes of the sensitivity (the name gets `_lagged` when the sensor lags the thermometer).
pub const TEMP_KINDS: [&str; 5] =
    ["bias_linear", "bias_quadratic", "scale_linear", "scale_quadratic", "bias_and_scale"];

impl TempEffect {
    /// A random effect over a temperature span of `span_c`: a bias change of 0.5-50 mg and/or a
    /// scale change of 1000-30 000 ppm across the span.
    pub fn random(rng: &mut Rng, span_c: f64, lag_tau_s: Option<f64>) -> Self {
        let kind = TEMP_KINDS[rng.index(TEMP_KINDS.len())];
        let mut e = Self {
            shape: format!("{kind}{}", if lag_tau_s.is_some() { "_lagged" } else { "" }),
            bias_per_c: [0.0; 3],
            bias_per_c2: [0.0; 3],
            scale_per_c: [0.0; 3],
            scale_per_c2: [0.0; 3],
            lag_tau_s,
            magnitude: Magnitude { value: 0.0, unit: "mg", what: "" },
        };
        if kind.contains("scale") {
            e.set_scale(rng, kind.ends_with("quadratic"), span_c);
        }
        if kind.contains("bias") {
            e.set_bias(rng, kind.ends_with("quadratic"), span_c);
        }
        e
    }

    /// A bias change of 0.5-50 mg across `span_c`, linear or quadratic in temperature.
    fn set_bias(&mut self, rng: &mut Rng, quadratic: bool, span_c: f64) {
        let bias_mg = rng.log_uniform(0.5, 50.0);
        let change = scale(rng.unit_vector(), bias_mg * 1e-3 * G_MPS2);
        if quadratic {
            self.bias_per_c2 = scale(change, 1.0 / (span_c * span_c));
        } else {
            self.bias_per_c = scale(change, 1.0 / span_c);
        }
        self.magnitude = Magnitude { value: bias_mg, unit: "mg", what: "bias change over the temperature span" };
    }

    /// A relative scale change of 1000-30 000 ppm across `span_c`, random sign per axis.
    fn set_scale(&mut self, rng: &mut Rng, quadratic: bool, span_c: f64) {
        let scale_ppm = rng.log_uniform(1000.0, 30_000.0);
        let power = if quadratic { 2 } else { 1 };
        let per: V3 =
            core::array::from_fn(|_| rng.sign() * rng.range(0.5, 1.0) * scale_ppm * 1e-6 / span_c.powi(power));
        if quadratic {
            self.scale_per_c2 = per;
        } else {
            self.scale_per_c = per;
        }
        self.magnitude = Magnitude { value: scale_ppm, unit: "ppm", what: "scale change over the temperature span" };
    }
}

impl EffectModel for TempEffect {
    fn shape(&self) -> String {
        self.shape.clone()
    }

    fn params(&self) -> Value {
        json!({
            "bias_per_c_mps2": self.bias_per_c,
            "bias_per_c2_mps2": self.bias_per_c2,
            "scale_per_c": self.scale_per_c,
            "scale_per_c2": self.scale_per_c2,
            "lag_tau_s": self.lag_tau_s,
            "reference": "sensor temperature at t = 0",
        })
    }

    fn magnitude(&self) -> Magnitude {
        self.magnitude
    }

    fn injector(&self, _rng: Rng) -> Box<dyn Injector + '_> {
        Box::new(TempInjector { effect: self, sensor_c: None, start_c: 0.0 })
    }
}

/// Tracks the sensor temperature (lagged or not) and applies the sensitivity.
struct TempInjector<'a> {
    effect: &'a TempEffect,
    sensor_c: Option<f64>,
    start_c: f64,
}

impl TempInjector<'_> {
    /// Sensor temperature minus its value at t = 0.
    fn delta_c(&self) -> f64 {
        self.sensor_c.map_or(0.0, |c| c - self.start_c)
    }
}

impl Injector for TempInjector<'_> {
    fn advance(&mut self, ctx: &Ctx) {
        let Some(ambient_c) = ctx.thermometer_c else { return };
        let next = match (self.sensor_c, self.effect.lag_tau_s) {
            (None, _) => {
                self.start_c = ambient_c;
                ambient_c
            }
            (Some(c), Some(tau_s)) => ambient_c + (c - ambient_c) * (-ctx.dt_s / tau_s).exp(),
            (Some(_), None) => ambient_c,
        };
        self.sensor_c = Some(next);
    }

    fn response_g(&mut self, _ctx: &Ctx, a_g: V3) -> V3 {
        let (d, e) = (self.delta_c(), self.effect);
        core::array::from_fn(|k| a_g[k] * (1.0 + e.scale_per_c[k] * d + e.scale_per_c2[k] * d * d))
    }

    fn bias_mps2(&mut self, _ctx: &Ctx) -> V3 {
        let (d, e) = (self.delta_c(), self.effect);
        core::array::from_fn(|k| e.bias_per_c[k] * d + e.bias_per_c2[k] * d * d)
    }
}
