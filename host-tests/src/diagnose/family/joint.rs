//! Both channels in one fit: a time-varying effect (drift, temperature) moves each pose's mean
//! *and* its course during the hold. The pose means alone see the effect only where the
//! calibration leaves room for it (a short log cannot withhold a pose and still fit 9 + k
//! parameters); the within-pose channel alone sees each pose's change only along that pose's own
//! direction. Stacked, the within-pose rows fix the effect's parameters and the pose means the
//! calibration, and a withheld pose's mean is predicted from both, each row whitened by its
//! noise. Cross-validated over the pose-level folds (a withheld pose loses both its mean and its
//! segments); only the withheld means are scored, with the pose level's penalty.

use super::{Context, Evaluation, gain_over};
use crate::diagnose::PARAMETER_PENALTY;
use crate::diagnose::VALUE_OVERSHOOT_WEIGHT;
use crate::diagnose::math::{cv_residuals, fit_residuals, sum_sq};
use crate::diagnose::within::{Within, WithinVariant};

/// The best stacked parametrisation of a family.
pub(crate) struct JointFit {
    ratio: f64,
    /// The held-out gain with the pose the nominal model predicts worst left out of both scores.
    gain_without_worst: f64,
    after: Vec<Option<f64>>,
    params: usize,
    detail: String,
}

/// Rows of the stacked design (pose means first, weighted by `1 / sqrt(e_white)`, then the
/// within-pose segments, already whitened), their targets and folds.
fn stacked(ctx: &Context<'_>, w: &Within, v: &WithinVariant) -> (Vec<Vec<f64>>, Vec<f64>, Vec<usize>) {
    ctx.stacked_rows(&v.pose_extra, Some((w, v)))
}

/// Penalised held-out ratio of the withheld pose means (1 for white noise and the nominal model),
/// and the held-out gain without the pose the nominal model predicts worst.
pub(crate) fn heldout_ratio(ctx: &Context<'_>, w: &Within, v: &WithinVariant) -> Option<(f64, f64)> {
    let (rows, r, fold) = stacked(ctx, w, v);
    let cv = cv_residuals(&rows, &r, &fold, ctx.folds, &vec![false; r.len()])?;
    let scored: Vec<Option<f64>> = (0..ctx.poses.len()).map(|i| cv[i].filter(|_| ctx.scored(i))).collect();
    let (ss, n) = (sum_sq(&scored).0, ctx.n_scored());
    let penalty = PARAMETER_PENALTY * v.params as f64;
    let ratio = ((ss + penalty) / n as f64).sqrt();
    let without_worst =
        ctx.worst_nominal_pose().filter(|&(_, nominal)| nominal > 1.0).map_or(0.0, |(worst, nominal)| {
            let left = scored[worst].map_or(0.0, |c| c * c);
            gain_over(nominal, ((ss - left + penalty) / n.saturating_sub(1) as f64).sqrt(), VALUE_OVERSHOOT_WEIGHT)
        });
    Some((ratio, without_worst))
}

/// The variant whose stacked fit predicts the withheld pose means best, with the pose residuals
/// (output unit) of its fit on every pose.
pub(crate) fn best(ctx: &Context<'_>, w: &Within, variants: &[WithinVariant]) -> Option<JointFit> {
    if !ctx.pose_level || !(ctx.e_white > 0.0) {
        return None;
    }
    let ((ratio, gain_without_worst), v) = variants
        .iter()
        .filter_map(|v| heldout_ratio(ctx, w, v).map(|r| (r, v)))
        .min_by(|a, b| a.0.0.total_cmp(&b.0.0))?;
    let (rows, r, _) = stacked(ctx, w, v);
    let fitted = fit_residuals(&rows, &r, &vec![false; r.len()])?;
    let scale = ctx.e_white.sqrt();
    let after = fitted[..ctx.poses.len()].iter().map(|x| x.map(|x| x * scale)).collect();
    Some(JointFit { ratio, gain_without_worst, after, params: v.params, detail: v.detail.clone() })
}

/// Puts the stacked fit in the candidate's pose-level line when it predicts the withheld pose
/// means better than the pose means alone; the parametrisation's detail when it did.
pub(crate) fn add(ctx: &Context<'_>, e: &mut Evaluation, fit: JointFit) -> Option<String> {
    let gain = ctx.value_gain(fit.ratio);
    let c = &mut e.candidate;
    if c.applicable && c.heldout_gain >= gain {
        return None;
    }
    let ratio_after = ctx.ratio_after(&fit.after)?;
    c.applicable = true;
    (c.heldout_ratio, c.heldout_gain, c.extra_params) = (fit.ratio, gain, fit.params);
    e.gain_without_worst = fit.gain_without_worst;
    e.residual_dof = None;
    c.ratio_after = ratio_after;
    c.detail = format!("{} (pose means and within-pose course together)", fit.detail);
    e.after = fit.after;
    Some(fit.detail)
}
