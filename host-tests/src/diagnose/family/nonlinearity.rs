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
        let z_alone = |k: i32| -> Vec<Vec<f64>> { design(&[k]).into_iter().map(|row| vec![row[2]]).collect() };
        vec![
            // One coefficient for all axes: testable on logs of few poses.
            Variant { extra: common(2), params: 1, detail: "k2 a^2, one k2 for all axes".into() },
            Variant { extra: common(3), params: 1, detail: "k3 a^3, one k3 for all axes".into() },
            // The out-of-plane axis alone: its proof mass and electrodes are built unlike the
            // in-plane pair's, and its non-linearity dominates.
            Variant { extra: z_alone(2), params: 1, detail: "k2 a^2 on z alone".into() },
            Variant { extra: z_alone(3), params: 1, detail: "k3 a^3 on z alone".into() },
            Variant { extra: design(&[2]), params: 3, detail: "k2 a^2 per axis".into() },
            Variant { extra: design(&[3]), params: 3, detail: "k3 a^3 per axis".into() },
            Variant { extra: design(&[2, 3]), params: 6, detail: "k2 a^2 + k3 a^3 per axis".into() },
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::{DiagnoseOptions, diagnose, gap};
    use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};

    #[test]
    fn a_square_term_on_the_out_of_plane_axis_alone_is_found_with_one_parameter() {
        for seed in [2, 3] {
            // The z reading off by k2 f_z^2, 2 mg at 1 g; x and y linear.
            let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
            let g = table.median_magnitude;
            for s in &mut table.samples {
                s[2] += 0.002 * s[2] * s[2] / g;
            }
            let opts = DiagnoseOptions::DEFAULT;
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            let fitted = ScaleNonlinearity.fit(&ctx).unwrap();
            assert_eq!(fitted.detail, "k2 a^2 on z alone", "seed {seed}: {:?}", fitted.tried);
            assert_eq!(diagnose(&table, &opts).unwrap().verdict, "scale-nonlinearity", "seed {seed}");
        }
    }
}
