//! How good a calibration is: modulus RMSE before and after, the noise floor the poses themselves
//! predict, how well each parameter is determined (from the information matrix), and pass / fail.
//!
//! ```
//! use accelcal::verdict::VerdictBounds;
//! let bounds = VerdictBounds::DEFAULT;
//! assert!(bounds.max_rmse_mg > 0.0);
//! ```

use crate::accumulator::Pose;
use crate::ellipsoid::PoseList;
use crate::frame::{Deviation, Frame, NormPose};
use crate::linalg::{Held, Matrix, larger, spd_inverse_holding_in_place};
use crate::model::{PARAM_COUNT, Params};
use crate::solve::normal_equations;

/// The poses of a calibration: the captured poses, the normalised poses the optimisers use, and for
/// each normalised pose the index of the captured pose it came from (poses left out have none).
#[derive(Debug, Clone, Copy)]
pub struct PoseSet<'a> {
    /// The captured poses.
    pub poses: &'a [Pose],
    /// The normalised poses used.
    pub norm: &'a [NormPose],
    /// `source[i]` is the index in `poses` of `norm[i]`.
    pub source: &'a [u16],
}

impl PoseSet<'_> {
    /// The pairs (captured, normalised) of the poses used.
    pub fn pairs(&self) -> impl Iterator<Item = (&Pose, &NormPose)> + '_ {
        (0..self.norm.len()).filter_map(|i| self.pair(i))
    }

    /// The pair (captured, normalised) of normalised pose `i`; `None` when it has no captured pose.
    /// Out of line: one copy instead of one per pass over the poses (100 bytes on a Cortex-M4F).
    #[inline(never)]
    fn pair(&self, i: usize) -> Option<(&Pose, &NormPose)> {
        let captured = self.poses.get(usize::from(*self.source.get(i)?))?;
        Some((captured, self.norm.get(i)?))
    }

    /// Number of poses used.
    pub fn len(&self) -> usize {
        self.norm.len().min(self.source.len())
    }

    /// `true` when no pose is used.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

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

/// Which bound failed (all `false` on a pass). Word-aligned: its copies are word copies, inlined (no
/// `memcpy` call on the calibration path).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[repr(align(4))]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
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

/// What the calibration could not do but reports instead of failing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Warnings {
    /// Per parameter: the poses do not determine it (their directions leave it free, or its standard
    /// deviation would exceed its bound), so it was held at its nominal value (non-orthogonality 0,
    /// scale and bias at the initial estimate) while the others were fitted.
    pub held: [bool; PARAM_COUNT],
    /// Poses left out of the fit as far off the ellipsoid (indices into the poses given).
    pub excluded: PoseList,
}

impl Warnings {
    /// `true` when nothing was held or left out.
    pub fn is_empty(&self) -> bool {
        !self.held.iter().any(|&h| h) && self.excluded.is_empty()
    }
}

/// The verdict on a calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
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
    /// Parameters held at nominal and poses left out.
    pub warnings: Warnings,
}

impl Verdict {
    /// `true` when no bound failed.
    pub fn pass(&self) -> bool {
        let f = &self.failures;
        !(f.rmse || f.model_misfit || f.implausible || f.not_converged || f.undetermined.iter().any(|&u| u))
    }

    /// `true` when the verdict passed with every parameter fitted and every pose used.
    pub fn complete(&self) -> bool {
        self.pass() && self.warnings.is_empty()
    }
}

/// A zero matrix ([`crate::linalg::zero_matrix`]: one `memclr` call).
const ZERO: Matrix<PARAM_COUNT> = crate::linalg::zero_matrix();

/// Largest plausible deviation from the coarse estimate of every deviation coordinate: bias 0.5 g,
/// scale 50 %, non-orthogonality 0.5 rad.
const PLAUSIBLE_DEVIATION: f32 = 0.5;

/// The normalised modulus error of a pose and its variance ([`error_variance`]), from its gradient
/// ([`crate::frame::modulus_error_gradient`], shared with the normal equations), out of line: every
/// pass of the verdict over the poses shares one copy.
#[inline(never)]
fn error_and_variance(x: &Deviation, frame: &Frame, pose: &Pose, norm: &NormPose) -> (f32, Option<f32>) {
    let (e, gradient) = crate::frame::modulus_error_gradient(x, norm);
    (e, error_variance(x, frame, pose, &gradient))
}

/// Variance of one pose's normalised modulus error `E / g^2` due to its averaging noise, from the
/// error's `gradient` (its first three entries are `-2 r`, `r = A u - beta`: halved back exactly);
/// `None` if the pose carries no variance.
#[inline]
fn error_variance(x: &Deviation, frame: &Frame, pose: &Pose, gradient: &Deviation) -> Option<f32> {
    if pose.n == 0 || pose.variance.iter().all(|&v| v == 0.0) {
        return None;
    }
    // dE = 2 r^T A du, du_a = dm_a / (k_a g).
    let r = [-0.5 * gradient[0], -0.5 * gradient[1], -0.5 * gradient[2]];
    // A^T r with A = I + diag(a) + lower(m) in deviation terms.
    let atr = [(1.0 + x[3]) * r[0] + x[6] * r[1] + x[7] * r[2], (1.0 + x[4]) * r[1] + x[8] * r[2], (1.0 + x[5]) * r[2]];
    let mut var = 0.0;
    for i in 0..3 {
        let s = frame.gain[i] * frame.gravity;
        var += 4.0 * atr[i] * atr[i] * pose.variance[i] / (pose.n as f32 * s * s);
    }
    crate::linalg::positive_finite(var).then_some(var)
}

/// Information matrix `sum g g^T / var(E)` of the deviation vector, with each pose's noise from its
/// variance, or (poses without variance) the residual variance `sum E^2 / (N - p)` for all, `p` the
/// number of parameters not in `held`; with `inflate`, every variance is scaled up by the reduced
/// chi-square when that exceeds 1 (the residuals are larger than the noise: the uncertainty of an
/// estimate that is not yet the optimum). `None` with fewer poses than free parameters (or no more,
/// when the residuals must give the noise). Only the lower triangle is written (the upper one is 0):
/// it is all the inverses read.
pub fn information_matrix(
    x: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    held: Held,
    inflate: bool,
) -> Option<Matrix<PARAM_COUNT>> {
    let mut info = ZERO;
    information_in_place(x, frame, set, held, inflate, &mut info).then_some(info)
}

/// [`information_matrix`] into `info` (no copies of the matrix); `false` where it gives `None`.
pub(crate) fn information_in_place(
    x: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    held: Held,
    inflate: bool,
    info: &mut Matrix<PARAM_COUNT>,
) -> bool {
    let n = set.len();
    let free = PARAM_COUNT - held.count();
    if n < free || n == 0 {
        return false;
    }
    // One pass for the residual variance, the chi-square and whether every pose carries its noise.
    let (mut sum, mut chi2, mut all_noisy) = (0.0f32, 0.0f32, true);
    for (p, m) in set.pairs() {
        let (e, variance) = error_and_variance(x, frame, p, m);
        let e2 = crate::model::square(e);
        sum += e2;
        match variance {
            Some(var) => chi2 += e2 / var,
            None => all_noisy = false,
        }
    }
    let dof = n.saturating_sub(free).max(1) as f32;
    let scale = if !all_noisy {
        if n == free {
            return false;
        }
        larger(sum / dof, f32::MIN_POSITIVE)
    } else if inflate && n > free {
        larger(chi2 / dof, 1.0)
    } else {
        1.0
    };
    let weight = |i: usize| {
        let (pose, m) = set.pair(i)?;
        let var = if all_noisy { scale * error_and_variance(x, frame, pose, m).1? } else { scale };
        Some(1.0 / var)
    };
    normal_equations(x, set.norm, Some(&weight), info, &mut [0.0; PARAM_COUNT]);
    true
}

/// Covariance of the deviation vector with the parameters in `held` fixed (their rows and columns 0):
/// the inverse of the information matrix of the others ([`information_matrix`], not inflated). This is
/// the Cramer-Rao bound when `x` is the truth and the variances are the true noise.
pub fn deviation_covariance(
    x: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    held: Held,
) -> Option<Matrix<PARAM_COUNT>> {
    let mut cov = ZERO;
    covariance_in_place(x, frame, set, held, &mut cov).then_some(cov)
}

/// [`deviation_covariance`] into `cov`; `false` where it gives `None`.
fn covariance_in_place(
    x: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    held: Held,
    cov: &mut Matrix<PARAM_COUNT>,
) -> bool {
    information_in_place(x, frame, set, held, false, cov) && covariance_holding_in_place(cov, held)
}

/// Inverse of `info` with the `held` rows and columns replaced by the identity, then zeroed.
pub fn covariance_holding(mut info: Matrix<PARAM_COUNT>, held: Held) -> Option<Matrix<PARAM_COUNT>> {
    covariance_holding_in_place(&mut info, held).then_some(info)
}

/// [`covariance_holding`] in place: `info` becomes the covariance; `false` (and `info` unusable)
/// when it cannot be inverted.
pub fn covariance_holding_in_place(info: &mut Matrix<PARAM_COUNT>, held: Held) -> bool {
    spd_inverse_holding_in_place(info, held).is_ok()
}

/// The largest standard deviation each parameter may have under `bounds` (paper convention,
/// [`Params::to_array`] order).
pub fn param_limits(params: &Params, bounds: &VerdictBounds, gravity: f32) -> [f32; PARAM_COUNT] {
    core::array::from_fn(|i| param_limit(i, params, bounds, gravity))
}

/// Entry `i` of [`param_limits`].
#[inline]
fn param_limit(i: usize, params: &Params, bounds: &VerdictBounds, gravity: f32) -> f32 {
    match i {
        0..=2 => bounds.max_bias_std_mg * gravity / 1000.0,
        3..=5 => bounds.max_scale_std_rel * params.scale[i - 3].abs(),
        _ => bounds.max_nonorth_std * params.scale[if i == 8 { 1 } else { 0 }].abs(),
    }
}

/// Standard deviation (deviation units: bias in g, scale relative, non-orthogonality in rad) above
/// which a parameter is held at nominal rather than fitted: the poses then say less about it than its
/// typical size (50 mg, 2 %, 0.01 rad), and fitting it would add more error than holding it.
pub const HOLD_STD: Deviation = [0.05, 0.05, 0.05, 0.02, 0.02, 0.02, 0.01, 0.01, 0.01];

/// Which parameters to hold at nominal: those in `held` already, those the directions leave free
/// ([`undetermined_parameters`]), then, one at a time, the one whose standard deviation (with the
/// others held) exceeds [`HOLD_STD`] by the largest factor, until every free parameter is within it.
/// The user's verdict bounds play no part: a parameter fitted but worse determined than they ask
/// fails the verdict instead.
#[inline(never)] // its matrices need not share a stack frame with the solvers'
pub fn parameters_to_hold(x: &Deviation, frame: &Frame, set: &PoseSet<'_>, held: Held) -> Held {
    // The information matrix of the parameters held so far, rebuilt at each step rather than copied
    // (first the scratch of the structural test).
    let mut cov = ZERO;
    let mut held = held.union(undetermined_in(x, set.norm, &mut cov));
    let first = held;
    loop {
        let inverted =
            information_in_place(x, frame, set, first, false, &mut cov) && covariance_holding_in_place(&mut cov, held);
        if !inverted {
            break;
        }
        // The largest ratio above 1 (or NaN), `PARAM_COUNT` for none.
        let mut worst = (PARAM_COUNT, 1.0f32);
        for i in 0..PARAM_COUNT {
            let ratio = crate::linalg::sqrt_clamped(cov[i][i]) / HOLD_STD[i];
            if !held.contains(i) && !(ratio <= worst.1) {
                worst = (i, ratio);
            }
        }
        if worst.0 == PARAM_COUNT {
            break;
        }
        held.insert(worst.0);
    }
    held
}

/// Which parameters the poses cannot determine at `x`: a Cholesky factorisation, in parameter order, of
/// the Jacobi-scaled information matrix `sum g g^T` ([`crate::linalg::weak_pivots`]); a parameter whose
/// remaining pivot is below [`crate::linalg::DETERMINED_PIVOT`] is (to f32 precision) a combination of
/// the ones before it and is flagged, then left out. With only axis-aligned poses, for example, the
/// non-orthogonality terms are flagged.
pub fn undetermined_parameters(x: &Deviation, norm: &[NormPose]) -> Held {
    let mut info = ZERO;
    undetermined_in(x, norm, &mut info)
}

/// [`undetermined_parameters`] with `scratch` (overwritten) for the information matrix: the caller's
/// own matrix, when it has one, is used instead of a second one (no zeros written first).
fn undetermined_in(x: &Deviation, norm: &[NormPose], scratch: &mut Matrix<PARAM_COUNT>) -> Held {
    normal_equations(x, norm, None, scratch, &mut [0.0; PARAM_COUNT]);
    crate::linalg::weak_pivots_in_place(scratch, crate::linalg::DETERMINED_PIVOT)
}

/// Standard deviations of the paper-convention parameters from a deviation covariance.
pub fn param_std(frame: &Frame, covariance: &Matrix<PARAM_COUNT>) -> [f32; PARAM_COUNT] {
    core::array::from_fn(|i| {
        let t = frame.params_jacobian_row(i);
        let mut v = 0.0;
        // Read as `covariance[b][a]`: the order (and the bits) of the sum over the inverse as its
        // columns are solved (`spd_inverse_holding_in_place` stores column `a` in row `a`).
        for a in 0..PARAM_COUNT {
            for b in 0..PARAM_COUNT {
                v += t[a] * covariance[b][a] * t[b];
            }
        }
        crate::linalg::sqrt_clamped(v)
    })
}

/// Sums over the poses used, in one pass: the squared modulus errors after (normalised, free of the
/// cancellation of raw counts) and before (under the "before" model, output unit), and the
/// variance of the modulus each pose's noise gives (`None` when a pose carries no variance).
struct ModulusSums {
    after: f32,
    before: f32,
    noise: Option<f32>,
}

impl ModulusSums {
    fn of(x: &Deviation, frame: &Frame, set: &PoseSet<'_>, before: &Params) -> Self {
        let mut sums = Self { after: 0.0, before: 0.0, noise: Some(0.0) };
        let g = frame.gravity;
        for (p, n) in set.pairs() {
            let (e, variance) = error_and_variance(x, frame, p, n);
            let after = crate::linalg::sqrt_clamped(1.0 + e);
            sums.after += crate::model::square(after - 1.0);
            let raw = before.modulus(p.mean);
            sums.before += crate::model::square(raw - g);
            // |f_b| / g = sqrt(1 + E): d|f_b|/g = dE / 2 near |f_b| = g.
            match (&mut sums.noise, variance) {
                (Some(s), Some(v)) => *s += v / 4.0,
                (noise, _) => *noise = None,
            }
        }
        sums
    }
}

/// RMSE (mg) expected at the optimum from the poses' own noise: `sqrt(mean(sigma_i^2) (N - p) / N)` with
/// `p` the parameters fitted.
pub fn noise_floor_mg(x: &Deviation, frame: &Frame, set: &PoseSet<'_>, fitted: usize) -> Option<f32> {
    noise_floor_of(ModulusSums::of(x, frame, set, &Params::IDENTITY).noise, set.len(), fitted)
}

/// [`noise_floor_mg`] from the sum of the poses' modulus variances over `n` poses.
fn noise_floor_of(noise: Option<f32>, n: usize, fitted: usize) -> Option<f32> {
    let sum = noise?;
    if n <= fitted {
        return None;
    }
    let n = n as f32;
    Some(crate::linalg::sqrt_f32(sum / n * (n - fitted as f32) / n) * 1000.0)
}

/// RMSE (mg) of a sum of squared modulus errors over `n` poses, in units of `g`; NaN for none.
fn rmse_of_mg(sum: f32, n: usize, g: f32) -> f32 {
    if n == 0 { f32::NAN } else { crate::linalg::sqrt_f32(sum / n as f32) / g * 1000.0 }
}

/// Judges `x` (deviation in `frame`) on the poses of `set` against `bounds`; `before` is the model the
/// RMSE before calibration is computed with; `held` (the parameters held at nominal) and `excluded`
/// (the poses left out) become the verdict's [`Warnings`].
pub fn judge(
    x: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    before: &Params,
    bounds: &VerdictBounds,
    held: Held,
    excluded: PoseList,
) -> Verdict {
    judge_run(x, frame, set, before, bounds, held, &excluded, false)
}

/// [`judge`] of a run that did (`not_converged`) or did not stop at its iteration limit. Left to the
/// inliner: in its one caller after the solvers (`Prepared::conclude`) its matrices do not add to the
/// peak stack of the calibration (3320 bytes either way on the bench), and the call is 40 bytes.
#[allow(clippy::too_many_arguments)] // the calibration's one call: `judge`'s and the solver's outcome
pub(crate) fn judge_run(
    x: &Deviation,
    frame: &Frame,
    set: &PoseSet<'_>,
    before: &Params,
    bounds: &VerdictBounds,
    held: Held,
    excluded: &PoseList,
    not_converged: bool,
) -> Verdict {
    let params = frame.to_params(x);
    let fitted = PARAM_COUNT - held.count();
    let sums = ModulusSums::of(x, frame, set, before);
    let rmse_after_mg = rmse_of_mg(sums.after, set.len(), 1.0);
    let noise_floor = noise_floor_of(sums.noise, set.len(), fitted);
    // The structural test first, in the covariance's matrix: it writes every entry, so the zeros
    // that initialise the matrix are never stored (no `memclr` call).
    let mut cov = ZERO;
    let structurally_undetermined = undetermined_in(x, set.norm, &mut cov);
    let mut std = if covariance_in_place(x, frame, set, held, &mut cov) {
        param_std(frame, &cov)
    } else {
        [f32::INFINITY; PARAM_COUNT]
    };
    let mut failures = Failures {
        rmse: !(rmse_after_mg <= bounds.max_rmse_mg),
        model_misfit: noise_floor.is_some_and(|f| f > 0.0 && rmse_after_mg > bounds.max_rmse_over_noise * f),
        implausible: !params.is_finite()
            || params.scale.iter().any(|&s| !(s > 0.0))
            || x.iter().any(|v| !(v.abs() <= PLAUSIBLE_DEVIATION)),
        not_converged,
        ..Failures::default()
    };
    let mut warnings = Warnings { held: [false; PARAM_COUNT], excluded: PoseList::EMPTY };
    warnings.excluded.copy_from(excluded);
    for i in 0..PARAM_COUNT {
        if held.contains(i) {
            (std[i], warnings.held[i]) = (f32::INFINITY, true);
        } else {
            let limit = param_limit(i, &params, bounds, frame.gravity);
            failures.undetermined[i] = structurally_undetermined.contains(i) || !(std[i] <= limit);
        }
    }
    let rmse_before_mg = rmse_of_mg(sums.before, set.len(), frame.gravity);
    Verdict { rmse_before_mg, rmse_after_mg, noise_floor_mg: noise_floor, param_std: std, failures, warnings }
}
