//! How good a calibration is: modulus RMSE before and after, the noise floor the poses themselves
//! predict, how well each parameter is determined (from the information matrix), and pass / fail.
//!
//! ```
//! use accelcal::verdict::VerdictBounds;
//! let bounds = VerdictBounds::DEFAULT;
//! assert!(bounds.max_rmse_mg > 0.0);
//! ```

use crate::accumulator::Pose;
use crate::frame::{Deviation, Frame, NormPose, modulus_error_gradient};
use crate::linalg::{Matrix, spd_inverse};
use crate::model::{PARAM_COUNT, Params};

/// Limits a calibration must meet to pass. Every field can be set by the user.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct VerdictBounds {
    /// Largest modulus RMSE after calibration, mg. Defaults to 10.
    pub max_rmse_mg: f32,
    /// Largest ratio of the RMSE after calibration to the noise floor (used only when the poses carry
    /// their variance). Defaults to 10.
    pub max_rmse_over_noise: f32,
    /// Largest standard deviation of a bias, mg. Defaults to 5.
    pub max_bias_std_mg: f32,
    /// Largest relative standard deviation of a scale factor. Defaults to 0.005.
    pub max_scale_std_rel: f32,
    /// Largest standard deviation of a non-orthogonality term, relative to its scale factor (rad).
    /// Defaults to 0.01.
    pub max_nonorth_std: f32,
}

impl VerdictBounds {
    /// The documented defaults.
    pub const DEFAULT: Self = Self {
        max_rmse_mg: 10.0,
        max_rmse_over_noise: 10.0,
        max_bias_std_mg: 5.0,
        max_scale_std_rel: 0.005,
        max_nonorth_std: 0.01,
    };
}

impl Default for VerdictBounds {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Which bound failed (all `false` on a pass).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Failures {
    /// RMSE after calibration above `max_rmse_mg`.
    pub rmse: bool,
    /// RMSE far above the noise floor: the 9-parameter model does not explain the data.
    pub model_misfit: bool,
    /// Per parameter: standard deviation above its bound, or not determined at all.
    pub undetermined: [bool; PARAM_COUNT],
    /// The parameters are not finite, a scale factor is not positive, or the fit left the plausible
    /// range around the coarse estimate (bias beyond 0.5 g, scale beyond 50 %, non-orthogonality beyond
    /// 0.5 rad).
    pub implausible: bool,
    /// The iterative solver stopped at its iteration limit without converging.
    pub not_converged: bool,
}

/// The verdict on a calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Verdict {
    /// Modulus RMSE of the poses with the "before" model, mg.
    pub rmse_before_mg: f32,
    /// Modulus RMSE with the calibration, mg.
    pub rmse_after_mg: f32,
    /// RMSE expected from the poses' own noise alone (`None` when the poses carry no variance), mg.
    pub noise_floor_mg: Option<f32>,
    /// Standard deviation of each parameter (paper convention, [`Params::to_array`] order);
    /// infinite where the poses do not determine it.
    pub param_std: [f32; PARAM_COUNT],
    /// What failed.
    pub failures: Failures,
}

impl Verdict {
    /// `true` when no bound failed.
    pub fn pass(&self) -> bool {
        let f = &self.failures;
        !(f.rmse || f.model_misfit || f.implausible || f.not_converged || f.undetermined.iter().any(|&u| u))
    }
}

/// Largest plausible deviation from the coarse estimate per deviation coordinate: bias 0.5 g, scale
/// 50 %, non-orthogonality 0.5 rad.
const PLAUSIBLE_DEVIATION: Deviation = [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5];

/// Variance of one pose's normalised modulus error `E / g^2` due to its averaging noise; `None` if the
/// pose carries no variance.
fn error_variance(x: &Deviation, frame: &Frame, pose: &Pose, norm: &NormPose) -> Option<f32> {
    if pose.n == 0 || pose.variance.iter().all(|&v| v == 0.0) {
        return None;
    }
    // dE = 2 r^T A du, du_a = dm_a / (k_a g).
    let u = norm.u;
    let r = crate::frame::deviation_residual(x, u);
    let r = [u[0] + r[0], u[1] + r[1], u[2] + r[2]];
    // A^T r with A = I + diag(a) + lower(m) in deviation terms.
    let atr = [(1.0 + x[3]) * r[0] + x[6] * r[1] + x[7] * r[2], (1.0 + x[4]) * r[1] + x[8] * r[2], (1.0 + x[5]) * r[2]];
    let mut var = 0.0;
    for i in 0..3 {
        let s = frame.gain[i] * frame.gravity;
        var += 4.0 * atr[i] * atr[i] * pose.variance[i] / (pose.n as f32 * s * s);
    }
    (var > 0.0 && var.is_finite()).then_some(var)
}

/// Covariance of the deviation vector: `(sum g g^T / var(E))^-1`, with each pose's noise from its
/// variance, or (poses without variance) the residual variance `sum E^2 / (N - 9)` for all.
/// This is the Cramer-Rao bound when `x` is the truth and the variances are the true noise.
pub fn deviation_covariance(
    x: &Deviation,
    frame: &Frame,
    poses: &[Pose],
    norm: &[NormPose],
) -> Option<Matrix<PARAM_COUNT>> {
    if poses.len() != norm.len() || poses.len() < PARAM_COUNT {
        return None;
    }
    let residual_variance = if poses.iter().zip(norm).all(|(p, n)| error_variance(x, frame, p, n).is_some()) {
        None
    } else if poses.len() > PARAM_COUNT {
        let sum: f32 = norm.iter().map(|n| crate::model::square(crate::frame::modulus_error(x, n))).sum();
        Some((sum / (poses.len() - PARAM_COUNT) as f32).max(f32::MIN_POSITIVE))
    } else {
        return None;
    };
    let mut info = [[0.0f32; PARAM_COUNT]; PARAM_COUNT];
    for (pose, n) in poses.iter().zip(norm) {
        let var = match residual_variance {
            Some(v) => v,
            None => error_variance(x, frame, pose, n)?,
        };
        let (_, g) = modulus_error_gradient(x, n);
        for i in 0..PARAM_COUNT {
            for j in 0..PARAM_COUNT {
                info[i][j] += g[i] * g[j] / var;
            }
        }
    }
    spd_inverse(&info).ok()
}

/// Smallest share of a parameter's information not explained by the parameters before it (the pivot
/// of the Jacobi-scaled Cholesky factorisation) for it to count as determined.
const DETERMINED_PIVOT: f32 = 1e-5;

/// Which parameters the poses cannot determine at `x`: a Cholesky factorisation, in parameter order, of
/// the Jacobi-scaled information matrix `sum g g^T`; a parameter whose remaining pivot is below 1e-5
/// is (to f32 precision) a combination of the ones before it and is flagged, then left out. With
/// only axis-aligned poses, for example, the non-orthogonality terms are flagged.
pub fn undetermined_parameters(x: &Deviation, norm: &[NormPose]) -> [bool; PARAM_COUNT] {
    let mut info = [[0.0f32; PARAM_COUNT]; PARAM_COUNT];
    for n in norm {
        let (_, g) = modulus_error_gradient(x, n);
        for i in 0..PARAM_COUNT {
            for j in 0..=i {
                info[i][j] += g[i] * g[j];
            }
        }
    }
    let mut out = [false; PARAM_COUNT];
    let mut l = [[0.0f32; PARAM_COUNT]; PARAM_COUNT];
    for j in 0..PARAM_COUNT {
        let diag = info[j][j];
        if !(diag > 0.0 && diag.is_finite()) {
            out[j] = true;
            continue;
        }
        // Scaled entries: info[i][j] / sqrt(info[i][i] info[j][j]).
        let scaled = |i: usize| info[j.max(i)][j.min(i)] / libm::sqrtf(info[i][i] * diag);
        let mut pivot = 1.0;
        for k in 0..j {
            pivot -= l[j][k] * l[j][k];
        }
        if !(pivot > DETERMINED_PIVOT) {
            out[j] = true;
            continue;
        }
        let root = libm::sqrtf(pivot);
        l[j][j] = root;
        for i in j + 1..PARAM_COUNT {
            if !(info[i][i] > 0.0) {
                continue;
            }
            let mut s = scaled(i);
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            l[i][j] = s / root;
        }
    }
    out
}

/// Standard deviations of the paper-convention parameters from a deviation covariance.
pub fn param_std(frame: &Frame, covariance: &Matrix<PARAM_COUNT>) -> [f32; PARAM_COUNT] {
    let t = frame.params_jacobian();
    let mut out = [0.0; PARAM_COUNT];
    for (i, o) in out.iter_mut().enumerate() {
        let mut v = 0.0;
        for a in 0..PARAM_COUNT {
            for b in 0..PARAM_COUNT {
                v += t[i][a] * covariance[a][b] * t[i][b];
            }
        }
        *o = libm::sqrtf(v.max(0.0));
    }
    out
}

/// RMSE (mg) expected at the optimum from the poses' own noise: `sqrt(mean(sigma_i^2) (N - 9) / N)`.
pub fn noise_floor_mg(x: &Deviation, frame: &Frame, poses: &[Pose], norm: &[NormPose]) -> Option<f32> {
    if poses.len() <= PARAM_COUNT || poses.len() != norm.len() {
        return None;
    }
    let mut sum = 0.0;
    for (p, n) in poses.iter().zip(norm) {
        // |f_b| / g = sqrt(1 + E): d|f_b|/g = dE / 2 near |f_b| = g.
        sum += error_variance(x, frame, p, n)? / 4.0;
    }
    let n = poses.len() as f32;
    Some(libm::sqrtf(sum / n * (n - PARAM_COUNT as f32) / n) * 1000.0)
}

/// Judges `x` (deviation in `frame`) on `poses` against `bounds`; `before` is the model the RMSE
/// before calibration is computed with.
#[inline(never)] // its matrices need not share a stack frame with the solvers'
pub fn judge(
    x: &Deviation,
    frame: &Frame,
    poses: &[Pose],
    norm: &[NormPose],
    before: &Params,
    bounds: &VerdictBounds,
) -> Verdict {
    let params = frame.to_params(x);
    let g = frame.gravity;
    let rmse = |p: &Params| {
        let mut sum = 0.0;
        for pose in poses {
            let m = libm::sqrtf(crate::model::norm_squared(p.apply(pose.mean)));
            sum += crate::model::square(m - g);
        }
        if poses.is_empty() { f32::NAN } else { libm::sqrtf(sum / poses.len() as f32) / g * 1000.0 }
    };
    let rmse_before_mg = rmse(before);
    // After: from the normalised errors, free of the cancellation of raw counts.
    let rmse_after_mg = {
        let mut sum = 0.0;
        for n in norm {
            let m = libm::sqrtf((1.0 + crate::frame::modulus_error(x, n)).max(0.0));
            sum += crate::model::square(m - 1.0);
        }
        if norm.is_empty() { f32::NAN } else { libm::sqrtf(sum / norm.len() as f32) * 1000.0 }
    };
    let noise_floor = noise_floor_mg(x, frame, poses, norm);
    let std = match deviation_covariance(x, frame, poses, norm) {
        Some(cov) => param_std(frame, &cov),
        None => [f32::INFINITY; PARAM_COUNT],
    };
    let mut failures = Failures {
        rmse: !(rmse_after_mg <= bounds.max_rmse_mg),
        model_misfit: noise_floor.is_some_and(|f| f > 0.0 && rmse_after_mg > bounds.max_rmse_over_noise * f),
        implausible: !params.is_finite()
            || params.scale.iter().any(|&s| !(s > 0.0))
            || x.iter().enumerate().any(|(i, v)| !(v.abs() <= PLAUSIBLE_DEVIATION[i])),
        ..Failures::default()
    };
    let structurally_undetermined = undetermined_parameters(x, norm);
    for i in 0..PARAM_COUNT {
        let limit = match i {
            0..=2 => bounds.max_bias_std_mg * g / 1000.0,
            3..=5 => bounds.max_scale_std_rel * params.scale[i - 3].abs(),
            _ => bounds.max_nonorth_std * params.scale[if i == 8 { 1 } else { 0 }].abs(),
        };
        failures.undetermined[i] = structurally_undetermined[i] || !(std[i] <= limit);
    }
    Verdict { rmse_before_mg, rmse_after_mg, noise_floor_mg: noise_floor, param_std: std, failures }
}
