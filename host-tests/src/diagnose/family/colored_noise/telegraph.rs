//! A telegraph (popcorn) noise seen where it switches inside a hold: the pose finder cuts a hold at
//! a jump of the bias, and the pieces of one hold (no movement between them) differ by the jump.
//! A two-level noise of a sensor axis jumps along that axis, by the same size each time; a part
//! that moves or settles jumps along a change of gravity's direction, which follows the pose. Two
//! pieces are of one hold when the readings between them sit at one level or the other
//! ([`switch_between`]): a telegraph's levels may lie farther apart than one hold may move. A jump
//! the pose finder did not cut a hold at is the largest jump inside the piece ([`jump_inside`]).

use crate::diagnose::SEGMENTS;
use crate::diagnose::family::Context;
use crate::diagnose::gap::PoseData;
use crate::diagnose::jump::{MIN_SEGMENT_READINGS, jump_in_hold};
use crate::diagnose::math::{V3, median, norm};
use crate::vec3::sub;

/// Fewest jumps inside holds the test asks for: a transient or a step splits a hold once or twice, a
/// switching noise many times (the telegraph noises named from their jumps on stop 46's development
/// sets and blindgen4 115: 7-34). Asking 3, stop 45's first version (jumps judged against the
/// pieces' own sample variance) also named a settling and a drift colored noise. Asking 5 (stop 78)
/// turned a popcorn noise of 5 clear jumps (holds of 2-7 s, dwell 9.5 s) and a random walk moving
/// the holds 2.8 times white noise to colored noise on the development sets (2 304 logs), and one
/// telegraph noise of CI's blindgen4 seeds, but also the real FXOS8700 session `data_sample`
/// (hand-placed, `unexplained`): 5 jumps inside its holds of 0.9-2.4 mg, on y and z, of two sizes
/// each within the band.
const MIN_JUMPS: usize = 6;

/// Share of its size from which a jump takes part on an axis.
const TAKES_PART: f64 = 0.3;

/// Least share of an axis's jumps within [`LEVEL_BAND`] of their median size: a two-level noise
/// jumps by one size (a jump back and forth inside one piece, or two axes switching in one piece,
/// leaves a few others).
const ONE_SIZE_SHARE: f64 = 0.6;

/// Ratio band about the median size within which a jump is of that size.
const LEVEL_BAND: f64 = 1.33;

/// Least size of a jump in standard deviations of the difference of two pieces' means (the log's
/// white noise and the quantisation a mean keeps): the pose finder also cuts a hold where a
/// block's mean moves by noise.
const SIGNIFICANT_JUMP_Z: f64 = 10.0;

/// Least size of a jump found inside a piece ([`jump_inside`]), in standard deviations of its fit
/// over a constant (chi-square on three axes, the best of the `4 SEGMENTS - 1` places searched):
/// white noise passes 36 on one place with probability 7.5e-8, on the 23 at most 1.7e-6 per
/// hold. At [`SIGNIFICANT_JUMP_Z`] a popcorn noise of 1.8 mg on a part of 3 mg white noise
/// (holds of 1-9 s) counted 5 of its 9 jumps beyond 6 standard deviations; on the development
/// sets (2 304 logs) 6 turned it and one telegraph noise from `unexplained` to colored noise and
/// changed no other answer, 5 lost the telegraph again (more jumps, not of one size).
const SIGNIFICANT_INSIDE_Z: f64 = 6.0;

/// Largest jump between two pieces of a hold that a switch of the bias can be, share of gravity's
/// modulus (a turn of 6 degrees): a telegraph noise's levels may lie farther apart than
/// [`Context::same_hold`] lets pieces of one hold move (a blindgen4 telegraph's 32 mg).
const MAX_SWITCH_SHARE: f64 = 0.1;

/// Pieces `q` then `p` of one hold, or of a hold whose bias switched between them: close in time,
/// at most [`MAX_SWITCH_SHARE`] apart, and the readings between them at the level of one piece or
/// the other.
fn switch_between(ctx: &Context<'_>, q: &PoseData, p: &PoseData) -> bool {
    norm(sub(p.mean, q.mean)) < MAX_SWITCH_SHARE * norm(p.mean)
        && ctx.still_between(q, p, &|near_q, near_p| near_q || near_p)
}

/// The jumps between successive pieces of one hold ([`switch_between`]) beyond
/// [`SIGNIFICANT_JUMP_Z`], input unit.
fn jumps_in_holds(ctx: &Context<'_>) -> Vec<V3> {
    let (white, quantisation) = (ctx.m.white, ctx.m.quantisation);
    let jump = |q: &PoseData, p: &PoseData| -> (V3, f64) {
        let d = sub(p.mean, q.mean);
        let variance = |a: usize| white[a] * (1.0 / p.n as f64 + 1.0 / q.n as f64) + 2.0 * quantisation[a];
        (d, (0..3).map(|a| d[a] * d[a] / variance(a)).sum::<f64>())
    };
    ctx.poses
        .windows(2)
        .filter(|w| switch_between(ctx, &w[0], &w[1]))
        .map(|w| jump(&w[0], &w[1]))
        .filter(|(_, z2)| *z2 >= SIGNIFICANT_JUMP_Z * SIGNIFICANT_JUMP_Z)
        .map(|(d, _)| d)
        .collect()
}

/// The largest jump inside one piece ([`jump_in_hold`] on its segment means, per sensor axis at one
/// place), when it lies beyond [`SIGNIFICANT_INSIDE_Z`] and fits the segments better than a line in
/// time does (a telegraph's level changes at once; a drift or a slow settling moves along). The
/// jump, input unit.
fn jump_inside(ctx: &Context<'_>, p: &PoseData) -> Option<V3> {
    let var: V3 = ctx.m.white.map(|w| w / p.seg_n as f64);
    if p.seg_n < MIN_SEGMENT_READINGS || var.iter().any(|v| !(*v > 0.0)) {
        return None;
    }
    let y: [[f64; SEGMENTS]; 3] = std::array::from_fn(|a| std::array::from_fn(|j| p.seg[j][a] - p.mean[a]));
    let jump = jump_in_hold(&y, var);
    let significant = jump.over_constant >= SIGNIFICANT_INSIDE_Z * SIGNIFICANT_INSIDE_Z;
    (significant && jump.over_line > 0.0).then_some(jump.size)
}

/// Which jumps of the bias [`switching_holds`] counts.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Jumps {
    /// Between the pieces the pose finder cut a hold into.
    BetweenPieces,
    /// Those, and the largest step inside each piece ([`jump_inside`]): a telegraph's jump the pose
    /// finder did not cut the hold at.
    AlsoInsidePieces,
}

/// The holds switch between two levels: at least [`MIN_JUMPS`] jumps inside holds (those `counted`),
/// and on each sensor axis the jumps that take part in it mostly of one size. The description, or
/// `None`.
pub(crate) fn switching_holds(ctx: &Context<'_>, counted: Jumps) -> Option<String> {
    let mut jumps = jumps_in_holds(ctx);
    if counted == Jumps::AlsoInsidePieces {
        jumps.extend(ctx.poses.iter().filter_map(|p| jump_inside(ctx, p)));
    }
    if jumps.len() < MIN_JUMPS {
        return None;
    }
    let sizes = |a: usize| -> Vec<f64> {
        jumps.iter().filter(|d| d[a].abs() >= TAKES_PART * norm(**d)).map(|d| d[a].abs()).collect()
    };
    let one_size = |s: &[f64]| {
        let m = median(s);
        let of_it = s.iter().filter(|x| **x * LEVEL_BAND >= m && **x <= LEVEL_BAND * m).count();
        s.len() < 2 || of_it as f64 >= ONE_SIZE_SHARE * s.len() as f64
    };
    let axes: Vec<Vec<f64>> = (0..3).map(sizes).collect();
    let taking_part: Vec<String> = (0..3)
        .filter(|&a| !axes[a].is_empty())
        .map(|a| format!("{} on {}", axes[a].len(), ["x", "y", "z"][a]))
        .collect();
    axes.iter().all(|s| one_size(s)).then(|| {
        format!(
            "the bias switches between levels inside the holds: {} jumps inside them, of one size per \
             sensor axis ({})",
            jumps.len(),
            taking_part.join(", ")
        )
    })
}
