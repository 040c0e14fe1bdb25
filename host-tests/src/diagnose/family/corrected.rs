//! Pose means corrected (a transient left out or extrapolated, shaken segments left out) and
//! scored as the nominal model's on withheld poses: the pose means change, the model does not.

use super::{Context, Evaluation};
use crate::diagnose::PARAMETER_PENALTY;
use crate::diagnose::math::{V3, fit_residuals, norm, rms, sum_sq};

/// Pose means corrected and scored as the nominal model's: the held-out ratio, the
/// residuals of the fit to every pose and their gap ratio, the parameters charged, what was done.
pub(crate) struct Corrected {
    pub(crate) ratio: f64,
    pub(crate) after: Vec<Option<f64>>,
    pub(crate) ratio_after: f64,
    pub(crate) params: usize,
    pub(crate) detail: String,
}

/// Pose means `means` whose white noise is `more_noise` times the plain means': their modulus
/// residuals under the nominal model, cross-validated and charged `params`.
pub(crate) fn score_means(
    ctx: &Context<'_>,
    means: &[V3],
    more_noise: f64,
    params: usize,
    detail: String,
) -> Option<Corrected> {
    let m = ctx.m;
    let r: Vec<f64> = means.iter().map(|x| norm(m.model.apply(*x)) - m.gravity).collect();
    let cv = ctx.base_cv_residuals(&r)?;
    let expected = ctx.e_white * more_noise;
    let ms = (sum_sq(&cv).0 + params as f64 * PARAMETER_PENALTY * expected) / ctx.n_scored() as f64;
    let after = fit_residuals(&ctx.base_rows, &r, &ctx.none_dropped)?;
    let kept: Vec<f64> = after.iter().flatten().copied().collect();
    let ratio_after = m.to_mg(rms(&kept)) / (m.gap.sim_rmse_mg * more_noise.sqrt());
    Some(Corrected { ratio: (ms / expected).sqrt(), after, ratio_after, params, detail })
}

/// `e` becomes the corrected pose means' evaluation if they gain more on the withheld poses.
pub(crate) fn take_if_better(ctx: &Context<'_>, e: &mut Evaluation, fit: Corrected) {
    let gain = ctx.value_gain(fit.ratio);
    if gain <= e.candidate.evidence() {
        return;
    }
    let c = &mut e.candidate;
    c.applicable = true;
    (c.heldout_ratio, c.heldout_gain, c.ratio_after, c.extra_params) = (fit.ratio, gain, fit.ratio_after, fit.params);
    c.detail = fit.detail;
    e.after = fit.after;
    e.gain_without_worst = f64::NAN;
}
