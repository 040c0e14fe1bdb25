//! The paper's adaptive crossover / mutation policies (AGA, LAGA, TAGA), each its own type so that a
//! GA links only the one it runs (the device: TAGA).
//!
//! Every policy has the same shape: below the population's average fitness a fixed probability, from
//! the average up to the best a curve that descends from its value at the average to its value at the
//! best. A policy gives the two curves (crossover, mutation) of a generation ([`Operators::curves`]) and
//! the curve's shape ([`Operators::descend`]); [`Operators::probability`] evaluates one.
//!
//! ```
//! use accelcal::ga::{Aga, FitnessStats, Operators, Taga};
//! let stats = FitnessStats { max: -1.0, avg: -3.0, lg_generation: 0.0 };
//! // TAGA below average: Pc1 = 1/(2 + lg 1) + 0.8 = 1.3, clamped to 1.
//! assert_eq!(Taga::PAPER.crossover_probability(-5.0, &stats), 1.0);
//! // AGA as printed: the best gets nothing.
//! assert_eq!(Aga::PAPER.mutation_probability(-1.0, &stats), 0.0);
//! ```

/// Population fitness statistics the adaptive policies need (`f = -cost`).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FitnessStats {
    /// Largest fitness.
    pub max: f32,
    /// Mean fitness.
    pub avg: f32,
    /// `lg N` (base 10) of the generation `N` (from 1) being produced: TAGA's `Pc1` and `Pm1` use it.
    pub lg_generation: f32,
}

impl FitnessStats {
    /// `Some(t)` with `t = (f - f_avg) / (f_max - f_avg)` in `[0, 1]` when `f >= f_avg`, else `None`.
    /// A population of equal fitness gives `t = 1` (everyone is the best).
    pub fn above_average(&self, f: f32) -> Option<f32> {
        if f < self.avg {
            return None;
        }
        let spread = self.max - self.avg;
        if spread > 0.0 { Some(unit_interval((f - self.avg) / spread)) } else { Some(1.0) }
    }
}

/// One adaptive probability of one generation: `below` under the average fitness, then
/// [`Operators::descend`] from `average` (at the average) to `best` (at the best).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Curve {
    /// The probability below the average fitness.
    pub below: f32,
    /// Where the descent starts (`t = 0`, at the average).
    pub average: f32,
    /// Where it ends (`t = 1`, at the best).
    pub best: f32,
}

/// An adaptive crossover / mutation policy (fitness `f = -cost`, larger is better). All probabilities
/// are clamped to `[0, 1]`: TAGA's `Pc1 = 1/(2 + lg N) + phi` exceeds 1 for `N < 1000` with the paper's
/// `phi = 0.8`, so its crossover is certain early on.
pub trait Operators: Copy + core::fmt::Debug + PartialEq {
    /// The paper's constants.
    const PAPER: Self;

    /// The four constants, in declaration order (a GA refuses non-finite ones).
    fn constants(&self) -> [f32; 4];

    /// The crossover and the mutation curve of the generation whose `lg N` is `lg_generation`.
    fn curves(&self, lg_generation: f32) -> [Curve; 2];

    /// The curve's value at `t` in `[0, 1]` from `average` (`t = 0`) to `best` (`t = 1`).
    fn descend(average: f32, best: f32, t: f32) -> f32;

    /// The probability of `curve` for fitness `f`, clamped to `[0, 1]`.
    fn probability(curve: &Curve, f: f32, stats: &FitnessStats) -> f32 {
        unit_interval(stats.above_average(f).map_or(curve.below, |t| Self::descend(curve.average, curve.best, t)))
    }

    /// Crossover probability for a pair whose better parent has fitness `f_better`.
    fn crossover_probability(&self, f_better: f32, stats: &FitnessStats) -> f32 {
        Self::probability(&self.curves(stats.lg_generation)[0], f_better, stats)
    }

    /// Per-gene mutation probability for an individual of fitness `f`.
    fn mutation_probability(&self, f: f32, stats: &FitnessStats) -> f32 {
        Self::probability(&self.curves(stats.lg_generation)[1], f, stats)
    }
}

/// Srinivas & Patnaik: `Pc = k1 (f_max - f') / (f_max - f_avg)` if `f' >= f_avg` else `k3`;
/// `Pm = k2 (f_max - f) / (f_max - f_avg)` if `f >= f_avg` else `k4`. As printed, the best individual
/// gets `Pc = Pm = 0`: once clones of it fill the population the search freezes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Aga {
    /// Crossover factor for above-average pairs (paper: 0.8).
    pub k1: f32,
    /// Mutation factor for above-average individuals (paper: 0.8).
    pub k2: f32,
    /// Crossover probability below average (paper: 0.05).
    pub k3: f32,
    /// Mutation probability below average (paper: 0.03).
    pub k4: f32,
}

impl Operators for Aga {
    const PAPER: Self = Self { k1: 0.8, k2: 0.8, k3: 0.05, k4: 0.03 };

    fn constants(&self) -> [f32; 4] {
        [self.k1, self.k2, self.k3, self.k4]
    }

    fn curves(&self, _lg_generation: f32) -> [Curve; 2] {
        [Curve { below: self.k3, average: self.k1, best: 0.0 }, Curve { below: self.k4, average: self.k2, best: 0.0 }]
    }

    /// `k (1 - t)`: the curves end at 0.
    fn descend(average: f32, _best: f32, t: f32) -> f32 {
        average * (1.0 - t)
    }
}

/// Linear adaptive ("IAGA" in the paper): `Pc = Pc1 - (Pc1 - Pc2)(f' - f_avg)/(f_max - f_avg)` if
/// `f' >= f_avg` else `Pc1`, the same form for `Pm`. The paper prints `Pc1 = Pc2 = 0.8`, so its
/// crossover is not adaptive.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Laga {
    /// Crossover probability at and below average (paper: 0.8).
    pub pc1: f32,
    /// Crossover probability of the best (paper: 0.8).
    pub pc2: f32,
    /// Mutation probability at and below average (paper: 0.05).
    pub pm1: f32,
    /// Mutation probability of the best (paper: 0.03).
    pub pm2: f32,
}

impl Operators for Laga {
    const PAPER: Self = Self { pc1: 0.8, pc2: 0.8, pm1: 0.05, pm2: 0.03 };

    fn constants(&self) -> [f32; 4] {
        [self.pc1, self.pc2, self.pm1, self.pm2]
    }

    fn curves(&self, _lg_generation: f32) -> [Curve; 2] {
        [
            Curve { below: self.pc1, average: self.pc1, best: self.pc2 },
            Curve { below: self.pm1, average: self.pm1, best: self.pm2 },
        ]
    }

    fn descend(average: f32, best: f32, t: f32) -> f32 {
        average - (average - best) * t
    }
}

/// The paper's TAGA, eqs. (8)-(9): sinusoidal between `Pc1(N)` and `Pc2`, with `Pc1 = 1/(2 + lg N) +
/// phi` and `Pm1 = -0.1/(2 + 0.8 lg N) + varphi`, `N` the generation (from 1).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Taga {
    /// Limit of `Pc1` (paper: 0.8).
    pub phi: f32,
    /// Crossover probability of the best (paper: 0.8).
    pub pc2: f32,
    /// Limit of `Pm1` (paper: 0.13).
    pub varphi: f32,
    /// Mutation probability of the best (paper: 0.01).
    pub pm2: f32,
}

impl Operators for Taga {
    const PAPER: Self = Self { phi: 0.8, pc2: 0.8, varphi: 0.13, pm2: 0.01 };

    fn constants(&self) -> [f32; 4] {
        [self.phi, self.pc2, self.varphi, self.pm2]
    }

    fn curves(&self, lg_generation: f32) -> [Curve; 2] {
        let pc1 = 1.0 / (2.0 + lg_generation) + self.phi;
        let pm1 = -0.1 / (2.0 + 0.8 * lg_generation) + self.varphi;
        [Curve { below: pc1, average: pc1, best: self.pc2 }, Curve { below: pm1, average: pm1, best: self.pm2 }]
    }

    /// `(p1 + p2)/2 - (p1 - p2)/2 sin(pi/2 t)`: it starts half-way at the average.
    fn descend(average: f32, best: f32, t: f32) -> f32 {
        0.5 * (average + best) - 0.5 * (average - best) * sin_half_pi(t)
    }
}

/// `p` clamped to `[0, 1]`; NaN gives 0. Out of line: the probability's two clamps share it (flash).
#[inline(never)]
pub(super) fn unit_interval(p: f32) -> f32 {
    if !(p > 0.0) {
        0.0
    } else if p > 1.0 {
        1.0
    } else {
        p
    }
}

/// `sin(pi/2 t)` for `t` in `[0, 1]`: its Taylor series to `t^9`, in `f32` (error below 7e-6;
/// `libm::sinf` works in `f64`, which a Cortex-M4F computes in software).
fn sin_half_pi(t: f32) -> f32 {
    const C: [f32; 5] = [core::f32::consts::FRAC_PI_2, -0.645_964_1, 0.079_692_63, -0.004_681_754, 0.000_160_441_2];
    let t2 = t * t;
    t * (C[0] + t2 * (C[1] + t2 * (C[2] + t2 * (C[3] + t2 * C[4]))))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sine_polynomial_matches_libm_on_the_unit_interval() {
        for i in 0..=1000 {
            let t = i as f32 / 1000.0;
            let exact = libm::sinf(core::f32::consts::FRAC_PI_2 * t);
            assert!((sin_half_pi(t) - exact).abs() < 7e-6, "t = {t}");
        }
    }

    #[test]
    fn taga_probabilities_are_clamped_and_follow_the_paper() {
        let stats = FitnessStats { max: -1.0, avg: -3.0, lg_generation: 0.0 };
        let taga = Taga::PAPER;
        // Below average: Pc1 = 1/(2 + lg 1) + 0.8 = 1.3, clamped to 1; Pm1 = -0.1/2 + 0.13 = 0.08.
        assert_eq!(taga.crossover_probability(-5.0, &stats), 1.0);
        assert!((taga.mutation_probability(-5.0, &stats) - 0.08).abs() < 1e-6);
        // The best: Pc2 and Pm2.
        assert!((taga.crossover_probability(-1.0, &stats) - 0.8).abs() < 1e-6);
        assert!((taga.mutation_probability(-1.0, &stats) - 0.01).abs() < 1e-6);
        // Half-way between at the average: (Pm1 + Pm2)/2.
        assert!((taga.mutation_probability(-3.0, &stats) - 0.045).abs() < 1e-6);
        // Pm1 grows towards varphi: -0.1/(2 + 0.8 lg 100) + 0.13 = 0.1023.
        let late = FitnessStats { lg_generation: 2.0, ..stats };
        assert!((taga.mutation_probability(-5.0, &late) - (0.13 - 0.1 / 3.6)).abs() < 1e-6);
    }

    #[test]
    fn aga_and_laga_follow_the_paper() {
        let stats = FitnessStats { max: -1.0, avg: -3.0, lg_generation: 1.0 };
        // AGA as printed: the best gets nothing, half-way gets half of k1 / k2, below average k3 / k4.
        assert_eq!(Aga::PAPER.crossover_probability(-1.0, &stats), 0.0);
        assert_eq!(Aga::PAPER.mutation_probability(-1.0, &stats), 0.0);
        assert!((Aga::PAPER.crossover_probability(-2.0, &stats) - 0.4).abs() < 1e-6);
        assert!((Aga::PAPER.crossover_probability(-4.0, &stats) - 0.05).abs() < 1e-6);
        assert!((Aga::PAPER.mutation_probability(-4.0, &stats) - 0.03).abs() < 1e-6);
        // LAGA: crossover 0.8 throughout, mutation linear from 0.05 to 0.03.
        assert!((Laga::PAPER.crossover_probability(-2.0, &stats) - 0.8).abs() < 1e-6);
        assert!((Laga::PAPER.mutation_probability(-2.0, &stats) - 0.04).abs() < 1e-6);
        assert!((Laga::PAPER.mutation_probability(-1.0, &stats) - 0.03).abs() < 1e-6);
    }

    #[test]
    fn equal_fitness_counts_as_all_best() {
        let flat = FitnessStats { max: -2.0, avg: -2.0, lg_generation: 0.0 };
        assert_eq!(flat.above_average(-2.0), Some(1.0));
        assert_eq!(flat.above_average(-2.5), None);
    }
}
