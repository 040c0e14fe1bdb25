//! The simulator's random draws: independent seeded streams, and the distributions of `rand_distr`
//! (uniform, standard normal, unit sphere) with a uniform rotation built on them.
//!
//! Every host module that simulates draws through these functions (the independent generator
//! `blindgen` keeps its own, on purpose).

use glam::DQuat;
use rand_core::{Rng, SeedableRng};
use rand_distr::{Distribution, StandardNormal, StandardUniform, UnitSphere};
use rand_xoshiro::Xoshiro256PlusPlus;

/// Independent random streams derived from one seed.
#[derive(Clone, Copy)]
pub(crate) enum Stream {
    /// Placements (flip errors, random orientations).
    Geometry = 1,
    /// The hand's moves between poses.
    Motion = 2,
    /// White noise of every sample.
    Noise = 3,
    /// The pose means of the Monte Carlo fast path.
    PoseMeans = 4,
    /// Random sensor errors.
    Truth = 5,
}

/// SplitMix64 finaliser: decorrelates nearby seeds.
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// The generator of `stream` for `seed`.
pub(crate) fn stream_rng(seed: u64, stream: Stream) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(mix64(seed ^ mix64(stream as u64)))
}

/// Uniform in `[low, high)`: `low + (high - low) u` with `u` from `StandardUniform` (53 random bits
/// in `[0, 1)`). Unlike `rand_distr::Uniform` it accepts `low == high` and always takes one draw, so
/// a zero-width range (a flip error of 0°) does not shift the stream.
pub fn uniform_in(rng: &mut impl Rng, low: f64, high: f64) -> f64 {
    let u: f64 = StandardUniform.sample(rng);
    low + (high - low) * u
}

/// A standard normal draw (`rand_distr::StandardNormal`, ziggurat).
pub fn standard_normal(rng: &mut impl Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// A direction uniform on the unit sphere (`rand_distr::UnitSphere`).
pub fn unit_vector(rng: &mut impl Rng) -> [f64; 3] {
    UnitSphere.sample(rng)
}

/// `+1` or `-1`, equally likely (the lowest bit of one draw).
pub fn random_sign(rng: &mut impl Rng) -> f64 {
    if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 }
}

/// A rotation uniform on SO(3) (Shoemake's method: three uniform draws).
pub(crate) fn random_rotation(rng: &mut impl Rng) -> DQuat {
    let (u1, u2, u3) = (uniform_in(rng, 0.0, 1.0), uniform_in(rng, 0.0, 1.0), uniform_in(rng, 0.0, 1.0));
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    let (t2, t3) = (std::f64::consts::TAU * u2, std::f64::consts::TAU * u3);
    DQuat::from_xyzw(a * t2.sin(), a * t2.cos(), b * t3.sin(), b * t3.cos()).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_draws_have_unit_variance_and_uniform_draws_fill_the_range() {
        let mut rng = stream_rng(4, Stream::Noise);
        let draws: Vec<f64> = (0..40_000).map(|_| standard_normal(&mut rng)).collect();
        let mean = draws.iter().sum::<f64>() / draws.len() as f64;
        let variance = draws.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / draws.len() as f64;
        // 40 000 draws: the mean's std is 0.005, the variance's 0.007.
        assert!(mean.abs() < 0.025 && (variance - 1.0).abs() < 0.035, "{mean} {variance}");
        let uniform: Vec<f64> = (0..10_000).map(|_| uniform_in(&mut rng, -2.0, 3.0)).collect();
        assert!(uniform.iter().all(|u| (-2.0..3.0).contains(u)));
        assert!(uniform.iter().any(|&u| u < -1.9) && uniform.iter().any(|&u| u > 2.9));
        assert_eq!(uniform_in(&mut rng, 1.5, 1.5), 1.5);
    }

    #[test]
    fn streams_differ_and_repeat() {
        let a: Vec<u64> = (0..4).map(|_| stream_rng(1, Stream::Noise).next_u64()).collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(stream_rng(1, Stream::Noise).next_u64(), stream_rng(1, Stream::Motion).next_u64());
        assert_ne!(stream_rng(1, Stream::Noise).next_u64(), stream_rng(2, Stream::Noise).next_u64());
    }

    #[test]
    fn random_rotations_are_unit_and_unbiased() {
        let mut rng = stream_rng(9, Stream::Geometry);
        let mut sum = glam::DVec3::ZERO;
        for _ in 0..4000 {
            let q = random_rotation(&mut rng);
            assert!((q.length() - 1.0).abs() < 1e-12);
            sum += q * glam::DVec3::Z;
        }
        // The mean of 4000 uniform directions: std 0.009 per axis.
        assert!(sum.length() / 4000.0 < 0.05, "{sum}");
    }
}
