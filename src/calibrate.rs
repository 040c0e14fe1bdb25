//! The whole calibration from captured poses: coarse, then the chosen optimiser, then the verdict.
//!
//! ```
//! use accelcal::accumulator::Pose;
//! use accelcal::calibrate::{calibrate, CalibrationConfig, Method};
//! use accelcal::model::Params;
//! use rand_core::SeedableRng;
//! let truth = Params { bias: [0.12; 3], scale: [0.97, 0.98, 0.99], nonorth: [-0.015, 0.01, 0.02] };
//! let g = 9.80665;
//! let dirs = [[1.0f32, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0],
//!     [0.0, 0.0, -1.0], [0.6, 0.8, 0.0], [0.0, 0.6, -0.8], [-0.8, 0.0, 0.6], [0.57735027, 0.57735027, 0.57735027],
//!     [-0.57735027, 0.57735027, -0.57735027], [0.57735027, -0.57735027, -0.57735027]];
//! let poses = dirs.map(|d| Pose::from_mean(truth.invert(d.map(|v| v * g)).unwrap(), 1000));
//! let rng = rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(7);
//! let cal = calibrate::<_, 40, 24>(&poses, &CalibrationConfig::DEFAULT, rng).unwrap();
//! assert!((cal.params.scale[1] - 0.98).abs() < 1e-4);
//! ```

use rand_core::Rng;

use crate::accumulator::Pose;
use crate::coarse::{CoarseError, SearchWidths};
use crate::ellipsoid::OutlierRule;
use crate::frame::{Deviation, Frame, NormPose, objective};
use crate::ga::{Ga, GaConfig, GaError, SearchBox};
pub use crate::init::{Init, InitError, Initial, NormalizedPoses};
use crate::linalg::{Held, larger};
use crate::model::{PARAM_COUNT, Params};
use crate::solve::{
    LmConfig, NewtonConfig, SolveError, SolveTermination, levenberg_marquardt_in_place, newton_holding,
};
use crate::verdict::{PoseSet, Verdict, VerdictBounds, information_in_place, judge_run, parameters_to_hold};

/// The recommended seeded generator for the GA: 32-bit state arithmetic, fast on a Cortex-M4.
#[cfg(feature = "default-rng")]
pub type DefaultRng = rand_xoshiro::Xoshiro128PlusPlus;

/// Which optimiser runs after the initial estimate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Method {
    /// The paper's classical Newton baseline, from the initial estimate.
    Newton,
    /// Levenberg-Marquardt from the initial estimate.
    Lm,
    /// The paper's TAGA alone.
    Taga,
    /// TAGA, then an LM polish from its best.
    #[default]
    TagaLm,
}

impl Method {
    /// Lower-case name as used on the command line (`newton`, `lm`, `taga`, `taga+lm`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Newton => "newton",
            Self::Lm => "lm",
            Self::Taga => "taga",
            Self::TagaLm => "taga+lm",
        }
    }
}

/// How the GA's search intervals are set around the initial estimate.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Intervals {
    /// Fixed half-widths (the paper's way).
    Fixed(SearchWidths),
    /// `sigmas` standard deviations of the initial estimate on each side: the covariance of the
    /// information matrix at the start, inflated by the reduced chi-square of its residuals (so a
    /// rough start gets a wide box, an informative set of poses a tight one); fixed widths when the
    /// covariance cannot be formed.
    Uncertainty {
        /// Standard deviations per side.
        sigmas: f32,
    },
}

impl Intervals {
    /// The default: 6 standard deviations.
    pub const DEFAULT: Self = Self::Uncertainty { sigmas: 6.0 };
}

/// Calibration settings.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibrationConfig {
    /// Local gravity, output unit. Defaults to 9.80665 (m/s^2).
    pub gravity: f32,
    /// Optimiser. Defaults to [`Method::TagaLm`].
    pub method: Method,
    /// The initial estimate. Defaults to [`Init::Auto`] (ellipsoid fit, six faces as a fallback).
    pub init: Init,
    /// Which poses the ellipsoid fit leaves out as far off. Defaults to [`OutlierRule::DEFAULT`].
    pub outliers: OutlierRule,
    /// GA search intervals. Defaults to [`Intervals::DEFAULT`].
    pub intervals: Intervals,
    /// GA settings. Defaults to [`GaConfig::DEFAULT`] with 30 generations at most and a 10-generation
    /// stall stop: enough to seed the LM polish (TAGA+LM reaches the least-squares optimum from it).
    /// TAGA alone needs 150-200 generations to come within 2x of the Cramer-Rao bound on the paper's
    /// 24 positions (`accelcal paper`): see [`CalibrationConfig::TAGA_ALONE`].
    pub ga: GaConfig,
    /// LM settings. Defaults to [`LmConfig::DEFAULT`].
    pub lm: LmConfig,
    /// Newton settings. Defaults to [`NewtonConfig::DEFAULT`].
    pub newton: NewtonConfig,
    /// Verdict bounds. Defaults to [`VerdictBounds::DEFAULT`].
    pub bounds: VerdictBounds,
    /// Model the "before" RMSE is computed with; `None` (default) uses the initial estimate without
    /// its non-orthogonality (centre and per-axis gains), the only meaningful reference for raw counts. Use `Some(Params::IDENTITY)` for readings
    /// already in the gravity unit.
    pub before: Option<Params>,
}

impl CalibrationConfig {
    /// The documented defaults.
    pub const DEFAULT: Self = Self {
        gravity: crate::model::STANDARD_GRAVITY_MPS2,
        method: Method::TagaLm,
        init: Init::Auto,
        outliers: OutlierRule::DEFAULT,
        intervals: Intervals::DEFAULT,
        ga: GaConfig { max_generations: 30, stall_generations: 10, ..GaConfig::DEFAULT },
        lm: LmConfig::DEFAULT,
        newton: NewtonConfig::DEFAULT,
        bounds: VerdictBounds::DEFAULT,
        before: None,
    };

    /// The paper's method alone: TAGA with 200 generations at most (30-generation stall stop), no
    /// polish: about 7 640 cost evaluations with population 40.
    pub const TAGA_ALONE: Self = Self {
        method: Method::Taga,
        ga: GaConfig { max_generations: 200, stall_generations: 30, ..GaConfig::DEFAULT },
        ..Self::DEFAULT
    };
}

impl Default for CalibrationConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why a calibration could not run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum CalibrationError {
    /// More poses than the `MAX_POSES` buffer holds.
    TooManyPoses {
        /// Poses given.
        got: usize,
        /// Capacity.
        capacity: usize,
    },
    /// No initial estimate (too few poses, a degenerate spread of directions, no faces).
    Init(InitError),
    /// The GA could not be set up.
    Ga(GaError),
    /// The gradient solver failed.
    Solve(SolveError),
}

impl core::fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooManyPoses { got, capacity } => write!(f, "{got} poses given, capacity is {capacity}"),
            Self::Init(e) => write!(f, "initial estimate: {e}"),
            Self::Ga(e) => write!(f, "genetic algorithm: {e}"),
            Self::Solve(e) => write!(f, "solver: {e}"),
        }
    }
}

impl core::error::Error for CalibrationError {}

impl From<InitError> for CalibrationError {
    fn from(e: InitError) -> Self {
        match e {
            InitError::TooManyPoses { got, capacity } => Self::TooManyPoses { got, capacity },
            e => Self::Init(e),
        }
    }
}
impl From<CoarseError> for CalibrationError {
    fn from(e: CoarseError) -> Self {
        Self::Init(InitError::Coarse(e))
    }
}
impl From<GaError> for CalibrationError {
    fn from(e: GaError) -> Self {
        Self::Ga(e)
    }
}
impl From<SolveError> for CalibrationError {
    fn from(e: SolveError) -> Self {
        Self::Solve(e)
    }
}

/// A finished calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Calibration {
    /// The calibrated parameters (paper convention).
    pub params: Params,
    /// The initial estimate (which initialisation, its model, what it left out or held).
    pub initial: Initial,
    /// The optimiser used.
    pub method: Method,
    /// The paper's objective `fE` at `params`, output unit to the fourth.
    pub objective: f32,
    /// GA generations run (0 without GA).
    pub generations: u32,
    /// Cost evaluations by the GA (0 without GA).
    pub evaluations: u32,
    /// Newton or LM iterations (0 for TAGA alone).
    pub iterations: u32,
    /// Why the GA stopped (`None` without GA).
    pub ga_termination: Option<crate::ga::Termination>,
    /// Why Newton or LM stopped (`None` for TAGA alone).
    pub solver_termination: Option<SolveTermination>,
    /// The verdict.
    pub verdict: Verdict,
}

/// Runs a GA of population `POP` on the normalised problem: the box from `widths` around `start`, which
/// is injected as one individual.
pub fn ga_solver<R: Rng, const POP: usize>(
    norm: &[NormPose],
    start: &Deviation,
    widths: &SearchWidths,
    config: GaConfig,
    rng: R,
) -> Result<Ga<R, POP, PARAM_COUNT>, GaError> {
    let mut ga = Ga::empty(config, SearchBox::UNSET, rng);
    seed_population(&mut ga, norm, start, &widths.half_widths())?;
    Ok(ga)
}

/// Sets the box `start +- half` of a calibration GA (built with [`SearchBox::UNSET`]), draws its initial
/// population and injects the start.
fn seed_population<R: Rng, const POP: usize>(
    ga: &mut Ga<R, POP, PARAM_COUNT>,
    norm: &[NormPose],
    start: &Deviation,
    half: &[f32; PARAM_COUNT],
) -> Result<(), GaError> {
    ga.set_bounds_around(start, half)?;
    ga.initialize_with(start, &PoseCost(norm))?;
    Ok(())
}

/// The calibration GA's cost: the normalised objective over the poses. One type for every GA call of
/// a calibration, so that the GA's code is instantiated once.
#[derive(Clone, Copy)]
struct PoseCost<'a>(&'a [NormPose]);

impl crate::ga::CostFunction<PARAM_COUNT> for PoseCost<'_> {
    fn cost(&self, x: &Deviation) -> f32 {
        objective(x, self.0)
    }
}

/// The half-widths of the GA's search box for `intervals` around `start` (held parameters pinned to a
/// zero-width-like interval); the box is `start +- half` ([`SearchBox::around`]).
#[inline] // into the caller's array (returned, it was copied); the matrices are out of line below
pub fn search_half_widths(
    intervals: &Intervals,
    start: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    held: Held,
) -> [f32; PARAM_COUNT] {
    let mut half = SearchWidths::DEFAULT.half_widths();
    match intervals {
        Intervals::Fixed(widths) => half = widths.half_widths(),
        Intervals::Uncertainty { sigmas } => uncertainty_half_widths(*sigmas, start, frame, set, held, &mut half),
    }
    half
}

/// `sigmas` standard deviations of each parameter at `start` ([`Intervals::Uncertainty`]) into `half`;
/// `half` is left as it is when the covariance cannot be formed. Out of line: its matrices need not
/// share a stack frame with the GA's state.
#[inline(never)]
fn uncertainty_half_widths(
    sigmas: f32,
    start: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    held: Held,
    half: &mut [f32; PARAM_COUNT],
) {
    let mut cov = [[0.0f32; PARAM_COUNT]; PARAM_COUNT];
    if !information_in_place(start, frame, set, held, true, &mut cov)
        || !crate::verdict::covariance_holding_in_place(&mut cov, held)
    {
        return;
    }
    // A floor keeps the box valid where a parameter is held or determined exactly.
    for (i, h) in half.iter_mut().enumerate() {
        *h = larger(sigmas * crate::linalg::sqrt_clamped(cov[i][i]), MIN_HALF_WIDTH);
    }
}

/// Smallest half-width of a GA interval, deviation units.
const MIN_HALF_WIDTH: f32 = 1e-7;

/// Runs the GA to termination and returns what it found. Out of line: the GA state (population and
/// offspring, `2 POP 9` floats) then lives in this frame alone, not in one merged with the LM and
/// verdict frames, and is never moved. The box is set in place from its half-widths (a box by value
/// was a `memcpy` call), the result written into `out` (returned in a `Result`, it was copied).
#[inline(never)]
fn run_ga<R: Rng, const POP: usize>(
    norm: &[NormPose],
    start: &Deviation,
    half: &[f32; PARAM_COUNT],
    config: &GaConfig,
    rng: R,
    out: &mut Optimised,
) -> Result<(), GaError> {
    let mut ga = Ga::<R, POP, PARAM_COUNT>::empty(*config, SearchBox::UNSET, rng);
    seed_population(&mut ga, norm, start, half)?;
    *out = Optimised::from_ga(&ga.run(&PoseCost(norm)));
    Ok(())
}

/// What the optimiser did.
#[derive(Clone, Copy)]
struct Optimised {
    x: Deviation,
    generations: u32,
    evaluations: u32,
    iterations: u32,
    ga_termination: Option<crate::ga::Termination>,
    solver_termination: Option<SolveTermination>,
}

impl Optimised {
    /// Nothing run yet: the start.
    fn at(x: Deviation) -> Self {
        Self { x, generations: 0, evaluations: 0, iterations: 0, ga_termination: None, solver_termination: None }
    }

    fn from_ga(report: &crate::ga::GaReport<PARAM_COUNT>) -> Self {
        let ga_termination = Some(report.termination);
        Self {
            x: report.best,
            generations: report.generations,
            evaluations: report.evaluations,
            ga_termination,
            ..Self::at(report.best)
        }
    }
}

/// The problem every optimiser solves: the poses normalised in the frame of the initial estimate, the
/// parameters held at nominal, and the start (held parameters at 0).
pub struct Prepared<const MAX_POSES: usize> {
    normalized: NormalizedPoses<MAX_POSES>,
    held: Held,
    start: Deviation,
}

impl<const MAX_POSES: usize> Prepared<MAX_POSES> {
    /// The initial estimate ([`CalibrationConfig::init`]), the parameters to hold, the start.
    pub fn new(poses: &[Pose], config: &CalibrationConfig) -> Result<Self, CalibrationError> {
        let mut out = Self::EMPTY;
        out.refill(poses, config)?;
        Ok(out)
    }

    /// A placeholder to [`Prepared::refill`].
    const EMPTY: Self = Self { normalized: NormalizedPoses::EMPTY, held: Held::NONE, start: [0.0; PARAM_COUNT] };

    /// [`Prepared::new`] into `self`, where it stays: the pose buffer is never copied on the stack.
    fn refill(&mut self, poses: &[Pose], config: &CalibrationConfig) -> Result<(), CalibrationError> {
        let normalized = &mut self.normalized;
        normalized.refill(poses, config.init, config.gravity, &config.outliers)?;
        let set = normalized.pose_set(poses);
        // Written in place (a local start was copied into `self`).
        self.start = normalized.start();
        let held =
            parameters_to_hold(&self.start, normalized.frame(), &set, Held::from_flags(&normalized.initial().held));
        // One pose per parameter fitted (six faces fit the biases and scale factors).
        let norm = normalized.poses();
        if norm.len() < PARAM_COUNT - held.count() {
            return Err(SolveError::TooFewPoses { got: norm.len() }.into());
        }
        for i in 0..PARAM_COUNT {
            if held.contains(i) {
                self.start[i] = 0.0;
            }
        }
        self.held = held;
        Ok(())
    }

    /// The normalised poses used.
    pub fn poses(&self) -> &[NormPose] {
        self.normalized.poses()
    }

    /// The half-widths of the GA's search box ([`search_half_widths`]).
    fn search_half_widths(&self, poses: &[Pose], config: &CalibrationConfig) -> [f32; PARAM_COUNT] {
        let (frame, set) = (self.normalized.frame(), self.normalized.pose_set(poses));
        search_half_widths(&config.intervals, &self.start, frame, &set, self.held)
    }

    /// Newton or LM (per `config.method`; LM for TAGA+LM) from `run.x`, into `run` (in place: an
    /// `Optimised` returned in a `Result` was copied).
    fn polish(&self, run: &mut Optimised, config: &CalibrationConfig) -> Result<(), CalibrationError> {
        let norm = self.poses();
        let (iterations, termination) = match config.method {
            Method::Newton => {
                let r = newton_holding(run.x, norm, &config.newton, self.held)?;
                run.x = r.x;
                (r.iterations, r.termination)
            }
            // In place; the number of poses was checked by `refill`.
            _ => {
                let end = levenberg_marquardt_in_place(&mut run.x, norm, &config.lm, self.held)?;
                (end.iterations, end.termination)
            }
        };
        (run.iterations, run.solver_termination) = (iterations, Some(termination));
        Ok(())
    }

    /// The calibration at the optimiser's result: held parameters exactly at nominal, the verdict.
    #[inline(never)]
    fn conclude(&self, poses: &[Pose], run: &mut Optimised, config: &CalibrationConfig) -> Calibration {
        let frame = self.normalized.frame();
        let set = self.normalized.pose_set(poses);
        let initial = self.normalized.initial();
        // The GA moves held genes within its smallest interval; they are held exactly (in place: no copy).
        for i in 0..PARAM_COUNT {
            if self.held.contains(i) {
                run.x[i] = self.start[i];
            }
        }
        let x = &run.x;
        let before = config.before.unwrap_or_else(|| frame.to_params(&[0.0; PARAM_COUNT]));
        let not_converged = run.solver_termination == Some(SolveTermination::MaxIterations);
        // The verdict is judged last, straight into the result (no copy of it: no memcpy call).
        Calibration {
            params: frame.to_params(x),
            initial: *initial,
            method: config.method,
            objective: objective_value(x, set.norm, config.gravity),
            generations: run.generations,
            evaluations: run.evaluations,
            iterations: run.iterations,
            ga_termination: run.ga_termination,
            solver_termination: run.solver_termination,
            verdict: judge_run(x, frame, &set, &before, &config.bounds, self.held, &initial.excluded, not_converged),
        }
    }
}

/// Calibrates from captured poses with a GA population of `POP` and room for `MAX_POSES` poses, in one
/// call (see [`Calibrator`] for the same in bounded steps).
pub fn calibrate<R: Rng, const POP: usize, const MAX_POSES: usize>(
    poses: &[Pose],
    config: &CalibrationConfig,
    rng: R,
) -> Result<Calibration, CalibrationError> {
    let mut prepared = Prepared::<MAX_POSES>::EMPTY;
    prepared.refill(poses, config)?;
    let mut run = Optimised::at(prepared.start);
    if matches!(config.method, Method::Taga | Method::TagaLm) {
        let half = prepared.search_half_widths(poses, config);
        run_ga::<R, POP>(prepared.poses(), &prepared.start, &half, &config.ga, rng, &mut run)?;
    }
    if config.method != Method::Taga {
        prepared.polish(&mut run, config)?;
    }
    Ok(prepared.conclude(poses, &mut run, config))
}

/// What one [`Calibrator::step`] did.
// No allocator to box the calibration in, and it is returned once: the size difference is the point.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Step {
    /// One GA generation ran; call again.
    Running {
        /// Generations run so far.
        generation: u32,
    },
    /// The calibration is finished (the polish and the verdict ran in this step).
    Finished(Calibration),
}

/// [`calibrate`] in bounded steps, to run beside a control loop or in an async task: [`Calibrator::new`]
/// makes the initial estimate and the first population, each [`Calibrator::step`] runs one GA
/// generation (about 66 k cycles on a Cortex-M4F at population 24 and 24 poses, `cargo xtask report`), and
/// the last step polishes (LM, some 100 k cycles) and judges. The same seeds give the same result as [`calibrate`].
///
/// ```
/// use accelcal::accumulator::Pose;
/// use accelcal::calibrate::{calibrate, CalibrationConfig, Calibrator, DefaultRng, Step};
/// use accelcal::model::Params;
/// use rand_core::SeedableRng;
/// let truth = Params { bias: [0.1, -0.2, 0.05], scale: [0.98, 1.01, 1.0], nonorth: [0.01, -0.01, 0.005] };
/// let dirs = [[0.3f32, 0.9, 0.3], [-0.8, 0.5, 0.33], [0.1, -0.7, 0.7], [0.6, 0.0, -0.8], [-0.2, -0.3, -0.93],
///     [0.9, -0.4, 0.17], [-0.5, -0.8, 0.33], [0.0, 0.6, -0.8], [-0.7, 0.1, -0.7], [0.57, 0.57, 0.57]];
/// let poses = dirs.map(|d| {
///     let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
///     Pose::from_mean(truth.invert(d.map(|v| v / n * 9.80665)).unwrap(), 500)
/// });
/// let config = CalibrationConfig::DEFAULT;
/// let mut calibrator = Calibrator::<_, 40, 16>::new(&poses, &config, DefaultRng::seed_from_u64(3)).unwrap();
/// let stepped = loop {
///     match calibrator.step(&poses).unwrap() {
///         Step::Running { .. } => continue, // other work here
///         Step::Finished(cal) => break cal,
///     }
/// };
/// let at_once = calibrate::<_, 40, 16>(&poses, &config, DefaultRng::seed_from_u64(3)).unwrap();
/// assert_eq!(stepped, at_once);
/// ```
pub struct Calibrator<R, const POP: usize, const MAX_POSES: usize> {
    config: CalibrationConfig,
    prepared: Prepared<MAX_POSES>,
    /// The GA, for the GA methods.
    ga: Option<Ga<R, POP, PARAM_COUNT>>,
}

impl<R: Rng, const POP: usize, const MAX_POSES: usize> Calibrator<R, POP, MAX_POSES> {
    /// The initial estimate, the held parameters and (for the GA methods) the first population.
    pub fn new(poses: &[Pose], config: &CalibrationConfig, rng: R) -> Result<Self, CalibrationError> {
        let prepared = Prepared::<MAX_POSES>::new(poses, config)?;
        let ga = match config.method {
            Method::Newton | Method::Lm => None,
            Method::Taga | Method::TagaLm => {
                let half = prepared.search_half_widths(poses, config);
                let mut ga = Ga::empty(config.ga, SearchBox::UNSET, rng);
                seed_population(&mut ga, prepared.poses(), &prepared.start, &half)?;
                Some(ga)
            }
        };
        Ok(Self { config: *config, prepared, ga })
    }

    /// The GA between steps (the GA methods), to watch its best and mean cost per generation.
    pub fn ga(&self) -> Option<&Ga<R, POP, PARAM_COUNT>> {
        self.ga.as_ref()
    }

    /// The frame of the initial estimate: the GA's individuals are deviations in it.
    pub fn frame(&self) -> &Frame {
        self.prepared.normalized.frame()
    }

    /// One bounded step on the same `poses` as [`Calibrator::new`]: a GA generation while the GA runs,
    /// then the polish and the verdict.
    pub fn step(&mut self, poses: &[Pose]) -> Result<Step, CalibrationError> {
        let norm = self.prepared.poses();
        let mut run = Optimised::at(self.prepared.start);
        if let Some(ga) = self.ga.as_mut() {
            let Some(termination) = ga.termination() else {
                ga.step(&PoseCost(norm));
                return Ok(Step::Running { generation: ga.generation() });
            };
            run = Optimised {
                x: *ga.best(),
                generations: ga.generation(),
                evaluations: ga.evaluations(),
                ga_termination: Some(termination),
                ..run
            };
        }
        if self.config.method != Method::Taga {
            self.prepared.polish(&mut run, &self.config)?;
        }
        Ok(Step::Finished(self.prepared.conclude(poses, &mut run, &self.config)))
    }
}

/// The paper's objective `fE` (output unit to the fourth) at `x`. The per-pose errors are accurate to
/// f32; their mean square is summed in f32 from small numbers (each `E / g^2` is near 0).
fn objective_value(x: &Deviation, norm: &[NormPose], gravity: f32) -> f32 {
    let g2 = gravity * gravity;
    objective(x, norm) * g2 * g2
}
