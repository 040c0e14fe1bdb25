//! Calibrating a set of poses with the library, plus the host-only extras: leave-one-pose-out RMSE
//! and a JSON-ready summary. Every number comes from `accelcal`; nothing is re-implemented here.

use accelcal::accumulator::Pose;
use std::ops::ControlFlow;

use accelcal::calibrate::{Calibration, CalibrationConfig, CalibrationError, Calibrator, NormalizedPoses, Step};
use accelcal::frame::{Deviation, Frame, modulus_error};
use accelcal::ga::Ga;
use accelcal::model::{Params, STANDARD_GRAVITY_MPS2};

use crate::csvio::{DroppedRows, Units};
use accelcal::ellipsoid::OutlierRule;
use accelcal::linalg::Held;
use accelcal::solve::{levenberg_marquardt, levenberg_marquardt_holding};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

/// GA population used by the host (the paper's setting and the firmware's).
pub const POPULATION: usize = 40;
/// Largest pose count the host handles in one calibration.
pub const MAX_POSES: usize = 512;

/// Fewest poses a calibration is tried on: the six faces determine six parameters (the coarse
/// start); with fewer the pose finder falls back to shorter holds ([`crate::poses::accumulate_holds`]).
pub const MIN_POSES: usize = 6;

/// The poses are enough to calibrate with `config`: at least [`MIN_POSES`], and the initial estimate
/// `config.init` asks for fits them (the ellipsoid needs nine directions, the six faces poses along
/// the faces). More than [`MAX_POSES`] count as enough: what to do with them is the caller's error.
/// The pose finder tries its later settings while the poses are not enough
/// ([`crate::poses::accumulate_until`]).
pub fn enough_poses(poses: &[Pose], config: &CalibrationConfig) -> bool {
    poses.len() > MAX_POSES
        || poses.len() >= MIN_POSES
            && NormalizedPoses::<MAX_POSES>::prepare(poses, config.init, config.gravity, &config.outliers).is_ok()
}

/// Range of ratios of `--gravity` to the gravity the readings measure that [`check_gravity`] accepts.
pub const GRAVITY_RATIO_RANGE: (f64, f64) = (0.5, 2.0);

/// Refuses a non-positive or non-finite gravity (m/s^2), before any file is read.
///
/// # Errors
/// A message naming the value.
pub fn check_gravity_positive(gravity_mps2: f64) -> Result<(), String> {
    if gravity_mps2.is_finite() && gravity_mps2 > 0.0 {
        Ok(())
    } else {
        Err(format!("--gravity {gravity_mps2:?} must be a positive number of m/s^2 (e.g. 9.81)"))
    }
}

/// Refuses a gravity (m/s^2) the data cannot be calibrated against: non-positive, non-finite, or
/// outside [`GRAVITY_RATIO_RANGE`] of the modulus the readings measure (median |a|, g and m/s^2
/// data) or of standard gravity (counts, whose scale is unknown).
///
/// # Errors
/// A message saying what was given and what was measured.
pub fn check_gravity(gravity_mps2: f64, units: Units, median_magnitude: f64) -> Result<(), String> {
    check_gravity_positive(gravity_mps2)?;
    let standard = f64::from(STANDARD_GRAVITY_MPS2);
    let (reference_mps2, what) = match units.one_g() {
        Some(one_g) => {
            let measured = median_magnitude / one_g * standard;
            (
                measured,
                format!("the readings measure |a| = {measured:.4} m/s^2 (median, {median_magnitude:.4} {units})"),
            )
        }
        None => (standard, format!("standard gravity is {standard} m/s^2 (counts: the scale is unknown)")),
    };
    let ratio = gravity_mps2 / reference_mps2;
    if (GRAVITY_RATIO_RANGE.0..=GRAVITY_RATIO_RANGE.1).contains(&ratio) {
        return Ok(());
    }
    Err(format!(
        "--gravity {gravity_mps2:?} m/s^2 is implausible: {what}; give the local gravity in m/s^2 (within {}x-{}x of \
         that)",
        GRAVITY_RATIO_RANGE.0, GRAVITY_RATIO_RANGE.1
    ))
}

/// A calibration and its leave-one-pose-out RMSE.
#[derive(Debug, Clone, Copy)]
pub struct HostCalibration {
    /// The library's result.
    pub calibration: Calibration,
    /// Leave-one-pose-out modulus RMSE, mg (`None` with fewer than 11 poses).
    pub rmse_loo_mg: Option<f32>,
}

/// The GA of a calibration as [`run_observed`] shows it.
pub type HostGa = Ga<Xoshiro128PlusPlus, POPULATION, { accelcal::model::PARAM_COUNT }>;

/// Runs the library's calibration with a GA seeded by `seed`: `accelcal calibrate`'s pipeline, and
/// the paper reproduction's (with the paper's initialisation, intervals and operators in `config`).
pub fn run(poses: &[Pose], config: &CalibrationConfig, seed: u64) -> Result<Calibration, CalibrationError> {
    match run_observed(poses, config, seed, |_, _| ControlFlow::Continue(()))? {
        Some(calibration) => Ok(calibration),
        None => unreachable!("an observer that never breaks runs to the end"),
    }
}

/// [`run`] stepped (the library's [`Calibrator`], same result for the same seed), with `observe`
/// shown the GA and the frame of its individuals after the first population and after each
/// generation (never for Newton or LM alone). `observe` breaking stops the run: `Ok(None)`.
pub fn run_observed(
    poses: &[Pose],
    config: &CalibrationConfig,
    seed: u64,
    mut observe: impl FnMut(&HostGa, &Frame) -> ControlFlow<()>,
) -> Result<Option<Calibration>, CalibrationError> {
    let rng = Xoshiro128PlusPlus::seed_from_u64(seed);
    let mut calibrator = Calibrator::<_, POPULATION, MAX_POSES>::new(poses, config, rng)?;
    loop {
        if let Some(ga) = calibrator.ga()
            && observe(ga, calibrator.frame()).is_break()
        {
            return Ok(None);
        }
        if let Step::Finished(calibration) = calibrator.step(poses)? {
            return Ok(Some(calibration));
        }
    }
}

/// [`run`] plus the leave-one-pose-out RMSE: each pose is predicted by an LM fit of the others
/// (started at the full solution).
pub fn run_with_loo(
    poses: &[Pose],
    config: &CalibrationConfig,
    seed: u64,
) -> Result<HostCalibration, CalibrationError> {
    let calibration = run(poses, config, seed)?;
    Ok(HostCalibration { calibration, rmse_loo_mg: loo_rmse_mg(poses, config, &calibration.params) })
}

fn loo_rmse_mg(poses: &[Pose], config: &CalibrationConfig, params: &Params) -> Option<f32> {
    let norm = NormalizedPoses::<MAX_POSES>::prepare(poses, config.init, config.gravity, &config.outliers).ok()?;
    let all = norm.poses();
    if all.len() < accelcal::model::PARAM_COUNT + 2 {
        return None;
    }
    let x0: Deviation = norm.frame().to_deviation(params);
    let mut sum = 0.0f64;
    let mut others = Vec::with_capacity(all.len());
    for i in 0..all.len() {
        others.clear();
        others.extend(all.iter().enumerate().filter(|(j, _)| *j != i).map(|(_, p)| *p));
        let fit = levenberg_marquardt(x0, &others, &config.lm).ok()?;
        let e = modulus_error(&fit.x, &all[i]);
        let modulus_error_g = (1.0 + f64::from(e)).max(0.0).sqrt() - 1.0;
        sum += modulus_error_g * modulus_error_g;
    }
    Some(((sum / all.len() as f64).sqrt() * 1000.0) as f32)
}

/// An LM fit of every pose in `poses` (none left out as an outlier) started at `start` (paper
/// convention) instead of the initial estimate, in the frame of `config`'s initial estimate, the
/// parameters flagged in `held` held at nominal: the local minimum nearest `start`. `None` when the
/// poses cannot be prepared or the fit fails.
pub fn lm_from(poses: &[Pose], config: &CalibrationConfig, start: &Params, held: &[bool]) -> Option<Params> {
    let keep_all = OutlierRule::KEEP_ALL;
    let norm = NormalizedPoses::<MAX_POSES>::prepare(poses, config.init, config.gravity, &keep_all).ok()?;
    let held = Held::from_flags(held);
    let mut x0: Deviation = norm.frame().to_deviation(start);
    for (i, x) in x0.iter_mut().enumerate() {
        if held.contains(i) {
            *x = 0.0;
        }
    }
    let fit = levenberg_marquardt_holding(x0, norm.poses(), &config.lm, held).ok()?;
    Some(norm.frame().to_params(&fit.x))
}

/// JSON of the parameters: `{"bias": [..], "scale": [..], "nonorth": [..]}` (the library's
/// `Serialize`).
pub fn params_json(p: &Params) -> serde_json::Value {
    serde_json::to_value(p).unwrap_or_default()
}

/// A verdict as the host reports it: what failed, by name, and what was held or left out.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct VerdictSummary {
    /// No bound failed.
    pub pass: bool,
    /// RMSE after calibration above its bound.
    pub rmse_over_limit: bool,
    /// RMSE far above the noise floor.
    pub model_misfit: bool,
    /// Parameters outside the plausible range.
    pub implausible: bool,
    /// Names of the parameters the poses do not determine well enough.
    pub undetermined: Vec<&'static str>,
    /// Names of the parameters held at nominal.
    pub held_at_nominal: Vec<&'static str>,
    /// Poses left out (indices from 0).
    pub poses_left_out: Vec<u16>,
}

impl From<&accelcal::verdict::Verdict> for VerdictSummary {
    fn from(v: &accelcal::verdict::Verdict) -> Self {
        let f = &v.failures;
        Self {
            pass: v.pass(),
            rmse_over_limit: f.rmse,
            model_misfit: f.model_misfit,
            implausible: f.implausible,
            undetermined: held_names(&f.undetermined),
            held_at_nominal: held_names(&v.warnings.held),
            poses_left_out: v.warnings.excluded.as_slice().to_vec(),
        }
    }
}

/// JSON of a verdict ([`VerdictSummary`], keys sorted).
pub fn verdict_json(v: &accelcal::verdict::Verdict) -> serde_json::Value {
    serde_json::to_value(VerdictSummary::from(v)).unwrap_or_default()
}

/// Names of the parameters flagged (held, or undetermined).
pub fn held_names(held: &[bool; accelcal::model::PARAM_COUNT]) -> Vec<&'static str> {
    accelcal::model::PARAM_NAMES.iter().zip(held).filter(|(_, h)| **h).map(|(n, _)| *n).collect()
}

/// One line of warnings for a verdict (empty when there are none): parameters held at nominal because
/// the poses do not determine them, and poses left out as far off the ellipsoid.
pub fn warnings_line(v: &accelcal::verdict::Verdict) -> String {
    let mut parts = Vec::new();
    let held = held_names(&v.warnings.held);
    if !held.is_empty() {
        parts.push(format!(
            "the orientations do not determine {}: held at nominal (non-orthogonality 0, scale and bias at the \
             initial estimate); capture more directions",
            held.join(" ")
        ));
    }
    let excluded = v.warnings.excluded.as_slice();
    if !excluded.is_empty() {
        let list: Vec<String> = excluded.iter().map(|i| format!("#{}", i + 1)).collect();
        parts.push(format!("poses {} left out: far off the fitted ellipsoid (a shock or a glitch?)", list.join(", ")));
    }
    parts.join("; ")
}

/// The rows dropped while reading (by reason), while finding poses (stale repeats), and their total.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct RowsDropped {
    /// A needed cell empty, NaN or infinite.
    pub non_finite: usize,
    /// Marked stale by a stale-flag column.
    pub stale_flag: usize,
    /// Repeats of the previous reading skipped by the pose detection.
    pub stale_repeat: usize,
    /// A truncated last line.
    pub truncated_last_line: usize,
    /// All of them.
    pub total: usize,
}

impl RowsDropped {
    /// The counts of `dropped` and the stale repeats.
    pub fn new(dropped: &DroppedRows, stale_repeats: usize) -> Self {
        let total = dropped.non_finite + dropped.stale_flag + stale_repeats + dropped.truncated;
        Self {
            non_finite: dropped.non_finite,
            stale_flag: dropped.stale_flag,
            stale_repeat: stale_repeats,
            truncated_last_line: dropped.truncated,
            total,
        }
    }

    /// The reasons by name, as in the JSON.
    fn reasons(&self) -> [(&'static str, usize); 4] {
        [
            ("non_finite", self.non_finite),
            ("stale_flag", self.stale_flag),
            ("stale_repeat", self.stale_repeat),
            ("truncated_last_line", self.truncated_last_line),
        ]
    }
}

/// JSON of the rows dropped, by reason, and their total: every reason, zeros included.
pub fn rows_dropped_json(dropped: &DroppedRows, stale_repeats: usize) -> serde_json::Value {
    serde_json::to_value(RowsDropped::new(dropped, stale_repeats)).unwrap_or_default()
}

/// One text line of the rows dropped (`rows dropped: 12 (non_finite 2, stale_flag 10)`), `None`
/// when none were.
pub fn rows_dropped_line(dropped: &DroppedRows, stale_repeats: usize) -> Option<String> {
    let rows = RowsDropped::new(dropped, stale_repeats);
    let total = rows.total;
    let parts: Vec<String> = rows.reasons().iter().filter(|r| r.1 > 0).map(|(name, n)| format!("{name} {n}")).collect();
    (total > 0).then(|| format!("rows dropped: {total} ({})", parts.join(", ")))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{SimConfig, simulate_pose_means};
    use accelcal::calibrate::{Method, calibrate};

    fn paper_poses() -> (Vec<Pose>, f32) {
        let cfg = SimConfig::paper(3);
        (simulate_pose_means(&cfg), cfg.gravity as f32)
    }

    #[test]
    fn poses_are_enough_when_the_initial_estimate_fits_them() {
        let g = 9.80665_f32;
        let at = |d: [f32; 3]| {
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            Pose::from_mean(d.map(|v| g * v / n), 1000)
        };
        let faces: Vec<Pose> =
            [[1., 0., 0.], [-1., 0., 0.], [0., 1., 0.], [0., -1., 0.], [0., 0., 1.], [0., 0., -1.]].map(at).to_vec();
        // Eight directions between the faces (the corners of a cube): too few for the ellipsoid, not
        // along the faces.
        let sign = |i: usize, bit: usize| if i >> bit & 1 == 1 { 1.0 } else { -1.0 };
        let corners: Vec<Pose> = (0..8).map(|i| at([sign(i, 0), sign(i, 1), sign(i, 2)])).collect();
        let config = CalibrationConfig { gravity: g, ..CalibrationConfig::DEFAULT };
        assert!(enough_poses(&faces, &config), "the six faces");
        assert!(!enough_poses(&faces[..5], &config), "five faces");
        assert!(!enough_poses(&corners, &config), "eight corners");
        let both: Vec<Pose> = faces.iter().chain(&corners).copied().collect();
        assert!(enough_poses(&both, &config), "fourteen directions");
    }

    #[test]
    fn the_stepped_pipeline_equals_the_librarys_calibrate_and_shows_every_generation() {
        let (poses, gravity) = paper_poses();
        let config = CalibrationConfig { gravity, ..CalibrationConfig::DEFAULT };
        let rng = Xoshiro128PlusPlus::seed_from_u64(7);
        let at_once = calibrate::<_, POPULATION, MAX_POSES>(&poses, &config, rng).unwrap();
        let mut seen = Vec::new();
        let stepped = run_observed(&poses, &config, 7, |ga, _| {
            seen.push((ga.generation(), ga.best_cost()));
            ControlFlow::Continue(())
        });
        let stepped = stepped.unwrap().expect("runs to the end");
        assert_eq!(stepped, at_once);
        assert!(stepped.generations > 0);
        assert_eq!(seen.len(), stepped.generations as usize + 1, "the first population and each generation");
        assert!(seen.iter().enumerate().all(|(i, (g, _))| *g == i as u32), "{seen:?}");
        assert!(seen.windows(2).all(|w| w[1].1 <= w[0].1), "elitism: the best never worsens: {seen:?}");
    }

    /// The device's population (24, the bench's and the firmware report's) reaches the optimum of the
    /// host's and the paper's 40 on the paper's 24-position simulation: TAGA seeds the LM polish, which
    /// lands on the same least-squares optimum.
    #[test]
    fn population_24_reaches_the_objective_of_population_40() {
        for run in 0..12u64 {
            let cfg = SimConfig::paper(run);
            let poses = simulate_pose_means(&cfg);
            let config = CalibrationConfig { gravity: cfg.gravity as f32, ..CalibrationConfig::DEFAULT };
            let rng = || Xoshiro128PlusPlus::seed_from_u64(run);
            let device = calibrate::<_, 24, MAX_POSES>(&poses, &config, rng()).unwrap();
            let host = calibrate::<_, 40, MAX_POSES>(&poses, &config, rng()).unwrap();
            let relative = (device.objective - host.objective).abs() / host.objective;
            eprintln!(
                "run {run}: population 24 {:e}, 40 {:e}, relative {relative:.1e}",
                device.objective, host.objective
            );
            assert!(relative <= 1e-6, "run {run}: objective {} (24) vs {} (40)", device.objective, host.objective);
            assert_eq!(device.verdict.pass(), host.verdict.pass(), "run {run}");
        }
    }

    #[test]
    fn breaking_stops_the_run_and_gradient_methods_show_no_ga() {
        let (poses, gravity) = paper_poses();
        let config = CalibrationConfig { gravity, ..CalibrationConfig::TAGA_ALONE };
        let mut calls = 0;
        let stopped = run_observed(&poses, &config, 1, |ga, _| {
            calls += 1;
            if ga.generation() == 3 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
        assert_eq!(stopped, Ok(None));
        assert_eq!(calls, 4);
        let newton = CalibrationConfig { method: Method::Newton, ..config };
        let mut ga_seen = false;
        let cal = run_observed(&poses, &newton, 1, |_, _| {
            ga_seen = true;
            ControlFlow::Continue(())
        });
        assert_eq!(cal.unwrap().map(|c| c.generations), Some(0));
        assert!(!ga_seen);
    }
}
