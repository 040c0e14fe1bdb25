//! Probes for gaps outside the catalogue: shapes no physical family of the catalogue has (a
//! periodic bias, a bias step at one time, cross-axis products, a bias following the direction of
//! the last rotation, one pose far off the others), judged by the same held-out criterion. A probe
//! never becomes a verdict: when one explains the withheld poses better than every family, the
//! verdict is `unexplained` and the probe says where the gap lies.

use std::ops::Range;

use super::SEGMENTS;
use super::family::{Context, Variant};
use super::gap::PoseData;
use super::jump::{MIN_SEGMENT_READINGS, jump_in_hold};
use super::math::{V3, dot, kept_design, lstsq_with_covariance};
use super::report::Probe;
use crate::vec3::{cross, norm};

/// Periodic bias `u . (s sin(2 pi t / P) + c cos(2 pi t / P))`, at least three periods in the log.
/// The period's search is charged as `ln` of the independent periods searched (one per cycle over
/// the log; the grid is five times finer) parameters: the best of `M` independent tries of pure
/// noise gains about `2 ln M` expected variances by chance (each parameter costs
/// [`PARAMETER_PENALTY`](super::PARAMETER_PENALTY) = 2).
fn periodic(ctx: &Context<'_>) -> Vec<Variant> {
    let t_end = ctx.poses.last().map_or(1.0, PoseData::t_mid);
    let mut out = Vec::new();
    // Frequencies from 3 periods per log to one per 10 s, a fifth of a cycle over the log apart.
    let step_hz = 0.2 / t_end.max(1e-9);
    let (lowest_hz, highest_hz) = (3.0 / t_end.max(1e-9), 0.1);
    let independent = ((highest_hz - lowest_hz) * t_end).max(1.0);
    let params = 6 + (independent.ln().ceil() as usize).max(1);
    let mut f_hz = lowest_hz;
    while f_hz <= highest_hz {
        let (period, w) = (1.0 / f_hz, std::f64::consts::TAU * f_hz);
        let extra = ctx
            .poses
            .iter()
            .zip(ctx.directions())
            .map(|(p, u)| {
                let (s, c) = (w * p.t_mid()).sin_cos();
                u.iter().map(|x| x * s).chain(u.iter().map(|x| x * c)).collect()
            })
            .collect();
        out.push(Variant { extra, params, detail: format!("a periodic bias, period {period:.0} s") });
        f_hz += step_hz;
    }
    out
}

/// A bias step at one time: `u . s` on the poses after the step, for every step between two poses
/// with at least [`STEP_SIDE_POSES`] poses on each side, and inside each such hold whose segments a
/// jump fits better than a line in time by more than its search gains by chance ([`JUMP_SEARCH_CHI2`];
/// a drift moves a hold as a line), at the jump ([`jump_in_hold`]): that hold's mean takes the share
/// of its samples after it. The place in a hold comes from the hold's segments about their own mean,
/// which white noise leaves independent of the hold's mean that the withheld poses test. The step's
/// search is charged as the periodic one's: `ln` of the places searched.
fn bias_step(ctx: &Context<'_>) -> Vec<Variant> {
    let n = ctx.poses.len();
    let between = (STEP_SIDE_POSES..=n.saturating_sub(STEP_SIDE_POSES)).map(|first_after| (first_after, 1.0));
    let inside = (STEP_SIDE_POSES..n.saturating_sub(STEP_SIDE_POSES)).filter_map(|p| {
        let (y, var) = hold_deviations(ctx, p)?;
        let jump = jump_in_hold(&[y], [var]);
        (jump.over_line >= JUMP_SEARCH_CHI2).then_some((p, jump.share_after))
    });
    let places: Vec<(usize, f64)> = between.chain(inside).collect();
    let params = 3 + ((places.len().max(1) as f64).ln().ceil() as usize).max(1);
    places.into_iter().map(|(first_after, share)| step_variant(ctx, first_after, share, params)).collect()
}

/// The bias step whose first pose after it is `first_after`, which takes `share` of it (1: the step
/// lies before that pose, less: inside its hold).
fn step_variant(ctx: &Context<'_>, first_after: usize, share: f64, params: usize) -> Variant {
    let weight = |i: usize| match i.cmp(&first_after) {
        std::cmp::Ordering::Less => 0.0,
        std::cmp::Ordering::Equal => share,
        std::cmp::Ordering::Greater => 1.0,
    };
    let extra = ctx.directions().iter().enumerate().map(|(i, u)| u.iter().map(|x| x * weight(i)).collect()).collect();
    let pose = &ctx.poses[first_after];
    let detail = if share < 1.0 {
        format!("a bias step at {:.0} s, inside a hold", pose.t_end - share * pose.duration())
    } else {
        format!("a bias step at {:.0} s", 0.5 * (ctx.poses[first_after - 1].t_mid() + pose.t_mid()))
    };
    Variant { extra, params, detail }
}

/// Evidence by which a bias step must exceed a family to veto it: a warm-up or a wander is a smooth
/// step, and on a few poses a step fits a slow drift nearly as well as the drift does. None over a
/// slow change (drift, temperature) when a hold beside the step shows it as a jump
/// ([`step_seen_in_holds`]), nor over a penalised wander the step fits every pose closer than
/// (`verdict::beaten`).
const STEP_OVER_DRIFT: f64 = 0.2;

/// The step fitted in `rows` (the calibration columns, then the step's three): the first pose after
/// it and the step's modulus change per unit direction (the columns enter as `r + rows . x`, the
/// modulus moves by `-u . x`).
fn fitted_step(ctx: &Context<'_>, rows: &[Vec<f64>]) -> Option<(usize, V3)> {
    let base = ctx.base_columns();
    let after = rows.iter().position(|r| r[base..].iter().any(|x| *x != 0.0))?;
    let (x, _, _) = lstsq_with_covariance(rows, &ctx.m.r)?;
    (after > 0 && x.len() >= base + 3).then(|| (after, std::array::from_fn(|a| -x[base + a])))
}

/// One of the two holds beside a bias step shows it as a jump ([`jump_inside_hold`]): the bias
/// jumped within that hold, where a slow change that imitates the step on the pose means would move
/// it as a line.
fn step_seen_in_holds(ctx: &Context<'_>, (after, step): (usize, V3)) -> bool {
    [after - 1, after].iter().any(|&p| jump_inside_hold(ctx, p, step))
}

/// Hold `p`'s segments show the step as a jump at one time in the hold: along the step's own
/// direction in the readings (a bias step moves the whole reading vector, whatever the pose's
/// orientation; its component along gravity, which the pose means see, may be a small part of it),
/// of the step's sign and within a factor of two of its size, fitting them better than a line in
/// time by more than the search over its places gains by chance ([`JUMP_SEARCH_CHI2`], as for
/// placing a step inside a hold: the agreement in sign and size is the further evidence). The bias
/// jumped within the hold (too little for the pose finder to cut it there); a drift moves a hold as
/// a line. (At 9, three standard deviations of one degree of freedom with the place given, an
/// offset step a hold's segments showed at 7.2, its size 1.2 times the fitted step's, stayed a drift
/// on the development sets.)
fn jump_inside_hold(ctx: &Context<'_>, p: usize, step: V3) -> bool {
    // The readings' change the calibrated step implies: `Ka^-1 step` (input unit).
    let change = ctx.m.model.ka_inverse_times(step);
    let expected = norm(change);
    if !(expected > 0.0) {
        return false;
    }
    let Some((y, var)) = segments_along(ctx, p, change.map(|c| c / expected)) else { return false };
    let jump = jump_in_hold(&[y], [var]);
    let size = jump.size[0];
    let agrees = size > 0.0 && (0.5..=2.0).contains(&(size / expected));
    agrees && jump.over_line >= JUMP_SEARCH_CHI2
}

/// Chi-square by which a jump searched in a hold must fit its segments better than a line in time
/// to be placed there: the best of `M` places on pure noise gains about `2 ln M` by chance, and
/// [`jump_in_hold`] searches `4 SEGMENTS - 1`.
const JUMP_SEARCH_CHI2: f64 = 6.3;

/// Pose `p`'s segment means as modulus deviations from its mean (output unit) and their variance
/// under white noise; `None` with too few samples per segment.
fn hold_deviations(ctx: &Context<'_>, p: usize) -> Option<([f64; SEGMENTS], f64)> {
    segments_along(ctx, p, ctx.m.model.kt_times(ctx.m.directions[p]))
}

/// Pose `p`'s segment means as deviations from its mean projected on `along` (input unit per
/// projected unit) and their variance under white noise; `None` with too few samples per segment.
fn segments_along(ctx: &Context<'_>, p: usize, along: V3) -> Option<([f64; SEGMENTS], f64)> {
    let (pose, m) = (&ctx.poses[p], ctx.m);
    let var: f64 = (0..3).map(|a| along[a] * along[a] * m.white[a]).sum::<f64>() / pose.seg_n as f64;
    let y = std::array::from_fn(|j| dot(along, std::array::from_fn(|a| pose.seg[j][a] - pose.mean[a])));
    (pose.seg_n >= MIN_SEGMENT_READINGS && var > 0.0).then_some((y, var))
}

/// Fewest poses on each side of a probed bias step.
const STEP_SIDE_POSES: usize = 2;

/// Cross-axis products: axis `a` reading `c f_b f_c / g` for pairs of axes `b < c`. Through the
/// modulus (`u . delta`, `f = g u`) a pair's product on the third axis reads as `g u_x u_y u_z`
/// whichever axis carries it, and on one of its own axes as `g u_a^2 u_b`: the 9 couplings show as
/// 7 terms. Three of them are the square terms per axis with the biases (`u_x^3 = u_x - u_x (u_y^2 +
/// u_z^2)`): a square non-linearity and a coupling are the same modulus there, and the family
/// takes them. The probe is the other four: `u_x u_y u_z` (alone, one column: a coupling of the
/// other two axes on each) and `u_a (u_b^2 - u_c^2)` per axis.
fn cross_axis(ctx: &Context<'_>) -> Vec<Variant> {
    let g = ctx.m.gravity;
    let xyz = |u: &V3| g * u[0] * u[1] * u[2];
    let beyond_squares =
        |u: &V3| [(0, 1, 2), (1, 2, 0), (2, 0, 1)].map(|(a, b, c)| g * u[a] * (u[b] * u[b] - u[c] * u[c]));
    let third: Vec<Vec<f64>> = ctx.directions().iter().map(|u| vec![xyz(u)]).collect();
    let all = ctx.directions().iter().map(|u| std::iter::once(xyz(u)).chain(beyond_squares(u)).collect()).collect();
    vec![
        Variant { extra: third, params: 1, detail: "cross-axis terms (products of the other two axes)".into() },
        Variant {
            extra: all,
            params: 4,
            detail: "cross-axis terms beyond the square terms' (products of two axes)".into(),
        },
    ]
}

/// Smallest move between poses that sets a hysteresis state: a change of an axis' reading of this
/// many g, or a rotation of `asin` of it. A pose split in two without a turn keeps its state.
const HYSTERESIS_MOVE: f64 = 0.002;

/// A hysteresis state per pose, set by the move from the previous pose: `moved(i)`, the state a
/// move of at least [`HYSTERESIS_MOVE`] sets (`None` for a smaller step); after a smaller step, the
/// previous pose's state if the state `persists`, else `rest` (a mount that only takes an offset
/// while it is moved). The first pose is at `rest`.
fn held_states<S: Copy>(n: usize, persists: bool, rest: S, moved: impl Fn(usize) -> Option<S>) -> Vec<S> {
    let mut state = rest;
    (0..n)
        .map(|i| {
            match (i > 0).then(|| moved(i)).flatten() {
                Some(s) => state = s,
                None if !persists => state = rest,
                None => {}
            }
            state
        })
        .collect()
}

/// [`held_states`] of one axis: `sign(step(i))` after a move, 0 at rest.
fn hysteresis_states(n: usize, persists: bool, step: impl Fn(usize) -> f64) -> Vec<f64> {
    held_states(n, persists, 0.0, |i| {
        let s = step(i);
        (s.abs() >= HYSTERESIS_MOVE).then(|| s.signum())
    })
}

/// Hysteresis per axis: a bias on each axis with the sign of that axis' last change of reading.
fn rotation_direction(ctx: &Context<'_>) -> Vec<Variant> {
    let (cal, dirs, g) = (ctx.calibrated(), ctx.directions(), ctx.m.gravity);
    [
        (true, "a bias per axis following the sign of its last change"),
        (false, "a bias per axis following the sign of its change from the previous pose"),
    ]
    .into_iter()
    .map(|(persists, detail)| {
        let states: Vec<Vec<f64>> =
            (0..3).map(|a| hysteresis_states(cal.len(), persists, |i| (cal[i][a] - cal[i - 1][a]) / g)).collect();
        let extra = (0..cal.len()).map(|i| (0..3).map(|a| dirs[i][a] * states[a][i]).collect()).collect();
        Variant { extra, params: 3, detail: detail.into() }
    })
    .chain(approach_direction(ctx))
    .collect()
}

/// Hysteresis along the approach: a bias along the unit change of reading from the last pose that
/// moved (a proof mass held back by stiction along the direction gravity came from), per axis or
/// one size for all (1 parameter: testable on 12 poses); a pose reached without a turn keeps the
/// previous state.
fn approach_direction(ctx: &Context<'_>) -> [Variant; 2] {
    let (cal, dirs, g) = (ctx.calibrated(), ctx.directions(), ctx.m.gravity);
    let states = held_states(cal.len(), true, [0.0; 3], |i| {
        let step: V3 = std::array::from_fn(|a| (cal[i][a] - cal[i - 1][a]) / g);
        let size = norm(step);
        (size >= HYSTERESIS_MOVE).then(|| step.map(|c| c / size))
    });
    let per_axis: Vec<Vec<f64>> = states.iter().zip(dirs).map(|(s, u)| (0..3).map(|a| u[a] * s[a]).collect()).collect();
    let common = per_axis.iter().map(|row| vec![row.iter().sum()]).collect();
    [
        Variant {
            extra: per_axis,
            params: 3,
            detail: "a bias per axis along the direction its reading came from".into(),
        },
        Variant { extra: common, params: 1, detail: "a bias along the direction the reading came from".into() },
    ]
}

/// Turn axes searched by [`rotation_sense`]: points of a Fibonacci half-sphere (a turn axis and its
/// opposite give the same probe).
const TURN_AXES: usize = 32;

/// Evidence by which the sense-of-turn probe must exceed a family to veto it: searched over many
/// turn axes, on a log of 16 poses it explained a drift ramp and a square non-linearity by chance
/// 0.14-0.23 better than their families did (development sets).
const TURN_OVER_FAMILY: f64 = 0.25;

/// Hysteresis by the sense of the last turn: a bias vector whose sign follows the sense of the
/// rotation from the previous pose about one body axis `e` (`sign((u_prev x u) . e)`), for each of
/// [`TURN_AXES`] axes; the search is charged as the periodic one's.
fn rotation_sense(ctx: &Context<'_>) -> Vec<Variant> {
    let dirs = ctx.directions();
    let params = 3 + (TURN_AXES as f64).ln().ceil() as usize;
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..TURN_AXES)
        .map(|k| {
            let z = 1.0 - (k as f64 + 0.5) / TURN_AXES as f64;
            let (s, c) = (golden * k as f64).sin_cos();
            let r = (1.0 - z * z).sqrt();
            let e = [r * c, r * s, z];
            let states = hysteresis_states(dirs.len(), true, |i| dot(cross(dirs[i - 1], dirs[i]), e));
            let extra = dirs.iter().zip(&states).map(|(u, s)| u.iter().map(|x| x * s).collect()).collect();
            Variant {
                extra,
                params,
                detail: format!(
                    "a bias following the sense of the last turn about ({:.2}, {:.2}, {:.2})",
                    e[0], e[1], e[2]
                ),
            }
        })
        .collect()
}

/// One bad pose (a knock, a clamp, a hold misread): the nominal model without the pose that lies
/// furthest off the fit to the others (in units of their scatter, at least white noise), with the
/// other pieces of its hold the pose finder cut it into ([`Context::hold_runs`]), charged a parameter per
/// piece and its choice among the poses (`ln` of their number, as a step's places), when it lies
/// [`GROSS_OFF`] times the others' held-out scatter off that fit. A slow change can take such a
/// pose with the calibration it spoils (a warm-up of a few seconds on the early poses): it then
/// predicts the other poses better without explaining them. (The pose the nominal model predicts
/// worst withheld is not always the bad one: on 12-14 poses the bad pose, among the training poses,
/// moves the calibration so that others are predicted worse; a 13-pose log's was the fourth worst.)
fn one_pose(ctx: &Context<'_>) -> Option<Probe> {
    let n = ctx.poses.len();
    let without = |hold: &Range<usize>| {
        let mut dropped = ctx.none_dropped.clone();
        dropped[hold.clone()].iter_mut().for_each(|d| *d = true);
        dropped
    };
    let offs =
        ctx.hold_runs().into_iter().filter_map(|hold| Some((off_the_others(ctx, &without(&hold), &hold)?, hold)));
    let ((bad, off, _), hold) = offs.max_by(|a, b| (a.0.1 / a.0.2).total_cmp(&(b.0.1 / b.0.2)))?;
    let dropped = without(&hold);
    let params = hold.len() + (n as f64).ln().ceil() as usize;
    let ratio = ctx.heldout_ratio(&ctx.base_rows, &dropped, params)?;
    // The others' scatter no less than white noise (a held-out ratio below 1 on few poses is chance).
    let off_sigmas = off / ctx.e_white.sqrt() / ratio.max(1.0);
    let with = if hold.len() > 1 { format!(" (a hold cut into {} poses)", hold.len()) } else { String::new() };
    (off_sigmas >= GROSS_OFF).then(|| Probe {
        shape: "one-pose",
        heldout_gain: ctx.value_gain(ratio),
        detail: format!("one pose, #{bad}{with}, {off_sigmas:.0} times the others' scatter off them"),
        in_sample_ratio: ctx.fit_ratio(&ctx.base_rows, &dropped).map_or(f64::NAN, |(r, _)| r),
        veto_margin: 0.0,
        jump_in_hold: false,
        columns: hold.len(),
        step_before: None,
    })
}

/// The pose of `hold` furthest off the nominal fit to the poses not `dropped`, how far (output
/// unit, over the square root of one plus the fit's prediction variance there in units of one
/// pose's: a pose nearly alone in its direction is predicted from the others no better than their
/// fit's uncertainty allows), and their residual scatter (per residual degree of freedom, at least
/// the white noise of a withheld pose).
fn off_the_others(ctx: &Context<'_>, dropped: &[bool], hold: &Range<usize>) -> Option<(usize, f64, f64)> {
    let design = kept_design(&ctx.base_rows, dropped)?;
    let residuals = design.residuals_everywhere(&ctx.base_rows, &ctx.m.r)?;
    let kept = || residuals.iter().zip(dropped).filter(|(_, d)| !**d).map(|(r, _)| r);
    let dof = kept().count().checked_sub(ctx.base_columns()).filter(|&d| d > 0)?;
    let scatter = (kept().map(|r| r * r).sum::<f64>() / dof as f64).max(ctx.e_white).sqrt();
    let off = |i: usize| residuals[i].abs() / (1.0 + design.variance_factor(&ctx.base_rows[i])).sqrt();
    let worst = hold.clone().max_by(|&a, &b| off(a).total_cmp(&off(b)))?;
    Some((worst, off(worst), scatter))
}

/// How many standard deviations of the other poses' held-out scatter the pose must lie off the fit
/// to them ([`one_pose`]): a gross error, not the tail of the poses' spread. On the development and
/// validation sets (1 728 logs) 45 logs have a pose that far off: the 14 bad or clamped poses and
/// 31 others (most on 12-16 poses, or a moving pose of a motion log), of which 8 gain 0.2 or more
/// without the pose; one answer changed where visible, a wrong one to another (a square term on 12
/// poses, colored noise to `unexplained`). (Measured as the worst withheld
/// pose against the others' held-out scatter, colored noises and non-linearities reached 14.) Since
/// stop 82 the distance counts the others' fit's uncertainty at the pose ([`off_the_others`]): a
/// pose nearly alone in its direction lay thousands of times the scatter off on a blindgen3 drift
/// of 13 poses and vetoed the drift. That distance is never more than the old one, so the bound is
/// 15, just beyond the 14 measured then: at 20, a bad pose of 211 mg (`blind_eval` held-out seed
/// 8500, one of two poses looking along +x) fell to 16 and was named colored noise. On 3 264
/// development and seen fresh logs 15 and 20 gave the same answers.
const GROSS_OFF: f64 = 15.0;

/// A probe's parametrisations for the data. Only those that leave every fold enough training poses
/// beyond their columns are judged: a probe that interpolates its training poses could veto a
/// family (`unexplained`) by chance.
type MakeVariants = fn(&Context<'_>) -> Vec<Variant>;

/// A probe's test that a design leaves its folds enough training poses beyond its columns.
type LeavesDof = fn(&Context<'_>, &[Vec<f64>]) -> bool;

/// Fewest training poses beyond a bias step's columns on the families' own folds
/// ([`Context::trains_beyond`]). A step has three columns and its places are charged as a search
/// ([`bias_step`]); counted as for the other probes ([`Context::leaves_residual_dof`]: 3, as if a
/// fifth were withheld), it was not tested on logs of 15, 17 or 18 poses, where a drift's wander then followed
/// it; counted on the folds its fit is judged on, it is from 15 poses. On the development and
/// validation sets (1 728 logs) the change turned a bias step, an offset step and a flexed board
/// from drift or settling to `unexplained` and changed no other answer where visible; counting the
/// other probes the same way lost 12 right answers.
const STEP_RESIDUAL_DOF: usize = 2;

/// A searched probe: its shape, its variants, the evidence by which it must exceed a family to veto
/// it and the test of its residual degrees of freedom.
type Searched = (&'static str, MakeVariants, f64, LeavesDof);

/// The searched probes.
const SEARCHED: [Searched; 5] = [
    ("periodic", periodic, 0.0, |c, e| c.leaves_residual_dof(e)),
    ("bias-step", bias_step, STEP_OVER_DRIFT, |c, e| c.trains_beyond(e, STEP_RESIDUAL_DOF)),
    ("cross-axis", cross_axis, 0.0, |c, e| c.leaves_residual_dof(e)),
    ("rotation-direction", rotation_direction, 0.0, |c, e| c.leaves_residual_dof(e)),
    ("rotation-sense", rotation_sense, TURN_OVER_FAMILY, |c, e| c.leaves_residual_dof(e)),
];

/// The variants a searched probe tries: those that leave it its residual degrees of freedom.
fn variants_of(ctx: &Context<'_>, &(_, make, _, leaves_dof): &Searched) -> Vec<Variant> {
    make(ctx).into_iter().filter(|v| leaves_dof(ctx, &v.extra)).collect()
}

/// Probe `shape`'s search reaches the held-out gain `gain` in one of `draws` (pose residuals of a
/// noise model, in place of the log's). The one-pose probe searches no shape: never.
pub(crate) fn found_in_a_draw(ctx: &Context<'_>, shape: &str, draws: &[Vec<f64>], gain: f64) -> bool {
    SEARCHED
        .iter()
        .find(|(s, ..)| *s == shape)
        .is_some_and(|p| ctx.reached_in_a_draw(&variants_of(ctx, p), draws, gain))
}

/// Every probe with its held-out gain.
pub(crate) fn run(ctx: &Context<'_>) -> Vec<Probe> {
    SEARCHED
        .iter()
        .filter_map(|probe @ &(shape, _, veto_margin, _)| {
            let variants = variants_of(ctx, probe);
            let f = ctx.best_of(variants)?;
            let step = (shape == "bias-step").then(|| fitted_step(ctx, &f.rows)).flatten();
            let jump_in_hold = step.is_some_and(|s| step_seen_in_holds(ctx, s));
            let step_before = step.map(|(after, _)| after);
            let heldout_gain = ctx.value_gain(f.score_ratio);
            let in_sample_ratio = f.in_sample.map_or(f64::NAN, |fit| fit.ratio);
            let columns = f.rows.first().map_or(0, |r| r.len().saturating_sub(ctx.base_columns()));
            Some(Probe {
                shape,
                heldout_gain,
                detail: f.detail,
                in_sample_ratio,
                veto_margin,
                jump_in_hold,
                columns,
                step_before,
            })
        })
        .chain(one_pose(ctx))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csvio::{self, AccumulateOptions, Table};
    use crate::diagnose::{DiagnoseOptions, diagnose, gap};
    use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
    use crate::sim::{Plan, SimConfig, simulate_with};

    /// A clean simulated log whose bias along one direction changes by `size_mg` in the middle of
    /// the middle hold: at once (`ramp_s` 0: an offset step) or as a ramp over `ramp_s` seconds
    /// centred there (a drift as fast as a step on the pose means, moving the holds as it goes).
    fn shifted_log(seed: u64, size_mg: f64, ramp_s: f64) -> Table {
        shifted_log_at(seed, size_mg, ramp_s, 0.5)
    }

    /// [`shifted_log`] with the change centred at `share` of the middle hold's rows.
    fn shifted_log_at(seed: u64, size_mg: f64, ramp_s: f64, share: f64) -> Table {
        shifted_along(seed, size_mg, ramp_s, share, &|_| [0.48, -0.6, 0.64])
    }

    /// [`shifted_log_at`] along `direction(the middle hold's mean reading)`.
    fn shifted_along(seed: u64, size_mg: f64, ramp_s: f64, share: f64, direction: &dyn Fn(V3) -> V3) -> Table {
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "shift").unwrap();
        let acc = csvio::accumulate(&table, &AccumulateOptions::default()).unwrap();
        let rate = acc.sample_rate_hz.unwrap();
        let hold = acc.spans[acc.spans.len() / 2];
        let row = hold.first_row + ((hold.last_row - hold.first_row) as f64 * share) as usize;
        let at_s = gap::row_time(&table, row, rate);
        let mg = table.median_magnitude / 1000.0;
        let direction = direction(
            table.samples[hold.first_row..=hold.last_row]
                .iter()
                .fold([0.0; 3], |s, r| std::array::from_fn(|a| s[a] + r[a])),
        );
        for i in 0..table.samples.len() {
            let t = gap::row_time(&table, i, rate);
            let share = if ramp_s > 0.0 { ((t - at_s) / ramp_s + 0.5).clamp(0.0, 1.0) } else { f64::from(t >= at_s) };
            (0..3).for_each(|a| table.samples[i][a] += size_mg * mg * share * direction[a]);
        }
        table
    }

    #[test]
    fn an_offset_step_inside_a_hold_is_not_a_drift_but_a_ramp_as_large_is() {
        // 0.8 mg at once in the middle of the middle hold: that hold shows the jump, and the step
        // vetoes the drift that imitates it on the pose means (both seeds were drift without the
        // holds' evidence). The same change as a ramp over 40 s moves the holds as lines: drift.
        let opts = DiagnoseOptions::DEFAULT;
        for seed in [3, 8] {
            let step = diagnose(&shifted_log(seed, 0.8, 0.0), &opts).unwrap();
            assert_eq!(step.verdict, "unexplained", "seed {seed}: {}", step.to_text());
            let ramp = diagnose(&shifted_log(seed, 0.8, 40.0), &opts).unwrap();
            assert_eq!(ramp.verdict, "drift", "seed {seed}: {}", ramp.to_text());
        }
    }

    #[test]
    fn an_offset_step_a_third_into_a_hold_is_placed_inside_it_not_called_a_drift() {
        // 0.45 mg at once a third into the middle hold, which shows the jump: that hold's mean takes
        // two thirds of it. Placed between two poses, the step left the hold out of line (seed 3:
        // held-out gain 0.60, seed 8: the drift won); placed inside it, 0.87 and 0.82.
        let opts = DiagnoseOptions::DEFAULT;
        for seed in [3, 8] {
            let d = diagnose(&shifted_log_at(seed, 0.45, 0.0, 0.35), &opts).unwrap();
            assert_eq!(d.verdict, "unexplained", "seed {seed}: {}", d.to_text());
            let located = d.located.clone().unwrap_or_default();
            assert!(located.contains("a bias step") && located.contains("inside a hold"), "seed {seed}: {located}");
        }
    }

    #[test]
    fn a_step_across_gravity_in_the_hold_it_happens_in_is_seen_there_as_a_jump() {
        // 0.8 mg at once in the middle of the middle hold, at right angles to gravity there: the
        // hold's modulus hardly moves, its readings do. Tested along gravity only, its segments fit
        // a jump 2.5 (seed 3) and 1.2 (seed 8) chi-square better than a line, short of the search's
        // 6.3, and the step stood against a drift on its held-out gain alone; along the step's own
        // direction the hold shows it (50 on seed 3).
        let across = |g: V3| {
            let side = cross(g, [0.3, -0.5, 0.8]);
            side.map(|c| c / norm(side))
        };
        let opts = DiagnoseOptions::DEFAULT;
        for seed in [3, 8] {
            let step = diagnose(&shifted_along(seed, 0.8, 0.0, 0.5, &across), &opts).unwrap();
            assert_eq!(step.verdict, "unexplained", "seed {seed}: {}", step.to_text());
            let probe = step.probes.iter().find(|p| p.shape == "bias-step");
            assert!(probe.is_some_and(|p| p.jump_in_hold), "seed {seed}: the hold shows no jump");
        }
    }

    /// `table` up to the end of its `holds`-th hold.
    fn first_holds(mut table: Table, holds: usize) -> Table {
        let spans = csvio::accumulate(&table, &AccumulateOptions::default()).unwrap().spans;
        table.truncate(spans[holds - 1].last_row + 1);
        table
    }

    #[test]
    fn a_bias_step_is_tested_on_logs_of_seventeen_and_eighteen_poses() {
        // 3 mg at the start of the middle hold (seed 4), the log cut to 17 and 18 poses. Counted as
        // if a fifth of the poses were withheld, the step was not tried there, and a drift's wander
        // followed it (verdict drift on both).
        let opts = DiagnoseOptions::DEFAULT;
        for holds in [17, 18] {
            let d = diagnose(&first_holds(shifted_log_at(4, 3.0, 0.0, 0.0), holds), &opts).unwrap();
            assert_eq!(d.verdict, "unexplained", "{holds} holds: {}", d.to_text());
            let located = d.located.clone().unwrap_or_default();
            assert!(located.contains("a bias step"), "{holds} holds: {located}");
        }
    }

    /// A clean simulated log of `holds` holds whose hold `bad` reads `size_mg` off along one
    /// direction (a knocked sensor, a hold misread).
    fn bad_pose_log(seed: u64, holds: usize, bad: usize, size_mg: f64) -> Table {
        let mut table =
            first_holds(to_table(&generate(&random_scenario(EffectClass::None, seed)), "bad").unwrap(), holds);
        let hold = csvio::accumulate(&table, &AccumulateOptions::default()).unwrap().spans[bad];
        let mg = table.median_magnitude / 1000.0;
        for sample in &mut table.samples[hold.first_row..=hold.last_row] {
            (0..3).for_each(|a| sample[a] += size_mg * mg * [0.48, -0.6, 0.64][a]);
        }
        table
    }

    /// A simulated log on `poses` random poses whose axis `a` reads `c f_a f_b / g` more for the
    /// pairs `(a, b)` of `pairs` (a coupling of each pair on one of its own axes, `c` in g).
    fn coupled_log(seed: u64, poses: usize, pairs: &[(usize, usize, f64)]) -> Table {
        let cfg = SimConfig { plan: Plan::Random(poses), ..SimConfig::paper(seed) };
        let g = cfg.gravity;
        let recording = simulate_with(
            &cfg,
            &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                let f = *r;
                pairs.iter().for_each(|&(a, b, c)| r[a] += c * f[a] * f[b] / g);
            }],
        );
        crate::diagnose::testing::table_of_poses(recording, |_| true, "coupled")
    }

    #[test]
    fn pairwise_products_on_their_own_axes_are_seen_by_the_cross_axis_probe() {
        // x reads 4 mg x y more and z 4 mg z y less, y 3 mg y z more and x 3 mg x z less (at 1 g):
        // through the modulus u_y (u_x^2 - u_z^2) and u_z (u_y^2 - u_x^2), which no square term per
        // axis takes. The three products of the other two axes alone (one column, u_x u_y u_z) see
        // none of it; the terms beyond the square terms' take it on withheld poses.
        for seed in [3, 4] {
            let pairs = [(0, 1, 4.0e-3), (2, 1, -4.0e-3), (1, 2, 3.0e-3), (0, 2, -3.0e-3)];
            let table = coupled_log(seed, 32, &pairs);
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.verdict, "unexplained", "seed {seed}: {}", d.to_text());
            let probe = d.probes.iter().find(|p| p.shape == "cross-axis").expect("the cross-axis probe");
            assert_eq!(probe.detail, "cross-axis terms beyond the square terms' (products of two axes)", "seed {seed}");
            assert!(probe.heldout_gain >= 0.6, "seed {seed}: {}", probe.heldout_gain);
        }
    }

    #[test]
    fn one_bad_pose_among_thirteen_is_located_not_named_a_drift() {
        // 40 mg off along one direction on the third of 13 poses (seed 7). A warm-up's exponential
        // took it with the calibration it spoils (verdict drift); the nominal model without it
        // predicts the others to white noise, the pose 31 times their scatter off them. On 12 poses
        // (seed 2) the pose predicted worst withheld was another one (the bad pose, trained on, moved
        // the calibration): the pose chosen is the one furthest off the fit to the others.
        for (seed, holds) in [(7, 13), (2, 12)] {
            let d = diagnose(&bad_pose_log(seed, holds, 2, 40.0), &DiagnoseOptions::DEFAULT).unwrap();
            assert_eq!(d.verdict, "unexplained", "seed {seed}: {}", d.to_text());
            let located = d.located.clone().unwrap_or_default();
            assert!(located.starts_with("one pose, #2,"), "seed {seed}: {located}");
        }
    }

    /// A clean simulated log whose hold `bad` is clamped: its bias creeps along one direction in
    /// three steps, to `size_mg`, so that the pose finder cuts the hold at each step.
    fn creeping_clamp_log(seed: u64, bad: usize, size_mg: f64) -> Table {
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "clamp").unwrap();
        let hold = csvio::accumulate(&table, &AccumulateOptions::default()).unwrap().spans[bad];
        let mg = table.median_magnitude / 1000.0;
        let rows = hold.last_row + 1 - hold.first_row;
        for (k, sample) in table.samples[hold.first_row..=hold.last_row].iter_mut().enumerate() {
            let size = size_mg * [0.8, 0.9, 1.0][(3 * k / rows).min(2)];
            (0..3).for_each(|a| sample[a] += size * mg * [0.48, -0.6, 0.64][a]);
        }
        table
    }

    #[test]
    fn a_clamped_hold_cut_into_pieces_is_located_as_one_hold() {
        // A clamp flexes the board through the sixth hold, its bias creeping 32, 36 then 40 mg: the
        // pose finder cuts the hold into three poses of the same direction. Dropping any one of them
        // left the other two in the fit, which they spoil; the pieces are dropped together.
        for seed in [3, 5] {
            let d = diagnose(&creeping_clamp_log(seed, 5, 40.0), &DiagnoseOptions::DEFAULT).unwrap();
            assert_eq!(d.verdict, "unexplained", "seed {seed}: {}", d.to_text());
            let located = d.located.clone().unwrap_or_default();
            assert!(located.contains("a hold cut into 3 poses"), "seed {seed}: {located}");
        }
    }

    #[test]
    fn a_hysteresis_state_is_set_by_a_move_and_kept_or_cleared_by_a_still_step() {
        // A turn, a pose split in two by the pose finder (a step of noise), a turn back, a step
        // just under the smallest move, a turn.
        let steps = [f64::NAN, 0.5, 1e-4, -0.3, 0.5 * HYSTERESIS_MOVE, 0.2];
        let states = |persists| hysteresis_states(steps.len(), persists, |i| steps[i]);
        assert_eq!(states(true), [0.0, 1.0, 1.0, -1.0, -1.0, 1.0]);
        assert_eq!(states(false), [0.0, 1.0, 0.0, -1.0, 0.0, 1.0]);
    }

    /// A clean simulated log with stiction along the approach: from each hold's start to the next
    /// hold's, the bias is `size_mg` against the unit change of the sensor's reading from the
    /// previous hold (the proof mass held back along the direction gravity came from).
    fn stiction_log(seed: u64, size_mg: f64) -> Table {
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "stiction").unwrap();
        let spans = csvio::accumulate(&table, &AccumulateOptions::default()).unwrap().spans;
        let mean_reading = |first: usize, last: usize| -> V3 {
            let rows = &table.samples[first..=last];
            std::array::from_fn(|a| rows.iter().map(|s| s[a]).sum::<f64>() / rows.len() as f64)
        };
        let means: Vec<V3> = spans.iter().map(|h| mean_reading(h.first_row, h.last_row)).collect();
        let mg = table.median_magnitude / 1000.0;
        for k in 1..spans.len() {
            let change: V3 = std::array::from_fn(|a| means[k][a] - means[k - 1][a]);
            let size = norm(change);
            let end = spans.get(k + 1).map_or(table.samples.len(), |h| h.first_row);
            for sample in &mut table.samples[spans[k].first_row..end] {
                (0..3).for_each(|a| sample[a] -= size_mg * mg * change[a] / size);
            }
        }
        table
    }

    #[test]
    fn stiction_along_the_approach_is_located_there_not_named_a_family() {
        // 1 mg against the direction each pose was approached from: the modulus moves by about
        // 1 mg times sin(turn / 2), a function of the turn, not of the orientation or of time.
        for seed in [2, 5] {
            let d = diagnose(&stiction_log(seed, 1.0), &DiagnoseOptions::DEFAULT).unwrap();
            assert_eq!(d.verdict, "unexplained", "seed {seed}: {}", d.to_text());
            let located = d.located.clone().unwrap_or_default();
            assert!(located.contains("the direction the reading came from"), "seed {seed}: {located}");
        }
    }

    #[test]
    fn a_jump_a_hold_shows_beyond_what_its_search_gains_by_chance_confirms_the_step() {
        // 0.5 mg at once a third into the middle hold (seed 9): its segments show the jump 8.6
        // chi-square better than a line, beyond the search's chance level (6.3) but short of the 9
        // once asked; the drift that imitates the step on the pose means stood. As a 40 s ramp the
        // holds move as lines: drift.
        let opts = DiagnoseOptions::DEFAULT;
        let step = diagnose(&shifted_log_at(9, 0.5, 0.0, 0.35), &opts).unwrap();
        assert_eq!(step.verdict, "unexplained", "{}", step.to_text());
        let ramp = diagnose(&shifted_log_at(9, 0.5, 40.0, 0.35), &opts).unwrap();
        assert_eq!(ramp.verdict, "drift", "{}", ramp.to_text());
    }

    /// A cube's 6 faces, its 4 edges in the x-y plane and 4 in the y-z plane, and one edge in the
    /// x-z plane (15 poses), the bias drifting by `size_mg` along one direction (1 - exp(-t / 40 s)).
    fn lone_edge_log(seed: u64, size_mg: f64) -> Table {
        let cfg = SimConfig { plan: Plan::Cube26, ..SimConfig::paper(seed) };
        let g = cfg.gravity;
        let recording = simulate_with(
            &cfg,
            &mut [&mut |t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                let d = [0.48, -0.6, 0.64];
                (0..3).for_each(|a| r[a] += g * size_mg * 1e-3 * (1.0 - (-t / 40.0).exp()) * d[a]);
            }],
        );
        let mut xz_edges = 0;
        let keep = |u: &[f64; 3]| {
            let tilted: Vec<usize> = (0..3).filter(|&a| u[a].abs() > 0.3).collect();
            match tilted.as_slice() {
                [_] | [0, 1] | [1, 2] => true,
                [0, 2] => {
                    xz_edges += 1;
                    xz_edges == 1
                }
                _ => false,
            }
        };
        crate::diagnose::testing::table_of_poses(recording, keep, "lone edge")
    }

    #[test]
    fn a_pose_alone_in_its_direction_is_not_gross_for_the_uncertainty_of_the_others_fit_there() {
        // The one x-z edge alone tells the x-z non-orthogonality: the fit to the other 14 poses
        // predicts it with a variance many times a pose's. Measured against white noise alone it lay
        // 21-27 times the others' scatter off them on these seeds (a bad pose to the probe) though
        // only the drift moves it; counted with that uncertainty it is not gross, and no probe is
        // reported.
        for size_mg in [1.0, 3.0] {
            for seed in [5, 10] {
                let d = diagnose(&lone_edge_log(seed, size_mg), &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT })
                    .unwrap();
                assert_eq!(d.poses.len(), 15);
                assert_eq!(d.verdict, "drift", "{size_mg} mg, seed {seed}: {}", d.to_text());
                let one_pose: Vec<&str> =
                    d.probes.iter().filter(|p| p.shape == "one-pose").map(|p| p.detail.as_str()).collect();
                assert!(one_pose.is_empty(), "{size_mg} mg, seed {seed}: {one_pose:?}");
            }
        }
    }
}
