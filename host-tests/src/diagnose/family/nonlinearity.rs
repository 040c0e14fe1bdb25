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
        let both = design(&[2, 3]);
        let mut variants = vec![
            // One coefficient for all axes: testable on logs of few poses.
            Variant { extra: common(2), params: 1, detail: "k2 a^2, one k2 for all axes".into() },
            Variant { extra: common(3), params: 1, detail: "k3 a^3, one k3 for all axes".into() },
            Variant { extra: design(&[2]), params: 3, detail: "k2 a^2 per axis".into() },
            Variant { extra: design(&[3]), params: 3, detail: "k3 a^3 per axis".into() },
            Variant { extra: both.clone(), params: 6, detail: "k2 a^2 + k3 a^3 per axis".into() },
        ];
        // One axis bowing alone (the out-of-plane axis of most parts): its square and cube terms.
        let one_axis = |a: usize| -> Vec<Vec<f64>> { both.iter().map(|row| vec![row[a], row[3 + a]]).collect() };
        variants.extend((0..3).map(|a| Variant {
            extra: one_axis(a),
            params: 2,
            detail: format!("k2 a^2 + k3 a^3 on {} only", ["x", "y", "z"][a]),
        }));
        variants
    }
}

#[cfg(test)]
mod tests {
    use crate::diagnose::{DiagnoseOptions, diagnose};
    use crate::sim::scenario::{EffectClass, SimLog, random_scenario, to_table};
    use crate::sim::{Plan, SimConfig, simulate_with};

    #[test]
    fn square_and_cube_terms_on_the_out_of_plane_axis_alone_are_named() {
        // Only z bows (k2 2 mg, k3 -1.5 mg at 1 g), hand-placed random orientations. The six terms
        // per axis cost 15 columns with the calibration; on 24-44 poses their held-out ratio stays
        // high and the two z terms alone are what explains the withheld poses.
        for seed in [11, 12, 13] {
            let scenario = random_scenario(EffectClass::None, seed);
            let g = scenario.sim.gravity;
            let recording = simulate_with(
                &scenario.sim,
                &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    let z = r[2] / g;
                    r[2] += g * (2.0e-3 * z * z - 1.5e-3 * z * z * z);
                }],
            );
            let temps_c = vec![25.0; recording.samples.len()];
            let table = to_table(&SimLog { recording, temps_c }, "z-only").unwrap();
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}: {}", d.to_text());
            let named = d.candidates.iter().find(|c| c.effect == "scale-nonlinearity").unwrap();
            assert_eq!(named.detail, "k2 a^2 + k3 a^3 on z only", "seed {seed}");
        }
    }

    #[test]
    fn square_and_cube_terms_per_axis_on_a_cube_are_named() {
        // A cube's 6 faces, 12 edges and 4 of its 8 vertices (22 poses): on a face k2 acts as a bias
        // and k3 as a scale; only the other 16 poses tell them from the calibration, so the 6 terms
        // and the 9 calibration parameters leave few poses to withhold (in 5 folds: named
        // `unexplained` on seed 2, held-out gain 0.21).
        let (k2, k3) = ([2.0e-3, -1.5e-3, 2.5e-3], [-2.0e-3, 1.5e-3, 1.8e-3]);
        for seed in [1, 2, 3] {
            let cfg = SimConfig { plan: Plan::Cube26, ..SimConfig::paper(seed) };
            let g = cfg.gravity;
            let mut recording = simulate_with(
                &cfg,
                &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    (0..3).for_each(|a| r[a] += g * (k2[a] * (r[a] / g).powi(2) + k3[a] * (r[a] / g).powi(3)));
                }],
            );
            let vertex_rows: Vec<std::ops::Range<usize>> = recording
                .poses
                .iter()
                .filter(|p| p.direction.iter().all(|c| c.abs() > 0.3))
                .step_by(2)
                .map(|p| p.start..p.end)
                .collect();
            assert_eq!(vertex_rows.len(), 4);
            let kept = |i: &usize| !vertex_rows.iter().any(|r| r.contains(i));
            recording.samples = (0..recording.samples.len()).filter(kept).map(|i| recording.samples[i]).collect();
            recording.times_s = (0..recording.times_s.len()).filter(kept).map(|i| recording.times_s[i]).collect();
            let temps_c = vec![25.0; recording.samples.len()];
            let table = to_table(&SimLog { recording, temps_c }, "cube").unwrap();
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}: {}", d.to_text());
        }
    }
}
