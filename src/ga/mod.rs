//! A fixed-size, real-coded adaptive genetic algorithm with the paper's three operator policies.
//!
//! - **Problem**: any [`CostFunction`] (smaller is better) over a [`SearchBox`].
//! - **Solver**: [`GaConfig`] (operator policy, elitism, termination) and [`Ga`] (the state).
//! - **Operator policy**: a type ([`Taga`], the default; [`Aga`], [`Laga`]: [`Operators`]), so a firmware
//!   links the one it runs.
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
//! use accelcal::ga::{Aga, Ga, GaConfig, Operators, SearchBox, rastrigin};
//! use rand_xoshiro::Xoshiro128PlusPlus;
//! use rand_core::SeedableRng;
//! let bounds = SearchBox::new([-5.12; 2], [5.12; 2]).unwrap();
//! let config = GaConfig { max_generations: 150, ..GaConfig::DEFAULT }; // TAGA
//! let mut ga: Ga<_, 40, 2> = Ga::new(config, bounds, Xoshiro128PlusPlus::seed_from_u64(1), &rastrigin).unwrap();
//! assert!(ga.run(&rastrigin).cost < 1e-2);
//! let aga = GaConfig { operators: Aga::PAPER, ..GaConfig::DEFAULT };
//! let mut ga = Ga::<_, 40, 2, Aga>::new(aga, bounds, Xoshiro128PlusPlus::seed_from_u64(1), &rastrigin).unwrap();
//! assert!(ga.run(&rastrigin).cost.is_finite());
//! ```

mod operators;

use rand_core::Rng;

pub use operators::{Aga, Curve, FitnessStats, Laga, Operators, Taga};

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
    /// Interval `dim` is empty, inverted or not finite (`lower >= upper`, or an infinite or NaN width).
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
    /// A box; every interval must have `lower < upper` and a finite width.
    pub fn new(lower: [f32; DIM], upper: [f32; DIM]) -> Result<Self, GaError> {
        Self { lower, upper }.checked()
    }

    /// The box `center - half ..= center + half`, gene by gene (checked as by [`SearchBox::new`]).
    pub fn around(center: &[f32; DIM], half: &[f32; DIM]) -> Result<Self, GaError> {
        let mut out = Self::UNSET;
        out.set_around(center, half)?;
        Ok(out)
    }

    /// A placeholder (every interval empty) for [`Ga::empty`] before [`Ga::set_bounds_around`].
    pub const UNSET: Self = Self { lower: [0.0; DIM], upper: [0.0; DIM] };

    /// [`SearchBox::around`] into `self`, where it stays (a box returned in a `Result` is copied).
    fn set_around(&mut self, center: &[f32; DIM], half: &[f32; DIM]) -> Result<(), GaError> {
        for i in 0..DIM {
            (self.lower[i], self.upper[i]) = (center[i] - half[i], center[i] + half[i]);
            if !valid_width(self.upper[i] - self.lower[i]) {
                return Err(GaError::InvalidInterval { dim: i as u8 });
            }
        }
        Ok(())
    }

    /// `self` if every width `upper - lower` is positive and finite (so no bound is infinite or NaN).
    fn checked(self) -> Result<Self, GaError> {
        for i in 0..DIM {
            if !valid_width(self.upper[i] - self.lower[i]) {
                return Err(GaError::InvalidInterval { dim: i as u8 });
            }
        }
        Ok(self)
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
        reflect(v, self.lower[i], self.upper[i])
    }

    /// `v` clamped into the interval of gene `i`.
    #[inline(always)]
    fn clamp(&self, i: usize, v: f32) -> f32 {
        clamp(v, self.lower[i], self.upper[i])
    }
}

/// A search interval's width is positive and finite (so neither bound is infinite or NaN). `<= MAX`,
/// not `< INFINITY` (the same for every width): two float compares, not the bit tests of a class check.
fn valid_width(width: f32) -> bool {
    width > 0.0 && width <= f32::MAX
}

/// `v` reflected at `lo` and `hi`, then clamped into `[lo, hi]`. Out of line: three callers (flash
/// first; it costs a few % of a generation's cycles, two calls per gene in the crossover loop).
#[inline(never)]
fn reflect(v: f32, lo: f32, hi: f32) -> f32 {
    let r = if v < lo {
        2.0 * lo - v
    } else if v > hi {
        2.0 * hi - v
    } else {
        v
    };
    clamp(r, lo, hi)
}

/// `v` clamped into `[lo, hi]`. Comparisons, not `f32::clamp` (which asserts `lo <= hi` and drags in a
/// panic path) nor `min`/`max` (library calls on a Cortex-M4).
#[inline(always)]
fn clamp(v: f32, lo: f32, hi: f32) -> f32 {
    if v < lo {
        lo
    } else if v > hi {
        hi
    } else {
        v
    }
}

/// Solver settings. Every field is documented with its default ([`GaConfig::DEFAULT`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct GaConfig<O = Taga> {
    /// Operator policy. Defaults to the policy's paper constants ([`Operators::PAPER`]; [`Taga`] unless
    /// another policy type is named).
    pub operators: O,
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

impl<O: Operators> GaConfig<O> {
    /// The documented defaults.
    pub const DEFAULT: Self = Self {
        operators: O::PAPER,
        elites: 2,
        max_generations: 100,
        target_cost: f32::NEG_INFINITY,
        stall_generations: 0,
        blend_alpha: 0.5,
        mutation_floor: 1e-6,
        global_mutation: 0.5,
    };

    /// Checks the settings for a population of `population`.
    pub fn validate(&self, population: usize) -> Result<(), GaError> {
        if self.elites + 2 > population {
            return Err(GaError::TooManyElites);
        }
        let [a, b, c, d] = self.operators.constants();
        let finite = [a, b, c, d, self.blend_alpha, self.mutation_floor].iter().all(|v| v.is_finite());
        if !finite || !(0.0..=1.0).contains(&self.global_mutation) {
            return Err(GaError::InvalidOperators);
        }
        Ok(())
    }
}

impl<O: Operators> Default for GaConfig<O> {
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

/// The GA state: a population of `POP` individuals of `DIM` genes, the caller's seeded RNG `R` and the
/// operator policy `O` ([`Taga`] unless named).
// `repr(C)`, the fields [`Ga::empty`] zeroes before the two it copies: one `memset` call, not three.
#[repr(C)]
pub struct Ga<R, const POP: usize, const DIM: usize, O = Taga> {
    population: [[f32; DIM]; POP],
    costs: [f32; POP],
    offspring: [[f32; DIM]; POP],
    bounds: SearchBox<DIM>,
    generation: u32,
    evaluations: u32,
    best_index: usize,
    stall: u32,
    rng: R,
    config: GaConfig<O>,
}

impl<R: Rng, const POP: usize, const DIM: usize, O: Operators> Ga<R, POP, DIM, O> {
    const VALID: () = {
        assert!(POP >= 4, "a GA population needs at least 4 individuals");
        assert!(POP <= 1 << 16, "a GA population has at most 65536 individuals (parents are indexed in 16 bits)");
        assert!(DIM >= 1, "a GA needs at least one gene");
    };

    /// A population drawn uniformly from `bounds` and evaluated (generation 0).
    pub fn new(
        config: GaConfig<O>,
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
    pub const fn empty(config: GaConfig<O>, bounds: SearchBox<DIM>, rng: R) -> Self {
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

    /// Sets the search box to `center - half ..= center + half` (checked as by [`SearchBox::new`]), in
    /// place: for a GA built by [`Ga::empty`] with [`SearchBox::UNSET`], before [`Ga::initialize`].
    pub fn set_bounds_around(&mut self, center: &[f32; DIM], half: &[f32; DIM]) -> Result<(), GaError> {
        self.bounds.set_around(center, half)
    }

    /// Checks the configuration ([`GaConfig::validate`]), draws the population uniformly from the box
    /// and evaluates it (generation 0). On an error nothing is drawn.
    pub fn initialize(&mut self, cost: &impl CostFunction<DIM>) -> Result<(), GaError> {
        self.draw_population(cost)?;
        self.best_index = argmin(&self.costs);
        Ok(())
    }

    /// [`Ga::initialize`], then [`Ga::inject`] of `x`: the best is found once, after both.
    pub(crate) fn initialize_with(&mut self, x: &[f32; DIM], cost: &impl CostFunction<DIM>) -> Result<(), GaError> {
        self.draw_population(cost)?;
        self.replace_worst(x, cost);
        self.best_index = argmin(&self.costs);
        Ok(())
    }

    /// [`Ga::initialize`] but for the best's index.
    #[inline(always)]
    fn draw_population(&mut self, cost: &impl CostFunction<DIM>) -> Result<(), GaError> {
        self.config.validate(POP)?;
        self.generation = 0;
        self.evaluations = 0;
        self.stall = 0;
        for i in 0..POP {
            for d in 0..DIM {
                let u = uniform(&mut self.rng);
                self.population[i][d] = self.bounds.lower[d] + u * (self.bounds.upper[d] - self.bounds.lower[d]);
            }
            self.costs[i] = Self::evaluate(&mut self.evaluations, cost, &self.population[i]);
        }
        Ok(())
    }

    /// Replaces the worst individual by `x` (clamped into the box), e.g. a prior estimate.
    pub fn inject(&mut self, x: &[f32; DIM], cost: &impl CostFunction<DIM>) {
        self.replace_worst(x, cost);
        self.best_index = argmin(&self.costs);
    }

    /// [`Ga::inject`] but for the best's index.
    #[inline(always)]
    fn replace_worst(&mut self, x: &[f32; DIM], cost: &impl CostFunction<DIM>) {
        let worst = argmax(&self.costs);
        if worst >= POP {
            // Unreachable (argmax returns an index of `costs`); lets the optimiser drop the bounds checks
            // below when argmax is not inlined (opt-level "s").
            return;
        }
        for d in 0..DIM {
            self.population[worst][d] = self.bounds.clamp(d, x[d]);
        }
        self.costs[worst] = Self::evaluate(&mut self.evaluations, cost, &self.population[worst]);
    }

    /// The cost of `x` (an individual), counted in `evaluations`; non-finite costs become [`WORST_COST`].
    /// Out of line: three callers.
    #[inline(never)]
    fn evaluate(evaluations: &mut u32, cost: &impl CostFunction<DIM>, x: &[f32; DIM]) -> f32 {
        *evaluations = evaluations.saturating_add(1);
        let c = cost.cost(x);
        if c.is_finite() && c < WORST_COST { c } else { WORST_COST }
    }

    /// Binary tournament: the better of two individuals drawn at random (an index below `POP`). Out
    /// of line: two calls per pair.
    #[inline(never)]
    fn tournament(&mut self) -> usize {
        let r = draw(&mut self.rng);
        let a = (((r & 0xFFFF) as usize) * POP) >> 16;
        let b = (((r >> 16) as usize) * POP) >> 16;
        match (self.costs.get(a), self.costs.get(b)) {
            (Some(ca), Some(cb)) if cb < ca => b,
            _ => a,
        }
    }

    /// [`Ga::best_cost`] for the generation step: `min` (a compare and a move) spares the bounds check
    /// and the constant of the `get` in [`Ga::best_cost`] (`best_index` is always below `POP`). Not
    /// used by [`Ga::run`], whose loop grew when the check was written this way there.
    fn best_cost_in_step(&self) -> f32 {
        self.costs[self.best_index.min(POP - 1)]
    }

    /// Fitness statistics of the current population (`f = -cost`), for producing the next generation.
    pub fn fitness_stats(&self) -> FitnessStats {
        self.stats()
    }

    /// [`Ga::fitness_stats`], inlined into the step (its one caller there): no call, no result written
    /// to memory and read back.
    #[inline(always)]
    fn stats(&self) -> FitnessStats {
        let sum: f32 = self.costs.iter().sum();
        let next = self.generation.saturating_add(1);
        FitnessStats { max: -self.best_cost_in_step(), avg: -(sum / POP as f32), lg_generation: lg_count(next) }
    }

    /// Runs one generation: elitism, selection, crossover, mutation, evaluation.
    #[inline(never)]
    pub fn step(&mut self, cost: &impl CostFunction<DIM>) {
        let stats = self.stats();
        let [crossover, mutation] = self.config.operators.curves(stats.lg_generation);
        let spread = self.gene_spread();
        let previous_best = self.best_cost_in_step();
        // Per slot: the parent's fitness for a child, the cost for an elite (kept across the evaluation).
        let mut parent_fitness = [0.0f32; POP];
        let mut parent_index = [0u16; POP];
        self.keep_elites(&mut parent_fitness);
        self.breed(&crossover, &stats, &mut parent_fitness, &mut parent_index);
        for i in self.config.elites..POP {
            let pm = O::probability(&mutation, parent_fitness[i], &stats);
            self.mutate_child(i, pm, usize::from(parent_index[i]), &spread);
        }
        // Row by row beside the evaluation (which reads the row), not a swap (a 1.5 KB `memmove`) nor
        // one assignment of the arrays (a `memcpy` call): a row is copied inline. Elites keep their costs;
        // only offspring are evaluated.
        for i in 0..POP {
            self.population[i] = self.offspring[i];
            self.costs[i] = if i < self.config.elites {
                parent_fitness[i]
            } else {
                Self::evaluate(&mut self.evaluations, cost, &self.population[i])
            };
        }
        self.best_index = argmin(&self.costs);
        self.generation += 1;
        let best = self.best_cost_in_step();
        self.stall = if best < previous_best - 1e-6 * previous_best.abs() { 0 } else { self.stall.saturating_add(1) };
    }

    /// Copies the `elites` best into the first offspring slots, in the order of (cost, index) (the
    /// first index on ties; costs are finite: no sort, no copy of the costs), and their costs into
    /// `costs`.
    #[inline(always)]
    fn keep_elites(&mut self, costs: &mut [f32; POP]) {
        let (mut after_cost, mut after_index) = (f32::NEG_INFINITY, usize::MAX);
        // `min`: `elites` is below `POP` already (validated); it spares the bounds checks of `e`.
        for e in 0..self.config.elites.min(POP) {
            let best = next_smallest(&self.costs, after_cost, after_index);
            if let (Some(&cost), Some(genes)) = (self.costs.get(best), self.population.get(best)) {
                // `copy_from_slice`: an assignment of one row to another here linked `memmove` (1.5 KB).
                self.offspring[e].copy_from_slice(genes);
                costs[e] = cost;
                (after_cost, after_index) = (cost, best);
            }
        }
    }

    /// Fills the offspring slots after the elites with tournament-selected pairs, crossed with the
    /// probability of `crossover`; records each child's parent and its fitness. The first child is
    /// bred in its slot; the second beside it, or nowhere when the last slot is taken.
    #[inline(always)]
    fn breed(&mut self, crossover: &Curve, stats: &FitnessStats, fitness: &mut [f32; POP], parent: &mut [u16; POP]) {
        let mut slot = self.config.elites;
        while slot < POP {
            // `min`: the indices are below `POP` already; it spares the bounds checks below.
            let (a, b) = (self.tournament().min(POP - 1), self.tournament().min(POP - 1));
            let (fa, fb) = (-self.costs[a], -self.costs[b]);
            let pc = O::probability(crossover, if fa >= fb { fa } else { fb }, stats);
            // The parents copied into their children's slots; the second child into `spare` (bred for the
            // draws, then dropped) when the last slot is taken. One copy per parent.
            let mut spare;
            let Some((first, rest)) = self.offspring.get_mut(slot..).and_then(|s| s.split_first_mut()) else {
                break;
            };
            let second = match rest.first_mut() {
                Some(second) => second,
                None => {
                    spare = [0.0; DIM];
                    &mut spare
                }
            };
            second.copy_from_slice(&self.population[b]);
            first.copy_from_slice(&self.population[a]);
            if uniform(&mut self.rng) < pc {
                blend(&mut self.rng, &self.bounds, self.config.blend_alpha, first, second);
            }
            (fitness[slot], parent[slot]) = (fa, a as u16);
            if let (Some(f), Some(p)) = (fitness.get_mut(slot + 1), parent.get_mut(slot + 1)) {
                (*f, *p) = (fb, b as u16);
            }
            slot += 2;
        }
    }

    /// Mutates each gene of child `i` with probability `pm`; a child left equal to its parent gets one
    /// gene mutated.
    #[inline(always)]
    fn mutate_child(&mut self, i: usize, pm: f32, parent: usize, spread: &[f32; DIM]) {
        let mut mutated = false;
        for d in 0..DIM {
            if uniform(&mut self.rng) < pm {
                self.mutate(i, d, spread);
                mutated = true;
            }
        }
        if !mutated && self.population.get(parent) == self.offspring.get(i) {
            let d = ((draw(&mut self.rng) as u64 * DIM as u64) >> 32) as usize;
            self.mutate(i, d, spread);
        }
    }

    /// Gene `d` of offspring `i` takes a Cauchy (global) or triangular (local, `spread[d]` wide) step.
    fn mutate(&mut self, i: usize, d: usize, spread: &[f32; DIM]) {
        let (Some(&gene), Some(&lo), Some(&hi), Some(&width)) = (
            self.offspring.get(i).and_then(|x| x.get(d)),
            self.bounds.lower.get(d),
            self.bounds.upper.get(d),
            spread.get(d),
        ) else {
            return;
        };
        let rng = &mut self.rng;
        let step = if uniform(rng) < self.config.global_mutation {
            CAUCHY_SCALE * (hi - lo) * cauchy(rng)
        } else {
            (uniform(rng) + uniform(rng) - 1.0) * width
        };
        let mutated = self.bounds.reflect(d, gene + step);
        if let Some(g) = self.offspring.get_mut(i).and_then(|x| x.get_mut(d)) {
            *g = mutated;
        }
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
                return GaReport {
                    best: *self.best(),
                    cost: self.best_cost(),
                    generations: self.generation,
                    evaluations: self.evaluations,
                    termination,
                };
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

/// BLX-alpha: each child gene uniform in the parents' interval extended by `alpha` on both sides,
/// reflected into `bounds`.
#[inline(always)]
fn blend<R: Rng, const DIM: usize>(
    rng: &mut R,
    bounds: &SearchBox<DIM>,
    alpha: f32,
    c1: &mut [f32; DIM],
    c2: &mut [f32; DIM],
) {
    for d in 0..DIM {
        let (lo, hi) = if c1[d] <= c2[d] { (c1[d], c2[d]) } else { (c2[d], c1[d]) };
        let ext = alpha * (hi - lo);
        let (a, b) = (lo - ext, hi + ext);
        let (u1, u2) = two_uniforms(rng);
        c1[d] = bounds.reflect(d, a + u1 * (b - a));
        c2[d] = bounds.reflect(d, a + u2 * (b - a));
    }
}

/// One 32-bit draw. Out of line: the GA draws in a dozen places, and an inlined generator costs some
/// 40 bytes of flash at each.
#[inline(never)]
fn draw<R: Rng>(rng: &mut R) -> u32 {
    rng.next_u32()
}

/// Uniform in `[0, 1)`. Out of line: eight callers (flash first: in the per-gene mutation loop a call
/// per draw costs a few % of a generation's cycles).
#[inline(never)]
fn uniform<R: Rng>(rng: &mut R) -> f32 {
    to_unit(draw(rng))
}

/// The top 24 bits of `r` as a fraction in `[0, 1)`.
fn to_unit(r: u32) -> f32 {
    (r >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Two uniform draws in `[0, 1)` of 16-bit resolution from one 32-bit output (the hot loops need many;
/// 1/65536 of a crossover interval or of the population is resolution enough).
#[inline(always)]
fn two_uniforms<R: Rng>(rng: &mut R) -> (f32, f32) {
    let r = draw(rng);
    let scale = 1.0 / 65_536.0;
    ((r & 0xFFFF) as f32 * scale, (r >> 16) as f32 * scale)
}

/// Standard Cauchy: the ratio of the coordinates of a point uniform in the unit disc (no trigonometry;
/// a few tries at most, 0 if all eight fall outside the disc).
fn cauchy<R: Rng>(rng: &mut R) -> f32 {
    for _ in 0..8 {
        let (a, b) = (2.0 * uniform(rng) - 1.0, 2.0 * uniform(rng) - 1.0);
        if a * a + b * b <= 1.0 && b != 0.0 {
            return a / b;
        }
    }
    0.0
}

/// `lg n` (base 10) of a count `n >= 1` (0 gives `lg 1 = 0`), to about 1e-7 relative: `ln m = 2 atanh s`
/// with `s = (m - 1)/(m + 1)` for the mantissa `m` in `[sqrt(1/2), sqrt(2))`, four terms (truncation
/// below 3e-8). A third of `libm::log10f`'s code, which special-cases what a count never is. TAGA's
/// probabilities use it only in comparisons with 24-bit uniform draws, where a last-bit difference
/// from `log10f` changes a draw's outcome with probability below 1e-8.
#[inline(always)]
fn lg_count(n: u32) -> f32 {
    const LN_2: f32 = core::f32::consts::LN_2;
    const LOG10_E: f32 = core::f32::consts::LOG10_E;
    // The exponent and mantissa of `n`, the mantissa moved into [sqrt(1/2), sqrt(2)).
    let bits = (if n > 1 { n } else { 1 } as f32).to_bits() + (0x3f80_0000 - 0x3f35_04f3);
    let k = (bits >> 23) as i32 - 0x7f;
    let m = f32::from_bits((bits & 0x007f_ffff) + 0x3f35_04f3);
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    let ln_m = 2.0 * s * (1.0 + z * (1.0 / 3.0 + z * (1.0 / 5.0 + z * (1.0 / 7.0))));
    (k as f32 * LN_2 + ln_m) * LOG10_E
}

/// Index of the first smallest finite value (0 if there is none); NaN never wins.
#[inline(never)]
fn argmin(v: &[f32]) -> usize {
    let i = next_smallest(v, f32::NEG_INFINITY, usize::MAX);
    if i < v.len() { i } else { 0 }
}

/// Index of the smallest finite value after (`after_cost`, `after_index`) in the order of (value,
/// index) (`usize::MAX` when there is none; `(NEG_INFINITY, usize::MAX)` for the first); NaN never wins.
/// Out of line: the elites and `argmin`.
#[inline(never)]
fn next_smallest(v: &[f32], after_cost: f32, after_index: usize) -> usize {
    let (mut best, mut best_value) = (usize::MAX, f32::INFINITY);
    for (i, &c) in v.iter().enumerate() {
        let later = c > after_cost || (c == after_cost && i > after_index);
        if later && c < best_value {
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
    extern crate std;
    use super::*;
    use rand_core::SeedableRng;

    #[test]
    fn elites_are_the_best_in_cost_order_the_first_index_on_ties() {
        // Four cost levels over the box: ties are the rule, so the order among equals is exercised.
        let cost = |x: &[f32; 1]| (x[0] * 2.0).floor().abs();
        let bounds = SearchBox::new([-2.0], [2.0]).unwrap();
        let config = GaConfig { elites: 3, ..GaConfig::DEFAULT };
        let rng = rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(5);
        let mut ga: Ga<_, 10, 1> = Ga::new(config, bounds, rng, &cost).unwrap();
        for _ in 0..20 {
            let (population, costs) = (ga.population, ga.costs);
            let mut order: [usize; 10] = core::array::from_fn(|i| i);
            order.sort_unstable_by(|&a, &b| costs[a].total_cmp(&costs[b]).then(a.cmp(&b)));
            ga.step(&cost);
            for e in 0..3 {
                assert_eq!(ga.population[e], population[order[e]], "elite {e}");
                assert_eq!(ga.costs[e], costs[order[e]], "elite {e}");
            }
        }
    }

    #[test]
    fn a_box_of_the_largest_finite_width_is_valid_and_an_infinite_or_nan_one_is_not() {
        // Width `2 * (MAX / 2) = MAX`: the largest valid one; `2 * MAX` overflows to infinity.
        assert!(SearchBox::around(&[0.0, 1.0], &[f32::MAX / 2.0, 1.0]).is_ok());
        assert_eq!(SearchBox::around(&[0.0, 1.0], &[1.0, f32::MAX]), Err(GaError::InvalidInterval { dim: 1 }));
        assert_eq!(SearchBox::around(&[f32::NAN], &[1.0]), Err(GaError::InvalidInterval { dim: 0 }));
        assert_eq!(SearchBox::around(&[0.0], &[0.0]), Err(GaError::InvalidInterval { dim: 0 }));
        assert_eq!(SearchBox::new([f32::MIN], [f32::MAX]), Err(GaError::InvalidInterval { dim: 0 }));
    }

    #[test]
    fn lg_count_is_within_three_ulps_of_log10_for_every_count_to_a_million() {
        let (mut worst_ulps, mut differ) = (0u32, 0u32);
        for n in 1..=1_000_000u32 {
            let (fast, libm) = (lg_count(n), libm::log10f(n as f32));
            let ulps = fast.to_bits().abs_diff(libm.to_bits());
            worst_ulps = worst_ulps.max(ulps);
            differ += u32::from(ulps > 0);
        }
        std::println!("lg_count: {differ} of 1e6 counts differ from libm::log10f, by {worst_ulps} ulp at most");
        assert!(worst_ulps <= 3, "{worst_ulps} ulp");
        assert_eq!(lg_count(1), 0.0);
        assert_eq!(lg_count(0), 0.0);
        assert!((lg_count(u32::MAX) - 9.632_96).abs() < 1e-5);
    }
}
