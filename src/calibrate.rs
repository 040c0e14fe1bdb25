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
use crate::coarse::{CoarseCalibration, CoarseError, SearchWidths};
use crate::frame::{Deviation, NormPose, objective};
use crate::ga::{Ga, GaConfig, GaError};
use crate::model::{PARAM_COUNT, PARAM_NAMES, Params};
use crate::solve::{LmConfig, NewtonConfig, SolveError, SolveTermination, levenberg_marquardt, newton};
use crate::verdict::{Verdict, VerdictBounds, judge, undetermined_parameters};

/// The recommended seeded generator for the GA: 32-bit state arithmetic, fast on a Cortex-M4.
#[cfg(feature = "default-rng")]
pub type DefaultRng = rand_xoshiro::Xoshiro128PlusPlus;

/// Which optimiser runs after the coarse calibration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Method {
    /// The paper's classical Newton baseline, from the coarse estimate.
    Newton,
    /// Levenberg-Marquardt from the coarse estimate.
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

/// Calibration settings.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibrationConfig {
    /// Local gravity, output unit. Defaults to 9.80665 (m/s^2).
    pub gravity: f32,
    /// Optimiser. Defaults to [`Method::TagaLm`].
    pub method: Method,
    /// GA search half-widths around the coarse estimate. Defaults to [`SearchWidths::DEFAULT`].
    pub widths: SearchWidths,
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
    /// Model the "before" RMSE is computed with; `None` (default) uses the coarse calibration, which
    /// is the only meaningful reference for raw counts. Use `Some(Params::IDENTITY)` for readings
    /// already in the gravity unit.
    pub before: Option<Params>,
}

impl CalibrationConfig {
    /// The documented defaults.
    pub const DEFAULT: Self = Self {
        gravity: crate::model::STANDARD_GRAVITY_MPS2,
        method: Method::TagaLm,
        widths: SearchWidths::DEFAULT,
        ga: GaConfig { max_generations: 30, stall_generations: 10, ..GaConfig::DEFAULT },
        lm: LmConfig::DEFAULT,
        newton: NewtonConfig::DEFAULT,
        bounds: VerdictBounds::DEFAULT,
        before: None,
    };

    /// The paper's method alone: TAGA with 200 generations at most (30-generation stall stop), no
    /// polish: 7 641 cost evaluations with population 40.
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
    /// Coarse calibration failed (e.g. an axis was never pointed up or down).
    Coarse(CoarseError),
    /// The GA could not be set up.
    Ga(GaError),
    /// The gradient solver failed.
    Solve(SolveError),
    /// The poses cannot determine these parameters (`true` per parameter, [`PARAM_NAMES`] order): too
    /// few distinct directions. Capture orientations between the faces (edges, corners).
    Undetermined([bool; PARAM_COUNT]),
}

impl core::fmt::Display for CalibrationError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooManyPoses { got, capacity } => write!(f, "{got} poses given, capacity is {capacity}"),
            Self::Coarse(e) => write!(f, "coarse calibration: {e}"),
            Self::Ga(e) => write!(f, "genetic algorithm: {e}"),
            Self::Solve(e) => write!(f, "solver: {e}"),
            Self::Undetermined(which) => {
                f.write_str("the poses cannot determine")?;
                for (name, _) in PARAM_NAMES.iter().zip(which).filter(|(_, u)| **u) {
                    write!(f, " {name}")?;
                }
                f.write_str(": capture orientations between the faces (edges, corners)")
            }
        }
    }
}

impl core::error::Error for CalibrationError {}

impl From<CoarseError> for CalibrationError {
    fn from(e: CoarseError) -> Self {
        Self::Coarse(e)
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
    /// The coarse (six-position) estimate.
    pub coarse: Params,
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
    /// The verdict.
    pub verdict: Verdict,
}

/// Poses normalised into a coarse frame, in a fixed buffer of `MAX_POSES`.
pub struct NormalizedPoses<const MAX_POSES: usize> {
    coarse: CoarseCalibration,
    poses: heapless::Vec<NormPose, MAX_POSES>,
}

impl<const MAX_POSES: usize> NormalizedPoses<MAX_POSES> {
    /// Coarse-calibrates `poses` against `gravity` and normalises them.
    pub fn new(poses: &[Pose], gravity: f32) -> Result<Self, CalibrationError> {
        if poses.len() > MAX_POSES {
            return Err(CalibrationError::TooManyPoses { got: poses.len(), capacity: MAX_POSES });
        }
        let mut means: heapless::Vec<[f32; 3], MAX_POSES> = heapless::Vec::new();
        for p in poses {
            // Capacity checked above.
            let _ = means.push(p.mean);
        }
        let coarse = CoarseCalibration::from_means(&means, gravity)?;
        let mut out = heapless::Vec::new();
        for m in &means {
            let _ = out.push(coarse.frame().normalize(*m));
        }
        Ok(Self { coarse, poses: out })
    }

    /// The coarse calibration that defines the frame.
    pub fn coarse(&self) -> &CoarseCalibration {
        &self.coarse
    }

    /// The normalised poses.
    pub fn poses(&self) -> &[NormPose] {
        &self.poses
    }
}

/// Runs a GA of population `POP` on the normalised problem: the box from `widths` around the coarse
/// estimate, the coarse estimate injected as one individual.
pub fn ga_solver<R: Rng, const POP: usize>(
    norm: &[NormPose],
    widths: &SearchWidths,
    config: GaConfig,
    rng: R,
) -> Result<Ga<R, POP, PARAM_COUNT>, GaError> {
    let mut ga = Ga::empty(config, widths.search_box(&[0.0; PARAM_COUNT])?, rng);
    seed_population(&mut ga, norm)?;
    Ok(ga)
}

/// Draws the initial population of a calibration GA and injects the coarse estimate (`x = 0`).
fn seed_population<R: Rng, const POP: usize>(
    ga: &mut Ga<R, POP, PARAM_COUNT>,
    norm: &[NormPose],
) -> Result<(), GaError> {
    let cost = |x: &Deviation| objective(x, norm);
    ga.initialize(&cost)?;
    ga.inject(&[0.0; PARAM_COUNT], &cost);
    Ok(())
}

/// Runs the GA to termination and returns only its report. Out of line: the GA state (population
/// and offspring, `2 POP 9` floats) then lives in this frame alone, not in one merged with the LM
/// and verdict frames, and is never moved.
#[inline(never)]
fn run_ga<R: Rng, const POP: usize>(
    norm: &[NormPose],
    widths: &SearchWidths,
    config: GaConfig,
    rng: R,
) -> Result<crate::ga::GaReport<PARAM_COUNT>, GaError> {
    let mut ga = Ga::<R, POP, PARAM_COUNT>::empty(config, widths.search_box(&[0.0; PARAM_COUNT])?, rng);
    seed_population(&mut ga, norm)?;
    Ok(ga.run(&|x: &Deviation| objective(x, norm)))
}

/// Calibrates from captured poses with a GA population of `POP` and room for `MAX_POSES` poses.
pub fn calibrate<R: Rng, const POP: usize, const MAX_POSES: usize>(
    poses: &[Pose],
    config: &CalibrationConfig,
    rng: R,
) -> Result<Calibration, CalibrationError> {
    let normalized = NormalizedPoses::<MAX_POSES>::new(poses, config.gravity)?;
    let norm = normalized.poses();
    let frame = *normalized.coarse().frame();
    let start = [0.0; PARAM_COUNT];
    if norm.len() < PARAM_COUNT {
        return Err(SolveError::TooFewPoses { got: norm.len() }.into());
    }
    let undetermined = undetermined_parameters(&start, norm);
    if undetermined.iter().any(|&u| u) {
        return Err(CalibrationError::Undetermined(undetermined));
    }
    let (mut generations, mut evaluations, mut iterations) = (0, 0, 0);
    let mut converged = true;
    let x = match config.method {
        Method::Newton => {
            let r = newton(start, norm, &config.newton)?;
            iterations = r.iterations;
            converged = r.termination != SolveTermination::MaxIterations;
            r.x
        }
        Method::Lm => {
            let r = levenberg_marquardt(start, norm, &config.lm)?;
            iterations = r.iterations;
            converged = r.termination != SolveTermination::MaxIterations;
            r.x
        }
        Method::Taga | Method::TagaLm => {
            let report = run_ga::<R, POP>(norm, &config.widths, config.ga, rng)?;
            generations = report.generations;
            evaluations = report.evaluations;
            if config.method == Method::TagaLm {
                let r = levenberg_marquardt(report.best, norm, &config.lm)?;
                iterations = r.iterations;
                converged = r.termination != SolveTermination::MaxIterations;
                r.x
            } else {
                report.best
            }
        }
    };
    let params = frame.to_params(&x);
    let before = config.before.unwrap_or_else(|| normalized.coarse().params());
    let mut verdict = judge(&x, &frame, poses, norm, &before, &config.bounds);
    verdict.failures.not_converged = !converged;
    // fE in f64: the per-pose errors are accurate to f32, their sum of squares need not lose more.
    let g2 = f64::from(config.gravity) * f64::from(config.gravity);
    let sum_sq: f64 = norm
        .iter()
        .map(|p| {
            let e = f64::from(crate::frame::modulus_error(&x, p));
            e * e
        })
        .sum();
    let objective_value = (sum_sq / norm.len() as f64 * g2 * g2) as f32;
    Ok(Calibration {
        params,
        coarse: normalized.coarse().params(),
        method: config.method,
        objective: objective_value,
        generations,
        evaluations,
        iterations,
        verdict,
    })
}
