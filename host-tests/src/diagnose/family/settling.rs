//! Settling: a transient at the start of each pose. Parametrisations: a transient proportional to
//! the change from the previous pose decaying exponentially over `tau`, and the transient measured
//! in each pose (its mean minus the mean of its last half), scaled per axis or by one factor.
//!
//! Decay test: a time constant is tried only when the transient decays within the pose
//! (`tau` at most a third of the median hold); a slower "transient" is a constant offset per pose,
//! not settling. The measured transients and the trimmed starts (which take any movement at the
//! start of a hold for a transient) are tried only when the holds, pooled, move more in their first
//! half than in their second ([`transient_decays`]): a noise that wanders through the whole hold
//! (random walk, flicker, Gauss-Markov) also moves the start of a hold, but as much as its end.
//!
//! Any transient, whatever its shape (a ringing mount, an exponential), is also tested by leaving
//! out the start of every hold (its first sixth or third): if the pose means of the rest agree
//! better with the model on withheld poses, the start of the holds carried the gap. A transient
//! still decaying at a hold's end (a time constant near the hold's length) is tested by
//! extrapolating every hold to its settled value (an exponential from its set-down, fitted to the
//! hold's segment means). Motion (a tap, a sway) happens anywhere in a hold and is not removed so.
//! A mount ringing through the hold is tested by leaving out the holds that ring (a damped
//! oscillation at one common frequency).

use super::corrected::{Corrected, score_means, take_if_better};
use super::{Context, Evaluation, Family, Variant, motion, ringing, standard_evaluation};
use crate::diagnose::SEGMENTS;
use crate::diagnose::gap::PoseData;
use crate::diagnose::jump::shape_fit;
use crate::diagnose::locate::{early_late, within_chi2_of};
use crate::diagnose::math::{V3, axis, dot, mean_of, median};
use crate::diagnose::within::{Within, WithinVariant};

/// Leading segments of each hold left out by the start-trimmed variants.
const TRIMS: [usize; 2] = [1, 2];

/// Time constants of the within-pose transient tried, s (mechanical to thermal).
const WITHIN_TAUS_S: [f64; 7] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0];

/// Time constants tried, s.
const TAUS_S: [f64; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

/// The measured transients' descriptions: per axis, and one factor.
const MEASURED: [&str; 2] =
    ["measured transient (pose mean - last half), per axis", "measured transient (pose mean - last half)"];

/// A first hold starting within this time of the log's first row was not placed during the log
/// (the recording began with the part at rest): its transient, if any, is of unknown age and size.
const LOG_START_S: f64 = 1.0;

/// How many times the excess movement of the holds' first halves must exceed their second halves'
/// for a transient that decays (an exponential with `tau` a third of the hold gives about 20).
const DECAY_RATIO: f64 = 3.0;

/// Standard deviations of the pooled chi-square by which the first halves' movement must exceed
/// white noise.
const DECAY_Z: f64 = 3.0;

/// Standard deviations of its mean square by which the holds' modulus change from their first
/// third to their last must exceed white noise for the pose-level transients ([`moduli_settle`]).
/// On the development and validation sets (1 728 logs) 2 and 3 gave the same answers where the gap
/// is clearly visible (three non-linearities and a temperature no longer named settling, none of
/// them then right); 3 also took a settling at gap 1.5 whose thirds differ by 1.29 times white.
const MODULI_SETTLE_Z: f64 = 2.0;

/// Pooled slowing ([`crate::diagnose::within::Within::slowing`]) at or below which the holds
/// settle: minus this many of its standard deviations under a movement that does not slow (a
/// drift, a random walk).
const SLOWING_Z: f64 = 2.0;

pub(crate) struct Settling;

/// How firmly the decay test ([`decays`]) must pass.
#[derive(Clone, Copy)]
pub(crate) enum Decay {
    /// The first halves' excess movement at least [`DECAY_RATIO`] times the second halves' and
    /// [`DECAY_Z`] standard deviations beyond white noise: the pose-level families' test
    /// ([`transient_decays`]).
    Ratio,
    /// The first halves' excess less [`DECAY_RATIO`] times the second halves' beyond [`DECAY_Z`]
    /// standard deviations of that difference under white noise: the holds' own answer, which no
    /// withheld pose checks. On the development and validation sets (1 728 logs) two Gauss-Markov
    /// noises whose holds moved 1.2 and 1.3 times white passed the ratio by chance and were named
    /// settling from the holds (gaps 3.4 and 6.0; now colored noise); a settling whose holds moved
    /// 7.1 times white passes either test.
    Significant,
}

/// The holds settle: their movement is significant, also without the hold that moves most (every
/// placement settles; one hold carrying it is a bad pose, a board pushed as it was set down:
/// [`Within::significant_beyond_one_hold`]) and slows down within each hold (the decay test
/// [`decays`], or the pooled slowing), whatever its direction. A transient in a fresh direction at
/// each placement does not carry to the withheld poses, so only the holds show it. The
/// description, or `None`.
pub(crate) fn settling_holds(ctx: &Context<'_>, decay: Decay) -> Option<String> {
    let holds = ctx.hold_runs();
    let within = ctx.within.as_ref().filter(|w| w.significant && w.significant_beyond_one_hold(&holds))?;
    let slowing = within.slowing();
    let how = if slowing <= -SLOWING_Z {
        format!("pooled slowing {slowing:.1} sigma")
    } else if decays(ctx, decay) {
        format!("their first halves move more than {DECAY_RATIO} times their second halves beyond white noise")
    } else {
        return None;
    };
    Some(format!(
        "the holds settle: their movement ({:.1}x white) slows down within each hold ({how}), in a direction that does not carry to the withheld poses",
        within.nominal_ratio
    ))
}

/// When each pose's hold was set down, s: the start of the first of the poses the pose finder cut
/// the hold into; `None` for a hold the log began in.
fn placements(ctx: &Context<'_>) -> Vec<Option<f64>> {
    let mut out: Vec<Option<f64>> = Vec::with_capacity(ctx.poses.len());
    for (i, p) in ctx.poses.iter().enumerate() {
        out.push(match i {
            0 => (p.t_start > LOG_START_S).then_some(p.t_start),
            _ if ctx.same_hold(&ctx.poses[i - 1], p) => out[i - 1],
            _ => Some(p.t_start),
        });
    }
    out
}

/// The holds, pooled, move more in their first half than in their second, beyond white noise
/// ([`Decay::Ratio`]).
pub(crate) fn transient_decays(ctx: &Context<'_>) -> bool {
    decays(ctx, Decay::Ratio)
}

/// The holds, pooled, move more in their first half than in their second, beyond white noise, as
/// firmly as `decay` asks: the chi-square of each half's segment means about their own mean,
/// summed over the poses, less its degrees of freedom.
fn decays(ctx: &Context<'_>, decay: Decay) -> bool {
    let half = SEGMENTS / 2;
    let white = &ctx.m.white;
    let axes = white.iter().filter(|w| **w > 0.0).count();
    let poses: Vec<_> = ctx.poses.iter().filter(|p| p.seg_n > 0).collect();
    let dof = (poses.len() * axes * (half - 1)) as f64;
    let early: f64 = poses.iter().map(|p| within_chi2_of(p, white, 0..half)).sum::<f64>() - dof;
    let late: f64 = poses.iter().map(|p| within_chi2_of(p, white, half..2 * half)).sum::<f64>() - dof;
    // The white-noise standard deviation of each half's excess, and of the first's less the ratio
    // times the second's.
    let sd = (2.0 * dof).sqrt();
    let beyond_late = early - DECAY_RATIO * late.max(0.0);
    dof > 0.0
        && match decay {
            Decay::Ratio => early > DECAY_Z * sd && beyond_late > 0.0,
            Decay::Significant => beyond_late > DECAY_Z * sd * (1.0 + DECAY_RATIO * DECAY_RATIO).sqrt(),
        }
}

/// The holds' moduli settle: the change from the first to the last third of each hold
/// ([`early_late`]), pooled, exceeds white noise by [`MODULI_SETTLE_Z`] standard deviations of its
/// mean square. A transient that decays within its hold and moves the pose means (the pose-level
/// variants: toward the previous pose, the measured transients, the trimmed starts) moves the first
/// third against the last 1.7 (tau a third of the hold) to 3 times as far as the mean; where the
/// thirds agree to white noise, a pose-level "transient" is a regressor fitting something else (on
/// the development sets: square and cube terms of 12-14-pose logs, a temperature).
fn moduli_settle(ctx: &Context<'_>) -> bool {
    let (mut changes, mut white, mut n) = (0.0_f64, 0.0_f64, 0.0_f64);
    for i in (0..ctx.poses.len()).filter(|&i| ctx.poses[i].seg_n > 0) {
        let (change, expected) = early_late(ctx.m, i);
        // White noise: each third's mean has 3x the variance of the pose mean, the difference 6x.
        (changes, white, n) = (changes + change * change, white + 6.0 * expected * expected, n + 1.0);
    }
    n > 0.0 && white > 0.0 && changes / white > 1.0 + MODULI_SETTLE_Z * (2.0 / n).sqrt()
}

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

/// The pose means with the leading `drop` segments of every hold left out (one parameter: the trim).
fn trimmed_start(ctx: &Context<'_>, drop: usize) -> Option<Corrected> {
    let means: Vec<V3> = ctx.poses.iter().map(|p| if p.seg_n > 0 { mean_of(&p.seg[drop..]) } else { p.mean }).collect();
    let detail = format!("transient: the first {drop}/{SEGMENTS} of every hold left out");
    // Fewer samples per mean: more white noise in each.
    score_means(ctx, &means, SEGMENTS as f64 / (SEGMENTS - drop) as f64, 1, detail)
}

/// The pose means settled: each hold's segment means fitted, per axis, by `c + b exp(-(t - t0) /
/// tau)` from its set-down `t0` (`placed`, [`placements`]), and `c`, the value the transient
/// decays to, kept (a hold the log began in keeps its mean). Where `tau` is near the hold's length
/// the transient has not died out by the hold's end, and neither the mean nor the hold's last half
/// is the settled value.
fn settled_means(ctx: &Context<'_>, placed: &[Option<f64>], tau: f64) -> Vec<V3> {
    let n = SEGMENTS as f64;
    let extrapolated = |p: &PoseData, t0: f64| -> V3 {
        let decay = |k: usize| (-(p.t_start + (k as f64 + 0.5) / n * p.duration() - t0) / tau).exp();
        let decay_mean = (0..SEGMENTS).map(decay).sum::<f64>() / n;
        let y_mean = mean_of(&p.seg);
        std::array::from_fn(|a| {
            let (_, b) = shape_fit(&p.seg.map(|y| y[a]), 1.0, &decay);
            y_mean[a] - b * decay_mean
        })
    };
    ctx.poses
        .iter()
        .zip(placed)
        .map(|(p, t0)| t0.filter(|_| p.seg_n > 0).map_or(p.mean, |t0| extrapolated(p, t0)))
        .collect()
}

/// The best settled pose means ([`settled_means`]) over the time constants up to the median hold,
/// charged one parameter and the search's `ln` (rounded up). They are scored against the plain
/// means' white noise: the noise the extrapolation adds (the exponential and the constant are
/// nearly collinear over a hold as long as `tau`) counts against it. Scored against its own larger
/// noise, as the trimmed starts are against theirs, an extrapolation of a noise wandering through
/// the holds (a walk, a telegraph, a mixture) looked explained: on eighteen development groups 15
/// colored noises and 2 out-of-catalogue logs were named settling so.
fn settled(ctx: &Context<'_>) -> Option<Corrected> {
    let hold = median(&ctx.poses.iter().map(|p| p.duration()).collect::<Vec<_>>());
    let taus: Vec<f64> = WITHIN_TAUS_S.iter().copied().filter(|tau| *tau <= hold).collect();
    let params = 1 + (taus.len().max(1) as f64).ln().ceil() as usize;
    let detail = |tau| format!("transient: every hold extrapolated to its settled value (exponential, tau {tau} s)");
    let placed = placements(ctx);
    taus.iter()
        .filter_map(|&tau| score_means(ctx, &settled_means(ctx, &placed, tau), 1.0, params, detail(tau)))
        .min_by(|a, b| a.ratio.total_cmp(&b.ratio))
}

/// The holds disturbed by a ringing mount (a damped oscillation at a common frequency) left out.
fn ringing_holds_dropped(ctx: &Context<'_>) -> Option<Evaluation> {
    let dropped = motion::disturbed(ctx)?;
    if !ringing::placements_ring(ctx, &dropped) {
        return None;
    }
    let fitted = motion::without(ctx, dropped, "a ringing mount (damped, at one frequency): ringing holds dropped")?;
    Some(ctx.evaluate_fitted("settling", fitted))
}

impl Family for Settling {
    fn name(&self) -> &'static str {
        "settling"
    }

    /// A bias transient along one sensor-frame direction from every hold's start, decaying over
    /// `tau` (package stress released by the set-down, a hand's warmth leaving the board): the same
    /// course in every hold, whose sign and size along each pose's direction follow that direction.
    /// `tau` up to the median hold (slower is a line per hold: drift's). The transient runs from the
    /// set-down, across the poses one hold was cut into; a first hold the log began in has no
    /// set-down in the log, and no transient.
    fn within_variants(&self, ctx: &Context<'_>, within: &Within) -> Vec<WithinVariant> {
        let placed = placements(ctx);
        // The hold's age at each pose's end: a hold the pose finder cut up is as long as its pieces.
        let ages: Vec<f64> = ctx.poses.iter().zip(&placed).map(|(p, t0)| p.t_end - t0.unwrap_or(p.t_start)).collect();
        let hold = median(&ages);
        let mut out = Vec::new();
        for &tau in WITHIN_TAUS_S.iter().filter(|tau| **tau <= hold) {
            let decay = |p: usize, t: f64| placed[p].map_or(0.0, |t0| (-(t - t0) / tau).exp());
            let detail = format!("bias transient along one sensor direction from each hold's start, tau {tau} s");
            out.push(within.variant(ctx.m, 3, detail, &|p, t, _| (0..3).map(|a| axis(a, decay(p, t))).collect()));
        }
        out
    }

    fn evaluate(&self, ctx: &Context<'_>) -> Evaluation {
        let mut e = standard_evaluation(self, ctx);
        if !ctx.pose_level {
            return e;
        }
        if let Some(ring) = ringing_holds_dropped(ctx)
            && ring.candidate.evidence() > e.candidate.evidence()
        {
            e = ring;
        }
        if transient_decays(ctx) && moduli_settle(ctx) {
            for fit in TRIMS.iter().filter_map(|&drop| trimmed_start(ctx, drop)).chain(settled(ctx)) {
                take_if_better(ctx, &mut e, fit);
            }
        }
        // The measured transients, like every variant, are offered only when the holds settle,
        // whatever the direction (`transient_decays`): the holds support them in every pose, and the
        // one-pose test (for a gain the holds do not support) does not apply.
        if MEASURED.contains(&e.candidate.detail.as_str()) {
            e.gain_without_worst = f64::NAN;
        }
        e
    }

    /// Offered only when the holds' moduli settle and the holds move more early than late
    /// ([`moduli_settle`], [`transient_decays`]): a pose-level transient the holds do not show
    /// decaying is a regressor fitting something else. The transient toward the previous pose was
    /// asked without the second test: on the Python development and seen fresh sets (2 448 logs)
    /// requiring it turned a flicker noise of 15 poses from settling to colored noise and a
    /// footsteps log from settling to `unexplained`, and changed no other answer.
    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        if !(moduli_settle(ctx) && transient_decays(ctx)) {
            return Vec::new();
        }
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
        out.push(Variant { extra: per_axis, params: 3, detail: MEASURED[0].into() });
        let common = (0..ctx.poses.len()).map(|i| vec![dot(dirs[i], transient[i])]).collect();
        out.push(Variant { extra: common, params: 1, detail: MEASURED[1].into() });
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::{DiagnoseOptions, gap};
    use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};

    fn decays(class: EffectClass, seed: u64) -> bool {
        let table = to_table(&generate(&random_scenario(class, seed)), "sim").unwrap();
        let opts = DiagnoseOptions::DEFAULT;
        let m = gap::measure(&table, &opts).unwrap();
        transient_decays(&Context::new(&table, &m, &opts).unwrap())
    }

    #[test]
    fn a_settling_transient_decays_a_random_walk_and_white_noise_do_not() {
        for seed in 1..4 {
            assert!(decays(EffectClass::Settling, seed), "settling seed {seed}");
            assert!(!decays(EffectClass::ColoredNoise, seed), "random walk seed {seed}");
            assert!(!decays(EffectClass::None, seed), "clean seed {seed}");
        }
    }

    #[test]
    fn holds_that_move_without_slowing_are_offered_no_transient() {
        // A random walk moves each hold's first third against its last (the moduli settle by that
        // test) but not more in the first half than in the second: a pose-level transient toward
        // the previous pose would be a regressor fitting the walk's pose means (a flicker noise of 15
        // poses, blindgen4 138, was named settling so).
        let mut asked = 0;
        for seed in 1..=8 {
            let table = to_table(&generate(&random_scenario(EffectClass::ColoredNoise, seed)), "sim").unwrap();
            let opts = DiagnoseOptions::DEFAULT;
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            if moduli_settle(&ctx) && !transient_decays(&ctx) {
                asked += 1;
                assert!(Settling.variants(&ctx).is_empty(), "seed {seed}");
            }
        }
        assert!(asked >= 2, "{asked} of 8 walks move their moduli without slowing");
    }

    /// Whether the holds alone name settling ([`Decay::Significant`]) on `table`.
    fn holds_settle(table: &crate::csvio::Table) -> bool {
        let opts = DiagnoseOptions::DEFAULT;
        let m = gap::measure(table, &opts).unwrap();
        settling_holds(&Context::new(table, &m, &opts).unwrap(), Decay::Significant).is_some()
    }

    #[test]
    fn the_holds_of_a_gauss_markov_noise_do_not_settle_by_chance_where_a_settling_does() {
        // Of 40 Gauss-Markov noises each (0.3 mg, 8 s; 0.5 mg, 16 s), the ratio test alone
        // (`Decay::Ratio`) named 1 and 3 settling from their holds; the difference tested against
        // its own spread names 0 and 2 (seeds 23 and 34 of the second, which the ratio names too).
        let settled: Vec<(f64, u64)> = [(0.3, 8.0), (0.5, 16.0)]
            .into_iter()
            .flat_map(|(sigma_mg, tau_s)| {
                (1..=40)
                    .filter(move |&seed| holds_settle(&crate::diagnose::testing::markov_log(seed, sigma_mg, tau_s)))
                    .map(move |seed| (sigma_mg, seed))
            })
            .collect();
        assert!(settled.len() <= 2, "(mg, seed): {settled:?}");
        for seed in 1..=10 {
            let table = to_table(&generate(&random_scenario(EffectClass::Settling, seed)), "sim").unwrap();
            assert!(holds_settle(&table), "settling seed {seed}");
        }
    }

    #[test]
    fn pose_level_transients_are_offered_only_when_the_holds_moduli_settle() {
        // A settling log's holds change their modulus from the first third to the last beyond white
        // noise; a clean log's and a square-term log's do not, and there the pose-level transients
        // (toward the previous pose, measured, trimmed) are not tried.
        let opts = DiagnoseOptions::DEFAULT;
        for seed in 1..4 {
            for (class, settles) in
                [(EffectClass::Settling, true), (EffectClass::None, false), (EffectClass::ScaleNonlinearity, false)]
            {
                let table = to_table(&generate(&random_scenario(class, seed)), "sim").unwrap();
                let m = gap::measure(&table, &opts).unwrap();
                let ctx = Context::new(&table, &m, &opts).unwrap();
                assert_eq!(moduli_settle(&ctx), settles, "{class:?} seed {seed}");
                assert_eq!(Settling.variants(&ctx).is_empty(), !settles, "{class:?} seed {seed}");
            }
        }
    }

    /// An own-simulator log (random scenario `seed`) with `offset(hold, seconds since its set-down)`
    /// mg added to every hold but the first (the log begins at rest in it).
    fn transient_log(seed: u64, offset: &dyn Fn(usize, f64) -> [f64; 3]) -> crate::csvio::Table {
        use crate::sim::scenario::SimLog;
        use crate::sim::simulate_with;
        let scenario = random_scenario(EffectClass::None, seed);
        let g = scenario.sim.gravity;
        let (mut hold, mut start) = (None, 0.0);
        let recording = simulate_with(
            &scenario.sim,
            &mut [&mut |t: f64, pose: Option<usize>, r: &mut [f64; 3]| {
                if pose.is_some() && pose != hold {
                    (hold, start) = (pose, t);
                }
                if let Some(p) = pose.filter(|p| *p > 0) {
                    let b = offset(p, t - start);
                    (0..3).for_each(|a| r[a] += b[a] * 1e-3 * g);
                }
            }],
        );
        let temps_c = vec![25.0; recording.samples.len()];
        to_table(&SimLog { recording, temps_c }, "transient").unwrap()
    }

    /// The verdicts on [`transient_log`]s of seeds `seeds`.
    fn verdicts_with_transient(seeds: &[u64], offset: &dyn Fn(usize, f64) -> [f64; 3]) -> Vec<(u64, &'static str)> {
        let opts = |seed| DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
        let verdict = |seed| crate::diagnose::diagnose(&transient_log(seed, offset), &opts(seed)).unwrap().verdict;
        seeds.iter().map(|&seed| (seed, verdict(seed))).collect()
    }

    #[test]
    fn one_hold_that_settles_is_no_settling_of_the_holds() {
        // The board pushed once as it was set down: 4 mg along one direction at the set-down of
        // hold 9, relaxing with tau 3 s (slower than a move's tail); no other hold moves. The
        // holds' movement is significant but one hold carries it (a bad pose): the holds do not
        // settle, even by the ratio of their halves' movement alone. The same transient after
        // every set-down they do.
        let v = [0.6, -0.64, 0.48];
        let settle = |age: f64| v.map(|c| c * 4.0 * (-age / 3.0).exp());
        let (mut once, mut every) = (0, 0);
        for seed in 21..=24 {
            let opts = DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
            let table = transient_log(seed, &|hold, age| if hold == 9 { settle(age) } else { [0.0; 3] });
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            if ctx.holds_move() {
                once += 1;
                assert_eq!(settling_holds(&ctx, Decay::Ratio), None, "seed {seed}");
            }
            let table = transient_log(seed, &|_, age| settle(age));
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            every += usize::from(settling_holds(&ctx, Decay::Ratio).is_some());
        }
        assert!(
            once >= 3 && every >= 3,
            "one hold moved the holds significantly on {once}, every hold settled on {every} of 4"
        );
    }

    #[test]
    fn a_hands_warmth_leaving_after_each_set_down_but_the_first_is_settling() {
        // About 1 mg along one sensor direction, 0.4-1.6 times that at each set-down (drawn),
        // decaying with tau 3 s; the log begins at rest in its first hold, which has none. Seed 47
        // was colored-noise before the first hold was left out of the transient and a hold's
        // start taken from its set-down (of seeds 41-50, 9 are settling, 8 before; seed 48 is
        // scale-nonlinearity either way).
        use rand_core::SeedableRng;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(7);
        let sizes: Vec<f64> = (0..200).map(|_| crate::sim::random::uniform_in(&mut rng, 0.4, 1.6)).collect();
        let v = [0.8, -0.5, 0.33];
        let names =
            verdicts_with_transient(&[45, 46, 47], &|hold, age| v.map(|c| c * sizes[hold] * (-age / 3.0).exp()));
        assert!(names.iter().all(|(_, v)| *v == "settling"), "{names:?}");
    }

    /// After each placement the offset jumps by 1.5 mg in a random direction and recovers with a
    /// time constant of `tau_s`.
    fn recovering_in_fresh_directions(seed: u64, tau_s: f64) -> crate::csvio::Table {
        use crate::sim::random::standard_normal;
        use crate::sim::scenario::SimLog;
        use crate::sim::simulate_with;
        use rand_core::SeedableRng;
        let scenario = random_scenario(EffectClass::None, seed);
        let g = scenario.sim.gravity;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let (mut hold, mut start, mut direction) = (None, 0.0, [0.0; 3]);
        let recording = simulate_with(
            &scenario.sim,
            &mut [&mut |t: f64, pose: Option<usize>, r: &mut [f64; 3]| {
                if pose.is_some() && pose != hold {
                    let v: [f64; 3] = std::array::from_fn(|_| standard_normal(&mut rng));
                    let norm = v.iter().map(|c| c * c).sum::<f64>().sqrt();
                    (hold, start, direction) = (pose, t, v.map(|c| c / norm));
                }
                if pose.is_some() {
                    let offset = 1.5e-3 * g * (-(t - start) / tau_s).exp();
                    (0..3).for_each(|a| r[a] += offset * direction[a]);
                }
            }],
        );
        let temps_c = vec![25.0; recording.samples.len()];
        to_table(&SimLog { recording, temps_c }, "recovery").unwrap()
    }

    /// [`recovering_in_fresh_directions`] diagnosed, asserted settling.
    fn named_settling(seed: u64, tau_s: f64) -> crate::diagnose::Diagnosis {
        let table = recovering_in_fresh_directions(seed, tau_s);
        let d = crate::diagnose::diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
        assert_eq!(d.verdict, "settling", "seed {seed}: {}", d.to_text());
        d
    }

    #[test]
    fn an_offset_recovering_in_a_fresh_direction_after_each_placement_is_settling() {
        // A time constant of 1 s (holds of 4-8 s): each hold decays alike, the pose means scatter as
        // independent offsets (the transient's average over each hold).
        for seed in [31, 32, 33] {
            named_settling(seed, 1.0);
        }
    }

    #[test]
    fn an_offset_recovering_over_half_a_hold_is_settling_from_the_holds_extrapolated_to_their_settled_values() {
        // A time constant of 2.5 s in holds of 4-8 s: the transient has not died out by a hold's
        // end, so a hold's last half still carries it. Fitted per hold from its set-down, the
        // exponential's settled value predicts the withheld poses better than the measured
        // transient (mean less last half) does, the noise the extrapolation adds counted against
        // it: 1.67-2.02 against 1.70-2.18 on these seeds. (On this simulator's long, quiet holds
        // the margin is small; on the generators' holds of about one time constant it is wider: a
        // blindgen2 exponential settling of gap ratio 18 in 2.9 s holds, 6.4 against 7.8, was
        // colored noise before and is settling.)
        for seed in [31, 32, 33] {
            let d = named_settling(seed, 2.5);
            let settling = d.candidates.iter().find(|c| c.effect == "settling").unwrap();
            assert!(
                settling.detail.starts_with("transient: every hold extrapolated"),
                "seed {seed}: {}",
                settling.detail
            );
            let measured = settling.variants.iter().filter(|(detail, _)| detail.starts_with("measured transient"));
            let best_measured = measured.map(|(_, ratio)| *ratio).fold(f64::INFINITY, f64::min);
            assert!(
                settling.heldout_ratio < best_measured,
                "seed {seed}: {} against {best_measured}",
                settling.heldout_ratio
            );
        }
    }
}
