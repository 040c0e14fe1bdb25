//! A fixed-size, real-coded adaptive genetic algorithm with the paper's three operator policies.
//!
//! - **Problem**: any [`CostFunction`] (smaller is better) over a [`SearchBox`].
//! - **Solver**: [`GaConfig`] (operator policy, elitism, termination) and [`Ga`] (the state).
//! - **Fitness transform**: `f = -cost`. The adaptive formulas use `(f - f_avg) / (f_max - f_avg)`, which
//!   is invariant to affine transforms of `f` but not to e.g. `1 / (1 + cost)`; with `-cost` the policies
//!   see the cost differences as they are.
//! - **Operators** (choices the paper leaves open): binary tournament selection; BLX-alpha blend
//!   crossover (alpha = 0.5) on parent pairs with probability `Pc`; per-gene mutation with probability
//!   `Pm`, half of the time a heavy-tailed Cauchy step (scale 0.1 of the box width: escapes local
//!   minima), half a triangular step 8 population standard deviations of that gene wide (never below
//!   `mutation_floor` of the box width: refines); steps are reflected into the box. A child that
//!   left crossover and mutation as an exact copy of its parent gets one gene mutated (duplicate
//!   avoidance: without it the population fills with clones of a local optimum). `elites` best are
//!   kept unchanged.
//!
//! Measured on the paper's 2-D Rastrigin (population 40, 100 generations, 200 seeds; `cargo test
//! --release --test ga_rastrigin -- --nocapture`): the duplicate rule and the Cauchy steps raise
//! TAGA's success (best < 1e-3) from 129/200 (local steps only) to 200/200. The local step width (8
//! standard deviations) was chosen on the paper's 24-position calibration (`accelcal paper`): of 1,
//! 2, 3, 5 and 8 it converged fastest there and kept 200/200 on Rastrigin.
//!
//! ```
//! use accelcal::ga::{Ga, GaConfig, SearchBox, rastrigin};
//! use rand_xoshiro::Xoshiro128PlusPlus;
//! use rand_core::SeedableRng;
//! let bounds = SearchBox::new([-5.12; 2], [5.12; 2]).unwrap();
//! let config = GaConfig { max_generations: 150, ..GaConfig::DEFAULT };
//! let mut ga: Ga<_, 40, 2> = Ga::new(config, bounds, Xoshiro128PlusPlus::seed_from_u64(1), &rastrigin).unwrap();
//! let report = ga.run(&rastrigin);
//! assert!(report.cost < 1e-2);
//! ```

use rand_core::Rng;

/// Something to minimise over `DIM` real genes.
pub trait CostFunction<const DIM: usize> {
    /// The cost of `x` (smaller is better). Non-finite values are treated as the worst possible.
    fn cost(&self, x: &[f32; DIM]) -> f32;
}

impl<F: Fn(&[f32; DIM]) -> f32, const DIM: usize> CostFunction<DIM> for F {
    fn cost(&self, x: &[f32; DIM]) -> f32 {
        self(x)
    }
}

/// The paper's multimodal test function: Rastrigin, `20 + sum(x_i^2 - 10 cos(2 pi x_i))` in 2-D.
pub fn rastrigin(x: &[f32; 2]) -> f32 {
    let mut s = 20.0;
    for &v in x {
        s += v * v - 10.0 * libm::cosf(2.0 * core::f32::consts::PI * v);
    }
    s
}

/// Cost given to non-finite evaluations: finite, so population averages stay finite.
const WORST_COST: f32 = 1.0e30;
/// Scale of the heavy-tailed (Cauchy) mutation step, as a fraction of the box width.
const CAUCHY_SCALE: f32 = 0.1;
/// Width of the local mutation step in population standard deviations of the gene.
const LOCAL_STEP: f32 = 8.0;

/// Why a GA cannot be set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum GaError {
    /// Interval `dim` is empty, inverted or not finite (`lower >= upper`).
    InvalidInterval {
        /// The gene index.
        dim: u8,
    },
    /// `elites` must leave at least two places for offspring.
    TooManyElites,
    /// A probability constant of the operator policy is not finite.
    InvalidOperators,
}

impl core::fmt::Display for GaError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::InvalidInterval { dim } => write!(f, "search interval {dim} is empty, inverted or not finite"),
            Self::TooManyElites => f.write_str("elites leave fewer than two places for offspring"),
            Self::InvalidOperators => f.write_str("an operator constant is not finite"),
        }
    }
}

impl core::error::Error for GaError {}

/// The search box: gene `i` lives in `[lower[i], upper[i]]`.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SearchBox<const DIM: usize> {
    lower: [f32; DIM],
    upper: [f32; DIM],
}

impl<const DIM: usize> SearchBox<DIM> {
    /// A box; every interval must be finite with `lower < upper`.
    pub fn new(lower: [f32; DIM], upper: [f32; DIM]) -> Result<Self, GaError> {
        for i in 0..DIM {
            if !(lower[i].is_finite() && upper[i].is_finite() && lower[i] < upper[i]) {
                return Err(GaError::InvalidInterval { dim: i as u8 });
            }
        }
        Ok(Self { lower, upper })
    }

    /// Lower bounds.
    pub fn lower(&self) -> &[f32; DIM] {
        &self.lower
    }

    /// Upper bounds.
    pub fn upper(&self) -> &[f32; DIM] {
        &self.upper
    }

    /// Reflects `v` at the bounds of gene `i` and clamps what is still outside.
    #[inline(always)]
    fn reflect(&self, i: usize, v: f32) -> f32 {
        let (lo, hi) = (self.lower[i], self.upper[i]);
        let r = if v < lo {
            2.0 * lo - v
        } else if v > hi {
            2.0 * hi - v
        } else {
            v
        };
        // Comparisons, not `clamp` (which asserts `lo <= hi` and drags in a panic path) nor `min`/`max`
        // (library calls on a Cortex-M4).
        if r < lo {
            lo
        } else if r > hi {
            hi
        } else {
            r
        }
    }
}

/// The adaptive crossover / mutation policy (fitness `f = -cost`, larger is better).
///
/// All probabilities are clamped to `[0, 1]`: TAGA's `Pc1 = 1/(2 + lg N) + phi` exceeds 1 for
/// `N < 1000` with the paper's `phi = 0.8`, so its crossover is certain early on.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Operators {
    /// Srinivas & Patnaik: `Pc = k1 (f_max - f') / (f_max - f_avg)` if `f' >= f_avg` else `k3`;
    /// `Pm = k2 (f_max - f) / (f_max - f_avg)` if `f >= f_avg` else `k4`. As printed, the best
    /// individual gets `Pc = Pm = 0`: once clones of it fill the population the search freezes.
    Aga {
        /// Crossover factor for above-average pairs (paper: 0.8).
        k1: f32,
        /// Mutation factor for above-average individuals (paper: 0.8).
        k2: f32,
        /// Crossover probability below average (paper: 0.05).
        k3: f32,
        /// Mutation probability below average (paper: 0.03).
        k4: f32,
    },
    /// Linear adaptive: `Pc = Pc1 - (Pc1 - Pc2)(f' - f_avg)/(f_max - f_avg)` if `f' >= f_avg` else `Pc1`,
    /// the same form for `Pm`. The paper prints `Pc1 = Pc2 = 0.8`, so its crossover is not adaptive.
    Laga {
        /// Crossover probability at and below average (paper: 0.8).
        pc1: f32,
        /// Crossover probability of the best (paper: 0.8).
        pc2: f32,
        /// Mutation probability at and below average (paper: 0.05).
        pm1: f32,
        /// Mutation probability of the best (paper: 0.03).
        pm2: f32,
    },
    /// The paper's TAGA, eqs. (8)-(9): sinusoidal between `Pc1(N)` and `Pc2`, with
    /// `Pc1 = 1/(2 + lg N) + phi` and `Pm1 = -0.1/(2 + 0.8 lg N) + varphi`, `N` the generation (from 1).
    Taga {
        /// Limit of `Pc1` (paper: 0.8).
        phi: f32,
        /// Crossover probability of the best (paper: 0.8).
        pc2: f32,
        /// Limit of `Pm1` (paper: 0.13).
        varphi: f32,
        /// Mutation probability of the best (paper: 0.01).
        pm2: f32,
    },
}

impl Operators {
    /// AGA with the paper's constants.
    pub const AGA_PAPER: Self = Self::Aga { k1: 0.8, k2: 0.8, k3: 0.05, k4: 0.03 };
    /// LAGA ("IAGA" in the paper) with the paper's constants.
    pub const LAGA_PAPER: Self = Self::Laga { pc1: 0.8, pc2: 0.8, pm1: 0.05, pm2: 0.03 };
    /// TAGA with the paper's constants.
    pub const TAGA_PAPER: Self = Self::Taga { phi: 0.8, pc2: 0.8, varphi: 0.13, pm2: 0.01 };

    fn constants(&self) -> [f32; 4] {
        match *self {
            Self::Aga { k1, k2, k3, k4 } => [k1, k2, k3, k4],
            Self::Laga { pc1, pc2, pm1, pm2 } => [pc1, pc2, pm1, pm2],
            Self::Taga { phi, pc2, varphi, pm2 } => [phi, pc2, varphi, pm2],
        }
    }

    /// Crossover probability for a pair whose better parent has fitness `f_better`.
    pub fn crossover_probability(&self, f_better: f32, stats: &FitnessStats) -> f32 {
        let above = stats.above_average(f_better);
        let p = match *self {
            Self::Aga { k1, k3, .. } => above.map_or(k3, |t| k1 * (1.0 - t)),
            Self::Laga { pc1, pc2, .. } => above.map_or(pc1, |t| pc1 - (pc1 - pc2) * t),
            Self::Taga { phi, pc2, .. } => {
                let pc1 = 1.0 / (2.0 + stats.lg_generation) + phi;
                above.map_or(pc1, |t| sine_blend(pc1, pc2, t))
            }
        };
        unit_interval(p)
    }

    /// Per-gene mutation probability for an individual of fitness `f`.
    pub fn mutation_probability(&self, f: f32, stats: &FitnessStats) -> f32 {
        let above = stats.above_average(f);
        let p = match *self {
            Self::Aga { k2, k4, .. } => above.map_or(k4, |t| k2 * (1.0 - t)),
            Self::Laga { pm1, pm2, .. } => above.map_or(pm1, |t| pm1 - (pm1 - pm2) * t),
            Self::Taga { varphi, pm2, .. } => {
                let pm1 = -0.1 / (2.0 + 0.8 * stats.lg_generation) + varphi;
                above.map_or(pm1, |t| sine_blend(pm1, pm2, t))
            }
        };
        unit_interval(p)
    }
}

impl Default for Operators {
    fn default() -> Self {
        Self::TAGA_PAPER
    }
}

/// `p` clamped to `[0, 1]`; NaN gives 0.
fn unit_interval(p: f32) -> f32 {
    if !(p > 0.0) {
        0.0
    } else if p > 1.0 {
        1.0
    } else {
        p
    }
}

/// `(p1 + p2)/2 - (p1 - p2)/2 sin(pi/2 t)`.
fn sine_blend(p1: f32, p2: f32, t: f32) -> f32 {
    0.5 * (p1 + p2) - 0.5 * (p1 - p2) * sin_half_pi(t)
}

/// `sin(pi/2 t)` for `t` in `[0, 1]`: its Taylor series to `t^9`, in `f32` (error below 7e-6;
/// `libm::sinf` works in `f64`, which a Cortex-M4F computes in software).
fn sin_half_pi(t: f32) -> f32 {
    const C: [f32; 5] = [core::f32::consts::FRAC_PI_2, -0.645_964_1, 0.079_692_63, -0.004_681_754, 0.000_160_441_2];
    let t2 = t * t;
    t * (C[0] + t2 * (C[1] + t2 * (C[2] + t2 * (C[3] + t2 * C[4]))))
}

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

/// Solver settings. Every field is documented with its default ([`GaConfig::DEFAULT`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GaConfig {
    /// Operator policy. Defaults to [`Operators::TAGA_PAPER`].
    pub operators: Operators,
    /// Best individuals copied unchanged into the next generation. Defaults to 2.
    pub elites: usize,
    /// Stop after this many generations. Defaults to 100.
    pub max_generations: u32,
    /// Stop once the best cost is at or below this. Defaults to `f32::NEG_INFINITY` (off).
    pub target_cost: f32,
    /// Stop after this many generations without a relative improvement of the best cost by more than
    /// `1e-6`. Defaults to 0 (off).
    pub stall_generations: u32,
    /// BLX-alpha crossover extension. Defaults to 0.5.
    pub blend_alpha: f32,
    /// Smallest mutation step width as a fraction of the box width. Defaults to 1e-6.
    pub mutation_floor: f32,
    /// Fraction of mutations that take a heavy-tailed (Cauchy, scale 0.1 box width) step for
    /// exploration; the rest take local steps of the population's spread. Defaults to 0.5.
    pub global_mutation: f32,
}

impl GaConfig {
    /// The documented defaults.
    pub const DEFAULT: Self = Self {
        operators: Operators::TAGA_PAPER,
        elites: 2,
        max_generations: 100,
        target_cost: f32::NEG_INFINITY,
        stall_generations: 0,
        blend_alpha: 0.5,
        mutation_floor: 1e-6,
        global_mutation: 0.5,
    };
}

impl Default for GaConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why [`Ga::run`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Termination {
    /// `max_generations` reached.
    MaxGenerations,
    /// `target_cost` reached.
    TargetReached,
    /// No improvement for `stall_generations`.
    Stalled,
}

/// What a GA run found.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GaReport<const DIM: usize> {
    /// The best genes.
    pub best: [f32; DIM],
    /// Their cost.
    pub cost: f32,
    /// Generations run.
    pub generations: u32,
    /// Cost function evaluations.
    pub evaluations: u32,
    /// Why it stopped.
    pub termination: Termination,
}

/// The GA state: a population of `POP` individuals of `DIM` genes, and the caller's seeded RNG `R`.
pub struct Ga<R, const POP: usize, const DIM: usize> {
    config: GaConfig,
    bounds: SearchBox<DIM>,
    rng: R,
    population: [[f32; DIM]; POP],
    costs: [f32; POP],
    offspring: [[f32; DIM]; POP],
    generation: u32,
    evaluations: u32,
    best_index: usize,
    stall: u32,
}

impl<R: Rng, const POP: usize, const DIM: usize> Ga<R, POP, DIM> {
    const VALID: () = {
        assert!(POP >= 4, "a GA population needs at least 4 individuals");
        assert!(POP <= 1 << 16, "a GA population has at most 65536 individuals (parents are indexed in 16 bits)");
        assert!(DIM >= 1, "a GA needs at least one gene");
    };

    /// A population drawn uniformly from `bounds` and evaluated (generation 0).
    pub fn new(
        config: GaConfig,
        bounds: SearchBox<DIM>,
        rng: R,
        cost: &impl CostFunction<DIM>,
    ) -> Result<Self, GaError> {
        let mut ga = Self::empty(config, bounds, rng);
        ga.initialize(cost)?;
        Ok(ga)
    }

    /// A GA whose population is not drawn yet: call [`Ga::initialize`] before [`Ga::step`]. Built in
    /// place by its caller (or in a `static`), so the `2 POP DIM` floats of state are never moved.
    pub const fn empty(config: GaConfig, bounds: SearchBox<DIM>, rng: R) -> Self {
        let () = Self::VALID;
        Self {
            config,
            bounds,
            rng,
            population: [[0.0; DIM]; POP],
            costs: [0.0; POP],
            offspring: [[0.0; DIM]; POP],
            generation: 0,
            evaluations: 0,
            best_index: 0,
            stall: 0,
        }
    }

    /// Checks the configuration, draws the population uniformly from the box and evaluates it
    /// (generation 0). On an error nothing is drawn.
    pub fn initialize(&mut self, cost: &impl CostFunction<DIM>) -> Result<(), GaError> {
        let config = &self.config;
        if config.elites + 2 > POP {
            return Err(GaError::TooManyElites);
        }
        if config.operators.constants().iter().any(|c| !c.is_finite())
            || !config.blend_alpha.is_finite()
            || !config.mutation_floor.is_finite()
            || !(0.0..=1.0).contains(&config.global_mutation)
        {
            return Err(GaError::InvalidOperators);
        }
        self.generation = 0;
        self.evaluations = 0;
        self.stall = 0;
        for i in 0..POP {
            for d in 0..DIM {
                let u = self.uniform();
                self.population[i][d] = self.bounds.lower[d] + u * (self.bounds.upper[d] - self.bounds.lower[d]);
            }
            self.costs[i] = self.evaluate(cost, i);
        }
        self.best_index = argmin(&self.costs);
        Ok(())
    }

    /// Replaces the worst individual by `x` (clamped into the box), e.g. a prior estimate.
    pub fn inject(&mut self, x: &[f32; DIM], cost: &impl CostFunction<DIM>) {
        let worst = argmax(&self.costs);
        if worst >= POP {
            // Unreachable (argmax returns an index of `costs`); lets the optimiser drop the bounds checks
            // below when argmax is not inlined (opt-level "s").
            return;
        }
        for d in 0..DIM {
            self.population[worst][d] = self.bounds.reflect(d, x[d]);
        }
        self.costs[worst] = self.evaluate(cost, worst);
        self.best_index = argmin(&self.costs);
    }

    fn evaluate(&mut self, cost: &impl CostFunction<DIM>, i: usize) -> f32 {
        self.evaluations = self.evaluations.saturating_add(1);
        let c = self.population.get(i).map_or(WORST_COST, |x| cost.cost(x));
        if c.is_finite() && c < WORST_COST { c } else { WORST_COST }
    }

    /// Uniform in `[0, 1)`.
    fn uniform(&mut self) -> f32 {
        (self.rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    /// Two uniform draws in `[0, 1)` of 16-bit resolution from one 32-bit output (the hot loops need
    /// many; 1/65536 of a crossover interval or of the population is resolution enough).
    fn two_uniforms(&mut self) -> (f32, f32) {
        let r = self.rng.next_u32();
        let scale = 1.0 / 65_536.0;
        ((r & 0xFFFF) as f32 * scale, (r >> 16) as f32 * scale)
    }

    /// Binary tournament: the better of two individuals drawn at random. Inlined: the caller then sees
    /// that the index is below `POP` and indexes without bounds checks.
    #[inline(always)]
    fn tournament(&mut self) -> usize {
        let r = self.rng.next_u32();
        let a = (((r & 0xFFFF) as usize) * POP) >> 16;
        let b = (((r >> 16) as usize) * POP) >> 16;
        match (self.costs.get(a), self.costs.get(b)) {
            (Some(ca), Some(cb)) if cb < ca => b,
            _ => a,
        }
    }

    /// Fitness statistics of the current population (`f = -cost`), for producing the next generation.
    pub fn fitness_stats(&self) -> FitnessStats {
        let sum: f32 = self.costs.iter().sum();
        let next = self.generation.saturating_add(1);
        FitnessStats { max: -self.best_cost(), avg: -(sum / POP as f32), lg_generation: libm::log10f(next as f32) }
    }

    /// Runs one generation: elitism, selection, crossover, mutation, evaluation.
    pub fn step(&mut self, cost: &impl CostFunction<DIM>) {
        let stats = self.fitness_stats();
        let generation = self.generation + 1;
        let spread = self.gene_spread();
        let previous_best = self.best_cost();

        // Elites: repeatedly take the best not yet taken (POP is small; no sort, no allocation).
        let mut taken = [false; POP];
        // Per slot: the parent's fitness for a child, the cost for an elite (kept across the evaluation).
        let mut parent_fitness = [0.0f32; POP];
        let elites = self.config.elites;
        for e in 0..elites {
            let mut best = usize::MAX;
            for i in 0..POP {
                if !taken[i] && (best == usize::MAX || self.costs[i] < self.costs[best]) {
                    best = i;
                }
            }
            if let (Some(flag), Some(slot), Some(cost), Some(genes)) =
                (taken.get_mut(best), self.offspring.get_mut(e), parent_fitness.get_mut(e), self.population.get(best))
            {
                *flag = true;
                // `copy_from_slice` is a non-overlapping copy; an assignment here linked `memmove` (1.5 KB).
                slot.copy_from_slice(genes);
                *cost = self.costs[best];
            }
        }

        let mut parent_index = [0u16; POP];
        let mut slot = elites;
        while slot < POP {
            let (a, b) = (self.tournament(), self.tournament());
            let (fa, fb) = (-self.costs[a], -self.costs[b]);
            let pc = self.config.operators.crossover_probability(if fa >= fb { fa } else { fb }, &stats);
            let (mut c1, mut c2) = (self.population[a], self.population[b]);
            if self.uniform() < pc {
                self.blend(&mut c1, &mut c2);
            }
            for (child, f, p) in [(c1, fa, a), (c2, fb, b)] {
                if slot < POP {
                    self.offspring[slot] = child;
                    parent_fitness[slot] = f;
                    parent_index[slot] = p as u16;
                    slot += 1;
                }
            }
        }
        for i in elites..POP {
            let pm = self.config.operators.mutation_probability(parent_fitness[i], &stats);
            let mut mutated = false;
            for d in 0..DIM {
                if self.uniform() < pm {
                    self.mutate(i, d, &spread);
                    mutated = true;
                }
            }
            if !mutated && self.population.get(usize::from(parent_index[i])) == Some(&self.offspring[i]) {
                let d = ((self.rng.next_u32() as u64 * DIM as u64) >> 32) as usize;
                self.mutate(i, d, &spread);
            }
        }

        // A copy, not a swap: every offspring slot is rewritten before it is read in the next generation,
        // and a swap of two large arrays links a 1.5 KB `memmove`.
        self.population = self.offspring;
        // Elites keep their costs; only offspring are evaluated.
        for i in 0..POP {
            self.costs[i] = if i < elites { parent_fitness[i] } else { self.evaluate(cost, i) };
        }
        self.best_index = argmin(&self.costs);
        self.generation = generation;
        let best = self.best_cost();
        if best < previous_best - 1e-6 * previous_best.abs() {
            self.stall = 0;
        } else {
            self.stall = self.stall.saturating_add(1);
        }
    }

    /// BLX-alpha: each child gene uniform in the parents' interval extended by alpha on both sides.
    fn blend(&mut self, c1: &mut [f32; DIM], c2: &mut [f32; DIM]) {
        let alpha = self.config.blend_alpha;
        for d in 0..DIM {
            let (lo, hi) = if c1[d] <= c2[d] { (c1[d], c2[d]) } else { (c2[d], c1[d]) };
            let ext = alpha * (hi - lo);
            let (a, b) = (lo - ext, hi + ext);
            let (u1, u2) = self.two_uniforms();
            c1[d] = self.bounds.reflect(d, a + u1 * (b - a));
            c2[d] = self.bounds.reflect(d, a + u2 * (b - a));
        }
    }

    fn mutate(&mut self, i: usize, d: usize, spread: &[f32; DIM]) {
        let (Some(&gene), Some(&lo), Some(&hi), Some(&width)) = (
            self.offspring.get(i).and_then(|x| x.get(d)),
            self.bounds.lower.get(d),
            self.bounds.upper.get(d),
            spread.get(d),
        ) else {
            return;
        };
        let step = if self.uniform() < self.config.global_mutation {
            CAUCHY_SCALE * (hi - lo) * self.cauchy()
        } else {
            self.triangular() * width
        };
        let mutated = self.bounds.reflect(d, gene + step);
        if let Some(g) = self.offspring.get_mut(i).and_then(|x| x.get_mut(d)) {
            *g = mutated;
        }
    }

    /// Standard Cauchy: the ratio of the coordinates of a point uniform in the unit disc (no
    /// trigonometry; a few tries at most, 0 if all eight fall outside the disc).
    fn cauchy(&mut self) -> f32 {
        for _ in 0..8 {
            let (a, b) = (2.0 * self.uniform() - 1.0, 2.0 * self.uniform() - 1.0);
            if a * a + b * b <= 1.0 && b != 0.0 {
                return a / b;
            }
        }
        0.0
    }

    /// Triangular on `[-1, 1]`.
    fn triangular(&mut self) -> f32 {
        self.uniform() + self.uniform() - 1.0
    }

    /// Per-gene local mutation width: `LOCAL_STEP` population standard deviations of that gene, at least
    /// `mutation_floor` of the box width.
    fn gene_spread(&self) -> [f32; DIM] {
        let mut out = [0.0; DIM];
        for d in 0..DIM {
            let mean = self.population.iter().map(|x| x[d]).sum::<f32>() / POP as f32;
            let var = self.population.iter().map(|x| (x[d] - mean) * (x[d] - mean)).sum::<f32>() / POP as f32;
            let floor = self.config.mutation_floor * (self.bounds.upper[d] - self.bounds.lower[d]);
            let width = LOCAL_STEP * crate::linalg::sqrt_f32(var);
            out[d] = if width > floor { width } else { floor };
        }
        out
    }

    /// Runs generations until a termination criterion holds.
    pub fn run(&mut self, cost: &impl CostFunction<DIM>) -> GaReport<DIM> {
        loop {
            if let Some(termination) = self.termination() {
                return self.report(termination);
            }
            self.step(cost);
        }
    }

    /// The criterion that holds now, if any.
    pub fn termination(&self) -> Option<Termination> {
        if self.best_cost() <= self.config.target_cost {
            Some(Termination::TargetReached)
        } else if self.config.stall_generations > 0 && self.stall >= self.config.stall_generations {
            Some(Termination::Stalled)
        } else if self.generation >= self.config.max_generations {
            Some(Termination::MaxGenerations)
        } else {
            None
        }
    }

    fn report(&self, termination: Termination) -> GaReport<DIM> {
        GaReport {
            best: *self.best(),
            cost: self.best_cost(),
            generations: self.generation,
            evaluations: self.evaluations,
            termination,
        }
    }

    /// The best individual so far.
    pub fn best(&self) -> &[f32; DIM] {
        // `best_index` always comes from `argmin` over the population.
        self.population.get(self.best_index).unwrap_or(&self.population[0])
    }

    /// Cost of [`Ga::best`].
    pub fn best_cost(&self) -> f32 {
        self.costs.get(self.best_index).copied().unwrap_or(WORST_COST)
    }

    /// Mean cost of the population.
    pub fn mean_cost(&self) -> f32 {
        self.costs.iter().sum::<f32>() / POP as f32
    }

    /// Generations run so far.
    pub fn generation(&self) -> u32 {
        self.generation
    }

    /// Cost evaluations so far.
    pub fn evaluations(&self) -> u32 {
        self.evaluations
    }

    /// The current population.
    pub fn population(&self) -> &[[f32; DIM]; POP] {
        &self.population
    }

    /// Gives the RNG back.
    pub fn into_rng(self) -> R {
        self.rng
    }
}

/// Index of the first smallest value (0 for an empty slice); NaN never wins.
fn argmin(v: &[f32]) -> usize {
    let (mut best, mut best_value) = (0, v.first().copied().unwrap_or(0.0));
    for (i, &c) in v.iter().enumerate() {
        if c < best_value {
            (best, best_value) = (i, c);
        }
    }
    best
}

/// Index of the first largest value (0 for an empty slice); NaN never wins.
fn argmax(v: &[f32]) -> usize {
    let (mut worst, mut worst_value) = (0, v.first().copied().unwrap_or(0.0));
    for (i, &c) in v.iter().enumerate() {
        if c > worst_value {
            (worst, worst_value) = (i, c);
        }
    }
    worst
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
        let taga = Operators::TAGA_PAPER;
        // Below average: Pc1 = 1/(2 + lg 1) + 0.8 = 1.3, clamped to 1; Pm1 = -0.1/2 + 0.13 = 0.08.
        assert_eq!(taga.crossover_probability(-5.0, &stats), 1.0);
        assert!((taga.mutation_probability(-5.0, &stats) - 0.08).abs() < 1e-6);
        // The best: Pc2 and Pm2.
        assert!((taga.crossover_probability(-1.0, &stats) - 0.8).abs() < 1e-6);
        assert!((taga.mutation_probability(-1.0, &stats) - 0.01).abs() < 1e-6);
        // AGA as printed: the best gets nothing.
        assert_eq!(Operators::AGA_PAPER.crossover_probability(-1.0, &stats), 0.0);
        assert_eq!(Operators::AGA_PAPER.mutation_probability(-1.0, &stats), 0.0);
    }
}
