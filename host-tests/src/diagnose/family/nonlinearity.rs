//! Scale non-linearity: the reading of axis `a` off by `k2 f_a^2` and/or `k3 f_a^3` (in g units),
//! per axis or (one parameter, for logs of few poses) with one coefficient for all axes.

use super::{Context, Family, Variant};

pub(crate) struct ScaleNonlinearity;

impl Family for ScaleNonlinearity {
    fn name(&self) -> &'static str {
        "scale-nonlinearity"
    }

    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        let g = ctx.m.gravity;
        let design = |powers: &[i32]| -> Vec<Vec<f64>> {
            ctx.directions()
                .iter()
                .zip(ctx.calibrated())
                .map(|(u, f)| powers.iter().flat_map(|&k| (0..3).map(move |a| u[a] * g * (f[a] / g).powi(k))).collect())
                .collect()
        };
        let common =
            |k: i32| -> Vec<Vec<f64>> { design(&[k]).into_iter().map(|row| vec![row.iter().sum::<f64>()]).collect() };
        vec![
            // One coefficient for all axes: testable on logs of few poses.
            Variant { extra: common(2), params: 1, detail: "k2 a^2, one k2 for all axes".into() },
            Variant { extra: common(3), params: 1, detail: "k3 a^3, one k3 for all axes".into() },
            Variant { extra: design(&[2]), params: 3, detail: "k2 a^2 per axis".into() },
            Variant { extra: design(&[3]), params: 3, detail: "k3 a^3 per axis".into() },
            Variant { extra: design(&[2, 3]), params: 6, detail: "k2 a^2 + k3 a^3 per axis".into() },
        ]
    }
}
