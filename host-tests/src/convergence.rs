//! How fast TAGA comes near the least-squares optimum from each initialisation: the first generation
//! whose best cost is within 1 % of the LM optimum, over many simulated experiments.
//!
//! - the paper's six-position start with fixed search widths ([`SearchWidths::DEFAULT`]);
//! - the same start with intervals from its uncertainty ([`Intervals::DEFAULT`]: the covariance at
//!   the start, inflated by its residuals);
//! - the closed-form ellipsoid start with intervals from its uncertainty.
//!
//! Both run the paper's TAGA at population 40 (the host's) with the library's own set-up
//! ([`ga_solver`] for the paper's box, [`search_box`] for the uncertainty box).

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, Init, Intervals, NormalizedPoses, search_box};
use accelcal::coarse::SearchWidths;
use accelcal::frame::{Deviation, objective};
use accelcal::ga::{Ga, GaConfig};
use accelcal::model::PARAM_COUNT;
use accelcal::solve::levenberg_marquardt;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

use crate::calib::{MAX_POSES, POPULATION};
use crate::sim::{Plan, SimConfig, simulate_pose_means};
use crate::stats::median;

/// Generations run at most.
pub const MAX_GENERATIONS: u32 = 200;

/// Within this factor of the LM optimum's cost counts as converged.
pub const WITHIN: f32 = 1.01;

/// Generations-to-1 % of one initialisation over the runs.
#[derive(Debug, Clone)]
pub struct Convergence {
    /// The set-up.
    pub init: &'static str,
    /// Median generations, rounded (runs that never got there count as `MAX_GENERATIONS + 1`).
    pub median: u32,
    /// 95th percentile, likewise.
    pub p95: u32,
    /// Share of runs within 1 % by generation 40.
    pub by_40: f64,
    /// Runs.
    pub runs: usize,
}

/// The generation at which TAGA's best is first within [`WITHIN`] of `optimum`, or `None`.
fn generations_to(
    mut ga: Ga<Xoshiro128PlusPlus, POPULATION, PARAM_COUNT>,
    norm: &[accelcal::frame::NormPose],
    optimum: f32,
) -> Option<u32> {
    let cost = |x: &Deviation| objective(x, norm);
    for generation in 0..=MAX_GENERATIONS {
        if ga.best_cost() <= WITHIN * optimum {
            return Some(generation);
        }
        ga.step(&cost);
    }
    None
}

/// One run from `init` with the paper's fixed box (`fixed`) or the uncertainty box: `None` when the
/// initial estimate or the GA could not be set up.
fn one(poses: &[Pose], init: Init, fixed: bool, seed: u64, gravity: f32) -> Option<Option<u32>> {
    let config =
        GaConfig { max_generations: MAX_GENERATIONS, stall_generations: 0, ..CalibrationConfig::TAGA_ALONE.ga };
    let norm = NormalizedPoses::<MAX_POSES>::prepare(poses, init, gravity, &Default::default()).ok()?;
    let p = norm.poses();
    let optimum = levenberg_marquardt(norm.start(), p, &CalibrationConfig::DEFAULT.lm).ok()?.cost;
    let start = norm.start();
    let rng = Xoshiro128PlusPlus::seed_from_u64(seed);
    let bounds = if fixed {
        SearchWidths::DEFAULT.search_box(&start).ok()?
    } else {
        search_box(&Intervals::DEFAULT, &start, norm.frame(), &norm.pose_set(poses), &[false; PARAM_COUNT]).ok()?
    };
    let mut ga = Ga::<_, POPULATION, PARAM_COUNT>::empty(config, bounds, rng);
    let cost = |x: &Deviation| objective(x, p);
    ga.initialize(&cost).ok()?;
    ga.inject(&start, &cost);
    Some(generations_to(ga, p, optimum))
}

fn summary(init: &'static str, mut generations: Vec<u32>) -> Convergence {
    generations.sort_unstable();
    let at = |q: f64| generations.get(((generations.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(0);
    let by_40 = generations.iter().filter(|&&g| g <= 40).count() as f64 / generations.len().max(1) as f64;
    let middle = median(&generations.iter().map(|&g| f64::from(g)).collect::<Vec<_>>()).round() as u32;
    Convergence { init, median: middle, p95: at(0.95), by_40, runs: generations.len() }
}

/// The set-ups compared: name, initialisation, fixed (paper) box.
const SETUPS: [(&str, Init, bool); 3] = [
    ("six-position, fixed box (paper)", Init::SixPosition, true),
    ("six-position, uncertainty box", Init::SixPosition, false),
    ("ellipsoid, uncertainty box", Init::Ellipsoid, false),
];

/// Generations-to-1 % for each set-up over `runs` experiments of `plan` (seeds `seed..`).
pub fn compare(plan: Plan, seed: u64, runs: usize, noise_mg: f64) -> Vec<Convergence> {
    SETUPS
        .iter()
        .map(|&(name, init, fixed)| {
            let generations = (0..runs)
                .filter_map(|run| {
                    let s = seed + run as u64;
                    let cfg = SimConfig { noise_mg, ..SimConfig::for_plan(plan, s) };
                    let poses: Vec<Pose> = simulate_pose_means(&cfg);
                    one(&poses, init, fixed, s, cfg.gravity as f32).map(|r| r.unwrap_or(MAX_GENERATIONS + 1))
                })
                .collect();
            summary(name, generations)
        })
        .collect()
}
