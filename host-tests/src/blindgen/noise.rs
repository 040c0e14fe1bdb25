//! Random numbers for the generator: a seeded xoshiro256++ stream per purpose, uniform, normal and
//! log-uniform draws, and the coloured processes (Gauss-Markov, random walk) built on them.

use rand_core::{Rng as _, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use super::vec3::V3;

/// Stream ids: one independent generator per purpose, so switching an effect off leaves the session
/// and the white noise of a log untouched.
pub(crate) const STREAM_SPEC: u64 = 0x5EC0_0001;
pub(crate) const STREAM_NOISE: u64 = 0x401E_0002;
pub(crate) const STREAM_EFFECT: u64 = 0xEFFE_0003;

/// A seeded random stream.
#[derive(Debug, Clone)]
pub struct Rng(Xoshiro256PlusPlus);

impl Rng {
    /// The stream `stream` of the log seeded `seed`.
    pub fn new(seed: u64, stream: u64) -> Self {
        let mixed = seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ stream.rotate_left(29);
        Self(Xoshiro256PlusPlus::seed_from_u64(mixed))
    }

    /// Uniform in `[0, 1)`.
    pub fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }

    /// Log-uniform in `[lo, hi)` (both positive).
    pub fn log_uniform(&mut self, lo: f64, hi: f64) -> f64 {
        (lo.ln() + (hi.ln() - lo.ln()) * self.uniform()).exp()
    }

    /// `+1` or `-1` with equal odds.
    pub fn sign(&mut self) -> f64 {
        if self.0.next_u64() & 1 == 0 { 1.0 } else { -1.0 }
    }

    /// `true` with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        self.uniform() < p
    }

    /// Uniform integer in `[0, n)`; `n` must be positive.
    pub fn index(&mut self, n: usize) -> usize {
        (self.0.next_u64() % n.max(1) as u64) as usize
    }

    /// Standard normal (Box-Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (core::f64::consts::TAU * u2).cos()
    }

    /// Three independent standard normals.
    pub fn normal3(&mut self) -> V3 {
        [self.normal(), self.normal(), self.normal()]
    }

    /// A direction uniform on the unit sphere.
    pub fn unit_vector(&mut self) -> V3 {
        let z = self.range(-1.0, 1.0);
        let phi = self.range(0.0, core::f64::consts::TAU);
        let r = (1.0 - z * z).sqrt();
        [r * phi.cos(), r * phi.sin(), z]
    }
}

/// A first-order Gauss-Markov process with stationary standard deviation `sigma` and correlation
/// time `tau_s`, started from its stationary distribution.
#[derive(Debug, Clone)]
pub struct GaussMarkov {
    value: f64,
    sigma: f64,
    tau_s: f64,
}

impl GaussMarkov {
    /// A process drawn from its stationary distribution.
    pub fn new(sigma: f64, tau_s: f64, rng: &mut Rng) -> Self {
        Self { value: sigma * rng.normal(), sigma, tau_s }
    }

    /// Advances by `dt_s` (exact discretisation) and returns the new value.
    pub fn step(&mut self, dt_s: f64, rng: &mut Rng) -> f64 {
        let phi = (-dt_s / self.tau_s).exp();
        self.value = phi * self.value + self.sigma * (1.0 - phi * phi).sqrt() * rng.normal();
        self.value
    }
}
