//! Drift: a bias that moves with time. Parametrisations: one exponential warm-up
//! `c (1 - exp(-t / tau))` per axis (`tau` from a grid), two exponentials (a fast and a slow
//! time constant), and polynomials in time of degree 1 to 3 (a smooth wander).

use super::{Context, Family, Variant};
use crate::diagnose::gap::PoseData;

/// Time constants tried, as fractions of the log's duration.
const TAU_FACTORS: [f64; 6] = [0.05, 0.1, 0.2, 0.4, 0.8, 1.6];

pub(crate) struct Drift;

/// Per axis, the bias basis functions `phi_k(t)` along the pose direction.
fn columns(ctx: &Context<'_>, basis: &dyn Fn(f64) -> Vec<f64>) -> Vec<Vec<f64>> {
    ctx.poses
        .iter()
        .zip(ctx.directions())
        .map(|(p, u)| basis(p.t_mid()).iter().flat_map(|phi| u.iter().map(move |c| c * phi)).collect())
        .collect()
}

impl Family for Drift {
    fn name(&self) -> &'static str {
        "drift"
    }

    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        let t_end = ctx.poses.last().map_or(1.0, PoseData::t_mid).max(1e-9);
        let warm = |tau: f64| move |t: f64| 1.0 - (-t / tau).exp();
        let mut out = Vec::new();
        for f in TAU_FACTORS {
            let tau = f * t_end;
            let extra = columns(ctx, &|t| vec![warm(tau)(t)]);
            out.push(Variant { extra, params: 4, detail: format!("bias (1 - exp(-t / {tau:.0} s))") });
        }
        for (i, f1) in TAU_FACTORS.iter().enumerate() {
            for f2 in TAU_FACTORS.iter().skip(i + 2) {
                let (t1, t2) = (f1 * t_end, f2 * t_end);
                let extra = columns(ctx, &|t| vec![warm(t1)(t), warm(t2)(t)]);
                out.push(Variant {
                    extra,
                    params: 8,
                    detail: format!("bias with two time constants, {t1:.0} s and {t2:.0} s"),
                });
            }
        }
        for degree in 1..=3usize {
            let extra = columns(ctx, &|t| (1..=degree).map(|k| (t / t_end).powi(k as i32)).collect());
            let detail = if degree == 1 {
                "bias linear in time".into()
            } else {
                format!("bias polynomial in time, degree {degree}")
            };
            out.push(Variant { extra, params: 3 * degree, detail });
        }
        out
    }
}
