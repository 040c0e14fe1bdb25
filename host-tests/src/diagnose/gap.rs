//! Step 1, the gap: the library's nominal fit, the same experiment simulated with the measured
//! noise and refitted by the library, and the pose statistics both rest on.

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, Method};
use accelcal::model::Params;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

use super::math::{Model, V3, cv_residuals, dot, fit_residuals, mean, median, norm, rms, std_dev, sum_sq};
use super::report::Gap;
use super::{DiagnoseError, DiagnoseOptions, SEGMENTS, SIGNIFICANT_RATIO, SIGNIFICANT_Z, err};
use crate::calib;
use crate::csvio::{self, AccumulateOptions, Table};
use crate::sim::random::standard_normal;

/// One pose's statistics from its own samples (input unit).
#[derive(Debug, Clone)]
pub(crate) struct PoseData {
    pub(crate) mean: V3,
    pub(crate) var: V3,
    pub(crate) n: usize,
    pub(crate) t_start: f64,
    pub(crate) t_end: f64,
    pub(crate) temp: Option<f64>,
    pub(crate) seg: [V3; SEGMENTS],
    pub(crate) seg_n: usize,
    /// Its rows in the table, `first..end`.
    pub(crate) rows: std::ops::Range<usize>,
}

impl PoseData {
    pub(crate) fn t_mid(&self) -> f64 {
        0.5 * (self.t_start + self.t_end)
    }
    pub(crate) fn duration(&self) -> f64 {
        (self.t_end - self.t_start).max(0.0)
    }
}

pub(crate) fn row_time(table: &Table, row: usize, rate: f64) -> f64 {
    table.times_s.as_ref().map_or(row as f64 / rate, |t| t[row])
}

/// Statistics of rows `first..end`.
pub(crate) fn pose_data(table: &Table, first: usize, end: usize, rate: f64) -> PoseData {
    let rows = &table.samples[first..end];
    let n = rows.len();
    let reference = rows[0];
    let mut sum = [0.0; 3];
    let mut sum_sq = [0.0; 3];
    for s in rows {
        for a in 0..3 {
            let d = s[a] - reference[a];
            sum[a] += d;
            sum_sq[a] += d * d;
        }
    }
    let pose_mean: V3 = std::array::from_fn(|a| reference[a] + sum[a] / n as f64);
    let var: V3 = std::array::from_fn(|a| (sum_sq[a] / n as f64 - (sum[a] / n as f64).powi(2)).max(0.0));
    let seg_n = n / SEGMENTS;
    let mut seg = [[0.0; 3]; SEGMENTS];
    for k in 0..SEGMENTS {
        let range = first + k * seg_n..first + (k + 1) * seg_n;
        if seg_n > 0 {
            for a in 0..3 {
                seg[k][a] = table.samples[range.clone()].iter().map(|s| s[a]).sum::<f64>() / seg_n as f64;
            }
        }
    }
    PoseData {
        mean: pose_mean,
        var,
        n,
        t_start: row_time(table, first, rate),
        t_end: row_time(table, end - 1, rate) + 1.0 / rate,
        temp: table.temps_c.as_ref().map(|t| mean(&t[first..end])),
        seg,
        seg_n,
        rows: first..end,
    }
}

/// Noise per axis in the input unit: white variance per sample, random-walk variance per second and
/// a bias-instability floor (variance of every pose mean, independent between poses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Noise {
    pub(crate) white: V3,
    pub(crate) walk: V3,
    pub(crate) floor: V3,
}

/// One draw of the pose-mean noise (input unit) for every pose: white over `n`, plus the random walk
/// at the pose mid times (and its averaging within the pose).
pub(crate) fn draw_noise(poses: &[PoseData], noise: &Noise, rng: &mut Xoshiro256PlusPlus) -> Vec<V3> {
    let mut walk = [0.0; 3];
    let mut last_t = 0.0;
    poses
        .iter()
        .map(|p| {
            let t = p.t_mid();
            let dt = (t - last_t).max(0.0);
            last_t = t;
            std::array::from_fn(|a| {
                walk[a] += (noise.walk[a] * dt).sqrt() * standard_normal(rng);
                let within = noise.walk[a] * p.duration() / 12.0;
                walk[a] + (noise.white[a] / p.n as f64 + within + noise.floor[a]).sqrt() * standard_normal(rng)
            })
        })
        .collect()
}

/// The modulus residuals (output unit) of `means` under `model`.
pub(crate) fn residuals(model: &Model, means: &[V3], gravity: f64) -> Vec<f64> {
    means.iter().map(|m| norm(model.apply(*m)) - gravity).collect()
}

/// Step 1's simulation: the fitted experiment with `noise`, refitted by the library (LM); the RMSE
/// of each repeat, mg.
pub(crate) fn simulate_gap(
    model: &Model,
    directions: &[V3],
    poses: &[PoseData],
    noise: &Noise,
    gravity: f64,
    repeats: usize,
    seed: u64,
) -> Vec<f64> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x0006_A951_u64);
    let clean: Vec<V3> = directions.iter().map(|u| model.invert(u.map(|c| c * gravity))).collect();
    let config = CalibrationConfig { gravity: gravity as f32, method: Method::Lm, ..CalibrationConfig::DEFAULT };
    let mut out = Vec::with_capacity(repeats);
    for rep in 0..repeats {
        let draws = draw_noise(poses, noise, &mut rng);
        let means: Vec<V3> = clean.iter().zip(&draws).map(|(c, d)| std::array::from_fn(|a| c[a] + d[a])).collect();
        let lib_poses: Vec<Pose> = means
            .iter()
            .zip(poses)
            .map(|(m, p)| Pose {
                mean: m.map(|v| v as f32),
                variance: noise.white.map(|v| v as f32),
                n: p.n as u32,
                start_index: 0,
                end_index: p.n as u32,
            })
            .collect();
        // Exact means in f64 for the residual; the library fits their f32 copies.
        let f32_means: Vec<V3> = lib_poses.iter().map(|p| p.mean.map(f64::from)).collect();
        if let Ok(cal) = calib::run(&lib_poses, &config, seed.wrapping_add(rep as u64)) {
            let fitted = Model::from_params(&cal.params);
            out.push(rms(&residuals(&fitted, &f32_means, gravity)) / gravity * 1000.0);
        }
    }
    out
}

/// Scalar modulus noise per pose (output unit) for `reps` draws.
pub(crate) fn residual_noise_draws(
    model: &Model,
    directions: &[V3],
    poses: &[PoseData],
    noise: &Noise,
    reps: usize,
    seed: u64,
) -> Vec<Vec<f64>> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0xD1A6);
    let kt: Vec<V3> = directions.iter().map(|u| model.kt_times(*u)).collect();
    (0..reps).map(|_| draw_noise(poses, noise, &mut rng).iter().zip(&kt).map(|(d, k)| dot(*d, *k)).collect()).collect()
}

/// Mean-square cross-validated residual of pure noise for a design (the expectation without effect).
pub(crate) fn expected_cv_ms(
    rows: &[Vec<f64>],
    draws: &[Vec<f64>],
    fold: &[usize],
    folds: usize,
    dropped: &[bool],
) -> f64 {
    let mut total = Vec::new();
    for e in draws {
        if let Some(cv) = cv_residuals(rows, e, fold, folds, dropped) {
            let (s, n) = sum_sq(&cv);
            if n > 0 {
                total.push(s / n as f64);
            }
        }
    }
    mean(&total)
}

/// Mean in-sample RMSE (mg) of pure noise for a design.
pub(crate) fn expected_fit_rmse_mg(rows: &[Vec<f64>], draws: &[Vec<f64>], dropped: &[bool], gravity: f64) -> f64 {
    let v: Vec<f64> = draws
        .iter()
        .filter_map(|e| fit_residuals(rows, e, dropped))
        .map(|res| {
            let kept: Vec<f64> = res.into_iter().flatten().collect();
            rms(&kept) / gravity * 1000.0
        })
        .collect();
    mean(&v)
}

/// Step 1's result: the poses, the library's fit and the simulated gap.
pub(crate) struct Measured {
    pub(crate) rate: f64,
    pub(crate) poses: Vec<PoseData>,
    pub(crate) params: Params,
    pub(crate) model: Model,
    pub(crate) calibrated: Vec<V3>,
    pub(crate) directions: Vec<V3>,
    /// Modulus residuals of the nominal fit, output unit.
    pub(crate) r: Vec<f64>,
    /// White variance per sample per axis, input unit.
    pub(crate) white: V3,
    /// Variance of a pose mean from quantisation that averaging does not remove, per axis, input unit.
    pub(crate) quantisation: V3,
    /// Simulated RMSE of each repeat, mg.
    pub(crate) sims: Vec<f64>,
    pub(crate) gap: Gap,
    pub(crate) gravity: f64,
}

impl Measured {
    pub(crate) fn to_mg(&self, v: f64) -> f64 {
        v / self.gravity * 1000.0
    }
}

/// The poses of the table (the CSV reader's accumulation) and the sample rate.
fn read_poses(table: &Table) -> Result<(Vec<Pose>, Vec<PoseData>, f64), DiagnoseError> {
    let acc =
        csvio::accumulate(table, &AccumulateOptions::default()).map_err(|e| err(format!("{}: {e}", table.file)))?;
    let rate = acc.sample_rate_hz.or_else(|| table.sample_rate_hz()).filter(|r| *r > 0.0).unwrap_or(1.0);
    // The fewest `calibrate` accepts: six faces fit six parameters (with no degree of freedom left, the
    // gap is not significant and the answer is `none`).
    let min_poses = 6;
    if acc.poses.len() < min_poses {
        return Err(err(format!(
            "{}: {} static poses found, diagnose needs at least {min_poses}",
            table.file,
            acc.poses.len()
        )));
    }
    let poses = acc.spans.iter().map(|s| pose_data(table, s.first_row, s.last_row + 1, rate)).collect();
    Ok((acc.poses, poses, rate))
}

/// White variance per axis: the median within-pose variance (quantisation included: a reading
/// rounded to a step `q` adds `q^2 / 12`, which the within-pose variance already holds, and at
/// least that is assumed).
/// Also returns the quantisation floor of a pose mean per axis ([`quantisation_floor`]).
fn white_variance(table: &Table, poses: &[PoseData]) -> Result<(V3, V3), DiagnoseError> {
    let white: V3 = std::array::from_fn(|a| median(&poses.iter().map(|p| p.var[a]).collect::<Vec<_>>()));
    let q = quantisation_step(table);
    // Readings that never change within a pose are a quantised sensor whose noise is below one step:
    // the rounding (q^2 / 12) is then the whole noise.
    let measurable = |a: usize| white[a] > 0.0 || q[a] > 0.0;
    if !white.iter().all(|v| v.is_finite()) || !(0..3).any(measurable) {
        return Err(err(format!(
            "{}: the poses show no noise (zero within-pose variance): the gap cannot be measured",
            table.file
        )));
    }
    let floor = std::array::from_fn(|a| quantisation_floor(q[a], white[a]));
    Ok((std::array::from_fn(|a| white[a].max(q[a] * q[a] / 12.0)), floor))
}

/// Variance of a pose mean's quantisation error that averaging does not remove (input unit
/// squared). A reading with Gaussian noise `sigma` rounded to a step `q` is biased by a periodic
/// function of its true value; over a uniformly placed true value its variance is
/// `sum_k q^2 / (2 pi^2 k^2) exp(-4 pi^2 k^2 sigma^2 / q^2)`: `q^2 / 12` for a noise well below one
/// step (the mean is stuck at a level), vanishing once `sigma` exceeds about `q / 2` (dither).
/// `sigma^2` is the measured variance less the rounding's own `q^2 / 12`.
pub(crate) fn quantisation_floor(q: f64, measured_variance: f64) -> f64 {
    if q <= 0.0 || !q.is_finite() {
        return 0.0;
    }
    let sigma_sq = (measured_variance - q * q / 12.0).max(0.0);
    let pi_sq = std::f64::consts::PI * std::f64::consts::PI;
    (1..=32)
        .map(|k| {
            let k_sq = f64::from(k * k);
            q * q / (2.0 * pi_sq * k_sq) * (-4.0 * pi_sq * k_sq * sigma_sq / (q * q)).exp()
        })
        .sum()
}

/// The smallest non-zero difference between consecutive readings per axis (the quantisation step
/// when the readings are quantised), input unit.
pub(crate) fn quantisation_step(table: &Table) -> V3 {
    std::array::from_fn(|a| {
        let step = table
            .samples
            .windows(2)
            .map(|w| (w[1][a] - w[0][a]).abs())
            .filter(|d| *d > 0.0)
            .fold(f64::INFINITY, f64::min);
        if step.is_finite() { step } else { 0.0 }
    })
}

/// Step 1: the library's nominal fit and the simulated experiment.
pub(crate) fn measure(table: &Table, opts: &DiagnoseOptions) -> Result<Measured, DiagnoseError> {
    let gravity = opts.gravity;
    let (lib_poses, poses, rate) = read_poses(table)?;
    let config = CalibrationConfig { gravity: gravity as f32, ..CalibrationConfig::DEFAULT };
    let cal = calib::run(&lib_poses, &config, opts.seed).map_err(|e| err(format!("{}: {e}", table.file)))?;
    let model = Model::from_params(&cal.params);
    let means: Vec<V3> = poses.iter().map(|p| p.mean).collect();
    let calibrated: Vec<V3> = means.iter().map(|m| model.apply(*m)).collect();
    let directions: Vec<V3> = calibrated.iter().map(|f| f.map(|c| c / norm(*f))).collect();
    let r = residuals(&model, &means, gravity);
    let (white, quantisation) = white_variance(table, &poses)?;
    let white_noise = Noise { white, walk: [0.0; 3], floor: quantisation };
    let sims = simulate_gap(&model, &directions, &poses, &white_noise, gravity, opts.repeats, opts.seed);
    if sims.len() < 2 {
        return Err(err(format!("{}: the simulated experiment could not be calibrated", table.file)));
    }
    let gap = gap_before(rms(&r) / gravity * 1000.0, &sims);
    Ok(Measured {
        rate,
        poses,
        params: cal.params,
        model,
        calibrated,
        directions,
        r,
        white,
        quantisation,
        sims,
        gap,
        gravity,
    })
}

/// The gap of the nominal model (the "after" fields equal to "before" until a verdict).
fn gap_before(real_rmse_mg: f64, sims: &[f64]) -> Gap {
    let (sim_rmse_mg, sim_spread_mg) = (mean(sims), std_dev(sims));
    let ratio_before = real_rmse_mg / sim_rmse_mg;
    let z = (real_rmse_mg - sim_rmse_mg) / sim_spread_mg.max(1e-12);
    Gap {
        real_rmse_mg,
        sim_rmse_mg,
        sim_spread_mg,
        z,
        significant: z >= SIGNIFICANT_Z && ratio_before >= SIGNIFICANT_RATIO,
        ratio_before,
        real_rmse_after_mg: real_rmse_mg,
        sim_rmse_after_mg: sim_rmse_mg,
        ratio_after: ratio_before,
    }
}
