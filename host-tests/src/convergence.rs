//! How fast TAGA comes near the least-squares optimum from each initialisation: the first generation
//! whose best cost is within 1 % of the LM optimum, over many simulated experiments.
//!
//! - the paper's six-position start with fixed search widths ([`SearchWidths::DEFAULT`]);
//! - the same start with intervals from its uncertainty ([`Intervals::DEFAULT`]: the covariance at
//!   the start, inflated by its residuals);
//! - the closed-form ellipsoid start with intervals from its uncertainty.
//!
//! Each runs the paper's TAGA at population 40 (the host's) through the calibration pipeline
//! ([`calib::run_observed`], as `accelcal calibrate` runs it), watching its best cost per generation.

use std::ops::ControlFlow;

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, Init, Intervals, Method};
use accelcal::coarse::SearchWidths;
use accelcal::ga::GaConfig;

use crate::calib;
use crate::sim::{Plan, SimConfig, simulate_pose_means};

/// Generations run at most.
pub const MAX_GENERATIONS: u32 = 200;

/// Within this factor of the LM optimum's cost counts as converged.
pub const WITHIN: f32 = 1.01;

/// Generations-to-1 % of one initialisation over the runs.
#[derive(Debug, Clone)]
pub struct Convergence {
    /// The set-up.
    pub init: &'static str,
    /// Median generations (runs that never got there count as `MAX_GENERATIONS + 1`).
    pub median: u32,
    /// 95th percentile, likewise.
    pub p95: u32,
    /// Share of runs within 1 % by generation 40.
    pub by_40: f64,
    /// Runs.
    pub runs: usize,
}

/// One run from `init` with the paper's fixed box (`fixed`) or the uncertainty box, through the
/// calibration pipeline ([`calib::run_observed`]): the first generation whose best cost is within
/// [`WITHIN`] of the LM optimum from the same start (`Some(None)` if none is by
/// [`MAX_GENERATIONS`]), or `None` when the initial estimate or the GA could not be set up.
fn one(poses: &[Pose], init: Init, fixed: bool, seed: u64, gravity: f32) -> Option<Option<u32>> {
    let intervals = if fixed { Intervals::Fixed(SearchWidths::DEFAULT) } else { Intervals::DEFAULT };
    let ga = GaConfig { max_generations: MAX_GENERATIONS, stall_generations: 0, ..CalibrationConfig::TAGA_ALONE.ga };
    let config = CalibrationConfig { gravity, init, intervals, ga, ..CalibrationConfig::TAGA_ALONE };
    let lm = CalibrationConfig { method: Method::Lm, ..config };
    // The objective is normalised by g^4 in the GA; the calibration reports it in (output unit)^4.
    let optimum = calib::run(poses, &lm, seed).ok()?.objective / gravity.powi(4);
    let mut reached = None;
    let finished = calib::run_observed(poses, &config, seed, |ga, _| {
        if ga.best_cost() <= WITHIN * optimum {
            reached = Some(ga.generation());
            return ControlFlow::Break(());
        }
        ControlFlow::Continue(())
    });
    finished.ok()?;
    Some(reached)
}

fn summary(init: &'static str, mut generations: Vec<u32>) -> Convergence {
    generations.sort_unstable();
    let at = |q: f64| generations.get(((generations.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(0);
    let by_40 = generations.iter().filter(|&&g| g <= 40).count() as f64 / generations.len().max(1) as f64;
    Convergence { init, median: at(0.5), p95: at(0.95), by_40, runs: generations.len() }
}

/// The set-ups compared: name, initialisation, fixed (paper) box.
const SETUPS: [(&str, Init, bool); 3] = [
    ("six-position, fixed box (paper)", Init::SixPosition, true),
    ("six-position, uncertainty box", Init::SixPosition, false),
    ("ellipsoid, uncertainty box", Init::Ellipsoid, false),
];

/// Generations-to-1 % for each set-up over `runs` experiments of `plan` (seeds `seed..`);
/// `progress` is called after each experiment of each set-up (`3 runs` times).
pub fn compare(plan: Plan, seed: u64, runs: usize, noise_mg: f64, mut progress: impl FnMut()) -> Vec<Convergence> {
    SETUPS
        .iter()
        .map(|&(name, init, fixed)| {
            let generations = (0..runs)
                .filter_map(|run| {
                    let s = seed + run as u64;
                    let cfg = SimConfig { noise_mg, ..SimConfig::for_plan(plan, s) };
                    let poses: Vec<Pose> = simulate_pose_means(&cfg);
                    let reached = one(&poses, init, fixed, s, cfg.gravity as f32);
                    progress();
                    reached.map(|r| r.unwrap_or(MAX_GENERATIONS + 1))
                })
                .collect();
            summary(name, generations)
        })
        .collect()
}
