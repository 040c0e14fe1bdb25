//! Effects injected as physics: what an [`Effect`] is (a change of the noise-free reading of every
//! sample, before the white noise and the unit conversion), and the catalogue the diagnosis knows
//! (warm-up drift, temperature, scale non-linearity, settling, slow motion, coloured bias noise).
//! Each effect's doc says in which [`Injected`](super::scenario::Injected) variant its magnitudes are
//! drawn.

use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

use super::random::standard_normal;

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

/// Temperature in deg C: `base + sum of amplitude * sin(2 pi t / period + phase)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TemperatureProfile {
    /// Mean temperature, deg C.
    pub base_c: f64,
    /// `(amplitude deg C, period s, phase rad)` of the two components.
    pub waves: [(f64, f64, f64); 2],
}

impl TemperatureProfile {
    /// Temperature at `t_s`.
    pub fn at(&self, t_s: f64) -> f64 {
        self.base_c + self.waves.iter().map(|&(a, p, ph)| a * (std::f64::consts::TAU * t_s / p + ph).sin()).sum::<f64>()
    }
}

/// Warm-up drift (see [`Injected::Drift`](super::scenario::Injected::Drift)).
pub struct WarmUpDrift {
    /// Final bias change per axis, m/s^2.
    pub amplitude: [f64; 3],
    /// Time constant, s.
    pub tau_s: f64,
}

impl Effect for WarmUpDrift {
    fn apply(&mut self, t_s: f64, _pose: Option<usize>, reading: &mut [f64; 3]) {
        let k = 1.0 - (-t_s / self.tau_s).exp();
        for a in 0..3 {
            reading[a] += self.amplitude[a] * k;
        }
    }
}

/// Temperature sensitivity (see [`Injected::Temperature`](super::scenario::Injected::Temperature)).
pub struct TemperatureEffect {
    /// The temperature over time.
    pub profile: TemperatureProfile,
    /// Bias coefficient per axis, m/s^2 / deg C.
    pub bias_per_c: [f64; 3],
    /// Relative scale coefficient per axis, 1 / deg C.
    pub scale_per_c: [f64; 3],
    /// Reference temperature, deg C.
    pub reference_c: f64,
}

impl Effect for TemperatureEffect {
    fn apply(&mut self, t_s: f64, _pose: Option<usize>, reading: &mut [f64; 3]) {
        let dt = self.profile.at(t_s) - self.reference_c;
        for a in 0..3 {
            reading[a] += self.bias_per_c[a] * dt + self.scale_per_c[a] * dt * reading[a];
        }
    }
}

/// Second-order scale term (see [`Injected::ScaleNonlinearity`](super::scenario::Injected::ScaleNonlinearity)).
pub struct ScaleNonlinearity {
    /// `k2` per axis, 1 / (m/s^2).
    pub k2: [f64; 3],
}

impl Effect for ScaleNonlinearity {
    fn apply(&mut self, _t_s: f64, _pose: Option<usize>, reading: &mut [f64; 3]) {
        for a in 0..3 {
            reading[a] += self.k2[a] * reading[a] * reading[a];
        }
    }
}

/// Settling: the output lags the orientation change and relaxes over `tau_s` (see
/// [`Injected::Settling`](super::scenario::Injected::Settling)).
pub struct Settling {
    /// Lag fraction per axis.
    pub lag: [f64; 3],
    /// Decay time, s.
    pub tau_s: f64,
    current: Option<(usize, f64, [f64; 3])>,
    previous_reading: Option<[f64; 3]>,
}

impl Settling {
    /// A settling effect.
    pub fn new(lag: [f64; 3], tau_s: f64) -> Self {
        Self { lag, tau_s, current: None, previous_reading: None }
    }
}

impl Effect for Settling {
    fn apply(&mut self, t_s: f64, pose: Option<usize>, reading: &mut [f64; 3]) {
        let Some(index) = pose else {
            return;
        };
        if self.current.is_none_or(|(i, _, _)| i != index) {
            if let Some((_, _, last)) = self.current {
                self.previous_reading = Some(last);
            }
            self.current = Some((index, t_s, *reading));
        }
        let Some((_, start, clean)) = self.current else {
            return;
        };
        if let Some(previous) = self.previous_reading {
            let k = (-(t_s - start) / self.tau_s).exp();
            for a in 0..3 {
                reading[a] += self.lag[a] * (previous[a] - clean[a]) * k;
            }
        }
    }
}

/// Slow motion on some poses: a half-sine hump of linear acceleration over the pose.
pub struct SlowMotion {
    /// `(pose index, unit direction, peak m/s^2)`.
    pub poses: Vec<(usize, [f64; 3], f64)>,
    /// Static time per pose, s.
    pub pose_seconds: f64,
    start: Option<(usize, f64)>,
}

impl SlowMotion {
    /// A slow-motion effect.
    pub fn new(poses: Vec<(usize, [f64; 3], f64)>, pose_seconds: f64) -> Self {
        Self { poses, pose_seconds, start: None }
    }
}

impl Effect for SlowMotion {
    fn apply(&mut self, t_s: f64, pose: Option<usize>, reading: &mut [f64; 3]) {
        let Some(index) = pose else {
            return;
        };
        if self.start.is_none_or(|(i, _)| i != index) {
            self.start = Some((index, t_s));
        }
        let Some((_, start)) = self.start else {
            return;
        };
        if let Some(&(_, dir, peak)) = self.poses.iter().find(|(i, _, _)| *i == index) {
            let phase = ((t_s - start) / self.pose_seconds).clamp(0.0, 1.0);
            let k = peak * (std::f64::consts::PI * phase).sin();
            for a in 0..3 {
                reading[a] += dir[a] * k;
            }
        }
    }
}

/// Colored bias noise per axis: a random walk plus a first-order Gauss-Markov bias instability
/// (see [`Injected::ColoredNoise`](super::scenario::Injected::ColoredNoise)).
pub struct ColoredBias {
    /// Random-walk coefficient per axis, m/s^2 per sqrt(s).
    pub walk: [f64; 3],
    /// Bias-instability standard deviation per axis, m/s^2.
    pub instability: [f64; 3],
    /// Bias-instability correlation time, s.
    pub correlation_s: f64,
    walk_bias: [f64; 3],
    markov_bias: Option<[f64; 3]>,
    last_t: Option<f64>,
    rng: Xoshiro256PlusPlus,
}

impl ColoredBias {
    /// Colored bias noise seeded by `seed`.
    pub fn new(walk: [f64; 3], instability: [f64; 3], correlation_s: f64, seed: u64) -> Self {
        Self {
            walk,
            instability,
            correlation_s,
            walk_bias: [0.0; 3],
            markov_bias: None,
            last_t: None,
            rng: Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x0C01_07ED),
        }
    }
}

impl Effect for ColoredBias {
    fn apply(&mut self, t_s: f64, _pose: Option<usize>, reading: &mut [f64; 3]) {
        let dt = self.last_t.map_or(0.0, |last| (t_s - last).max(0.0));
        self.last_t = Some(t_s);
        let rng = &mut self.rng;
        let instability = self.instability;
        // Stationary from the start.
        let markov =
            self.markov_bias.get_or_insert_with(|| std::array::from_fn(|a| instability[a] * standard_normal(rng)));
        let keep = (-dt / self.correlation_s).exp();
        for a in 0..3 {
            self.walk_bias[a] += self.walk[a] * dt.sqrt() * standard_normal(rng);
            markov[a] = keep * markov[a] + instability[a] * (1.0 - keep * keep).sqrt() * standard_normal(rng);
            reading[a] += self.walk_bias[a] + markov[a];
        }
    }
}
