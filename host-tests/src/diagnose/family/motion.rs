//! Motion: poses whose own samples move (taps, sway): the chi-square of the segment means after
//! the first third of the hold (a transient at the start is settling, not motion) is robustly
//! compared with the median pose's; so is the scatter of the readings about those segment means (a
//! vibration faster than a segment: footsteps, a fan). Disturbed poses are dropped, each at the
//! cost of an expected noise variance plus the penalty, and the gain is measured on the rest; or,
//! where a burst shakes only some segments of a pose, those segments are left out and the pose
//! kept. Disturbed holds that decay, or ring at a common frequency (`ringing`), are settling.

use accelcal::model::PARAM_COUNT;

use super::corrected::{Corrected, score_means, take_if_better};
use super::{Context, Evaluation, Family, Fitted, Variant, colored_noise, ringing, standard_evaluation};
use crate::diagnose::SEGMENTS;
use crate::diagnose::gap::{PoseData, quantisation_step};
use crate::diagnose::locate::{within_chi2_from, within_chi2_of};
use crate::diagnose::math::{V3, mean_of, median};

/// Leading segments of a hold not looked at (a transient there is settling).
const SKIPPED_SEGMENTS: usize = 2;

pub(crate) struct Motion;

impl Family for Motion {
    fn name(&self) -> &'static str {
        "motion"
    }

    fn variants(&self, _ctx: &Context<'_>) -> Vec<Variant> {
        Vec::new()
    }

    /// Dropping moving poses, or, when every hold moves in the tremor band (hand-held, a vibrating
    /// support), the scatter the motion gives the pose means, measured in the holds as for colored
    /// noise: the better on withheld poses.
    fn evaluate(&self, ctx: &Context<'_>) -> Evaluation {
        let mut dropped = standard_evaluation(self, ctx);
        let moving_in_one_hold = || moving(ctx).filter(|d| in_one_hold(ctx, d));
        if let Some(one_hold) = (!dropped.candidate.applicable).then(moving_in_one_hold).flatten() {
            dropped.candidate.detail =
                format!("one hold moves (poses {}): a bad pose, not handling that recurs", marked(&one_hold));
        }
        if let Some(fit) = shaken_segments_left_out(ctx) {
            take_if_better(ctx, &mut dropped, fit);
        }
        let Some(tremor) = ctx.tremor() else { return dropped };
        let mut shaken = colored_noise::ColoredNoise.noise_model(ctx);
        let c = &mut shaken.candidate;
        if !c.applicable || (dropped.candidate.applicable && dropped.candidate.evidence() >= c.evidence()) {
            return dropped;
        }
        c.effect = self.name();
        c.detail = format!("the holds move at 2-20 Hz ({}): their means scatter as {}", tremor.describe(), c.detail);
        shaken
    }

    /// Dropping the moving poses, when they lie in more than one hold: handling that disturbs a
    /// log (taps, sway, footsteps) recurs, and one disturbed hold alone is one bad pose (the board
    /// lifted or pushed once), a place for `unexplained` to name, not the log's motion.
    fn fit(&self, ctx: &Context<'_>) -> Option<Fitted> {
        let dropped = moving(ctx).filter(|d| !in_one_hold(ctx, d))?;
        without(ctx, dropped, "moving poses dropped")
    }
}

/// The indices of the `marked` poses, space-separated.
fn marked(marked: &[bool]) -> String {
    let list: Vec<String> = (0..marked.len()).filter(|&i| marked[i]).map(|i| i.to_string()).collect();
    list.join(" ")
}

/// Every `dropped` pose is a piece of one hold ([`Context::hold_runs`]).
fn in_one_hold(ctx: &Context<'_>, dropped: &[bool]) -> bool {
    let touched = ctx.hold_runs().into_iter().filter(|run| dropped[run.clone()].iter().any(|d| *d)).count();
    touched == 1
}

/// The [`disturbed`] poses, when they move as handling does: not a transient that decays or rings
/// after each rotation (settling).
pub(crate) fn moving(ctx: &Context<'_>) -> Option<Vec<bool>> {
    let dropped = disturbed(ctx)?;
    let settles = decays(ctx, &dropped) || ringing::placements_ring(ctx, &dropped);
    (!settles).then_some(dropped)
}

/// The poses whose samples move after the first third of their hold, or whose readings are
/// [`shaken`] (`None`: none, or too many to leave enough for the fit).
pub(crate) fn disturbed(ctx: &Context<'_>) -> Option<Vec<bool>> {
    let chi: Vec<f64> = ctx.poses.iter().map(|p| within_chi2_from(p, &ctx.m.white, SKIPPED_SEGMENTS)).collect();
    let threshold = (6.0 * median(&chi)).max(40.0);
    let shaken = shaken(ctx);
    let dropped: Vec<bool> = chi.iter().zip(&shaken).map(|(c, s)| *c > threshold || *s).collect();
    let count = dropped.iter().filter(|d| **d).count();
    (count > 0 && ctx.poses.len() - count >= PARAM_COUNT + 3).then_some(dropped)
}

/// Standard errors by which a shaken pose's readings scatter beyond the median pose's.
const SHAKEN_Z: f64 = 6.0;

/// Least share by which a shaken pose's readings scatter beyond the median pose's.
const SHAKEN_SHARE: f64 = 0.1;

/// Each segment's readings' scatter about the segment's mean: the squared deviations over the
/// axis's white variance, summed over the axes, and the readings they rest on (counted per axis).
fn segment_scatters(ctx: &Context<'_>, p: &PoseData) -> [(f64, usize); SEGMENTS] {
    let (white, samples) = (ctx.m.white, &ctx.table.samples);
    std::array::from_fn(|k| {
        let rows = p.rows.start + k * p.seg_n..p.rows.start + (k + 1) * p.seg_n;
        let axes = (0..3).filter(|&a| white[a] > 0.0);
        let sum = axes
            .clone()
            .map(|a| samples[rows.clone()].iter().map(|s| (s[a] - p.seg[k][a]).powi(2)).sum::<f64>() / white[a]);
        (sum.sum(), rows.len() * axes.count())
    })
}

/// A pose's readings' scatter about their segment means after the first [`SKIPPED_SEGMENTS`]
/// (each axis's variance over its white variance, averaged over the axes), and the readings it
/// rests on.
fn scatter(segments: &[(f64, usize); SEGMENTS]) -> (f64, usize) {
    let (sum, count) = segments[SKIPPED_SEGMENTS..].iter().fold((0.0, 0), |(s, n), (a, b)| (s + a, n + b));
    (per_reading((sum, count)), count)
}

/// The white noise is below the rounding step on some axis: the readings' scatter about a segment
/// mean is then the rounding's, which depends on where a pose's value falls between two steps (on
/// a coarse part some poses read one value throughout, others dither between two).
fn rounding_rules(ctx: &Context<'_>) -> bool {
    let step = quantisation_step(ctx.table);
    (0..3).any(|a| ctx.m.white[a] < step[a] * step[a])
}

/// The poses whose readings scatter ([`scatter`]) beyond the median pose's by [`SHAKEN_SHARE`] and
/// [`SHAKEN_Z`] standard errors (a white noise's, the readings' correlation counted, or the poses'
/// own spread when larger: a noise slower than a segment scatters some poses more than others), and
/// every other piece the pose finder cut from their holds ([`Context::hold_runs`]): a vibration
/// faster than the segments (footsteps, a fan) moves no segment mean but shakes the readings, and
/// what shakes part of a hold disturbs all of it.
fn shaken(ctx: &Context<'_>) -> Vec<bool> {
    if rounding_rules(ctx) {
        return vec![false; ctx.poses.len()];
    }
    let scatters: Vec<(f64, usize)> = ctx.poses.iter().map(|p| scatter(&segment_scatters(ctx, p))).collect();
    let beyond = beyond_typical(ctx, &scatters);
    let mut out = vec![false; ctx.poses.len()];
    for run in ctx.hold_runs() {
        if beyond[run.clone()].iter().any(|b| *b) {
            out[run].fill(true);
        }
    }
    out
}

/// The `scatters` (each a mean scatter and the readings it rests on) beyond the median one by
/// [`SHAKEN_SHARE`] and [`SHAKEN_Z`] standard errors: a white noise's, the readings' correlation
/// counted, or the scatters' own spread when larger (a noise slower than a segment scatters some
/// poses more than others).
fn beyond_typical(ctx: &Context<'_>, scatters: &[(f64, usize)]) -> Vec<bool> {
    let finite: Vec<f64> = scatters.iter().map(|s| s.0).filter(|s| s.is_finite()).collect();
    let typical = median(&finite);
    let spread = 1.4826 * median(&finite.iter().map(|s| (s / typical - 1.0).abs()).collect::<Vec<_>>());
    let correlation = ctx.m.correlation.iter().copied().fold(1.0, f64::max);
    let beyond = |&(s, count): &(f64, usize)| {
        let excess = s / typical - 1.0;
        let standard_error = (2.0 * correlation / count.max(1) as f64).sqrt().max(spread);
        excess > SHAKEN_SHARE && excess > SHAKEN_Z * standard_error
    };
    scatters.iter().map(beyond).collect()
}

/// Segments a pose keeps at least for its mean to be taken from its quiet segments.
const QUIET_SEGMENTS_KEPT: usize = 2;

/// A scatter summed over `count` readings, per reading (NaN over none).
fn per_reading((sum, count): (f64, usize)) -> f64 {
    if count > 0 { sum / count as f64 } else { f64::NAN }
}

/// Per pose, its segments after the first [`SKIPPED_SEGMENTS`] whose readings scatter beyond the
/// typical such segment's ([`beyond_typical`]).
fn shaken_segments(ctx: &Context<'_>) -> Vec<[bool; SEGMENTS]> {
    const LOOKED_AT: usize = SEGMENTS - SKIPPED_SEGMENTS;
    let scatters: Vec<[(f64, usize); SEGMENTS]> = ctx.poses.iter().map(|p| segment_scatters(ctx, p)).collect();
    let looked_at: Vec<(f64, usize)> = scatters
        .iter()
        .flat_map(|pose| pose[SKIPPED_SEGMENTS..].iter().map(|&seg| (per_reading(seg), seg.1)))
        .collect();
    let beyond = beyond_typical(ctx, &looked_at);
    (0..ctx.poses.len())
        .map(|i| std::array::from_fn(|k| k >= SKIPPED_SEGMENTS && beyond[i * LOOKED_AT + k - SKIPPED_SEGMENTS]))
        .collect()
}

/// The pose means with their shaken segments ([`shaken_segments`]) left out, where at least
/// [`QUIET_SEGMENTS_KEPT`] stay quiet: footsteps passing or a fan starting shake part of a hold
/// with bursts of vibration faster than a segment, and each footfall's ringing, or the walker's
/// weight leaning the bench, leaves its part in the mean. Offered when the bursts touch more than
/// one hold (one is a bad pose); charged one parameter, the rule, as the trimmed starts of
/// `settling` are (which segments go is read from the readings' scatter, not fitted to the pose
/// means), and scored against the plain means' white noise.
fn shaken_segments_left_out(ctx: &Context<'_>) -> Option<Corrected> {
    if rounding_rules(ctx) {
        return None;
    }
    let shaken = shaken_segments(ctx);
    let (mut means, mut trimmed) = (Vec::with_capacity(ctx.poses.len()), Vec::with_capacity(ctx.poses.len()));
    for (p, shaken) in ctx.poses.iter().zip(&shaken) {
        let quiet: Vec<V3> = (0..SEGMENTS).filter(|&k| !shaken[k]).map(|k| p.seg[k]).collect();
        let trim = p.seg_n > 0 && quiet.len() >= QUIET_SEGMENTS_KEPT && quiet.len() < SEGMENTS;
        means.push(if trim { mean_of(&quiet) } else { p.mean });
        trimmed.push(trim);
    }
    if !trimmed.contains(&true) || in_one_hold(ctx, &trimmed) {
        return None;
    }
    let detail = format!("shaken segments left out: poses {}", marked(&trimmed));
    score_means(ctx, &means, 1.0, 1, detail)
}

/// The nominal model without the `dropped` poses, each charged one parameter.
pub(crate) fn without(ctx: &Context<'_>, dropped: Vec<bool>, what: &str) -> Option<Fitted> {
    let count = dropped.iter().filter(|d| **d).count();
    let rows = ctx.base_rows.clone();
    let ratio = ctx.heldout_ratio(&rows, &dropped, count)?;
    let list = marked(&dropped);
    Some(Fitted {
        rows,
        dropped,
        score_ratio: ratio,
        params: count,
        detail: format!("{what}: {list}"),
        tried: Vec::new(),
        in_sample: None,
    })
}

/// Most disturbed poses move far more in the first half of their hold than in the second: a
/// transient that decays after each rotation (settling), not motion, which comes at any time.
fn decays(ctx: &Context<'_>, dropped: &[bool]) -> bool {
    let half = SEGMENTS / 2;
    let (mut early, mut total) = (0, 0);
    for (p, _) in ctx.poses.iter().zip(dropped).filter(|(_, d)| **d) {
        let first = within_chi2_of(p, &ctx.m.white, 0..half);
        let second = within_chi2_of(p, &ctx.m.white, half..SEGMENTS);
        total += 1;
        if first > DECAY_FACTOR * second.max(half as f64) {
            early += 1;
        }
    }
    total > 0 && early * 4 >= total * 3
}

/// How much more a decaying transient moves in the first half of a hold than in the second.
const DECAY_FACTOR: f64 = 4.0;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::testing::{log_with, markov_log};
    use crate::diagnose::{DiagnoseOptions, diagnose, gap};
    use crate::sim::random::{mix64, uniform_in};
    use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
    use rand_core::SeedableRng;
    use rand_xoshiro::Xoshiro256PlusPlus;
    use std::ops::Range;

    /// The clean log of `seed` measured: its poses, and its white noise's standard deviation averaged
    /// over the axes, mg.
    fn clean_measured(seed: u64) -> (gap::Measured, f64) {
        let clean = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
        let m = gap::measure(&clean, &DiagnoseOptions::DEFAULT).unwrap();
        let white_mg = (m.white.iter().sum::<f64>() / 3.0).sqrt() / (clean.median_magnitude * 1e-3);
        (m, white_mg)
    }

    /// A footfall's ringing of the floor `since_step` s after it: 15 Hz, decaying in 50 ms, `peak_mg`
    /// at the step.
    fn footfall_mg(peak_mg: f64, since_step: f64) -> f64 {
        peak_mg * (-since_step / 0.05).exp() * (std::f64::consts::TAU * 15.0 * since_step).sin()
    }

    /// Footsteps near the bench during the holds `shaken`: a step about every 0.5 s rings the floor at
    /// 15 Hz (decaying in 50 ms, along one direction, 15 times the white noise's standard deviation
    /// at the step), and the walker's weight leans the bench, shifting the readings 1 mg along it.
    fn footsteps(seed: u64, shaken: &[usize]) -> crate::csvio::Table {
        let v = [0.3, -0.4, 0.866];
        let (_, white_mg) = clean_measured(seed);
        log_with(seed, &|p, t, _| {
            if !shaken.contains(&p) {
                return [0.0; 3];
            }
            // Steps 0.5 s apart, each up to 0.1 s early or late at random (a hash of the step and
            // the pose).
            let step_at = |k: f64| 0.5 * k + 0.1 * jitter(k as i64, p);
            let k = (t / 0.5).floor();
            let since_step = if t >= step_at(k) { t - step_at(k) } else { t - step_at(k - 1.0) };
            v.map(|c| c * (1.0 + footfall_mg(15.0 * white_mg, since_step)))
        })
    }

    /// A pseudo-random number in -1..1 of a step and a pose.
    fn jitter(step: i64, pose: usize) -> f64 {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(mix64(step as u64 ^ mix64(pose as u64)));
        uniform_in(&mut rng, -1.0, 1.0)
    }

    /// The poses [`shaken`] flags: their time spans, s.
    fn shaken_spans(table: &crate::csvio::Table) -> Vec<(f64, f64)> {
        let opts = DiagnoseOptions::DEFAULT;
        let m = gap::measure(table, &opts).unwrap();
        let ctx = Context::new(table, &m, &opts).unwrap();
        shaken(&ctx).iter().zip(&m.poses).filter(|(s, _)| **s).map(|(_, p)| (p.t_start, p.t_end)).collect()
    }

    #[test]
    fn holds_shaken_by_footsteps_are_dropped_and_named_motion() {
        // The ringing is faster than a segment: no segment mean moves, the readings do. Every piece
        // flagged lies in a shaken hold. The pose finder may cut a shaken hold in short pieces,
        // whose scatter rests on too few readings: on seed 3 (100 Hz, holds of 5.3 s) none is
        // flagged and motion is not named.
        let shaken_poses = [3, 9, 15];
        let mut named = 0;
        for seed in 1..=6 {
            let clean = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
            let clean_poses = gap::measure(&clean, &DiagnoseOptions::DEFAULT).unwrap().poses;
            let spans: Vec<(f64, f64)> =
                shaken_poses.iter().map(|&i| (clean_poses[i].t_start, clean_poses[i].t_end)).collect();
            let table = footsteps(seed, &shaken_poses);
            let flagged = shaken_spans(&table);
            let inside = |f: &(f64, f64), s: &(f64, f64)| f.0 >= s.0 - 0.5 && f.1 <= s.1 + 0.5;
            assert!(
                flagged.iter().all(|f| spans.iter().any(|s| inside(f, s))),
                "seed {seed}: {flagged:?} vs {spans:?}"
            );
            let d = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap();
            assert_eq!(d.verdict == "motion", !flagged.is_empty(), "seed {seed}: {}", d.to_text());
            named += usize::from(d.verdict == "motion");
        }
        assert!(named >= 5, "{named} of 6 named motion");
    }

    /// Footsteps passing the bench in bursts: during 30 % of the holds (drawn at random), from 45 %
    /// to 70 % of the hold, a step every 0.5 s rings the floor (10 times the white noise's standard
    /// deviation at the step, [`footfall_mg`]) and the walker's weight leans the bench along one
    /// direction, up to 2 mg and back as half a sine.
    fn footsteps_in_bursts(seed: u64) -> crate::csvio::Table {
        let v = [0.3, -0.4, 0.866];
        let (m, white_mg) = clean_measured(seed);
        let holds_s: Vec<f64> = m.poses.iter().map(|p| p.t_end - p.t_start).collect();
        log_with(seed, &|p, t, _| {
            let (start, end) = (0.45 * holds_s[p], 0.7 * holds_s[p]);
            if jitter(-1, p) < 0.4 || t < start || t > end {
                return [0.0; 3];
            }
            let ring = footfall_mg(10.0 * white_mg, (t - start) % 0.5);
            let lean = 2.0 * (std::f64::consts::PI * (t - start) / (end - start)).sin();
            v.map(|c| c * (lean + ring))
        })
    }

    #[test]
    fn footsteps_in_bursts_are_left_out_of_the_holds_they_shake_and_named_motion() {
        // The bursts' quiet segments, before and after, keep their holds. Only the segments a burst
        // shakes hard are left out: on a sensor whose readings are correlated (a low-pass filter)
        // a burst must shake harder to be seen (seeds 2, 3, 5, 6 and 8 here), and on seed 4 the
        // lean is not seen in the pose means (gap ratio 1.2).
        let mut named = 0;
        for seed in 1..=8 {
            let table = footsteps_in_bursts(seed);
            let opts = DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            let Some(trimmed) = shaken_segments_left_out(&ctx) else { continue };
            let poses = trimmed.detail.rsplit(": poses ").next().unwrap();
            for pose in poses.split(' ').map(|p| p.parse::<usize>().unwrap()) {
                assert!(jitter(-1, pose) >= 0.4, "seed {seed}: pose {pose} is not shaken ({})", trimmed.detail);
            }
            let d = diagnose(&table, &opts).unwrap();
            let motion = d.candidates.iter().find(|c| c.effect == "motion").unwrap();
            if ctx.value_gain(trimmed.ratio) >= 0.5 {
                assert_eq!(d.verdict, "motion", "seed {seed}: {}", d.to_text());
                assert_eq!(motion.detail, trimmed.detail, "seed {seed}");
                named += 1;
            }
        }
        assert!(named >= 2, "{named} of 8 named motion from the shaken segments left out");
    }

    /// Two knocks on the bench during hold `pose`, at a third and two thirds of it: each lurches the
    /// board for one cycle at 2 Hz (16 mg along one direction: the pose finder cuts the hold there)
    /// and rings the mount at 12 Hz (30 mg at the knock, decaying in 0.5 s).
    fn knocked_twice(seed: u64, pose: usize) -> crate::csvio::Table {
        use std::f64::consts::TAU;
        let v = [0.6, 0.0, -0.8];
        let clean = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
        let m = gap::measure(&clean, &DiagnoseOptions::DEFAULT).unwrap();
        let hold_s = m.poses[pose].t_end - m.poses[pose].t_start;
        log_with(seed, &|p, t, _| {
            let knocks = [hold_s / 3.0, 2.0 * hold_s / 3.0].into_iter().filter(|at| p == pose && t >= *at);
            let knock_mg = |s: f64| {
                let lurch = if s < 0.5 { 16.0 * (TAU * 2.0 * s).sin() } else { 0.0 };
                lurch + 30.0 * (-s / 0.5).exp() * (TAU * 12.0 * s).sin()
            };
            let mg: f64 = knocks.map(|at| knock_mg(t - at)).sum();
            v.map(|c| c * mg)
        })
    }

    #[test]
    fn a_hold_knocked_twice_is_one_placement_not_a_mount_ringing_after_each() {
        // The knocks cut the hold in pieces that each ring at the mount's resonance from their
        // start, as a mount ringing after every placement would; only the first piece follows a
        // placement. On some seeds the pose finder keeps the hold whole, or parts its pieces as
        // holds of their own; on some the pieces are too short to show the decay.
        let mut rung = 0;
        for seed in 1..=6 {
            let table = knocked_twice(seed, 9);
            let opts = DiagnoseOptions::DEFAULT;
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            let Some(run) = ctx.hold_runs().into_iter().find(|r| r.len() > 1) else { continue };
            let pieces: Vec<Range<usize>> = run.clone().map(|p| m.poses[p].rows.clone()).collect();
            rung += usize::from(ringing::rings(&table.samples, &pieces, m.rate));
            let mut knocked = vec![false; m.poses.len()];
            knocked[run].fill(true);
            assert!(!ringing::placements_ring(&ctx, &knocked), "seed {seed}");
        }
        assert!(rung >= 3, "the pieces of {rung} of 6 holds ring alike");
    }

    /// The setup set moving during the holds `pushed` (a lift or a cart starting off): over the
    /// middle 60 % of the hold an acceleration along one direction rising to `peak_mg` and falling
    /// back as half a sine.
    fn pushed(seed: u64, pushed: &[usize], peak_mg: f64) -> crate::csvio::Table {
        let v = [0.48, 0.6, -0.64];
        let clean = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
        let m = gap::measure(&clean, &DiagnoseOptions::DEFAULT).unwrap();
        let holds_s: Vec<f64> = m.poses.iter().map(|p| p.t_end - p.t_start).collect();
        log_with(seed, &|p, t, _| {
            let (start, end) = (0.2 * holds_s[p], 0.8 * holds_s[p]);
            if !pushed.contains(&p) || t < start || t > end {
                return [0.0; 3];
            }
            let cycle = (std::f64::consts::PI * (t - start) / (end - start)).sin();
            v.map(|c| c * peak_mg * cycle)
        })
    }

    #[test]
    fn one_hold_pushed_is_a_bad_pose_and_holds_pushed_again_and_again_are_motion() {
        // Handling that disturbs a log recurs; one disturbed hold is one bad pose, which the
        // verdict leaves unexplained and places; holds pushed again and again the motion family drops.
        // When the pose finder leaves the pushed holds out as moving, no gap shows them.
        let (mut seen, mut seen_again) = (0, 0);
        for seed in 1..=4 {
            let opts = DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
            let once = diagnose(&pushed(seed, &[9], 10.0), &opts).unwrap();
            if once.gap.significant && once.gap.ratio_before > 2.0 {
                seen += 1;
                let motion = once.candidates.iter().find(|c| c.effect == "motion").unwrap();
                assert!(
                    !motion.applicable && motion.detail.starts_with("one hold moves"),
                    "seed {seed}: {}",
                    once.to_text()
                );
                assert_eq!(once.verdict, "unexplained", "seed {seed}: {}", once.to_text());
                let located = once.located.as_deref().unwrap_or_default();
                assert!(located.starts_with("one pose"), "seed {seed}: {located}\n{}", once.to_text());
            }
            let again = diagnose(&pushed(seed, &[5, 11, 17], 10.0), &opts).unwrap();
            if again.gap.significant && again.gap.ratio_before > 2.0 {
                seen_again += 1;
                let motion = again.candidates.iter().find(|c| c.effect == "motion").unwrap();
                assert!(motion.applicable, "seed {seed}: {}", again.to_text());
            }
        }
        assert!(seen >= 2 && seen_again >= 2, "significant gaps: {seen} and {seen_again} of 4");
    }

    #[test]
    fn a_coarse_parts_rounding_shakes_none() {
        // Readings rounded to 20 times the white noise's standard deviation: a pose whose value
        // falls near a step dithers between two readings, one in the middle reads one throughout.
        for seed in [1, 2, 3] {
            let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
            let m = gap::measure(&table, &DiagnoseOptions::DEFAULT).unwrap();
            let step = 20.0 * (m.white.iter().sum::<f64>() / 3.0).sqrt();
            table.samples.iter_mut().for_each(|s| *s = s.map(|v| (v / step).round() * step));
            assert_eq!(shaken_spans(&table), Vec::new(), "seed {seed}");
        }
    }

    #[test]
    fn a_gauss_markov_noise_scattering_some_holds_more_than_others_shakes_none() {
        // A bias noise of a 1 s correlation time moves the readings within every segment, some
        // poses more than others by chance: the poses' own spread, not white noise's, is the yardstick.
        for seed in [1, 2, 3] {
            let table = markov_log(seed, 1.0, 1.0);
            assert_eq!(shaken_spans(&table), Vec::new(), "seed {seed}");
        }
    }
}
