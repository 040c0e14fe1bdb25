//! Scale non-linearity: the reading of axis `a` off by `k2 f_a^2` and/or `k3 f_a^3`, or by the
//! signed square `ks f_a |f_a|` (in g units), per axis or (one parameter, for logs of few poses)
//! with one coefficient for all axes.

use super::{Context, Family, Fitted, Variant};

pub(crate) struct ScaleNonlinearity;

/// A term's shape in the reading of one axis, both in g.
type Shape = fn(f64) -> f64;

fn square(a: f64) -> f64 {
    a.powi(2)
}

fn cube(a: f64) -> f64 {
    a.powi(3)
}

/// An odd compression (or expansion) growing with the square of the reading: a symmetric soft
/// saturation's leading term, where the cube's is the next order's.
fn signed_square(a: f64) -> f64 {
    a * a.abs()
}

/// The modulus' columns of `shapes`' terms on each axis, shape by shape (`u_a g shape(f_a / g)`).
fn per_axis_terms(ctx: &Context<'_>, shapes: &[Shape]) -> Vec<Vec<f64>> {
    let g = ctx.m.gravity;
    ctx.directions()
        .iter()
        .zip(ctx.calibrated())
        .map(|(u, f)| shapes.iter().flat_map(|shape| (0..3).map(move |a| u[a] * g * shape(f[a] / g))).collect())
        .collect()
}

/// Fewest training poses beyond the columns of a one-axis parametrisation (the axis chosen among
/// three) in every fold.
const AXIS_CHOICE_MIN_DOF: usize = 1;

impl Family for ScaleNonlinearity {
    fn name(&self) -> &'static str {
        "scale-nonlinearity"
    }

    /// The orientation alone: where the holds stay still, the square and cube terms per axis (the
    /// only shape of six columns) are tried exactly determined.
    fn fit(&self, ctx: &Context<'_>) -> Option<Fitted> {
        ctx.best_of_orientation(self.variants(ctx))
    }

    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        let [squares, cubes, signed_squares] = [square, cube, signed_square].map(|shape| per_axis_terms(ctx, &[shape]));
        let common = |terms: &[Vec<f64>]| -> Vec<Vec<f64>> { terms.iter().map(|row| vec![row.iter().sum()]).collect() };
        let both = per_axis_terms(ctx, &[square, cube]);
        let mut variants = vec![
            // One coefficient for all axes: testable on logs of few poses.
            Variant { extra: common(&squares), params: 1, detail: "k2 a^2, one k2 for all axes".into() },
            Variant { extra: common(&cubes), params: 1, detail: "k3 a^3, one k3 for all axes".into() },
            Variant { extra: squares, params: 3, detail: "k2 a^2 per axis".into() },
            Variant { extra: cubes, params: 3, detail: "k3 a^3 per axis".into() },
            Variant { extra: both.clone(), params: 6, detail: "k2 a^2 + k3 a^3 per axis".into() },
            Variant { extra: common(&signed_squares), params: 1, detail: "ks a|a|, one ks for all axes".into() },
        ];
        // The signed square per axis, a second odd shape of three columns beside the cube's: where
        // every fold's fit is exactly determined, the best of two such chances is no evidence (see
        // the one-axis variants below). Offered there too on the development sets, on logs of 13
        // poses it named two out-of-catalogue effects and a drift a non-linearity and lost one
        // non-linearity to drift, for 3 non-linearities gained.
        let signed = Variant { extra: signed_squares, params: 3, detail: "ks a|a| per axis".into() };
        if ctx.trains_beyond(&signed.extra, AXIS_CHOICE_MIN_DOF) {
            variants.push(signed);
        }
        // One axis bowing alone (the out-of-plane axis of most parts): its square and cube terms. The
        // axis is chosen among three on the same withheld poses: where every fold's fit is exactly
        // determined each predicts its withheld pose by chance, and the best of three chances is no
        // evidence. On the development sets (1 536 logs) the 7 logs of 12 poses named so were right
        // once (4 out-of-catalogue effects, a temperature, a hand); without these variants there 3
        // of the out-of-catalogue effects are `unexplained` and the one non-linearity is too.
        let one_axis = |a: usize| -> Vec<Vec<f64>> { both.iter().map(|row| vec![row[a], row[3 + a]]).collect() };
        let one_axis_variants = (0..3).map(|a| Variant {
            extra: one_axis(a),
            params: 2,
            detail: format!("k2 a^2 + k3 a^3 on {} only", ["x", "y", "z"][a]),
        });
        variants.extend(one_axis_variants.filter(|v| ctx.trains_beyond(&v.extra, AXIS_CHOICE_MIN_DOF)));
        variants
    }
}

#[cfg(test)]
mod tests {
    use crate::csvio::Table;
    use crate::diagnose::{DiagnoseOptions, diagnose};
    use crate::sim::scenario::{SimLog, to_table};
    use crate::sim::{Plan, SimConfig, simulate_with};

    #[test]
    fn square_and_cube_terms_on_the_out_of_plane_axis_alone_are_named() {
        // Only z bows (k2 2 mg, k3 -1.5 mg at 1 g), hand-placed random orientations. The six terms
        // per axis cost 15 columns with the calibration; on 24-44 poses their held-out ratio stays
        // high and the two z terms alone are what explains the withheld poses.
        for seed in [11, 12, 13] {
            let table = crate::diagnose::testing::z_bowed(seed);
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}: {}", d.to_text());
            let named = d.candidates.iter().find(|c| c.effect == "scale-nonlinearity").unwrap();
            assert_eq!(named.detail, "k2 a^2 + k3 a^3 on z only", "seed {seed}");
        }
    }

    #[test]
    fn the_bowing_axis_is_chosen_only_where_the_folds_leave_a_residual_degree_of_freedom() {
        // Left one out, 12 poses train each fold on 11: the calibration's 9 columns and one axis's 2
        // terms are exactly determined; 13 poses leave one degree of freedom.
        for (poses, searched) in [(12, false), (13, true)] {
            let cfg = SimConfig { plan: Plan::Random(poses), ..SimConfig::paper(7) };
            let g = cfg.gravity;
            let recording = simulate_with(
                &cfg,
                &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| r[2] += g * 3.0e-3 * (r[2] / g).powi(2)],
            );
            let temps_c = vec![25.0; recording.samples.len()];
            let table = to_table(&SimLog { recording, temps_c }, "z-bow").unwrap();
            let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
            assert_eq!(d.poses.len(), poses);
            let family = d.candidates.iter().find(|c| c.effect == "scale-nonlinearity").unwrap();
            let tried: Vec<&str> = family.variants.iter().map(|(detail, _)| detail.as_str()).collect();
            assert_eq!(tried.iter().any(|v| v.ends_with(" only")), searched, "{poses} poses: {tried:?}");
            assert!(tried.contains(&"k2 a^2, one k2 for all axes"), "{tried:?}");
        }
    }

    /// A cube's poses (faces, edges, vertices) that `keep` keeps, each axis reading off by
    /// `k2 a^2 + k3 a^3` (g units).
    fn cube_log(seed: u64, k2: [f64; 3], k3: [f64; 3], keep: impl FnMut(&[f64; 3]) -> bool) -> Table {
        plan_log(Plan::Cube26, seed, k2, k3, keep)
    }

    /// [`cube_log`] on another plan.
    fn plan_log(plan: Plan, seed: u64, k2: [f64; 3], k3: [f64; 3], keep: impl FnMut(&[f64; 3]) -> bool) -> Table {
        bowed_log(plan, seed, &|a, x| k2[a] * x.powi(2) + k3[a] * x.powi(3), keep)
    }

    /// Random orientations, each axis reading off by `ks a|a|` (g units): an odd compression or
    /// expansion growing with the square of the reading.
    fn signed_square_log(seed: u64, poses: usize, ks: [f64; 3]) -> Table {
        bowed_log(Plan::Random(poses), seed, &|a, x| ks[a] * x * x.abs(), |_| true)
    }

    /// The poses of `plan` that `keep` keeps, axis `a` reading off by `bow(a, reading)` (g units).
    fn bowed_log(plan: Plan, seed: u64, bow: &dyn Fn(usize, f64) -> f64, keep: impl FnMut(&[f64; 3]) -> bool) -> Table {
        let cfg = SimConfig { plan, ..SimConfig::paper(seed) };
        let g = cfg.gravity;
        let recording = simulate_with(
            &cfg,
            &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                (0..3).for_each(|a| r[a] += g * bow(a, r[a] / g))
            }],
        );
        crate::diagnose::testing::table_of_poses(recording, keep, "bowed")
    }

    #[test]
    fn signed_square_terms_on_fourteen_random_poses_are_named_by_their_own_shape() {
        // 14 random orientations, `ks a|a|` of 4, -5 and 6 mg at 1 g (gap ratios 5-22). On a face the
        // term is a scale; on a tilted pose it departs from the scale by `1 / (1 + |a|)` times what a
        // cube term does. Without the shape, square and cube terms named 10 of these 16 logs (held-out
        // gains 0.36-0.77); with it 11, 7 of them by their own shape (gains 0.45-1.00).
        let (mut named, mut own_shape) = (0, 0);
        for seed in 1..=16 {
            let table = signed_square_log(seed, 14, [4.0e-3, -5.0e-3, 6.0e-3]);
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.poses.len(), 14);
            let family = d.candidates.iter().find(|c| c.effect == "scale-nonlinearity").unwrap();
            if d.verdict == "scale-nonlinearity" {
                named += 1;
                own_shape += usize::from(family.detail.starts_with("ks a|a|"));
            }
        }
        assert!(named >= 11 && own_shape >= 6, "{named} of 16 named, {own_shape} by their own shape");
    }

    /// `table` diagnosed on `poses` poses as a scale non-linearity: the family's fit to every pose.
    fn named_with_its_fit(table: &Table, seed: u64, poses: usize) -> crate::diagnose::report::InSampleFit {
        let d = diagnose(table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
        assert_eq!(d.poses.len(), poses);
        assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}: {}", d.to_text());
        let family = d.candidates.into_iter().find(|c| c.effect == "scale-nonlinearity").unwrap();
        family.in_sample.expect("a fit to every pose")
    }

    /// Of a cube's poses, how many of the three axes a pose tilts.
    fn tilted_axes(direction: &[f64; 3]) -> usize {
        direction.iter().filter(|c| c.abs() > 0.3).count()
    }

    #[test]
    fn square_and_cube_terms_per_axis_on_a_cube_are_named() {
        // A cube's 6 faces, 12 edges and 4 of its 8 vertices (22 poses): on a face k2 acts as a bias
        // and k3 as a scale; only the other 16 poses tell them from the calibration, so the 6 terms
        // and the 9 calibration parameters leave few poses to withhold (in 5 folds: named
        // `unexplained` on seed 2, held-out gain 0.21).
        let (k2, k3) = ([2.0e-3, -1.5e-3, 2.5e-3], [-2.0e-3, 1.5e-3, 1.8e-3]);
        for seed in [1, 2, 3] {
            let mut vertices = 0;
            let table = cube_log(seed, k2, k3, |u| {
                vertices += usize::from(tilted_axes(u) == 3);
                tilted_axes(u) < 3 || vertices % 2 == 0
            });
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.poses.len(), 22);
            assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn square_and_cube_terms_per_axis_on_a_jig_of_faces_and_edges_are_named_from_three_degrees_of_freedom() {
        // A cube jig's 6 faces and 12 edges (18 poses): the 6 terms and the calibration's 9 columns
        // leave 3 residual degrees of freedom, fewer than the terms' columns; withheld, an edge is
        // not predicted (the few tilted poses decide the terms). Fitted to every pose the terms leave
        // white noise (a blindgen5 jig of gap ratio 39 on 18 poses was `unexplained` while a fit to
        // every pose was asked to leave as many degrees of freedom as its extra columns).
        let (k2, k3) = ([2.0e-3, -1.5e-3, 2.5e-3], [-2.0e-3, 1.5e-3, 1.8e-3]);
        for seed in [1, 2, 3] {
            let fit = named_with_its_fit(&cube_log(seed, k2, k3, |u| tilted_axes(u) < 3), seed, 18);
            assert_eq!((fit.residual_dof, fit.detail.as_str()), (3, "k2 a^2 + k3 a^3 per axis"), "seed {seed}");
        }
    }

    #[test]
    fn cube_terms_that_few_tilted_poses_determine_are_named_from_their_fit_to_every_pose() {
        // A cube's 6 faces and 9 of its 12 edges (15 poses), a cube term on x (-3 mg at 1 g) and small
        // ones on y and z: on the faces the terms act as scales, so the 9 edges alone decide the 3
        // terms; withheld, an edge is predicted from the 8 others as the calibration's 9 columns and
        // the 3 terms allow (named `unexplained` before the fit to every pose was asked, 3 seeds).
        // Fitted to every pose the terms leave white noise, and no other family does. On faces and
        // edges alone the signed square `a|a|` is the cube term's shape beside the scale (each departs
        // from the scale on an edge only, by 0.15 and 0.25 of g): either names them.
        let mut from_every_pose = 0;
        for seed in [1, 3, 4] {
            let mut edges = 0;
            let table = cube_log(seed, [0.0; 3], [-3.0e-3, 0.4e-3, 0.8e-3], |u| {
                edges += usize::from(tilted_axes(u) == 2);
                tilted_axes(u) == 1 || tilted_axes(u) == 2 && edges <= 9
            });
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.poses.len(), 15);
            assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}: {}", d.to_text());
            let why = d.located.as_deref().unwrap_or_default();
            if why.contains("not confirmed on withheld poses") {
                from_every_pose += 1;
                assert!(why.contains("k3 a^3 per axis") || why.contains("ks a|a| per axis"), "seed {seed}: {why}");
            }
        }
        // Seed 3's withheld edges confirm the signed square (held-out gain 0.35): named either way.
        assert!(from_every_pose >= 2, "{from_every_pose} of 3 named from their fit to every pose");
    }

    #[test]
    fn square_and_cube_terms_per_axis_on_sixteen_still_random_poses_are_named_from_their_exactly_determined_fit() {
        // 16 random orientations, square and cube terms of 10-15 mg at 1 g on every axis (gap ratio
        // 90 on the first seed). Left one out, the six terms and the calibration's 9 columns are exactly
        // determined on 15 training poses; the family tries no other shape of six columns and the
        // holds stay still, so the withheld pose is predicted from that one shape (never tried when
        // a residual degree of freedom was asked of it: 1 of these 8 logs was named, seed 2 by the
        // square terms alone). Where one pose's exactly determined prediction is too noisy (a pose
        // nearly alone in its direction) the verdict stays `unexplained`, never another family.
        let (k2, k3) = ([10.0e-3, -12.5e-3, 15.0e-3], [-15.0e-3, 10.0e-3, 12.5e-3]);
        let mut named = 0;
        for seed in 1..=8 {
            let table = plan_log(Plan::Random(16), seed, k2, k3, |_| true);
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.poses.len(), 16);
            assert!(["scale-nonlinearity", "unexplained"].contains(&d.verdict), "seed {seed}: {}", d.to_text());
            let family = d.candidates.iter().find(|c| c.effect == "scale-nonlinearity").unwrap();
            if d.verdict == "scale-nonlinearity" {
                assert_eq!(family.detail, "k2 a^2 + k3 a^3 per axis", "seed {seed}");
                named += 1;
            }
        }
        assert!(named >= 4, "{named} of 8 named");
    }

    #[test]
    fn one_cube_term_on_twelve_random_poses_is_fitted_to_every_pose_on_two_degrees_of_freedom() {
        // 12 random orientations, one cube term of 3 mg at 1 g on every axis: the calibration's 9
        // columns and the term leave 2 residual degrees of freedom. The fit to every pose is made
        // there for one extra column (for the verdict when the withheld poses, each predicted from
        // 1, do not support it: a blindgen3 log of gap ratio 43, held-out gain 0.16, fit 0.55).
        for seed in 1..=3 {
            let fit = named_with_its_fit(&plan_log(Plan::Random(12), seed, [0.0; 3], [3.0e-3; 3], |_| true), seed, 12);
            assert_eq!((fit.residual_dof, fit.detail.as_str()), (2, "k3 a^3, one k3 for all axes"), "seed {seed}");
            assert!(fit.ratio < 1.5, "seed {seed}: {}", fit.ratio);
        }
    }

    #[test]
    fn cube_terms_on_sixteen_random_poses_are_not_taken_by_an_exactly_determined_wider_shape() {
        // 16 random orientations, cube terms of -3, 2 and 2.5 mg at 1 g. Left one out, a shape of
        // 6 columns is exactly determined on 15 training poses: on seed 4 the best of drift's
        // two-time-constant pairs predicted the withheld poses by chance and the verdict was drift.
        for seed in 1..=4 {
            let table = plan_log(Plan::Random(16), seed, [0.0; 3], [-3.0e-3, 2.0e-3, 2.5e-3], |_| true);
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.poses.len(), 16);
            assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}: {}", d.to_text());
        }
    }
}
