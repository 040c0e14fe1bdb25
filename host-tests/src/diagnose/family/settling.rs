//! Settling: a transient at the start of each pose. Parametrisations: a transient proportional to
//! the change from the previous pose decaying exponentially over `tau`, and the transient measured
//! in each pose (its mean minus the mean of its last half), scaled per axis or by one factor.
//!
//! Decay test: a time constant is tried only when the transient decays within the pose
//! (`tau` at most a third of the median hold); a slower "transient" is a constant offset per pose,
//! not settling.

use super::{Context, Family, Variant};
use crate::diagnose::SEGMENTS;
use crate::diagnose::math::{V3, dot, mean_of, median};

/// Time constants tried, s.
const TAUS_S: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

pub(crate) struct Settling;

/// The exponential transient toward the previous pose, `tau` seconds.
fn toward_previous(ctx: &Context<'_>, tau: f64) -> Vec<Vec<f64>> {
    let (cal, dirs) = (ctx.calibrated(), ctx.directions());
    (0..ctx.poses.len())
        .map(|i| {
            let t = ctx.poses[i].duration().max(1e-9);
            let w = tau / t * (1.0 - (-t / tau).exp());
            let delta: V3 = if i == 0 { [0.0; 3] } else { std::array::from_fn(|a| cal[i - 1][a] - cal[i][a]) };
            (0..3).map(|a| dirs[i][a] * delta[a] * w).collect()
        })
        .collect()
}

/// Each pose's mean minus the mean of its last half, calibrated (output unit).
fn measured_transients(ctx: &Context<'_>) -> Vec<V3> {
    ctx.poses
        .iter()
        .map(|p| {
            let late = mean_of(&p.seg[SEGMENTS / 2..]);
            let d: V3 = std::array::from_fn(|a| p.mean[a] - late[a]);
            std::array::from_fn(|i| (0..3).map(|j| ctx.m.model.ka[i][j] * d[j]).sum())
        })
        .collect()
}

impl Family for Settling {
    fn name(&self) -> &'static str {
        "settling"
    }

    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        let hold = median(&ctx.poses.iter().map(|p| p.duration()).collect::<Vec<_>>());
        let mut out: Vec<Variant> = TAUS_S
            .iter()
            .filter(|tau| 3.0 * **tau <= hold)
            .map(|&tau| Variant {
                extra: toward_previous(ctx, tau),
                params: 4,
                detail: format!("transient toward the previous pose, tau {tau} s"),
            })
            .collect();
        let transient = measured_transients(ctx);
        let dirs = ctx.directions();
        let per_axis = (0..ctx.poses.len()).map(|i| (0..3).map(|a| dirs[i][a] * transient[i][a]).collect()).collect();
        out.push(Variant {
            extra: per_axis,
            params: 3,
            detail: "measured transient (pose mean - last half), per axis".into(),
        });
        let common = (0..ctx.poses.len()).map(|i| vec![dot(dirs[i], transient[i])]).collect();
        out.push(Variant { extra: common, params: 1, detail: "measured transient (pose mean - last half)".into() });
        out
    }
}
