//! Drift as a slow wander: a bias that moves smoothly in time, with no fixed shape (a warm-up,
//! a Brownian wander low-passed by the sensor's thermal mass). Per axis it is a uniform cubic
//! spline over the log (4 to 18 basis functions), whose neighbouring coefficients' differences are
//! penalised (first differences: a random walk's steps, a Brownian prior; second: an integrated
//! random walk's) with a prior standard deviation relative to the noise of a pose mean: a
//! penalised spline (P-spline), not `3 x basis` free parameters, so a log of 16 poses can still
//! withhold some. Each pose's column is the spline averaged over its hold; when the log has the
//! within-pose channel, the spline's course during each hold is stacked with the pose means (as in
//! `joint.rs`). Basis and prior are chosen on withheld pose means; the penalty charges the fit's
//! effective parameters (the trace of the pose rows' hat matrix beyond the calibration's). The
//! spline runs along a course ([`Course`]): time for the drift, the thermometer's reading for the
//! temperature family (a coefficient that is no polynomial in temperature).

use super::{Context, Evaluation};
use crate::diagnose::PARAMETER_PENALTY;
use crate::diagnose::math::{
    ScaledFactor, V3, add_matrices, add_vectors, axis, cholesky_solve, dot, fold_is_small, identity_less_hat, normals,
    predict, rhs, sums_without,
};
use std::ops::Range;

/// Knot counts tried.
const KNOTS: [usize; 4] = [4, 6, 10, 18];

/// Prior step standard deviations between knots, in pose-mean noise standard deviations.
const STEP_SIGMAS: [f64; 6] = [0.3, 1.0, 3.0, 10.0, 30.0, 100.0];

/// One penalised spline: knots, the order of the differences its prior penalises and their prior
/// standard deviation (in pose-mean noise standard deviations).
#[derive(Clone, Copy)]
struct Shape {
    knots: usize,
    order: usize,
    step: f64,
}

impl Shape {
    fn detail(&self, course: &Course<'_>, edf: f64) -> String {
        let h = course.span / (self.knots - 3) as f64;
        let what = if self.order == 1 { "steps" } else { "bends" };
        let (along, unit, digits) = (&course.along, course.unit, course.digits);
        format!(
            "bias wandering smoothly {along} (cubic spline, {} basis functions {h:.digits$} {unit} apart, {what} of {} pose-noise sigmas, {edf:.1} effective params)",
            self.knots, self.step
        )
    }
}

/// What the wander follows, over `0..span`: time (a drift) or a thermometer's reading (a
/// temperature), as a function of a segment's mid time (s) and its table rows.
pub(crate) struct Course<'a> {
    pub(crate) span: f64,
    pub(crate) at: &'a dyn Fn(f64, Range<usize>) -> f64,
    /// How the detail names it ("in time"), its unit and the digits of its knot spacing.
    pub(crate) along: String,
    pub(crate) unit: &'static str,
    pub(crate) digits: usize,
}

/// The best penalised wander.
pub(crate) struct SmoothFit {
    ratio: f64,
    after: Vec<Option<f64>>,
    edf: f64,
    detail: String,
    /// The bias at each knot, per axis (output unit), fitted to every pose, and the course's span.
    knots: Vec<V3>,
    span: f64,
}

impl SmoothFit {
    /// Its penalised held-out ratio.
    pub(crate) fn ratio(&self) -> f64 {
        self.ratio
    }

    /// Its effective parameters beyond the calibration.
    pub(crate) fn edf(&self) -> f64 {
        self.edf
    }

    /// The largest rate of change of the fitted bias on any axis at the course's values `xs`
    /// (output unit per course unit).
    pub(crate) fn steepest(&self, xs: &[f64]) -> f64 {
        let count = self.knots.len();
        let rate = |x: f64, a: usize| -> f64 {
            (0..count).map(|j| self.knots[j][a] * bspline_rate(j, count, self.span, x)).sum::<f64>().abs()
        };
        xs.iter().flat_map(|&x| (0..3).map(move |a| rate(x, a))).fold(0.0, f64::max)
    }
}

/// Basis function `j` of `count` uniform cubic B-splines over `0..t_end` at `t` (their sum is 1 on
/// `0..t_end`; centres `h` apart from `-h` to `t_end + h`).
pub(crate) fn bspline(j: usize, count: usize, t_end: f64, t: f64) -> f64 {
    let h = t_end / (count - 3) as f64;
    let x = ((t - (j as f64 - 1.0) * h) / h).abs();
    if x < 1.0 {
        (4.0 - 6.0 * x * x + 3.0 * x * x * x) / 6.0
    } else if x < 2.0 {
        (2.0 - x).powi(3) / 6.0
    } else {
        0.0
    }
}

/// The rate of change of [`bspline`] in `t`.
fn bspline_rate(j: usize, count: usize, t_end: f64, t: f64) -> f64 {
    let h = t_end / (count - 3) as f64;
    let u = (t - (j as f64 - 1.0) * h) / h;
    let x = u.abs();
    let d = if x < 1.0 {
        (-12.0 * x + 9.0 * x * x) / 6.0
    } else if x < 2.0 {
        -(2.0 - x).powi(2) / 2.0
    } else {
        0.0
    };
    d * u.signum() / h
}

/// The stacked design of one knot count: whitened pose rows (calibration columns, then `3 knots`
/// wander columns: the bias at each knot along the pose direction, averaged over the hold), then,
/// when the log has the within-pose channel, its segments' rows (the wander's course during each
/// hold, already whitened); their targets and folds (a segment in its pose's fold).
fn design(ctx: &Context<'_>, knots: usize, course: &Course<'_>) -> (Vec<Vec<f64>>, Vec<f64>, Vec<usize>) {
    let span = course.span;
    let effect = |_: usize, t: f64, rows: Range<usize>| -> Vec<V3> {
        let x = (course.at)(t, rows);
        (0..knots).flat_map(|j| (0..3).map(move |a| axis(a, bspline(j, knots, span, x)))).collect()
    };
    let within = ctx.within.as_ref().map(|w| (w, w.variant(ctx.m, 3 * knots, String::new(), &effect)));
    let pose_extra: Vec<Vec<f64>> = match &within {
        Some((_, v)) => v.pose_extra.clone(),
        None => ctx
            .poses
            .iter()
            .zip(ctx.directions())
            .map(|(p, u)| effect(0, p.t_mid(), p.rows.clone()).iter().map(|e| dot(*u, *e)).collect())
            .collect(),
    };
    ctx.stacked_rows(&pose_extra, within.as_ref().map(|(w, v)| (*w, v)))
}

/// The prior's normal matrix per axis: the knots' differences of `order` (1: a random walk's
/// steps, 2: an integrated random walk's, a smooth wander) have standard deviation `step`
/// (whitened like the pose rows: `w` is their weight), added to `a` on the wander columns.
fn add_prior(a: &mut [Vec<f64>], base: usize, knots: usize, order: usize, step: f64, w: f64) {
    let weights: &[f64] = if order == 1 { &[-1.0, 1.0] } else { &[1.0, -2.0, 1.0] };
    let c = (w / step).powi(2);
    for first in 0..=knots - weights.len() {
        for axis in 0..3 {
            let col = |k: usize| base + 3 * (first + k) + axis;
            for (j, wj) in weights.iter().enumerate() {
                for (k, wk) in weights.iter().enumerate() {
                    a[col(j)][col(k)] += c * wj * wk;
                }
            }
        }
    }
}

/// The normal equations every shape of one knot count shares: `sum x x^T` (lower triangle) and
/// `sum x r` over every row, and how its folds are withheld.
struct Normals {
    all: (Vec<Vec<f64>>, Vec<f64>),
    withheld: Withheld,
}

enum Withheld {
    /// Large folds, each refitted: per fold, the sums over the others' rows.
    Refit(Vec<(Vec<Vec<f64>>, Vec<f64>)>),
    /// Small folds (a pose and its segments, [`fold_is_small`]): per fold, its rows,
    /// predicted through the fit to every row. For a fixed penalty the residuals of fold `F`'s
    /// rows without it are `(I - H_FF)^-1 e_F` (`e` the full fit's residuals, `H` its hat
    /// matrix): one factorisation per shape instead of one per fold.
    Hat(Vec<Vec<usize>>),
}

impl Normals {
    fn new(rows: &[Vec<f64>], r: &[f64], fold: &[usize], folds: usize) -> Self {
        let p = rows.first().map_or(0, Vec::len);
        let n = rows.len().min(r.len()).min(fold.len());
        // Part `folds` is empty: the sum without it is the sum over all folds.
        let blocks: Vec<Vec<usize>> = (0..=folds).map(|f| (0..n).filter(|&i| fold[i] == f).collect()).collect();
        if blocks.iter().all(|b| fold_is_small(b.len(), p)) {
            let all = (normals(rows, 0..n), rhs(rows, r, 0..n));
            return Self { all, withheld: Withheld::Hat(blocks) };
        }
        let parts: Vec<(Vec<Vec<f64>>, Vec<f64>)> =
            blocks.iter().map(|b| (normals(rows, b.iter().copied()), rhs(rows, r, b.iter().copied()))).collect();
        let zero = (vec![vec![0.0; p]; p], vec![0.0; p]);
        let mut without = sums_without(&parts, zero, |a, b| (add_matrices(&a.0, &b.0), add_vectors(&a.1, &b.1)));
        let all = without.pop().expect("the empty part");
        Self { all, withheld: Withheld::Refit(without) }
    }
}

/// Ridge on the scaled diagonal of a shape's normal matrix.
const RIDGE: f64 = 1e-10;

/// A shape's penalised held-out ratio, in-sample pose residuals (output unit), effective
/// parameters and the bias at each knot per axis fitted to every pose (output unit; [`score`]).
type ShapeScore = (f64, Vec<Option<f64>>, f64, Vec<V3>);

/// Penalised held-out ratio, in-sample pose residuals (output unit) and effective parameters of
/// one shape, from the design's normals.
fn score(
    ctx: &Context<'_>,
    design: &(Vec<Vec<f64>>, Vec<f64>, Vec<usize>),
    normals: &Normals,
    shape: Shape,
) -> Option<ShapeScore> {
    let (rows, r, fold) = design;
    let (n, base) = (ctx.poses.len(), ctx.base_rows.first()?.len());
    let w = 1.0 / ctx.e_white.sqrt();
    // A normal matrix with the shape's prior, factored.
    let penalised = |a: &Vec<Vec<f64>>| -> Option<ScaledFactor> {
        let mut a = a.clone();
        add_prior(&mut a, base, shape.knots, shape.order, shape.step, w);
        ScaledFactor::new(a, RIDGE)
    };
    let full = penalised(&normals.all.0)?;
    let x = full.solve(&normals.all.1)?;
    let ss = match &normals.withheld {
        Withheld::Refit(without) => {
            let mut ss = 0.0;
            for (f, (a, b)) in without.iter().enumerate() {
                let x = penalised(a)?.solve(b)?;
                ss += (0..n)
                    .filter(|&i| fold[i] == f && ctx.scored(i))
                    .map(|i| predict(rows, r, &x, i).powi(2))
                    .sum::<f64>();
            }
            ss
        }
        Withheld::Hat(blocks) => {
            let e: Vec<f64> = (0..rows.len()).map(|i| predict(rows, r, &x, i)).collect();
            hat_heldout_ss(ctx, rows, &e, &full, blocks)?
        }
    };
    // Effective parameters: the trace of the pose rows' hat matrix less the calibration's.
    let trace: f64 = rows[..n].iter().map(|row| full.whiten(row).iter().map(|v| v * v).sum::<f64>()).sum();
    let edf = (trace - base as f64).max(0.0);
    let ratio = ((ss + PARAMETER_PENALTY * edf) / ctx.n_scored() as f64).sqrt();
    let after = (0..n).map(|i| Some(predict(rows, r, &x, i) / w)).collect();
    let knots = x[base..].chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
    Some((ratio, after, edf, knots))
}

/// The held-out sum of squares of the scored poses, each fold's rows (`blocks`) withheld through
/// the full fit `full` with residuals `e` ([`withheld_through_hat`]).
fn hat_heldout_ss(
    ctx: &Context<'_>,
    rows: &[Vec<f64>],
    e: &[f64],
    full: &ScaledFactor,
    blocks: &[Vec<usize>],
) -> Option<f64> {
    let n = ctx.poses.len();
    let mut ss = 0.0;
    for block in blocks.iter().filter(|b| !b.is_empty()) {
        let withheld = withheld_through_hat(rows, e, full, block)?;
        ss += block.iter().zip(&withheld).filter(|(i, _)| **i < n && ctx.scored(**i)).map(|(_, v)| v * v).sum::<f64>();
    }
    Some(ss)
}

/// The residuals of rows `block` under the fit without them, from the fit `full` to every row and
/// its residuals `e`: `(I - H_FF)^-1 e_F`, `H_FF` the block's part of the hat matrix; `None` when
/// the block's rows leave the others' fit undetermined.
fn withheld_through_hat(rows: &[Vec<f64>], e: &[f64], full: &ScaledFactor, block: &[usize]) -> Option<Vec<f64>> {
    let z: Vec<Vec<f64>> = block.iter().map(|&i| full.whiten(&rows[i])).collect();
    let e_block: Vec<f64> = block.iter().map(|&i| e[i]).collect();
    cholesky_solve(&identity_less_hat(&z), &e_block, 0.0)
}

/// The knot count and prior step that predict the withheld pose means best, each scored by the
/// median of its own held-out ratio and those of its neighbouring prior steps (same knots and order,
/// [`median_of_neighbours`]): the ratios of 48 shapes scatter, and one alone among neighbours that
/// predict far worse is luck, not a wander (a 16-pose log fitted with its holds' course: withheld sums of squares 87, 16 and 63
/// at steps of 0.3, 1 and 3 sigmas, against the nominal model's 212).
pub(crate) fn best(ctx: &Context<'_>) -> Option<SmoothFit> {
    let t_end = ctx.poses.last()?.t_end.max(1e-9);
    let at = |t: f64, _: Range<usize>| t;
    best_along(ctx, &Course { span: t_end, at: &at, along: "in time".into(), unit: "s", digits: 0 })
}

/// [`best`] along `course`.
pub(crate) fn best_along(ctx: &Context<'_>, course: &Course<'_>) -> Option<SmoothFit> {
    if !ctx.pose_level || !(ctx.e_white > 0.0) || !(course.span > 0.0) {
        return None;
    }
    let mut scored: Vec<(Shape, Option<ShapeScore>)> = Vec::new();
    for knots in KNOTS {
        let d = design(ctx, knots, course);
        let normals = Normals::new(&d.0, &d.1, &d.2, ctx.folds);
        for order in [1, 2] {
            for step in STEP_SIGMAS {
                let shape = Shape { knots, order, step };
                scored.push((shape, score(ctx, &d, &normals, shape)));
            }
        }
    }
    let ratios: Vec<(Shape, Option<f64>)> = scored.iter().map(|(shape, s)| (*shape, s.as_ref().map(|s| s.0))).collect();
    let (i, ratio) = (0..scored.len())
        .filter_map(|i| median_of_neighbours(&ratios, i).map(|r| (i, r)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let (shape, (_, after, edf, knots)) = (scored[i].0, scored[i].1.clone()?);
    Some(SmoothFit { ratio, after, edf, detail: shape.detail(course, edf), knots, span: course.span })
}

/// The median held-out ratio of shape `i` and its neighbours in `ratios` (the prior steps beside it,
/// same knots and order; at the ends of the steps the worse of two); `None` when one of them could
/// not be scored.
fn median_of_neighbours(ratios: &[(Shape, Option<f64>)], i: usize) -> Option<f64> {
    let (shape, _) = ratios[i];
    let same = |s: &Shape| s.knots == shape.knots && s.order == shape.order;
    let around = &ratios[i.saturating_sub(1)..(i + 2).min(ratios.len())];
    let mut values: Vec<f64> = around.iter().filter(|(s, _)| same(s)).map(|(_, r)| *r).collect::<Option<_>>()?;
    values.sort_by(f64::total_cmp);
    values.get(1).copied()
}

/// Puts the wander in the candidate's pose-level line when it predicts the withheld pose means
/// better than the family's other shapes.
pub(crate) fn add(ctx: &Context<'_>, e: &mut Evaluation, fit: SmoothFit) {
    let gain = ctx.value_gain(fit.ratio);
    let c = &mut e.candidate;
    c.variants.push((fit.detail.clone(), fit.ratio));
    if c.applicable && c.heldout_gain >= gain {
        return;
    }
    let Some(ratio_after) = ctx.ratio_after(&fit.after) else { return };
    c.applicable = true;
    (c.heldout_ratio, c.heldout_gain, c.extra_params) = (fit.ratio, gain, fit.edf.round() as usize);
    (e.gain_without_worst, e.wander) = (f64::NAN, true);
    c.ratio_after = ratio_after;
    c.detail = fit.detail;
    e.after = fit.after;
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_splines_sum_to_one_over_the_log_and_are_local() {
        for count in KNOTS {
            for k in 0..=100 {
                let t = 300.0 * k as f64 / 100.0;
                let sum: f64 = (0..count).map(|j| bspline(j, count, 300.0, t)).sum();
                assert!((sum - 1.0).abs() < 1e-12, "{count} bases at t = {t}: sum {sum}");
                let nonzero = (0..count).filter(|&j| bspline(j, count, 300.0, t) > 0.0).count();
                assert!(nonzero <= 4, "{count} bases at t = {t}: {nonzero} non-zero");
            }
        }
    }

    #[test]
    fn a_wander_that_leaves_the_pose_means_far_worse_than_the_nominal_fit_is_not_taken() {
        use crate::diagnose::{DiagnoseOptions, gap};
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let opts = DiagnoseOptions::DEFAULT;
        let table = to_table(&generate(&random_scenario(EffectClass::None, 1)), "sim").unwrap();
        let m = gap::measure(&table, &opts).unwrap();
        let ctx = Context::new(&table, &m, &opts).unwrap();
        // A wander carried by the holds' course that leaves the pose means 10 times the nominal
        // residuals (a warm touch after each placement read as one drift), and one that leaves them.
        let taken = |scale: f64| {
            let after = m.r.iter().map(|r| Some(scale * r)).collect();
            let fit = SmoothFit { ratio: 0.5, after, edf: 1.0, detail: String::new(), knots: Vec::new(), span: 1.0 };
            let mut e = ctx.not_testable("drift");
            add(&ctx, &mut e, fit);
            e.candidate.applicable
        };
        assert!(!taken(10.0), "contradicted by the pose means");
        assert!(taken(1.0));
    }

    #[test]
    fn the_splines_rate_is_their_slope() {
        // Against central differences over the span and beyond its ends.
        let (count, span, dt) = (6, 12.0, 1e-6);
        for j in 0..count {
            for k in -10..=130 {
                let t = 0.1 * k as f64 + 0.013;
                let slope = (bspline(j, count, span, t + dt) - bspline(j, count, span, t - dt)) / (2.0 * dt);
                let rate = bspline_rate(j, count, span, t);
                assert!((rate - slope).abs() < 1e-6, "basis {j} at {t}: rate {rate}, slope {slope}");
            }
        }
        // A course rising 0.5 per unit on the second axis and falling 0.25 on the third (a line's
        // coefficients are its values at the basis functions' centres, h apart from -h).
        let h = span / (count - 3) as f64;
        let knots = (0..count).map(|j| [0.0, 0.5 * (j as f64 - 1.0) * h, -0.25 * (j as f64 - 1.0) * h]).collect();
        let fit = SmoothFit { ratio: 1.0, after: Vec::new(), edf: 2.0, detail: String::new(), knots, span };
        assert!((fit.steepest(&[1.0, 6.0, 11.0]) - 0.5).abs() < 1e-9, "{}", fit.steepest(&[1.0, 6.0, 11.0]));
    }

    #[test]
    fn a_fold_withheld_through_the_hat_matrix_is_the_fit_without_it() {
        // 20 rows of 6 columns, a penalty on the last three; rows 4-6 withheld: refitted without
        // them, and through the full fit's hat matrix.
        let value = |i: usize, j: usize| ((i * 7 + j * 13) as f64 * 0.37).sin() + if i == j { 1.0 } else { 0.0 };
        let rows: Vec<Vec<f64>> = (0..20).map(|i| (0..6).map(|j| value(i, j)).collect()).collect();
        let r: Vec<f64> = (0..20).map(|i| (i as f64 * 1.3).cos()).collect();
        let penalised = |kept: &dyn Fn(usize) -> bool| {
            let mut a = normals(&rows, (0..20).filter(|&i| kept(i)));
            (3..6).for_each(|j| a[j][j] += 2.0);
            (a, rhs(&rows, &r, (0..20).filter(|&i| kept(i))))
        };
        let block = [4, 5, 6];
        let (a, b) = penalised(&|i| !block.contains(&i));
        let without = ScaledFactor::new(a, 0.0).unwrap().solve(&b).unwrap();
        let (a, b) = penalised(&|_| true);
        let full = ScaledFactor::new(a, 0.0).unwrap();
        let x = full.solve(&b).unwrap();
        let e: Vec<f64> = (0..20).map(|i| predict(&rows, &r, &x, i)).collect();
        let through_hat = withheld_through_hat(&rows, &e, &full, &block).unwrap();
        for (k, &i) in block.iter().enumerate() {
            assert!(
                (through_hat[k] - predict(&rows, &r, &without, i)).abs() < 1e-9,
                "row {i}: {} {}",
                through_hat[k],
                predict(&rows, &r, &without, i)
            );
            assert!((through_hat[k] - e[i]).abs() > 1e-3, "row {i}: withholding it changes its residual");
        }
    }

    #[test]
    fn a_lone_low_held_out_ratio_is_scored_by_its_neighbours() {
        let shape = |knots, order, step| Shape { knots, order, step };
        // Steps of one knot count and order, then the next order: a lone dip at 1 sigma between 3.0
        // and 2.8 counts as 2.8; at the ends the worse of two; orders are not neighbours.
        let ratios = vec![
            (shape(4, 1, 0.3), Some(3.0)),
            (shape(4, 1, 1.0), Some(1.0)),
            (shape(4, 1, 3.0), Some(2.8)),
            (shape(4, 2, 0.3), Some(0.5)),
            (shape(4, 2, 1.0), Some(1.5)),
            (shape(4, 2, 3.0), None),
        ];
        assert_eq!(median_of_neighbours(&ratios, 1), Some(2.8));
        assert_eq!(median_of_neighbours(&ratios, 0), Some(3.0));
        assert_eq!(median_of_neighbours(&ratios, 2), Some(2.8));
        assert_eq!(median_of_neighbours(&ratios, 3), Some(1.5), "the 4-knot first-order shapes are not its neighbours");
        assert_eq!(median_of_neighbours(&ratios, 4), None, "a neighbour that could not be scored");
    }

    #[test]
    fn the_prior_leaves_a_constant_and_penalises_steps() {
        // One axis' knots at 1, 1, 1, 1 (a constant): no penalty of either order; at 0, 0, 1, 1 (a
        // step of 1): (w / step)^2 for the first order.
        let (base, knots, w, step) = (0, 4, 2.0, 0.5);
        for order in [1, 2] {
            let mut a = vec![vec![0.0; 3 * knots]; 3 * knots];
            add_prior(&mut a, base, knots, order, step, w);
            let quad = |b: &[f64]| -> f64 {
                let x: Vec<f64> = (0..3 * knots).map(|c| if c % 3 == 0 { b[c / 3] } else { 0.0 }).collect();
                (0..x.len()).map(|j| (0..x.len()).map(|k| x[j] * a[j][k] * x[k]).sum::<f64>()).sum()
            };
            assert!(quad(&[1.0; 4]).abs() < 1e-12, "order {order}");
            let expected = if order == 1 { 16.0 } else { 2.0 * 16.0 };
            assert!(
                (quad(&[0.0, 0.0, 1.0, 1.0]) - expected).abs() < 1e-9,
                "order {order}: {}",
                quad(&[0.0, 0.0, 1.0, 1.0])
            );
        }
    }
}
