//! Motion: poses whose own samples move (taps, sway): the chi-square of the segment means after
//! the first is robustly compared with the median pose's; disturbed poses are dropped, each at the
//! cost of an expected noise variance plus the penalty, and the gain is measured on the rest.

use accelcal::model::PARAM_COUNT;

use super::{Context, Family, Fitted, Variant};
use crate::diagnose::locate::within_chi2;
use crate::diagnose::math::median;

pub(crate) struct Motion;

impl Family for Motion {
    fn name(&self) -> &'static str {
        "motion"
    }

    fn variants(&self, _ctx: &Context<'_>) -> Vec<Variant> {
        Vec::new()
    }

    fn fit(&self, ctx: &Context<'_>) -> Option<Fitted> {
        let chi: Vec<f64> = ctx.poses.iter().map(|p| within_chi2(p, &ctx.m.white)).collect();
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
            params: count,
            detail: format!("moving poses dropped: {}", list.join(" ")),
            tried: Vec::new(),
        })
    }
}
