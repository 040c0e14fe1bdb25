//! Coloured bias noise, independent per axis: a random walk, a first-order Gauss-Markov process, or
//! flicker (1/f, approximated by a sum of Gauss-Markov processes of equal variance with correlation
//! times spread one decade apart).

use serde_json::{Value, json};

use super::noise::{GaussMarkov, Rng};
use super::session::{Ctx, G_MPS2};
use super::vec3::V3;
use super::{Effect, EffectModel, Injector, LogSpec, Magnitude};

/// Correlation times of the flicker components (s).
pub const FLICKER_TAUS_S: [f64; 4] = [1.0, 10.0, 100.0, 1000.0];

/// A coloured-noise effect.
#[derive(Debug, Clone, PartialEq)]
pub enum Colored {
    /// Bias random walk: `sigma sqrt(t)` after `t` seconds.
    RandomWalk {
        /// Density (m/s^2 per sqrt(s)).
        sigma_mps2_per_rt_s: f64,
    },
    /// Gauss-Markov bias.
    GaussMarkov {
        /// Stationary standard deviation (m/s^2).
        sigma_mps2: f64,
        /// Correlation time (s).
        tau_s: f64,
    },
    /// Flicker: one Gauss-Markov process per entry of [`FLICKER_TAUS_S`], each of this deviation.
    Flicker {
        /// Standard deviation of each component (m/s^2).
        sigma_each_mps2: f64,
    },
}

/// Sets a random coloured noise on `spec`; its deviation over the session is 0.3-30 mg.
pub fn randomise(rng: &mut Rng, spec: &mut LogSpec) {
    super::temperature::TempProfile::hold_steady(&mut spec.session.temperature);
    let total_s = spec.session.total_s();
    let sigma = rng.log_uniform(0.3, 30.0) * 1e-3 * G_MPS2;
    let effect = match rng.index(3) {
        0 => Colored::RandomWalk { sigma_mps2_per_rt_s: sigma / total_s.sqrt() },
        1 => Colored::GaussMarkov { sigma_mps2: sigma, tau_s: rng.log_uniform(1.0, 100.0) },
        _ => Colored::Flicker { sigma_each_mps2: sigma / (FLICKER_TAUS_S.len() as f64).sqrt() },
    };
    spec.set_effect(Effect::Colored(effect));
}

impl EffectModel for Colored {
    fn shape(&self) -> String {
        match self {
            Self::RandomWalk { .. } => "random_walk",
            Self::GaussMarkov { .. } => "gauss_markov",
            Self::Flicker { .. } => "flicker",
        }
        .into()
    }

    fn params(&self) -> Value {
        match self {
            Self::RandomWalk { sigma_mps2_per_rt_s } => json!({"sigma_mps2_per_rt_s": sigma_mps2_per_rt_s}),
            Self::GaussMarkov { sigma_mps2, tau_s } => json!({"sigma_mps2": sigma_mps2, "tau_s": tau_s}),
            Self::Flicker { sigma_each_mps2 } => {
                json!({"sigma_each_mps2": sigma_each_mps2, "taus_s": FLICKER_TAUS_S})
            }
        }
    }

    fn magnitude(&self) -> Magnitude {
        let (sigma, what) = match *self {
            Self::RandomWalk { sigma_mps2_per_rt_s } => (sigma_mps2_per_rt_s, "random walk per sqrt(s)"),
            Self::GaussMarkov { sigma_mps2, .. } => (sigma_mps2, "stationary deviation"),
            Self::Flicker { sigma_each_mps2 } => {
                (sigma_each_mps2 * (FLICKER_TAUS_S.len() as f64).sqrt(), "stationary deviation (all components)")
            }
        };
        let unit = if matches!(self, Self::RandomWalk { .. }) { "mg/sqrt(s)" } else { "mg" };
        Magnitude { value: sigma / G_MPS2 * 1e3, unit, what }
    }

    fn injector(&self, mut rng: Rng) -> Box<dyn Injector + '_> {
        let processes = match *self {
            Self::RandomWalk { .. } => Vec::new(),
            Self::GaussMarkov { sigma_mps2, tau_s } => {
                (0..3).map(|_| GaussMarkov::new(sigma_mps2, tau_s, &mut rng)).collect()
            }
            Self::Flicker { sigma_each_mps2 } => (0..3)
                .flat_map(|_| FLICKER_TAUS_S)
                .map(|tau| GaussMarkov::new(sigma_each_mps2, tau, &mut rng))
                .collect(),
        };
        Box::new(ColoredInjector { effect: self, rng, processes, walk: [0.0; 3], bias: [0.0; 3], start: None })
    }
}

/// The processes' state. The bias is counted from its value at the first sample (the truth is the
/// sensor at t = 0), so the slow components of flicker appear as slow drift.
struct ColoredInjector<'a> {
    effect: &'a Colored,
    rng: Rng,
    processes: Vec<GaussMarkov>,
    walk: V3,
    bias: V3,
    start: Option<V3>,
}

impl Injector for ColoredInjector<'_> {
    fn advance(&mut self, ctx: &Ctx) {
        if let Colored::RandomWalk { sigma_mps2_per_rt_s } = *self.effect {
            let step = sigma_mps2_per_rt_s * ctx.dt_s.sqrt();
            for k in 0..3 {
                self.walk[k] += step * self.rng.normal();
            }
            self.bias = self.walk;
            return;
        }
        let per_axis = self.processes.len() / 3;
        let mut bias = [0.0; 3];
        for (i, p) in self.processes.iter_mut().enumerate() {
            bias[i / per_axis] += p.step(ctx.dt_s, &mut self.rng);
        }
        let start = *self.start.get_or_insert(bias);
        self.bias = core::array::from_fn(|k| bias[k] - start[k]);
    }

    fn bias_mps2(&mut self, _ctx: &Ctx) -> V3 {
        self.bias
    }
}
