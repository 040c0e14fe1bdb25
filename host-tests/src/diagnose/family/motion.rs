//! Motion: poses whose own samples move (taps, sway): the chi-square of the segment means after
//! the first third of the hold (a transient at the start is settling, not motion) is robustly
//! compared with the median pose's; disturbed poses are dropped, each at the
//! cost of an expected noise variance plus the penalty, and the gain is measured on the rest.
//! Disturbed holds that decay, or ring at a common frequency (`ringing`), are settling.

use accelcal::model::PARAM_COUNT;

use super::{Context, Evaluation, Family, Fitted, Variant, colored_noise, ringing, standard_evaluation};
use crate::diagnose::SEGMENTS;
use crate::diagnose::locate::{within_chi2_from, within_chi2_of};

/// Leading segments of a hold not looked at (a transient there is settling).
const SKIPPED_SEGMENTS: usize = 2;
use crate::diagnose::math::median;

pub(crate) struct Motion;

impl Family for Motion {
    fn name(&self) -> &'static str {
        "motion"
    }

    fn variants(&self, _ctx: &Context<'_>) -> Vec<Variant> {
        Vec::new()
    }

    /// Dropping moving poses, or, when every hold moves in the tremor band (hand-held, a vibrating
    /// support), the scatter the motion gives the pose means, measured in the holds as for colored
    /// noise: the better on withheld poses.
    fn evaluate(&self, ctx: &Context<'_>) -> Evaluation {
        let dropped = standard_evaluation(self, ctx);
        let Some(tremor) = ctx.tremor() else { return dropped };
        let mut shaken = colored_noise::ColoredNoise.noise_model(ctx);
        let c = &mut shaken.candidate;
        if !c.applicable || (dropped.candidate.applicable && dropped.candidate.evidence() >= c.evidence()) {
            return dropped;
        }
        c.effect = self.name();
        c.detail = format!("the holds move at 2-20 Hz ({}): their means scatter as {}", tremor.describe(), c.detail);
        shaken
    }

    fn fit(&self, ctx: &Context<'_>) -> Option<Fitted> {
        without(ctx, moving(ctx)?, "moving poses dropped")
    }
}

/// The [`disturbed`] poses, when they move as handling does: not a transient that decays or rings
/// after each rotation (settling).
pub(crate) fn moving(ctx: &Context<'_>) -> Option<Vec<bool>> {
    let dropped = disturbed(ctx)?;
    let settles = decays(ctx, &dropped) || ringing::rings(&ctx.table.samples, ctx.poses, &dropped, ctx.m.rate);
    (!settles).then_some(dropped)
}

/// The poses whose samples move after the first third of their hold (`None`: none, or too many to
/// leave enough for the fit).
pub(crate) fn disturbed(ctx: &Context<'_>) -> Option<Vec<bool>> {
    let chi: Vec<f64> = ctx.poses.iter().map(|p| within_chi2_from(p, &ctx.m.white, SKIPPED_SEGMENTS)).collect();
    let threshold = (6.0 * median(&chi)).max(40.0);
    let dropped: Vec<bool> = chi.iter().map(|c| *c > threshold).collect();
    let count = dropped.iter().filter(|d| **d).count();
    (count > 0 && ctx.poses.len() - count >= PARAM_COUNT + 3).then_some(dropped)
}

/// The nominal model without the `dropped` poses, each charged one parameter.
pub(crate) fn without(ctx: &Context<'_>, dropped: Vec<bool>, what: &str) -> Option<Fitted> {
    let count = dropped.iter().filter(|d| **d).count();
    let rows = ctx.base_rows.clone();
    let ratio = ctx.heldout_ratio(&rows, &dropped, count)?;
    let list: Vec<String> = dropped.iter().enumerate().filter(|(_, d)| **d).map(|(i, _)| i.to_string()).collect();
    Some(Fitted {
        rows,
        dropped,
        score_ratio: ratio,
        params: count,
        detail: format!("{what}: {}", list.join(" ")),
        tried: Vec::new(),
        in_sample: None,
    })
}

/// Most disturbed poses move far more in the first half of their hold than in the second: a
/// transient that decays after each rotation (settling), not motion, which comes at any time.
fn decays(ctx: &Context<'_>, dropped: &[bool]) -> bool {
    let half = SEGMENTS / 2;
    let (mut early, mut total) = (0, 0);
    for (p, _) in ctx.poses.iter().zip(dropped).filter(|(_, d)| **d) {
        let first = within_chi2_of(p, &ctx.m.white, 0..half);
        let second = within_chi2_of(p, &ctx.m.white, half..SEGMENTS);
        total += 1;
        if first > DECAY_FACTOR * second.max(half as f64) {
            early += 1;
        }
    }
    total > 0 && early * 4 >= total * 3
}

/// How much more a decaying transient moves in the first half of a hold than in the second.
const DECAY_FACTOR: f64 = 4.0;
