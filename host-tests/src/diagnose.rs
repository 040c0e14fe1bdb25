//! `accelcal diagnose`: why a calibration leaves more residual than the noise explains, and which
//! physical effect the 9-parameter model leaves out.
//!
//! 1. **The gap.** The library fits the nominal 9-parameter model ([`calib::run`], TAGA+LM). The same
//!    experiment (the fitted orientations, sample counts, durations and the white noise measured
//!    within the poses) is simulated `repeats` times and refitted by the library (LM); the gap is
//!    the real modulus RMSE over the mean simulated RMSE (1 = no gap), significant when the real RMSE
//!    is at least [`SIGNIFICANT_Z`] simulated standard deviations above the simulated mean.
//! 2. **Where it lies.** Residual per pose and per orientation, against time and temperature, within
//!    each pose (first third against last third), and in the noise (Allan deviation of the longest
//!    rest against white noise).
//! 3. **Which effect.** Each candidate is a physical augmentation, fitted in `f64` by linear least
//!    squares around the library's solution (the modulus residual linearised in the 9 parameters plus
//!    the effect's parameters), or a noise model fitted on other data than the pose means. Each is
//!    judged by `folds`-fold cross-validation over the poses: the mean-square residual of the
//!    withheld poses, plus [`PARAMETER_PENALTY`] expected noise variances per extra parameter, over
//!    what white noise predicts for the nominal model (the noise model's prediction for
//!    `colored-noise`). `heldout_gain = 1 - ln(ratio) / ln(nominal ratio)` is the fraction of the
//!    withheld gap (in log ratio) the candidate removes; a ratio below 1 (more scatter predicted
//!    than seen) counts [`OVERSHOOT_WEIGHT`] times its `|ln ratio|`.
//!    The verdict is the candidate with the largest gain, if the gap is significant and the gain is
//!    at least [`MIN_GAIN`]; `none` otherwise.
//! 4. **How far it shrinks.** The winner is added (to the model, or to the simulator for
//!    `colored-noise`) and step 1 redone: `shrink = (before - after) / (before - 1)`, clipped to
//!    `[0, 1]`.
//!
//! The candidates:
//! - `drift`: bias `c (1 - exp(-t / tau))` per axis, `tau` from a grid (or linear in time);
//! - `temperature`: bias, relative scale, or both, linear in the measured temperature;
//! - `scale-nonlinearity`: `k2 a^2` per axis;
//! - `settling`: a transient proportional to the change from the previous pose, decaying over
//!   `tau` from the start of each pose, or the transient measured in each pose (its mean minus the
//!   mean of its last half) scaled per axis or by one factor;
//! - `motion`: poses whose own samples move slowly (chi-square of segment means after the first,
//!   above 6 times the median pose's and 40) are dropped, each at the cost of an expected noise
//!   variance plus the penalty;
//! - `colored-noise`: a bias random walk or a bias-instability floor (whichever fits the Allan
//!   variance better) measured on the longest rest (detrended quadratically in time and linearly in
//!   temperature, overlapping Allan variance in excess of white noise); the simulator gets it.
//!
//! ```
//! use accelcal_host::diagnose::{diagnose, DiagnoseOptions};
//! use accelcal_host::effects::{generate, random_scenario, to_table, EffectClass};
//! let log = generate(&random_scenario(EffectClass::ScaleNonlinearity, 4));
//! let table = to_table(&log, "sim").unwrap();
//! let report = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
//! assert!(report.gap.ratio_before > 1.0);
//! ```

use std::fmt;
use std::path::Path;

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, Method};
use accelcal::model::{PARAM_COUNT, Params};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;
use serde_json::{Value, json};

use crate::calib;
use crate::csvio::{self, AccumulateOptions, Table};
use crate::effects::gaussian;
use crate::plots::{Series, line_chart};

/// The candidate effects, in report order.
pub const EFFECT_NAMES: [&str; 6] =
    ["drift", "temperature", "scale-nonlinearity", "settling", "motion", "colored-noise"];

/// A gap is significant when the real RMSE exceeds the simulated mean by this many simulated
/// standard deviations (and by [`SIGNIFICANT_RATIO`]).
pub const SIGNIFICANT_Z: f64 = 3.0;

/// ... and when the ratio is at least this.
pub const SIGNIFICANT_RATIO: f64 = 1.2;

/// Expected noise variances charged per extra parameter in the held-out score (AIC-like).
pub const PARAMETER_PENALTY: f64 = 2.0;

/// Weight of a held-out ratio below 1 (the candidate predicts more scatter than the withheld poses
/// show) relative to one above 1, in the gain.
pub const OVERSHOOT_WEIGHT: f64 = 2.0;

/// Smallest held-out gain for a candidate to be named.
pub const MIN_GAIN: f64 = 0.3;

/// Excess of the longest rest's Allan variance over white noise (at its longest `tau`, in units of
/// the white variance) below which no random walk is fitted.
pub const WALK_EXCESS: f64 = 1.0;

/// Pure-noise draws averaged for the expected cross-validated residual.
const CV_NOISE_DRAWS: usize = 20;

/// Segments each pose is split into for the within-pose statistics.
const SEGMENTS: usize = 6;

/// Diagnosis settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiagnoseOptions {
    /// Local gravity, m/s^2 (the calibration's target). Defaults to 9.80665.
    pub gravity: f64,
    /// Seed of the GA and of every simulation. Defaults to 1.
    pub seed: u64,
    /// Simulated repeats of the experiment. Defaults to 30.
    pub repeats: usize,
    /// Cross-validation folds. Defaults to 5.
    pub folds: usize,
}

impl DiagnoseOptions {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { gravity: 9.806_65, seed: 1, repeats: 30, folds: 5 };
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why a diagnosis could not run (bad input).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagnoseError(pub String);

impl fmt::Display for DiagnoseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for DiagnoseError {}

fn err(msg: impl Into<String>) -> DiagnoseError {
    DiagnoseError(msg.into())
}

// ---------------------------------------------------------------------------------------------
// Report types
// ---------------------------------------------------------------------------------------------

/// Step 1 and 4: the gap before and after the winning effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// Real modulus RMSE of the nominal fit, mg.
    pub real_rmse_mg: f64,
    /// Mean simulated RMSE, mg.
    pub sim_rmse_mg: f64,
    /// Standard deviation of the simulated RMSE over the repeats, mg.
    pub sim_spread_mg: f64,
    /// `(real - sim) / spread`.
    pub z: f64,
    /// See [`SIGNIFICANT_Z`].
    pub significant: bool,
    /// `real / sim` with the nominal model.
    pub ratio_before: f64,
    /// Real RMSE after adding the winning effect, mg.
    pub real_rmse_after_mg: f64,
    /// Simulated RMSE after adding the winning effect, mg.
    pub sim_rmse_after_mg: f64,
    /// `real / sim` after adding the winning effect (= before for `none`).
    pub ratio_after: f64,
}

/// One pose in the report.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseReport {
    /// Mid time, s.
    pub t_mid_s: f64,
    /// Static duration, s.
    pub duration_s: f64,
    /// Mean temperature, deg C.
    pub temp_c: Option<f64>,
    /// Calibrated unit direction (sensor axes).
    pub direction: [f64; 3],
    /// Modulus residual of the nominal fit, mg.
    pub residual_mg: f64,
    /// Its white-noise standard deviation, mg.
    pub expected_mg: f64,
    /// Modulus residual after the winning effect, mg (`None` for a pose it drops).
    pub residual_after_mg: Option<f64>,
    /// Modulus of the last-third mean minus that of the first third, mg.
    pub early_late_mg: f64,
    /// Chi-square of the within-pose segment means (white noise: about 12).
    pub within_chi2: f64,
}

/// Allan deviation of the longest rest.
#[derive(Debug, Clone, PartialEq)]
pub struct Allan {
    /// Duration of the longest rest, s.
    pub rest_s: f64,
    /// Cluster times, s.
    pub tau_s: Vec<f64>,
    /// Allan deviation (RMS over the axes), mg.
    pub adev_mg: Vec<f64>,
    /// White-noise prediction, mg.
    pub white_mg: Vec<f64>,
}

/// One candidate's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Effect name (see [`EFFECT_NAMES`]).
    pub effect: &'static str,
    /// `false` when the data cannot test it (e.g. no temperature column).
    pub applicable: bool,
    /// Withheld-pose ratio (penalised), 1 = fully explained.
    pub heldout_ratio: f64,
    /// `1 - ln(heldout_ratio) / ln(nominal heldout ratio)` (a ratio below 1 weighted by
    /// [`OVERSHOOT_WEIGHT`]).
    pub heldout_gain: f64,
    /// The gap ratio with this effect added.
    pub ratio_after: f64,
    /// Extra parameters.
    pub extra_params: usize,
    /// The chosen variant (time constant, bias/scale, dropped poses, walk).
    pub detail: String,
}

/// The whole diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    /// The file (as named in the table).
    pub file: String,
    /// Rows read.
    pub samples: usize,
    /// Units of the readings.
    pub units: String,
    /// Calibration gravity, m/s^2.
    pub gravity: f64,
    /// Seed used.
    pub seed: u64,
    /// Simulated repeats of the experiment.
    pub repeats: usize,
    /// The library's nominal parameters.
    pub params: Params,
    /// White noise per axis, mg (median within-pose standard deviation).
    pub white_mg: [f64; 3],
    /// Step 1 / 4.
    pub gap: Gap,
    /// Step 2: per pose.
    pub poses: Vec<PoseReport>,
    /// Step 2: noise.
    pub allan: Allan,
    /// Step 3.
    pub candidates: Vec<Candidate>,
    /// Held-out ratio of the nominal model.
    pub heldout_ratio_nominal: f64,
    /// Step 3 verdict: an [`EFFECT_NAMES`] entry or `none`.
    pub verdict: &'static str,
    /// `true` when the gap is significant and a candidate explains it (gain >= [`MIN_GAIN`]).
    pub explained: bool,
    /// Step 4.
    pub shrink: f64,
}

// ---------------------------------------------------------------------------------------------
// Small f64 helpers
// ---------------------------------------------------------------------------------------------

type V3 = [f64; 3];

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 }
}

fn rms(v: &[f64]) -> f64 {
    if v.is_empty() { f64::NAN } else { (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt() }
}

fn std_dev(v: &[f64]) -> f64 {
    let m = mean(v);
    if v.len() < 2 { 0.0 } else { (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt() }
}

fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    if s.is_empty() {
        return f64::NAN;
    }
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) }
}

fn correlation(x: &[f64], y: &[f64]) -> Option<f64> {
    let (mx, my) = (mean(x), mean(y));
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let syy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// The 9-parameter model in `f64`: `f = Ka m - B`.
#[derive(Debug, Clone, Copy)]
struct Model {
    ka: [[f64; 3]; 3],
    bias: V3,
}

impl Model {
    fn from_params(p: &Params) -> Self {
        let (s, m) = (p.scale.map(f64::from), p.nonorth.map(f64::from));
        Self { ka: [[s[0], 0.0, 0.0], [m[0], s[1], 0.0], [m[1], m[2], s[2]]], bias: p.bias.map(f64::from) }
    }

    fn apply(&self, m: V3) -> V3 {
        std::array::from_fn(|i| (0..3).map(|j| self.ka[i][j] * m[j]).sum::<f64>() - self.bias[i])
    }

    /// The reading for calibrated `f`: `Ka^-1 (f + B)`.
    fn invert(&self, f: V3) -> V3 {
        let y = [f[0] + self.bias[0], f[1] + self.bias[1], f[2] + self.bias[2]];
        let k = &self.ka;
        let x0 = y[0] / k[0][0];
        let x1 = (y[1] - k[1][0] * x0) / k[1][1];
        let x2 = (y[2] - k[2][0] * x0 - k[2][1] * x1) / k[2][2];
        [x0, x1, x2]
    }

    /// `Ka^T u`: how a reading error (input unit) moves the modulus along `u`.
    fn kt_times(&self, u: V3) -> V3 {
        std::array::from_fn(|j| (0..3).map(|i| self.ka[i][j] * u[i]).sum())
    }
}

/// `d residual / d [B, S, M]` at reading `m` with calibrated direction `u`.
fn jacobian_row(m: V3, u: V3) -> [f64; PARAM_COUNT] {
    [-u[0], -u[1], -u[2], u[0] * m[0], u[1] * m[1], u[2] * m[2], u[1] * m[0], u[2] * m[0], u[2] * m[1]]
}

/// Least squares: the `x` minimising `sum over train of (r_i + rows_i . x)^2` (columns scaled, a tiny
/// ridge keeps collinear columns finite).
fn lstsq(rows: &[Vec<f64>], r: &[f64], train: &[usize]) -> Option<Vec<f64>> {
    let p = rows.first()?.len();
    if train.len() < p {
        return None;
    }
    let scale: Vec<f64> = (0..p)
        .map(|j| {
            let s = (train.iter().map(|&i| rows[i][j] * rows[i][j]).sum::<f64>() / train.len() as f64).sqrt();
            if s > 0.0 && s.is_finite() { s } else { 1.0 }
        })
        .collect();
    let mut a = vec![vec![0.0; p]; p];
    let mut b = vec![0.0; p];
    for &i in train {
        for j in 0..p {
            let xj = rows[i][j] / scale[j];
            b[j] -= xj * r[i];
            for k in 0..=j {
                a[j][k] += xj * rows[i][k] / scale[k];
            }
        }
    }
    let trace: f64 = (0..p).map(|j| a[j][j]).sum();
    let mut ridge = 1e-11 * trace / p as f64;
    for _ in 0..6 {
        if let Some(y) = cholesky_solve(&a, &b, ridge) {
            return Some(y.iter().zip(&scale).map(|(v, s)| v / s).collect());
        }
        ridge = ridge * 100.0 + 1e-300;
    }
    None
}

fn cholesky_solve(a: &[Vec<f64>], b: &[f64], ridge: f64) -> Option<Vec<f64>> {
    let p = b.len();
    let mut l = vec![vec![0.0; p]; p];
    for i in 0..p {
        for j in 0..=i {
            let mut s = a[i][j] + if i == j { ridge } else { 0.0 };
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0) {
                    return None;
                }
                l[i][i] = s.sqrt();
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut y = vec![0.0; p];
    for i in 0..p {
        y[i] = (b[i] - (0..i).map(|k| l[i][k] * y[k]).sum::<f64>()) / l[i][i];
    }
    let mut x = vec![0.0; p];
    for i in (0..p).rev() {
        x[i] = (y[i] - (i + 1..p).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

fn predict(rows: &[Vec<f64>], r: &[f64], x: &[f64], i: usize) -> f64 {
    r[i] + rows[i].iter().zip(x).map(|(a, b)| a * b).sum::<f64>()
}

/// Cross-validated residuals: pose `i` predicted by the fit on the other folds; `None` for dropped
/// poses (and everywhere when a fold leaves too few poses).
fn cv_residuals(
    rows: &[Vec<f64>],
    r: &[f64],
    fold: &[usize],
    folds: usize,
    dropped: &[bool],
) -> Option<Vec<Option<f64>>> {
    let n = r.len();
    let mut out = vec![None; n];
    for f in 0..folds {
        let train: Vec<usize> = (0..n).filter(|&i| fold[i] != f && !dropped[i]).collect();
        if !(0..n).any(|i| fold[i] == f) {
            continue;
        }
        let x = lstsq(rows, r, &train)?;
        for i in (0..n).filter(|&i| fold[i] == f && !dropped[i]) {
            out[i] = Some(predict(rows, r, &x, i));
        }
    }
    Some(out)
}

/// In-sample residuals of the fit on the kept poses (`None` for dropped ones).
fn fit_residuals(rows: &[Vec<f64>], r: &[f64], dropped: &[bool]) -> Option<Vec<Option<f64>>> {
    let train: Vec<usize> = (0..r.len()).filter(|&i| !dropped[i]).collect();
    let x = lstsq(rows, r, &train)?;
    Some((0..r.len()).map(|i| (!dropped[i]).then(|| predict(rows, r, &x, i))).collect())
}

fn sum_sq(v: &[Option<f64>]) -> (f64, usize) {
    v.iter().flatten().fold((0.0, 0), |(s, n), x| (s + x * x, n + 1))
}

// ---------------------------------------------------------------------------------------------
// Pose data
// ---------------------------------------------------------------------------------------------

/// One pose's statistics from its own samples (input unit).
#[derive(Debug, Clone)]
struct PoseData {
    mean: V3,
    var: V3,
    n: usize,
    t_start: f64,
    t_end: f64,
    temp: Option<f64>,
    seg: [V3; SEGMENTS],
    seg_n: usize,
}

impl PoseData {
    fn t_mid(&self) -> f64 {
        0.5 * (self.t_start + self.t_end)
    }
    fn duration(&self) -> f64 {
        (self.t_end - self.t_start).max(0.0)
    }
}

fn row_time(table: &Table, row: usize, rate: f64) -> f64 {
    table.times_s.as_ref().map_or(row as f64 / rate, |t| t[row])
}

/// Statistics of rows `first..end`.
fn pose_data(table: &Table, first: usize, end: usize, rate: f64) -> PoseData {
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
    }
}

// ---------------------------------------------------------------------------------------------
// Noise model and simulation
// ---------------------------------------------------------------------------------------------

/// Noise per axis in the input unit: white variance per sample, random-walk variance per second and
/// a bias-instability floor (variance of every pose mean, independent between poses).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Noise {
    white: V3,
    walk: V3,
    floor: V3,
}

/// One draw of the pose-mean noise (input unit) for every pose: white over `n`, plus the random walk
/// at the pose mid times (and its averaging within the pose).
fn draw_noise(poses: &[PoseData], noise: &Noise, rng: &mut Xoshiro256PlusPlus) -> Vec<V3> {
    let mut walk = [0.0; 3];
    let mut last_t = 0.0;
    poses
        .iter()
        .map(|p| {
            let t = p.t_mid();
            let dt = (t - last_t).max(0.0);
            last_t = t;
            std::array::from_fn(|a| {
                walk[a] += (noise.walk[a] * dt).sqrt() * gaussian(rng);
                let within = noise.walk[a] * p.duration() / 12.0;
                walk[a] + (noise.white[a] / p.n as f64 + within + noise.floor[a]).sqrt() * gaussian(rng)
            })
        })
        .collect()
}

/// The modulus residuals (output unit) of `means` under `model`.
fn residuals(model: &Model, means: &[V3], gravity: f64) -> Vec<f64> {
    means.iter().map(|m| norm(model.apply(*m)) - gravity).collect()
}

/// Step 1's simulation: the fitted experiment with `noise`, refitted by the library (LM); the RMSE
/// of each repeat, mg.
fn simulate_gap(
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
fn residual_noise_draws(
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
fn expected_cv_ms(rows: &[Vec<f64>], draws: &[Vec<f64>], fold: &[usize], folds: usize, dropped: &[bool]) -> f64 {
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
fn expected_fit_rmse_mg(rows: &[Vec<f64>], draws: &[Vec<f64>], dropped: &[bool], gravity: f64) -> f64 {
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

// ---------------------------------------------------------------------------------------------
// Allan deviation
// ---------------------------------------------------------------------------------------------

fn allan(table: &Table, first: usize, end: usize, rate: f64, scale: V3, white: V3, gravity: f64) -> Allan {
    let rows = &table.samples[first..end];
    let n = rows.len();
    let to_mg = |v: f64| v / gravity * 1000.0;
    let mut out = Allan { rest_s: n as f64 / rate, tau_s: Vec::new(), adev_mg: Vec::new(), white_mg: Vec::new() };
    let mut m = 1usize;
    while n / m >= 8 {
        let clusters = n / m;
        let mut avar = 0.0f64;
        let mut white_var = 0.0f64;
        for a in 0..3 {
            let means: Vec<f64> =
                (0..clusters).map(|k| rows[k * m..(k + 1) * m].iter().map(|s| s[a]).sum::<f64>() / m as f64).collect();
            let d: f64 = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (2 * (clusters - 1)) as f64;
            avar += d * scale[a] * scale[a] / 3.0;
            white_var += white[a] * scale[a] * scale[a] / m as f64 / 3.0;
        }
        out.tau_s.push(m as f64 / rate);
        out.adev_mg.push(to_mg(avar.sqrt()));
        out.white_mg.push(to_mg(white_var.sqrt()));
        m *= 2;
    }
    out
}

// ---------------------------------------------------------------------------------------------
// The diagnosis
// ---------------------------------------------------------------------------------------------

struct Context<'a> {
    model: Model,
    gravity: f64,
    poses: &'a [PoseData],
    calibrated: Vec<V3>,
    directions: Vec<V3>,
    r: Vec<f64>,
    base_rows: Vec<Vec<f64>>,
    fold: Vec<usize>,
    folds: usize,
    white_draws: Vec<Vec<f64>>,
    e_white: f64,
    none_dropped: Vec<bool>,
}

/// A model-type candidate's best variant.
struct Fitted {
    rows: Vec<Vec<f64>>,
    dropped: Vec<bool>,
    score_ratio: f64,
    k: usize,
    detail: String,
}

impl Context<'_> {
    fn rows_with(&self, extra: &[Vec<f64>]) -> Vec<Vec<f64>> {
        self.base_rows.iter().zip(extra).map(|(b, e)| b.iter().chain(e).copied().collect()).collect()
    }

    /// Penalised held-out ratio of a design (`k` extra parameters, some poses dropped).
    fn heldout_ratio(&self, rows: &[Vec<f64>], dropped: &[bool], k: usize) -> Option<f64> {
        let n = self.r.len() as f64;
        let cv = cv_residuals(rows, &self.r, &self.fold, self.folds, dropped)?;
        let (ss, _) = sum_sq(&cv);
        let n_dropped = dropped.iter().filter(|d| **d).count() as f64;
        // Against the nominal model's expectation: a design that merely predicts noisily (and so
        // expects more) must not look better for it; the penalty charges the extra parameters.
        let ms = (ss + (n_dropped + PARAMETER_PENALTY * k as f64) * self.e_white) / n;
        Some((ms / self.e_white).sqrt())
    }

    fn best_of(&self, variants: Vec<(Vec<Vec<f64>>, usize, String)>) -> Option<Fitted> {
        let mut best: Option<Fitted> = None;
        for (extra, k, detail) in variants {
            let rows = self.rows_with(&extra);
            let dropped = self.none_dropped.clone();
            if let Some(ratio) = self.heldout_ratio(&rows, &dropped, k)
                && best.as_ref().is_none_or(|b| ratio < b.score_ratio)
            {
                best = Some(Fitted { rows, dropped, score_ratio: ratio, k, detail });
            }
        }
        best
    }
}

/// Runs the whole diagnosis on a table of raw samples.
pub fn diagnose(table: &Table, opts: &DiagnoseOptions) -> Result<Diagnosis, DiagnoseError> {
    let gravity = opts.gravity;
    if !(gravity.is_finite() && gravity > 0.0) {
        return Err(err(format!("gravity {gravity} must be a positive number of m/s^2")));
    }
    if opts.folds < 2 || opts.repeats < 2 {
        return Err(err("diagnose needs at least 2 folds and 2 repeats"));
    }
    let acc =
        csvio::accumulate(table, &AccumulateOptions::default()).map_err(|e| err(format!("{}: {e}", table.file)))?;
    let rate = acc.sample_rate_hz.or_else(|| table.sample_rate_hz()).filter(|r| *r > 0.0).unwrap_or(1.0);
    let min_poses = PARAM_COUNT + 3;
    if acc.poses.len() < min_poses {
        return Err(err(format!(
            "{}: {} static poses found, diagnose needs at least {min_poses}",
            table.file,
            acc.poses.len()
        )));
    }
    let poses: Vec<PoseData> = acc.spans.iter().map(|s| pose_data(table, s.first_row, s.last_row + 1, rate)).collect();

    // Step 1: the library's nominal fit.
    let config = CalibrationConfig { gravity: gravity as f32, ..CalibrationConfig::DEFAULT };
    let cal = calib::run(&acc.poses, &config, opts.seed).map_err(|e| err(format!("{}: {e}", table.file)))?;
    let model = Model::from_params(&cal.params);
    let means: Vec<V3> = poses.iter().map(|p| p.mean).collect();
    let calibrated: Vec<V3> = means.iter().map(|m| model.apply(*m)).collect();
    let directions: Vec<V3> = calibrated.iter().map(|f| f.map(|c| c / norm(*f))).collect();
    let r = residuals(&model, &means, gravity);
    let to_mg = |v: f64| v / gravity * 1000.0;
    let real_rmse_mg = to_mg(rms(&r));
    let white: V3 = std::array::from_fn(|a| median(&poses.iter().map(|p| p.var[a]).collect::<Vec<_>>()));
    if !white.iter().all(|v| v.is_finite()) || white.iter().all(|v| *v <= 0.0) {
        return Err(err(format!(
            "{}: the poses show no noise (zero within-pose variance): the gap cannot be measured",
            table.file
        )));
    }
    let white_noise = Noise { white, walk: [0.0; 3], floor: [0.0; 3] };
    let sims = simulate_gap(&model, &directions, &poses, &white_noise, gravity, opts.repeats, opts.seed);
    if sims.len() < 2 {
        return Err(err(format!("{}: the simulated experiment could not be calibrated", table.file)));
    }
    let (sim_rmse_mg, sim_spread_mg) = (mean(&sims), std_dev(&sims));
    let ratio_before = real_rmse_mg / sim_rmse_mg;
    let z = (real_rmse_mg - sim_rmse_mg) / sim_spread_mg.max(1e-12);
    let significant = z >= SIGNIFICANT_Z && ratio_before >= SIGNIFICANT_RATIO;

    // Cross-validation set-up.
    let n = poses.len();
    let folds = opts.folds.min(n);
    let mut order: Vec<usize> = (0..n).collect();
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(opts.seed ^ 0xF01D);
    for i in (1..n).rev() {
        let j = (rand_core::Rng::next_u64(&mut rng) % (i as u64 + 1)) as usize;
        order.swap(i, j);
    }
    let mut fold = vec![0; n];
    for (rank, &i) in order.iter().enumerate() {
        fold[i] = rank % folds;
    }
    let base_rows: Vec<Vec<f64>> = means.iter().zip(&directions).map(|(m, u)| jacobian_row(*m, *u).to_vec()).collect();
    let white_draws = residual_noise_draws(&model, &directions, &poses, &white_noise, CV_NOISE_DRAWS, opts.seed);
    let none_dropped = vec![false; n];
    let e_white = expected_cv_ms(&base_rows, &white_draws, &fold, folds, &none_dropped);
    let ctx = Context {
        model,
        gravity,
        poses: &poses,
        calibrated,
        directions,
        r,
        base_rows,
        fold,
        folds,
        white_draws,
        e_white,
        none_dropped,
    };
    let nominal_cv = cv_residuals(&ctx.base_rows, &ctx.r, &ctx.fold, folds, &ctx.none_dropped)
        .ok_or_else(|| err(format!("{}: too few poses for cross-validation", table.file)))?;
    let heldout_ratio_nominal = ((sum_sq(&nominal_cv).0 / n as f64) / e_white).sqrt();
    let base_fit_rmse = expected_fit_rmse_mg(&ctx.base_rows, &ctx.white_draws, &ctx.none_dropped, gravity);

    // Step 3: the candidates.
    let gain = |ratio: f64| {
        let before = heldout_ratio_nominal.ln().abs();
        // Predicting more scatter than there is counts double: it would "explain" any gap.
        let miss = if ratio >= 1.0 { ratio.ln() } else { OVERSHOOT_WEIGHT * ratio.ln().abs() };
        if before > 0.0 { 1.0 - miss / before } else { 0.0 }
    };
    let mut candidates = Vec::new();
    let mut after_residuals: Vec<Vec<Option<f64>>> = Vec::new();
    for name in EFFECT_NAMES {
        let fitted = match name {
            "drift" => ctx.best_of(drift_variants(&ctx)),
            "temperature" => ctx.best_of(temperature_variants(&ctx)),
            "scale-nonlinearity" => ctx.best_of(nonlinearity_variants(&ctx)),
            "settling" => ctx.best_of(settling_variants(&ctx)),
            "motion" => motion_candidate(&ctx),
            _ => None,
        };
        let candidate = if name == "colored-noise" {
            let longest = (0..n).max_by_key(|&i| poses[i].n).unwrap_or(0);
            let span = &acc.spans[longest];
            let (walk, floor) = colored_noise_estimate(table, span.first_row, span.last_row + 1, rate, white);
            let noise = Noise { white, walk, floor };
            let applicable = walk.iter().chain(&floor).any(|w| *w > 0.0);
            let draws = residual_noise_draws(&ctx.model, &ctx.directions, &poses, &noise, CV_NOISE_DRAWS, opts.seed);
            let e_col = expected_cv_ms(&ctx.base_rows, &draws, &ctx.fold, folds, &ctx.none_dropped);
            let ms = sum_sq(&nominal_cv).0 / n as f64 + PARAMETER_PENALTY * ctx.e_white / n as f64;
            let heldout_ratio = if applicable { (ms / e_col).sqrt() } else { heldout_ratio_nominal };
            let sims_after = if applicable {
                simulate_gap(&ctx.model, &ctx.directions, &poses, &noise, gravity, opts.repeats, opts.seed)
            } else {
                sims.clone()
            };
            let scale: V3 = std::array::from_fn(|a| ctx.model.ka[a][a]);
            after_residuals.push(ctx.r.iter().map(|v| Some(*v)).collect());
            Candidate {
                effect: name,
                applicable,
                heldout_ratio,
                heldout_gain: if applicable { gain(heldout_ratio) } else { 0.0 },
                ratio_after: real_rmse_mg / mean(&sims_after),
                extra_params: 1,
                detail: format!(
                    "random walk {:.3}/{:.3}/{:.3} mg/sqrt(s), bias instability {:.3}/{:.3}/{:.3} mg",
                    to_mg(walk[0].sqrt() * scale[0]),
                    to_mg(walk[1].sqrt() * scale[1]),
                    to_mg(walk[2].sqrt() * scale[2]),
                    to_mg(floor[0].sqrt() * scale[0]),
                    to_mg(floor[1].sqrt() * scale[1]),
                    to_mg(floor[2].sqrt() * scale[2])
                ),
            }
        } else if let Some(f) = fitted {
            let res = fit_residuals(&f.rows, &ctx.r, &f.dropped).unwrap_or_else(|| vec![None; n]);
            let kept: Vec<f64> = res.iter().flatten().copied().collect();
            let real_after = to_mg(rms(&kept));
            let sim_after = expected_fit_rmse_mg(&f.rows, &ctx.white_draws, &f.dropped, gravity);
            // The linearised sims and the library's differ slightly: scale to the library's.
            let sim_after = sim_after * sim_rmse_mg / base_fit_rmse;
            after_residuals.push(res);
            Candidate {
                effect: name,
                applicable: true,
                heldout_ratio: f.score_ratio,
                heldout_gain: gain(f.score_ratio),
                ratio_after: real_after / sim_after,
                extra_params: f.k,
                detail: f.detail,
            }
        } else {
            after_residuals.push(ctx.r.iter().map(|v| Some(*v)).collect());
            Candidate {
                effect: name,
                applicable: false,
                heldout_ratio: heldout_ratio_nominal,
                heldout_gain: 0.0,
                ratio_after: ratio_before,
                extra_params: 0,
                detail: "not testable on this data".into(),
            }
        };
        candidates.push(candidate);
    }

    // Verdict and step 4.
    let best = candidates
        .iter()
        .enumerate()
        .filter(|(_, c)| c.applicable && c.heldout_gain.is_finite())
        .max_by(|a, b| a.1.heldout_gain.total_cmp(&b.1.heldout_gain));
    let winner = best.filter(|(_, c)| significant && c.heldout_gain >= MIN_GAIN).map(|(i, _)| i);
    let (verdict, ratio_after, after) = match winner {
        Some(i) => (candidates[i].effect, candidates[i].ratio_after, after_residuals[i].clone()),
        None => ("none", ratio_before, ctx.r.iter().map(|v| Some(*v)).collect()),
    };
    let shrink = if significant && ratio_before > 1.0 {
        ((ratio_before - ratio_after) / (ratio_before - 1.0)).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let real_rmse_after_mg = match winner {
        Some(i) if candidates[i].effect != "colored-noise" => {
            to_mg(rms(&after.iter().flatten().copied().collect::<Vec<_>>()))
        }
        _ => real_rmse_mg,
    };

    // Step 2: where.
    let pose_reports: Vec<PoseReport> = (0..n)
        .map(|i| {
            let p = &poses[i];
            let kt = ctx.model.kt_times(ctx.directions[i]);
            let expected = (0..3).map(|a| kt[a] * kt[a] * white[a] / p.n as f64).sum::<f64>().sqrt();
            let early = mean_of(&p.seg[0..2]);
            let late = mean_of(&p.seg[SEGMENTS - 2..]);
            let early_late = norm(ctx.model.apply(late)) - norm(ctx.model.apply(early));
            PoseReport {
                t_mid_s: p.t_mid(),
                duration_s: p.duration(),
                temp_c: p.temp,
                direction: ctx.directions[i],
                residual_mg: to_mg(ctx.r[i]),
                expected_mg: to_mg(expected),
                residual_after_mg: after[i].map(to_mg),
                early_late_mg: to_mg(early_late),
                within_chi2: within_chi2(p, &white),
            }
        })
        .collect();
    let longest = (0..n).max_by_key(|&i| poses[i].n).unwrap_or(0);
    let span = &acc.spans[longest];
    let scale: V3 = std::array::from_fn(|a| ctx.model.ka[a][a]);
    let allan = allan(table, span.first_row, span.last_row + 1, rate, scale, white, gravity);
    let sim_rmse_after_mg = if ratio_after > 0.0 { real_rmse_after_mg / ratio_after } else { f64::NAN };

    Ok(Diagnosis {
        file: table.file.clone(),
        samples: table.samples.len(),
        units: table.units.to_string(),
        gravity,
        seed: opts.seed,
        repeats: sims.len(),
        params: cal.params,
        white_mg: std::array::from_fn(|a| to_mg(white[a].sqrt() * scale[a])),
        gap: Gap {
            real_rmse_mg,
            sim_rmse_mg,
            sim_spread_mg,
            z,
            significant,
            ratio_before,
            real_rmse_after_mg,
            sim_rmse_after_mg,
            ratio_after,
        },
        poses: pose_reports,
        allan,
        candidates,
        heldout_ratio_nominal,
        verdict,
        explained: winner.is_some(),
        shrink,
    })
}

fn mean_of(segs: &[V3]) -> V3 {
    std::array::from_fn(|a| segs.iter().map(|s| s[a]).sum::<f64>() / segs.len() as f64)
}

/// Chi-square of segment means 1.. (the first is left out: settling) about their mean, white noise.
fn within_chi2(p: &PoseData, white: &V3) -> f64 {
    if p.seg_n == 0 {
        return 0.0;
    }
    let m = mean_of(&p.seg[1..]);
    let mut chi2 = 0.0;
    for seg in &p.seg[1..] {
        for a in 0..3 {
            if white[a] > 0.0 {
                chi2 += (seg[a] - m[a]).powi(2) / (white[a] / p.seg_n as f64);
            }
        }
    }
    chi2
}

fn drift_variants(ctx: &Context<'_>) -> Vec<(Vec<Vec<f64>>, usize, String)> {
    let t_end = ctx.poses.last().map_or(1.0, PoseData::t_mid).max(1e-9);
    let mut out = Vec::new();
    for factor in [0.05, 0.1, 0.2, 0.4, 0.8, 1.6, f64::INFINITY] {
        let tau = factor * t_end;
        let extra: Vec<Vec<f64>> = ctx
            .poses
            .iter()
            .zip(&ctx.directions)
            .map(|(p, u)| {
                let phi = if tau.is_finite() { 1.0 - (-p.t_mid() / tau).exp() } else { p.t_mid() / t_end };
                u.iter().map(|c| c * phi).collect()
            })
            .collect();
        let detail =
            if tau.is_finite() { format!("bias (1 - exp(-t / {tau:.0} s))") } else { "bias linear in time".into() };
        out.push((extra, 4, detail));
    }
    out
}

fn temperature_variants(ctx: &Context<'_>) -> Vec<(Vec<Vec<f64>>, usize, String)> {
    let temps: Vec<f64> = ctx.poses.iter().filter_map(|p| p.temp).collect();
    if temps.len() != ctx.poses.len() {
        return Vec::new();
    }
    let t0 = mean(&temps);
    if temps.iter().map(|t| (t - t0).abs()).fold(0.0, f64::max) < 0.05 {
        return Vec::new();
    }
    let mut out = Vec::new();
    for (bias, scale, detail) in [
        (true, false, "bias linear in temperature"),
        (false, true, "scale linear in temperature"),
        (true, true, "bias and scale linear in temperature"),
    ] {
        let extra: Vec<Vec<f64>> = temps
            .iter()
            .zip(&ctx.directions)
            .zip(&ctx.calibrated)
            .map(|((t, u), f)| {
                let dt = t - t0;
                let mut row = Vec::new();
                if bias {
                    row.extend(u.iter().map(|c| c * dt));
                }
                if scale {
                    row.extend((0..3).map(|a| u[a] * f[a] * dt));
                }
                row
            })
            .collect();
        let k = 3 * (usize::from(bias) + usize::from(scale));
        out.push((extra, k, detail.to_string()));
    }
    out
}

fn nonlinearity_variants(ctx: &Context<'_>) -> Vec<(Vec<Vec<f64>>, usize, String)> {
    let g2 = ctx.gravity * ctx.gravity;
    let extra = ctx
        .directions
        .iter()
        .zip(&ctx.calibrated)
        .map(|(u, f)| (0..3).map(|a| u[a] * f[a] * f[a] / g2).collect())
        .collect();
    vec![(extra, 3, "k2 a^2 per axis".into())]
}

fn settling_variants(ctx: &Context<'_>) -> Vec<(Vec<Vec<f64>>, usize, String)> {
    let mut out = Vec::new();
    for tau in [0.25, 0.5, 1.0, 2.0, 4.0] {
        let extra = (0..ctx.poses.len())
            .map(|i| {
                let p = &ctx.poses[i];
                let t = p.duration().max(1e-9);
                let w = tau / t * (1.0 - (-t / tau).exp());
                let delta: V3 = if i == 0 {
                    [0.0; 3]
                } else {
                    std::array::from_fn(|a| ctx.calibrated[i - 1][a] - ctx.calibrated[i][a])
                };
                (0..3).map(|a| ctx.directions[i][a] * delta[a] * w).collect()
            })
            .collect();
        out.push((extra, 4, format!("transient toward the previous pose, tau {tau} s")));
    }
    // Measured transients: each pose's mean minus the mean of its last half (where a transient of a
    // few seconds has decayed), scaled per axis or by one factor.
    let transient: Vec<V3> = ctx
        .poses
        .iter()
        .map(|p| {
            let late = mean_of(&p.seg[SEGMENTS / 2..]);
            let d: V3 = std::array::from_fn(|a| p.mean[a] - late[a]);
            std::array::from_fn(|i| (0..3).map(|j| ctx.model.ka[i][j] * d[j]).sum())
        })
        .collect();
    let per_axis =
        (0..ctx.poses.len()).map(|i| (0..3).map(|a| ctx.directions[i][a] * transient[i][a]).collect()).collect();
    out.push((per_axis, 3, "measured transient (pose mean - last half), per axis".into()));
    let common = (0..ctx.poses.len()).map(|i| vec![dot(ctx.directions[i], transient[i])]).collect();
    out.push((common, 1, "measured transient (pose mean - last half)".into()));
    out
}

fn motion_candidate(ctx: &Context<'_>) -> Option<Fitted> {
    let white: V3 = std::array::from_fn(|a| median(&ctx.poses.iter().map(|p| p.var[a]).collect::<Vec<_>>()));
    let chi: Vec<f64> = ctx.poses.iter().map(|p| within_chi2(p, &white)).collect();
    let threshold = (6.0 * median(&chi)).max(40.0);
    let dropped: Vec<bool> = chi.iter().map(|c| *c > threshold).collect();
    let count = dropped.iter().filter(|d| **d).count();
    if count == 0 || ctx.poses.len() - count < PARAM_COUNT + 3 {
        return None;
    }
    let rows = ctx.base_rows.clone();
    let ratio = ctx.heldout_ratio(&rows, &dropped, count)?;
    let list: Vec<String> = dropped.iter().enumerate().filter(|(_, d)| **d).map(|(i, _)| i.to_string()).collect();
    Some(Fitted {
        rows,
        dropped,
        score_ratio: ratio,
        k: count,
        detail: format!("moving poses dropped: {}", list.join(" ")),
    })
}

/// The noise beyond white per axis (input unit), measured on the longest rest (a time segment, not
/// the pose means it is judged on): the rest is detrended (quadratic in time, linear in temperature
/// when there is a temperature column, so warm-up and temperature are not taken for noise), then
/// the excess of its overlapping Allan variance over white noise for `tau` from 1/50 to 1/5 of the
/// rest is fitted as a random walk `K^2 tau / 3` plus a flat bias-instability floor (weighted
/// least squares; when one term comes out negative, the better of the two alone). Returns `(K^2 per s, floor variance)`; both zero when the excess is not at
/// least [`WALK_EXCESS`] times the white noise at the longest `tau`.
fn colored_noise_estimate(table: &Table, first: usize, end: usize, rate: f64, white: V3) -> (V3, V3) {
    let n = end - first;
    let mut walk = [0.0; 3];
    let mut floor = [0.0; 3];
    if n < 200 {
        return (walk, floor);
    }
    let t0 = row_time(table, first, rate);
    let span = (row_time(table, end - 1, rate) - t0).max(1e-9);
    let temps = table.temps_c.as_ref().map(|t| &t[first..end]);
    let t_mean = temps.map_or(0.0, mean);
    let has_temp = temps.is_some_and(|t| t.iter().any(|v| (v - t_mean).abs() > 1e-9));
    let rows: Vec<Vec<f64>> = (first..end)
        .map(|i| {
            let x = 2.0 * (row_time(table, i, rate) - t0) / span - 1.0;
            let mut row = vec![1.0, x, x * x];
            if let (true, Some(t)) = (has_temp, temps) {
                row.push(t[i - first] - t_mean);
            }
            row
        })
        .collect();
    let idx: Vec<usize> = (0..n).collect();
    for a in 0..3 {
        let y: Vec<f64> = table.samples[first..end].iter().map(|s| -s[a]).collect();
        let Some(x) = lstsq(&rows, &y, &idx) else { continue };
        let detrended: Vec<f64> = (0..n).map(|i| -predict(&rows, &y, &x, i)).collect();
        // Prefix sums for the overlapping Allan variance.
        let mut prefix = vec![0.0; n + 1];
        for i in 0..n {
            prefix[i + 1] = prefix[i] + detrended[i];
        }
        let mut points = Vec::new();
        let mut last_excess = 0.0;
        let mut m = ((n as f64 / 50.0) as usize).max(1);
        while 5 * m <= n {
            let tau = m as f64 / rate;
            let count = n - 2 * m + 1;
            let mut sum = 0.0;
            for k in 0..count {
                let first_mean = prefix[k + m] - prefix[k];
                let second_mean = prefix[k + 2 * m] - prefix[k + m];
                sum += (second_mean - first_mean).powi(2);
            }
            let avar = sum / (2.0 * count as f64 * (m * m) as f64);
            let white_avar = white[a] / m as f64;
            let excess = avar - white_avar;
            // Weighted by the number of independent clusters over the relative variance.
            let w = (n as f64 / m as f64) / (avar * avar).max(1e-300);
            points.push((tau, excess, w));
            last_excess = excess / white_avar;
            m *= 2;
        }
        if points.is_empty() || !(last_excess > WALK_EXCESS) {
            continue;
        }
        let sum = |f: &dyn Fn(f64, f64) -> f64| points.iter().map(|&(t, e, w)| w * f(t, e)).sum::<f64>();
        let k2 = (sum(&|t, e| e * t / 3.0) / sum(&|t, _| (t / 3.0).powi(2))).max(0.0);
        let level = (sum(&|_, e| e) / sum(&|_, _| 1.0)).max(0.0);
        // Both terms together when both come out positive, else the better single term.
        let (saa, sab, sbb) = (sum(&|t, _| (t / 3.0).powi(2)), sum(&|t, _| t / 3.0), sum(&|_, _| 1.0));
        let (sea, seb) = (sum(&|t, e| e * t / 3.0), sum(&|_, e| e));
        let det = saa * sbb - sab * sab;
        let joint = (det > 0.0).then(|| ((sea * sbb - seb * sab) / det, (saa * seb - sab * sea) / det));
        match joint {
            Some((k, c)) if k >= 0.0 && c >= 0.0 => {
                walk[a] = k;
                floor[a] = c;
            }
            _ => {
                let misfit_walk = sum(&|t, e| (e - k2 * t / 3.0).powi(2));
                let misfit_floor = sum(&|_, e| (e - level).powi(2));
                if misfit_walk <= misfit_floor {
                    walk[a] = k2;
                } else {
                    floor[a] = level;
                }
            }
        }
    }
    (walk, floor)
}

// ---------------------------------------------------------------------------------------------
// Output
// ---------------------------------------------------------------------------------------------

fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

fn orientation_label(u: V3) -> String {
    let a = (0..3).max_by(|&i, &j| u[i].abs().total_cmp(&u[j].abs())).unwrap_or(2);
    format!("{}{}", if u[a] >= 0.0 { "+" } else { "-" }, ["x", "y", "z"][a])
}

impl Diagnosis {
    fn by_orientation(&self) -> Vec<(String, usize, f64)> {
        let mut out = Vec::new();
        for label in ["+x", "-x", "+y", "-y", "+z", "-z"] {
            let v: Vec<f64> =
                self.poses.iter().filter(|p| orientation_label(p.direction) == label).map(|p| p.residual_mg).collect();
            out.push((label.to_string(), v.len(), rms(&v)));
        }
        out
    }

    fn time_stats(&self) -> (Option<f64>, f64, f64) {
        let t: Vec<f64> = self.poses.iter().map(|p| p.t_mid_s).collect();
        let r: Vec<f64> = self.poses.iter().map(|p| p.residual_mg).collect();
        let half = r.len() / 2;
        (correlation(&t, &r), rms(&r[..half]), rms(&r[half..]))
    }

    fn temperature_stats(&self) -> Option<(Option<f64>, f64, f64)> {
        let temps: Vec<f64> = self.poses.iter().filter_map(|p| p.temp_c).collect();
        if temps.len() != self.poses.len() || temps.is_empty() {
            return None;
        }
        let r: Vec<f64> = self.poses.iter().map(|p| p.residual_mg).collect();
        let lo = temps.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = temps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Some((correlation(&temps, &r), lo, hi))
    }

    fn within_stats(&self) -> (f64, f64) {
        let el: Vec<f64> = self.poses.iter().map(|p| p.early_late_mg).collect();
        // White noise: two thirds of n/3 samples each -> sqrt(2 * 3) * sigma_pose_mean.
        let expected: Vec<f64> = self.poses.iter().map(|p| p.expected_mg * 6f64.sqrt()).collect();
        (rms(&el), rms(&expected))
    }

    /// Step 2 in one line: the share of the squared residual in the three worst poses (and their
    /// orientations), the correlation with time and temperature, the within-pose change over white
    /// noise and the Allan deviation at the longest `tau` over white noise.
    pub fn where_summary(&self) -> String {
        let mut worst: Vec<&PoseReport> = self.poses.iter().collect();
        worst.sort_by(|a, b| b.residual_mg.abs().total_cmp(&a.residual_mg.abs()));
        let total: f64 = self.poses.iter().map(|p| p.residual_mg.powi(2)).sum();
        let top: f64 = worst.iter().take(3).map(|p| p.residual_mg.powi(2)).sum();
        let labels: Vec<String> = worst.iter().take(3).map(|p| orientation_label(p.direction)).collect();
        let (corr_t, _, _) = self.time_stats();
        let mut out = format!("worst 3 poses {:.0} % ({})", 100.0 * top / total.max(1e-300), labels.join(" "));
        if let Some(c) = corr_t {
            out += &format!("; time r {c:+.2}");
        }
        if let Some((Some(c), _, _)) = self.temperature_stats() {
            out += &format!("; temp r {c:+.2}");
        }
        let (within, expected) = self.within_stats();
        out += &format!("; within-pose {:.1}x white", within / expected);
        if let (Some(a), Some(w), Some(t)) =
            (self.allan.adev_mg.last(), self.allan.white_mg.last(), self.allan.tau_s.last())
        {
            out += &format!("; Allan {:.1}x white at {t:.0} s", a / w);
        }
        out
    }

    /// The JSON report.
    pub fn to_json(&self) -> Value {
        let (corr_t, first_half, second_half) = self.time_stats();
        let (within, within_expected) = self.within_stats();
        let allan_ratio = self.allan.adev_mg.last().zip(self.allan.white_mg.last()).map(|(a, w)| a / w);
        let best = self.candidates.iter().find(|c| c.effect == self.verdict);
        json!({
            "file": self.file,
            "samples": self.samples,
            "units": self.units,
            "gravity": self.gravity,
            "seed": self.seed,
            "repeats": self.repeats,
            "poses": self.poses.len(),
            "params": calib::params_json(&self.params),
            "noise": {"white_mg": self.white_mg.map(finite), "longest_rest_s": finite(self.allan.rest_s)},
            "gap": {
                "real_rmse_mg": finite(self.gap.real_rmse_mg),
                "sim_rmse_mg": finite(self.gap.sim_rmse_mg),
                "sim_spread_mg": finite(self.gap.sim_spread_mg),
                "z": finite(self.gap.z),
                "significant": self.gap.significant,
                "ratio_before": finite(self.gap.ratio_before),
                "real_rmse_after_mg": finite(self.gap.real_rmse_after_mg),
                "sim_rmse_after_mg": finite(self.gap.sim_rmse_after_mg),
                "ratio_after": finite(self.gap.ratio_after),
            },
            "where": {
                "per_pose": self.poses.iter().enumerate().map(|(i, p)| json!({
                    "index": i,
                    "t_mid_s": finite(p.t_mid_s),
                    "duration_s": finite(p.duration_s),
                    "temp_c": p.temp_c.map(finite),
                    "orientation": orientation_label(p.direction),
                    "direction": p.direction.map(finite),
                    "residual_mg": finite(p.residual_mg),
                    "expected_mg": finite(p.expected_mg),
                    "residual_after_mg": p.residual_after_mg.map(finite),
                    "early_late_mg": finite(p.early_late_mg),
                    "within_chi2": finite(p.within_chi2),
                })).collect::<Vec<_>>(),
                "by_orientation": self.by_orientation().into_iter().map(|(l, n, r)| json!({"orientation": l, "poses": n, "rms_mg": finite(r)})).collect::<Vec<_>>(),
                "time": {"correlation": corr_t.map(finite), "rms_first_half_mg": finite(first_half), "rms_second_half_mg": finite(second_half)},
                "temperature": self.temperature_stats().map(|(c, lo, hi)| json!({"correlation": c.map(finite), "min_c": finite(lo), "max_c": finite(hi)})),
                "within_pose": {"early_late_rms_mg": finite(within), "white_expected_mg": finite(within_expected), "ratio": finite(within / within_expected)},
                "noise": {
                    "allan_tau_s": self.allan.tau_s,
                    "allan_adev_mg": self.allan.adev_mg.iter().map(|v| finite(*v)).collect::<Vec<_>>(),
                    "allan_white_mg": self.allan.white_mg.iter().map(|v| finite(*v)).collect::<Vec<_>>(),
                    "ratio_at_longest_tau": allan_ratio.map(finite),
                },
            },
            "heldout_ratio_nominal": finite(self.heldout_ratio_nominal),
            "candidates": self.candidates.iter().map(|c| json!({
                "effect": c.effect,
                "applicable": c.applicable,
                "heldout_gain": finite(c.heldout_gain),
                "heldout_ratio": finite(c.heldout_ratio),
                "ratio_after": finite(c.ratio_after),
                "extra_params": c.extra_params,
                "detail": c.detail,
            })).collect::<Vec<_>>(),
            "verdict": {
                "effect": self.verdict,
                "explained": self.explained,
                "heldout_gain": best.map(|c| finite(c.heldout_gain)),
                "shrink": finite(self.shrink),
            },
        })
    }

    /// The human-readable report, one block per step.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let g = &self.gap;
        let _ = writeln!(
            s,
            "{}: {} rows ({}), {} poses, seed {}",
            self.file,
            self.samples,
            self.units,
            self.poses.len(),
            self.seed
        );
        let _ = writeln!(
            s,
            "1. gap: real modulus RMSE {:.4} mg, simulated {:.4} +- {:.4} mg ({} repeats, white noise {:.3}/{:.3}/{:.3} mg): ratio {:.2}, z {:.1} -> {}",
            g.real_rmse_mg,
            g.sim_rmse_mg,
            g.sim_spread_mg,
            self.repeats,
            self.white_mg[0],
            self.white_mg[1],
            self.white_mg[2],
            g.ratio_before,
            g.z,
            if g.significant { "significant" } else { "not significant" }
        );
        let _ = writeln!(s, "2. where:");
        let mut worst: Vec<(usize, &PoseReport)> = self.poses.iter().enumerate().collect();
        worst.sort_by(|a, b| b.1.residual_mg.abs().total_cmp(&a.1.residual_mg.abs()));
        let list: Vec<String> = worst
            .iter()
            .take(5)
            .map(|(i, p)| {
                format!("#{i} {} {:+.3} mg (noise {:.3})", orientation_label(p.direction), p.residual_mg, p.expected_mg)
            })
            .collect();
        let _ = writeln!(s, "   largest residuals: {}", list.join(", "));
        let orient: Vec<String> = self
            .by_orientation()
            .into_iter()
            .filter(|(_, n, _)| *n > 0)
            .map(|(l, n, r)| format!("{l} {r:.3} mg ({n})"))
            .collect();
        let _ = writeln!(s, "   by orientation (RMS): {}", orient.join(", "));
        let (corr_t, first_half, second_half) = self.time_stats();
        let _ = writeln!(
            s,
            "   vs time: correlation {}, RMS first half {first_half:.3} mg, second half {second_half:.3} mg",
            corr_t.map_or("n/a".into(), |c| format!("{c:+.2}"))
        );
        match self.temperature_stats() {
            Some((c, lo, hi)) => {
                let _ = writeln!(
                    s,
                    "   vs temperature ({lo:.2}..{hi:.2} C): correlation {}",
                    c.map_or("n/a".into(), |c| format!("{c:+.2}"))
                );
            }
            None => {
                let _ = writeln!(s, "   vs temperature: no temperature column");
            }
        }
        let (within, expected) = self.within_stats();
        let _ =
            writeln!(s, "   within poses (last third - first third): RMS {within:.3} mg, white noise {expected:.3} mg");
        if let (Some(a), Some(w), Some(t)) =
            (self.allan.adev_mg.last(), self.allan.white_mg.last(), self.allan.tau_s.last())
        {
            let _ = writeln!(
                s,
                "   noise: longest rest {:.1} s, Allan deviation at {t:.2} s {a:.4} mg vs white {w:.4} mg ({:.1}x)",
                self.allan.rest_s,
                a / w
            );
        }
        let _ = writeln!(s, "3. candidates (held-out ratio of the nominal model {:.2}):", self.heldout_ratio_nominal);
        for c in &self.candidates {
            let _ = writeln!(
                s,
                "   {:<19} gain {:>6.2}  held-out ratio {:>7.2}  ratio after {:>7.2}  +{} params  {}",
                c.effect, c.heldout_gain, c.heldout_ratio, c.ratio_after, c.extra_params, c.detail
            );
        }
        let _ = writeln!(
            s,
            "   verdict: {}{}",
            self.verdict,
            if self.gap.significant && !self.explained { " (significant gap, no candidate explains it)" } else { "" }
        );
        let _ = writeln!(
            s,
            "4. ratio {:.2} -> {:.2} (real {:.4} mg, simulated {:.4} mg): shrink {:.2}",
            g.ratio_before, g.ratio_after, g.real_rmse_after_mg, g.sim_rmse_after_mg, self.shrink
        );
        s
    }

    /// Writes the SVG plots into `dir` (created if needed): residual per pose before/after, against
    /// time, against temperature (with a temperature column) and the Allan deviation.
    pub fn write_plots(&self, dir: &Path) -> Result<(), String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let before: Vec<(f64, f64)> = self.poses.iter().enumerate().map(|(i, p)| (i as f64, p.residual_mg)).collect();
        let after: Vec<(f64, f64)> =
            self.poses.iter().enumerate().map(|(i, p)| (i as f64, p.residual_after_mg.unwrap_or(f64::NAN))).collect();
        let after_name = format!("after ({})", self.verdict);
        line_chart(
            &dir.join("residual_per_pose.svg"),
            "Modulus residual per pose",
            "pose",
            "residual (mg)",
            &[Series { name: "nominal", points: before }, Series { name: &after_name, points: after }],
            false,
        )?;
        let mut by_time: Vec<(f64, f64)> = self.poses.iter().map(|p| (p.t_mid_s, p.residual_mg)).collect();
        by_time.sort_by(|a, b| a.0.total_cmp(&b.0));
        line_chart(
            &dir.join("residual_vs_time.svg"),
            "Modulus residual against time",
            "time (s)",
            "residual (mg)",
            &[Series { name: "nominal", points: by_time }],
            false,
        )?;
        let mut by_temp: Vec<(f64, f64)> =
            self.poses.iter().filter_map(|p| p.temp_c.map(|t| (t, p.residual_mg))).collect();
        if by_temp.len() == self.poses.len() && !by_temp.is_empty() {
            by_temp.sort_by(|a, b| a.0.total_cmp(&b.0));
            line_chart(
                &dir.join("residual_vs_temperature.svg"),
                "Modulus residual against temperature",
                "temperature (C)",
                "residual (mg)",
                &[Series { name: "nominal", points: by_temp }],
                false,
            )?;
        }
        let tau =
            |v: &[f64]| -> Vec<(f64, f64)> { self.allan.tau_s.iter().zip(v).map(|(t, a)| (t.log10(), *a)).collect() };
        line_chart(
            &dir.join("allan_deviation.svg"),
            "Allan deviation of the longest rest",
            "log10 tau (s)",
            "mg",
            &[
                Series { name: "measured", points: tau(&self.allan.adev_mg) },
                Series { name: "white noise", points: tau(&self.allan.white_mg) },
            ],
            true,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lstsq_recovers_a_line() {
        let rows: Vec<Vec<f64>> = (0..10).map(|i| vec![1.0, i as f64]).collect();
        let r: Vec<f64> = (0..10).map(|i| -(2.0 + 0.5 * i as f64)).collect();
        let idx: Vec<usize> = (0..10).collect();
        let x = lstsq(&rows, &r, &idx).unwrap();
        assert!((x[0] - 2.0).abs() < 1e-9 && (x[1] - 0.5).abs() < 1e-9, "{x:?}");
    }

    #[test]
    fn a_clean_log_has_no_gap_and_the_report_has_the_documented_fields() {
        use crate::effects::{EffectClass, generate, random_scenario, to_table};
        let log = generate(&random_scenario(EffectClass::None, 5));
        let table = to_table(&log, "clean").unwrap();
        let report = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
        assert!(!report.gap.significant, "{}", report.to_text());
        assert_eq!(report.verdict, "none");
        let json = report.to_json();
        for key in ["real_rmse_mg", "sim_rmse_mg", "ratio_before", "ratio_after"] {
            assert!(json["gap"][key].is_number(), "{key}");
        }
        assert!(json["poses"].as_u64().unwrap() >= 24);
        assert!(json["where"].is_object());
        let names: Vec<&str> =
            json["candidates"].as_array().unwrap().iter().map(|c| c["effect"].as_str().unwrap()).collect();
        assert_eq!(names, EFFECT_NAMES);
        assert_eq!(json["verdict"]["effect"], "none");
        assert!(json["verdict"]["shrink"].is_number());
        assert!(report.to_text().contains("4. ratio"));
    }

    #[test]
    fn too_few_poses_is_an_error_not_a_panic() {
        let text: String = std::iter::once("t,ax,ay,az\n".to_string())
            .chain((0..2000).map(|i| format!("{},0.0,0.0,1.0\n", i as f64 * 0.01)))
            .collect();
        let table = crate::csvio::read_csv_str("still", &text, &crate::csvio::ReadOptions::default()).unwrap();
        let e = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap_err();
        assert!(e.to_string().contains("static poses"), "{e}");
        assert!(diagnose(&table, &DiagnoseOptions { gravity: f64::NAN, ..DiagnoseOptions::DEFAULT }).is_err());
    }

    #[test]
    fn model_inverts() {
        let p = Params { bias: [0.1, -0.2, 0.05], scale: [0.98, 1.01, 1.02], nonorth: [0.01, -0.02, 0.005] };
        let m = Model::from_params(&p);
        let f = [1.0, -9.0, 3.0];
        let back = m.apply(m.invert(f));
        assert!((0..3).all(|a| (back[a] - f[a]).abs() < 1e-12));
    }
}
