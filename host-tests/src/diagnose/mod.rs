//! `accelcal diagnose`: why a calibration leaves more residual than the noise explains, and which
//! physical effect the 9-parameter model leaves out.
//!
//! 1. **The gap.** The poses are the still intervals of at least [`MIN_POSE_S`] (shorter ones, a hold
//!    cut up by motion, are counted and left out; all are used when too few full holds remain and
//!    the holds do not move). The library fits the nominal 9-parameter model ([`calib::run`](crate::calib::run),
//!    TAGA+LM). The same experiment (the fitted orientations, sample counts, durations and the
//!    white noise measured within the poses) is simulated `repeats` times and refitted as the real
//!    log was (the library's LM from the truth on every pose, the real fit's held parameters held:
//!    a repeat's own initial estimate could hold more, or leave a pose out); the gap is the real modulus RMSE over the mean simulated RMSE (1 = no gap),
//!    significant when the real RMSE is at least [`SIGNIFICANT_Z`] simulated standard deviations
//!    above the simulated mean and the ratio at least [`SIGNIFICANT_RATIO`] (the noise model's own
//!    error on logs from other generators).
//! 2. **Where it lies.** Residual per pose and per orientation, against time and temperature, within
//!    each pose (first third against last third), and in the noise (Allan deviation of the longest
//!    rest against white noise).
//! 3. **Which effect.** Each candidate is a physical augmentation, fitted in `f64` by linear least
//!    squares around the library's solution (the modulus residual linearised in the 9 parameters plus
//!    the effect's parameters), or a noise model fitted on other data than the pose means. Each is
//!    judged by cross-validation over the poses (leaving one out up to 40 poses, else in `folds`
//!    folds): the mean-square residual of the
//!    withheld poses, plus [`PARAMETER_PENALTY`] expected noise variances per extra parameter, over
//!    what white noise predicts for the nominal model (the noise model's prediction for
//!    `colored-noise`). `heldout_gain = 1 - ln(ratio) / ln(nominal ratio)` is the fraction of the
//!    withheld gap (in log ratio) the candidate removes; a noise model's ratio below 1 (more
//!    scatter predicted than seen) counts [`OVERSHOOT_WEIGHT`] times its `|ln ratio|`, a value
//!    fit's [`VALUE_OVERSHOOT_WEIGHT`] times what exceeds the scored poses' chance, `1 / sqrt(2 n)`.
//!    Drift and temperature are also fitted on the pose means and the within-pose course together
//!    (`family/joint.rs`: the segments fix the effect, the means the calibration), which tests them
//!    on logs too short to withhold a pose and still fit 9 + k parameters.
//!    The verdict is the candidate with the largest gain, if the gap is significant and the gain is
//!    at least [`MIN_GAIN`] (the thermometer named before time when both explain alike; a noise
//!    model before a value family only when far ahead of one that leaves half the gap or is a
//!    penalised wander, or before a drift or temperature that misses the holds' movement, or a
//!    non-linearity, when the holds walk at the level of the pose means' spread; a noise model
//!    must also be far ahead of a probe that explains the withheld values; a drift or temperature
//!    whose gain rests on the worst-predicted pose alone, with no support in the holds, is not
//!    named). When the gap is significant and no family or probe explains it, the holds answer
//!    from how each one moves (`family::from_holds`: colored noise if the bias switches between
//!    levels inside them, splitting them; settling if it slows, drift if a line per
//!    hold explains it, colored noise if every hold wanders alike and a walk at their level spreads
//!    the pose means as much; no shrink claimed); else the value family that alone fits every pose
//!    to white noise (gap ratio <= 1.2, a chi-square drop of 10 times the residual per column, as
//!    many residual degrees of freedom as columns spent; its held-out evidence below [`MIN_GAIN`];
//!    no other family nor probe fitting them to white noise: a design that few poses determine,
//!    which the withheld poses cannot test); else
//!    `unexplained` (with where the gap lies). `none` when there is no significant gap.
//! 4. **How far it shrinks.** The winner is added (to the model, or to the simulator for
//!    `colored-noise`) and step 1 redone: `shrink = (before - after) / (before - 1)`, clipped to
//!    `[0, 1]`.
//!
//! The families (one file each under `family/`, several parametrisations each):
//! - `drift`: bias `c (1 - exp(-t / tau))` per axis (`tau` from a grid), two time constants, or
//!   polynomial in time (degree 1 to 3);
//! - `temperature`: bias, relative scale, or both, linear or quadratic in the measured
//!   temperature, optionally through a first-order lag of the thermometer;
//! - `scale-nonlinearity`: `k2 a^2`, `k3 a^3` or both per axis;
//! - `settling`: a transient proportional to the change from the previous pose, decaying over
//!   `tau` from the start of each pose (only a `tau` that decays within the hold), or the transient
//!   measured in each pose (its mean minus the mean of its last half) scaled per axis or by one
//!   factor, or the start of every hold left out (these two only when the holds, pooled, move more
//!   in their first half than in their second: a wandering noise moves them alike), or a ringing
//!   mount (disturbed holds oscillating at one common frequency, more early in the hold:
//!   `family/ringing.rs`) left out;
//! - `motion`: poses whose own samples move slowly (chi-square of segment means after the first,
//!   above 6 times the median pose's and 40) are dropped, each at the cost of an expected noise
//!   variance plus the penalty (not when they decay or ring: that is settling);
//! - `colored-noise`: a bias random walk and/or a bias-instability floor measured on the longest
//!   rest (detrended quadratically in time and linearly in temperature) and pooled over every hold
//!   (each cleared of its line), from the overlapping Allan variance in excess of white noise (two
//!   white levels: differences of successive blocks once a low-pass filter's correlation has died
//!   out, at least `q^2 / 12`, and the holds' median variance);
//!   and a random walk at the level the holds move (the method of moments on the within-pose
//!   segments) when it accounts for the pose means' spread; the level the withheld poses' scatter
//!   agrees with best is given to the simulator.
//!
//! ```
//! use accelcal_host::diagnose::{diagnose, DiagnoseOptions};
//! use accelcal_host::sim::scenario::{generate, random_scenario, to_table, EffectClass};
//! let log = generate(&random_scenario(EffectClass::ScaleNonlinearity, 4));
//! let table = to_table(&log, "sim").unwrap();
//! let report = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
//! assert!(report.gap.ratio_before > 1.0);
//! ```

mod family;
mod gap;
mod holds;
mod jump;
mod locate;
pub(crate) mod math;
mod probe;
mod report;
mod verdict;
mod within;

use std::fmt;

pub use gap::MIN_POSE_S;
pub(crate) use locate::orientation_label;
pub use report::{Allan, Candidate, Diagnosis, DiagnosisDocument, Gap, InSampleFit, PoseReport, Probe};

use crate::csvio::{AccumulateOptions, Table};

/// The candidate effects, in report order.
pub const EFFECT_NAMES: [&str; 6] =
    ["drift", "temperature", "scale-nonlinearity", "settling", "motion", "colored-noise"];

/// A gap is significant when the real RMSE exceeds the simulated mean by this many simulated
/// standard deviations (and by [`SIGNIFICANT_RATIO`]).
pub const SIGNIFICANT_Z: f64 = 3.0;

/// ... and when the ratio is at least this: below it the noise model's own error on logs it was
/// not made with is as large. On the development, validation and fresh logs of the independent
/// generators (2 304 logs) the 288 clean logs' ratios reached 1.3 on 16 % of them and 1.5 on 4 %;
/// four clean logs of 1.2-1.5 were `unexplained` (significant by `z`), and of the 23 effects
/// significant at 1.2-1.5 three were named right. From 1.2 to 1.5: false alarms on
/// the development and validation sets 4 -> 2 of 216, out-of-catalogue honest 197 -> 198, right
/// where visible (ratio >= 2) unchanged; three right answers at 1.4 are `none` now.
pub const SIGNIFICANT_RATIO: f64 = 1.5;

/// Expected noise variances charged per extra parameter in the held-out score (AIC-like).
pub const PARAMETER_PENALTY: f64 = 2.0;

/// Logs of at most this many poses are cross-validated leaving one pose out; longer ones in
/// `opts.folds` folds. Withholding a fifth of the poses of a 17-40-pose log left a design of
/// square and cube terms per axis on a cube jig's 12 edge poses (the only poses that tell them from
/// bias and scale) barely determined: it predicted its withheld poses at 129 times white noise, 11
/// leaving one out. On the Python development sets leaving one out up to 40 poses (with probes
/// counted as in [`DiagnoseOptions::folds`] folds) gained 35 answers and lost 13; 11 of the gains
/// were non-linearities the 5 folds had left `unexplained`.
pub const LEAVE_ONE_OUT_UP_TO: usize = 40;

/// Weight of a noise model's held-out ratio below 1 (it predicts more scatter than the withheld
/// poses show) relative to one above 1, in the gain: a noise model raised far enough "explains"
/// any gap.
pub const OVERSHOOT_WEIGHT: f64 = 2.0;

/// Weight of a held-out ratio below 1 relative to one above 1 for a fit that predicts the withheld
/// values (families, probes): its cross-validated residuals cannot fall short of the noise but by
/// the noise's own chance, so the ratio is as far from 1 either way. With twice the weight the
/// right shape, 0.63 on a 12-pose log (leave one out), lost to a spline at 1.91.
pub const VALUE_OVERSHOOT_WEIGHT: f64 = 1.0;

/// Smallest held-out gain for a candidate to be named.
pub const MIN_GAIN: f64 = 0.3;

/// Excess of the longest rest's Allan variance over white noise (at its longest `tau`, in units of
/// the white variance) below which no random walk is fitted.
pub const WALK_EXCESS: f64 = 1.0;

/// Pure-noise draws averaged for the expected cross-validated residual.
pub(crate) const CV_NOISE_DRAWS: usize = 20;

/// Segments each pose is split into for the within-pose statistics.
pub(crate) const SEGMENTS: usize = 6;

/// Diagnosis settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DiagnoseOptions {
    /// Local gravity, m/s^2 (the calibration's target). Defaults to 9.80665.
    pub gravity: f64,
    /// Seed of the GA and of every simulation. Defaults to 1.
    pub seed: u64,
    /// Simulated repeats of the experiment. Defaults to 30.
    pub repeats: usize,
    /// Cross-validation folds on logs of more than 40 poses (fewer are left one out). Defaults to 5.
    pub folds: usize,
}

impl DiagnoseOptions {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { gravity: 9.806_65, seed: 1, repeats: 30, folds: 5 };
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Why a diagnosis could not run (bad input).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct DiagnoseError(pub String);

impl fmt::Display for DiagnoseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for DiagnoseError {}

fn err(msg: impl Into<String>) -> DiagnoseError {
    DiagnoseError(msg.into())
}

/// Runs the whole diagnosis on a table of raw samples.
pub fn diagnose(table: &Table, opts: &DiagnoseOptions) -> Result<Diagnosis, DiagnoseError> {
    let gravity = opts.gravity;
    if !(gravity.is_finite() && gravity > 0.0) {
        return Err(err(format!("gravity {gravity} must be a positive number of m/s^2")));
    }
    if opts.folds < 2 || opts.repeats < 2 {
        return Err(err("diagnose needs at least 2 folds and 2 repeats"));
    }
    if !table.columns_agree() {
        return Err(err(format!("{}: the table's columns do not all have one value per row", table.file)));
    }
    match measure(table, opts)? {
        Step1::Measured(m) => Ok(diagnose_measured(table, opts, &m, true)),
        Step1::Answered(d) => Ok(d),
    }
}

/// Steps 2-4 on the measured gap; with `second_look`, a log with disturbed poses is looked at again
/// without them ([`without_disturbed`]).
fn diagnose_measured(table: &Table, opts: &DiagnoseOptions, m: &gap::Measured, second_look: bool) -> Diagnosis {
    let gravity = opts.gravity;
    // Too few poses to withhold some (a short log that calibrate still accepts): the gap is measured and
    // answered (`none` or `unexplained`), with no catalogue candidate tested.
    let ctx = family::Context::new(table, m, opts);
    let evaluations: Vec<family::Evaluation> = match &ctx {
        Some(ctx) => family::all()
            .iter()
            .map(|f| family::Evaluation { predicts_values: f.predicts_values(), ..f.evaluate(ctx) })
            .collect(),
        None => Vec::new(),
    };
    let probes = ctx.as_ref().map(probe::run).unwrap_or_default();
    let from_holds = ctx.as_ref().and_then(family::from_holds);
    let holds_walk = ctx.as_ref().is_some_and(family::colored_noise::walk_accounts);
    let quiet_walk = |probe: Option<&Probe>| ctx.as_ref().and_then(|c| family::colored_noise::quiet_walk(c, probe));
    let decision = verdict::decide(m, &evaluations, &probes, from_holds, holds_walk, quiet_walk);
    let scale = m.scale();
    let mut d = Diagnosis {
        file: table.file.clone(),
        samples: table.samples.len(),
        units: table.units.to_string(),
        gravity,
        seed: opts.seed,
        repeats: m.sims.len(),
        params: m.params,
        white_mg: std::array::from_fn(|a| m.to_mg(m.white[a].sqrt() * scale[a])),
        gap: decision.gap,
        poses: locate::pose_reports(m, &decision.after),
        short_poses: m.short_poses,
        tails_trimmed: m.tails_trimmed,
        moving_fragments: m.moving_fragments,
        mean_change_widened: m.mean_change_widened,
        allan: locate::longest_rest_allan(table, m),
        candidates: evaluations.into_iter().map(|e| e.candidate).collect(),
        heldout_ratio_nominal: ctx.as_ref().map_or(f64::NAN, |c| c.heldout_ratio_nominal),
        probes,
        verdict: decision.verdict,
        located: decision.located,
        explained: decision.winner.is_some(),
        shrink: decision.shrink,
        not_calibrated: None,
        disturbed_left_out: None,
    };
    if d.verdict == "unexplained" {
        d.located = Some(unexplained_where(&d, ctx.as_ref(), decision.probe_where));
    }
    match ctx.as_ref().filter(|_| second_look) {
        Some(ctx) => without_disturbed(table, opts, ctx, &d).unwrap_or(d),
        None => d,
    }
}

/// Parameters of the catalogue's widest shapes (square and cube terms per axis; a temperature's bias
/// and scale per axis). Where fewer can be tested on withheld poses, an `unexplained` verdict says
/// so: on the development and validation sets (1 728 logs of three Python generators) the answer
/// was right on 47 % of the clearly visible logs of up to 13 poses and on 94 % of those of 25 or
/// more.
const WIDEST_SHAPE_PARAMS: usize = 6;

/// Where the gap of an `unexplained` verdict lies: the best probe's place, a periodic component, or
/// the residuals' pattern (and, without a context, that the catalogue could not be tested).
fn unexplained_where(d: &Diagnosis, ctx: Option<&family::Context<'_>>, probe_where: Option<String>) -> String {
    let periodic = || ctx.and_then(family::periodic::location);
    let line = || ctx.and_then(|c| c.steady_line().map(|l| l.describe(|a, x| c.m.to_mg(x * c.m.scale()[a]))));
    let place = probe_where.or_else(line).or_else(periodic).unwrap_or_else(|| locate::unexplained_location(d));
    match ctx.map(|ctx| (ctx.poses.len(), ctx.widest_testable())) {
        Some((poses, widest)) if widest < WIDEST_SHAPE_PARAMS => format!(
            "{place}; with {poses} poses no shape of more than {widest} parameters could be tested on withheld poses (the catalogue's terms per axis take 3-6; more poses in varied directions test them)"
        ),
        Some(_) => place,
        None => format!("{place}; too few poses to test the catalogue on withheld poses"),
    }
}

/// The diagnosis of a log with a significant gap on the same poses but those that move within
/// their holds (a move begun before the pose finder ended the pose, a knock;
/// `family::motion::moving`), when on the others a catalogue family other than motion explains
/// the gap, and the first diagnosis named motion, explained nothing on withheld poses, or named a
/// family with less held-out gain: the handling disturbed those poses, the sensor's effect is what
/// the others show. `None` otherwise: the first diagnosis stands.
fn without_disturbed(
    table: &Table,
    opts: &DiagnoseOptions,
    ctx: &family::Context<'_>,
    first: &Diagnosis,
) -> Option<Diagnosis> {
    let settled = first.explained && first.verdict != "motion" && verdict_gain(first) >= SETTLED_GAIN;
    let few = |d: &Vec<bool>| d.iter().filter(|d| **d).count() <= MOST_LEFT_OUT;
    let dropped = family::motion::moving(ctx)
        .filter(|d| first.gap.significant && !settled && few(d) && !step_where_dropped(&first.probes, d))?;
    let poses: Vec<&gap::PoseData> = ctx.poses.iter().zip(&dropped).filter(|(_, d)| **d).map(|(p, _)| p).collect();
    let m = gap::measure_without(table, opts, ctx.m, &dropped).ok()?;
    let second = diagnose_measured(table, opts, &m, false);
    let named = second.explained && !matches!(second.verdict, "none" | "unexplained" | "motion");
    let stronger = !first.explained || first.verdict == "motion" || verdict_gain(&second) > verdict_gain(first);
    (named && stronger).then(|| Diagnosis { disturbed_left_out: Some(left_out_note(&poses, first)), ..second })
}

/// A bias step that explains the withheld poses (held-out gain at least [`MIN_GAIN`]) lies inside or
/// at the edge of a hold the second look would leave out: that hold moves because the bias jumped
/// in it. A sensor's offset step shifts every later pose, which the step's fit tests; a knock or a
/// move begun early disturbs its own hold only, and the board's orientation is free at every pose.
/// On the development sets (2 304 logs) one answer changed: a blindgen4 offset step 4 s into a 5 s
/// hold, drift without that hold, is `unexplained` with the step placed inside it.
fn step_where_dropped(probes: &[Probe], dropped: &[bool]) -> bool {
    let moving = |pose: usize| dropped.get(pose).copied().unwrap_or(false);
    let at_moving = |after: usize| moving(after) || after.checked_sub(1).is_some_and(moving);
    probes.iter().any(|p| p.heldout_gain >= MIN_GAIN && p.step_before.is_some_and(at_moving))
}

/// What the second look left out, and the first look's gap and verdict.
fn left_out_note(poses: &[&gap::PoseData], first: &Diagnosis) -> String {
    let one = poses.len() == 1;
    let spans: Vec<String> = poses.iter().map(|p| format!("{:.1}-{:.1} s", p.t_start, p.t_end)).collect();
    format!(
        "{} left out ({}); with {} the gap ratio is {:.2} and the verdict {}",
        if one { "a pose moving within its hold" } else { "poses moving within their holds" },
        spans.join(", "),
        if one { "it" } else { "them" },
        first.gap.ratio_before,
        first.verdict
    )
}

/// Most poses a second look leaves out: a knock or a move begun early disturbs a pose or two; many
/// moving poses are the log's own noise or motion, and a second look costs a second diagnosis.
const MOST_LEFT_OUT: usize = 2;

/// Held-out gain of a first verdict that needs no second look without the moving poses: the
/// second must gain more to replace it (gains are at most 1), and the look doubles the time.
const SETTLED_GAIN: f64 = 0.95;

/// The held-out gain of the verdict's candidate (NaN without one).
fn verdict_gain(d: &Diagnosis) -> f64 {
    d.candidates.iter().find(|c| c.effect == d.verdict).map_or(f64::NAN, |c| c.heldout_gain)
}

/// Step 1's outcome.
enum Step1 {
    /// The gap measured.
    Measured(gap::Measured),
    /// Too few still poses to calibrate, and the holds move, or poses that calibrate but determine
    /// no gap: the answer ([`moving_holds`], [`undetermined`]).
    Answered(Diagnosis),
}

/// Step 1 on the still intervals of at least [`MIN_POSE_S`]; when those cannot be calibrated, the
/// answer of holds that move, else step 1 on the poses found as `calibrate` would retry
/// ([`crate::poses::attempts`]: every still interval, then the test of a block's mean change widened
/// for correlated readings); poses that calibrate but determine no gap are answered [`undetermined`]
/// (a log that calibrate accepts is answered); when none of those retries calibrates, a log moving in
/// the tremor band is answered [`trembling_log`], and the others are tried in longer blocks. Poses
/// found among more fragments of holds than poses ([`crate::poses::fragmented`]) are measured on the
/// first retry that finds them whole, as `calibrate` does, and on their own when none does.
fn measure(table: &Table, opts: &DiagnoseOptions) -> Result<Step1, DiagnoseError> {
    let mut not_calibrated = None;
    let mut fragments = None;
    match gap::measure(table, opts) {
        Ok(m)
            if !m.fragmented
                || family::tremor::in_log(table, m.rate).is_some()
                || switches_in_pieces(table, opts, &m) =>
        {
            return Ok(Step1::Measured(m));
        }
        Ok(m) => fragments = Some(m),
        Err(gap::Refusal::NotCalibrated { still_poses, rate, .. }) => {
            if let Some(d) = moving_holds(table, opts, still_poses, rate) {
                return Ok(Step1::Answered(d));
            }
            not_calibrated = Some((still_poses, rate));
        }
        Err(gap::Refusal::Undetermined { .. } | gap::Refusal::Other(_)) => {}
    }
    // A hand's tremor moves block means as a low-pass filter does: the log's spectrum is asked before
    // the longer blocks, which would find the trembling holds and average the tremor out.
    let mut usual: Vec<AccumulateOptions> =
        crate::poses::attempts(&AccumulateOptions::default()).into_iter().skip(1).collect();
    let first_longer = usual.iter().position(|o| o.correlated_block_multiple > 1).unwrap_or(usual.len());
    let longer = usual.split_off(first_longer);
    let mut refused = None;
    let whole_only = fragments.is_some();
    if let Some(step) = first_measured(table, opts, &usual, &mut refused, whole_only) {
        return Ok(step);
    }
    if let Some((still_poses, rate)) = not_calibrated
        && let Some(d) = trembling_log(table, opts, still_poses, rate)
    {
        return Ok(Step1::Answered(d));
    }
    if let Some(step) = first_measured(table, opts, &longer, &mut refused, whole_only) {
        return Ok(step);
    }
    if let Some(m) = fragments {
        return Ok(Step1::Measured(m));
    }
    Err(refused.map_or_else(|| err(format!("{}: no still poses", table.file)), |(_, error)| error))
}

/// The holds found cut in pieces (asked only of poses [`crate::poses::fragmented`]) differ by jumps
/// of one size per sensor axis (a telegraph noise switching inside the holds,
/// [`family::colored_noise::switching_holds`]): the cuts are the effect's evidence, and the settings
/// that find the holds whole would hide it. On blindgen4's CI seeds two telegraph noises named from
/// their jumps were `unexplained` once a hold cut in pieces counted as fragmented
/// ([`crate::poses::split_holds`]).
fn switches_in_pieces(table: &Table, opts: &DiagnoseOptions, m: &gap::Measured) -> bool {
    family::Context::new(table, m, opts).is_some_and(|ctx| {
        family::colored_noise::switching_holds(&ctx, family::colored_noise::Jumps::BetweenPieces).is_some()
    })
}

/// Step 1 on the poses found with the first of `attempts` that calibrates them (or answers them
/// [`undetermined`]), only poses found whole with `whole_only`; `None` when none does, with
/// `refused` holding the refusal of the attempt that found the most still poses (the first of them;
/// as `calibrate` reports).
fn first_measured(
    table: &Table,
    opts: &DiagnoseOptions,
    attempts: &[AccumulateOptions],
    refused: &mut Option<(usize, DiagnoseError)>,
    whole_only: bool,
) -> Option<Step1> {
    for found_with in attempts {
        let (poses, error) = match gap::measure_with(table, opts, found_with) {
            Ok(m) if whole_only && m.fragmented && !switches_in_pieces(table, opts, &m) => continue,
            Ok(m) => return Some(Step1::Measured(m)),
            Err(gap::Refusal::Undetermined { .. }) if whole_only => continue,
            Err(gap::Refusal::Undetermined { still_poses }) => {
                return Some(Step1::Answered(undetermined(table, opts, still_poses)));
            }
            Err(gap::Refusal::NotCalibrated { still_poses, error, .. }) => (still_poses, error),
            Err(gap::Refusal::Other(error)) => (0, error),
        };
        if refused.as_ref().is_none_or(|(most, _)| poses > *most) {
            *refused = Some((poses, error));
        }
    }
    None
}

/// The answer for a log whose still poses calibrate (as `calibrate` does) but determine no gap: no
/// simulated repeat of the experiment refits (fragments of holds, too few directions). `unexplained`
/// with the reason, no gap measured: the log is answered, and no family is named.
fn undetermined(table: &Table, opts: &DiagnoseOptions, still_poses: usize) -> Diagnosis {
    let reason = format!(
        "{still_poses} still poses calibrate but do not determine the model (no simulated repeat of the experiment \
         refits): no gap measured"
    );
    unmeasured(table, opts, Vec::new(), reason)
}

/// The answer for a log whose still poses cannot be calibrated but whose holds mostly move
/// (`holds.rs`): `motion`, with the evidence, no gap measured; `None` when the holds do not move.
fn moving_holds(table: &Table, opts: &DiagnoseOptions, still_poses: usize, rate: f64) -> Option<Diagnosis> {
    let motion = holds::scan(table, rate).filter(holds::HoldMotion::explains_few_poses)?;
    Some(motion_answer(table, opts, still_poses, motion.describe(still_poses)))
}

/// The answer for a log that no retry of the pose finder calibrates and which moves in the tremor
/// band throughout (a hand that keeps the orientation moving too much for the holds scan to find
/// holds, `family/tremor.rs`): `motion`, no gap measured; `None` when it does not.
fn trembling_log(table: &Table, opts: &DiagnoseOptions, still_poses: usize, rate: f64) -> Option<Diagnosis> {
    let tremor = family::tremor::in_log(table, rate)?;
    let detail = format!(
        "the still-pose detector kept {still_poses} poses, too few to calibrate; the log moves at 2-20 Hz ({})",
        tremor.describe()
    );
    Some(motion_answer(table, opts, still_poses, detail))
}

/// `motion` without a measured gap, with the evidence.
fn motion_answer(table: &Table, opts: &DiagnoseOptions, still_poses: usize, detail: String) -> Diagnosis {
    let candidate = Candidate {
        effect: "motion",
        applicable: true,
        heldout_ratio: f64::NAN,
        heldout_gain: f64::NAN,
        ratio_after: f64::NAN,
        extra_params: 0,
        detail,
        within_gain: f64::NAN,
        within_detail: String::new(),
        within_disagreement: f64::NAN,
        variants: Vec::new(),
        in_sample: None,
    };
    let reason = format!("{} still poses: too few to calibrate", still_poses);
    Diagnosis { verdict: "motion", explained: true, ..unmeasured(table, opts, vec![candidate], reason) }
}

/// A diagnosis without a measured gap: `candidates` and why no gap was measured (verdict
/// `unexplained` until the caller names one).
fn unmeasured(table: &Table, opts: &DiagnoseOptions, candidates: Vec<Candidate>, reason: String) -> Diagnosis {
    Diagnosis {
        file: table.file.clone(),
        samples: table.samples.len(),
        units: table.units.to_string(),
        gravity: opts.gravity,
        seed: opts.seed,
        repeats: 0,
        params: accelcal::model::Params::IDENTITY,
        white_mg: [f64::NAN; 3],
        gap: Gap::UNMEASURED,
        poses: Vec::new(),
        short_poses: 0,
        tails_trimmed: 0,
        moving_fragments: 0,
        mean_change_widened: None,
        allan: Allan { rest_s: 0.0, tau_s: Vec::new(), adev_mg: Vec::new(), white_mg: Vec::new() },
        candidates,
        heldout_ratio_nominal: f64::NAN,
        probes: Vec::new(),
        verdict: "unexplained",
        located: None,
        explained: false,
        shrink: f64::NAN,
        not_calibrated: Some(reason),
        disturbed_left_out: None,
    }
}

/// Helpers the diagnosis's tests share.
#[cfg(test)]
pub(crate) mod testing {
    use crate::csvio::Table;

    /// A probe (its place not seen as a jump in a hold).
    pub(crate) fn probe(
        shape: &'static str,
        heldout_gain: f64,
        in_sample_ratio: f64,
        veto_margin: f64,
    ) -> super::Probe {
        super::Probe {
            shape,
            heldout_gain,
            detail: String::new(),
            in_sample_ratio,
            veto_margin,
            jump_in_hold: false,
            columns: 3,
            step_before: None,
        }
    }

    /// A clean simulated log with `bias(pose, seconds into its hold, seconds into the log)` (mg,
    /// sensor frame) added to every static pose's rows.
    pub(crate) fn log_with(seed: u64, bias: &dyn Fn(usize, f64, f64) -> super::math::V3) -> Table {
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
        let m = super::gap::measure(&table, &super::DiagnoseOptions::DEFAULT).unwrap();
        let mg = table.median_magnitude * 1e-3;
        for (p, pose) in m.poses.iter().enumerate() {
            for row in pose.rows.clone() {
                let t = super::gap::row_time(&table, row, m.rate);
                let b = bias(p, t - pose.t_start, t);
                table.samples[row] = std::array::from_fn(|a| table.samples[row][a] + b[a] * mg);
            }
        }
        table
    }

    /// A clean simulated log with a bias along one direction added as `shape(t / duration)` mg.
    pub(crate) fn biased_log(seed: u64, shape: &dyn Fn(f64) -> f64) -> Table {
        use crate::csvio::{self, AccumulateOptions};
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "bias").unwrap();
        let acc = csvio::accumulate(&table, &AccumulateOptions::default()).unwrap();
        let (mg, dt) = (table.median_magnitude / 1000.0, 1.0 / acc.sample_rate_hz.unwrap());
        let duration = table.samples.len() as f64 * dt;
        let direction = [0.36, -0.48, 0.8];
        for (i, sample) in table.samples.iter_mut().enumerate() {
            let along = shape(i as f64 * dt / duration) * mg;
            (0..3).for_each(|a| sample[a] += along * direction[a]);
        }
        table
    }

    /// The table of `recording` with only the poses whose direction `keep` keeps (the rows of the
    /// others, their holds, left out), at 25 C.
    pub(crate) fn table_of_poses(
        mut recording: crate::sim::record::Recording,
        mut keep: impl FnMut(&[f64; 3]) -> bool,
        name: &str,
    ) -> Table {
        use crate::sim::scenario::{SimLog, to_table};
        let dropped: Vec<std::ops::Range<usize>> =
            recording.poses.iter().filter(|p| !keep(&p.direction)).map(|p| p.start..p.end).collect();
        let kept = |i: &usize| !dropped.iter().any(|r| r.contains(i));
        recording.samples = (0..recording.samples.len()).filter(kept).map(|i| recording.samples[i]).collect();
        recording.times_s = (0..recording.times_s.len()).filter(kept).map(|i| recording.times_s[i]).collect();
        let temps_c = vec![25.0; recording.samples.len()];
        to_table(&SimLog { recording, temps_c }, name).unwrap()
    }

    /// An own-simulator log (random scenario `seed`, no effect) whose z axis alone bows: k2 2 mg,
    /// k3 -1.5 mg at 1 g.
    pub(crate) fn z_bowed(seed: u64) -> Table {
        use crate::sim::scenario::{EffectClass, SimLog, random_scenario, to_table};
        let scenario = random_scenario(EffectClass::None, seed);
        let g = scenario.sim.gravity;
        let recording = crate::sim::simulate_with(
            &scenario.sim,
            &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                let z = r[2] / g;
                r[2] += g * (2.0e-3 * z * z - 1.5e-3 * z * z * z);
            }],
        );
        let temps_c = vec![25.0; recording.samples.len()];
        to_table(&SimLog { recording, temps_c }, "z-only").unwrap()
    }

    /// A clean simulated log with a first-order Gauss-Markov bias noise on every axis (standard
    /// deviation `sigma_mg`, correlation time `tau_s`, independent between the axes).
    pub(crate) fn markov_log(seed: u64, sigma_mg: f64, tau_s: f64) -> Table {
        use crate::sim::random::standard_normal;
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        use rand_core::SeedableRng;
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "markov").unwrap();
        let acc = crate::csvio::accumulate(&table, &Default::default()).unwrap();
        let (mg, dt) = (table.median_magnitude / 1000.0, 1.0 / acc.sample_rate_hz.unwrap());
        let phi = (-dt / tau_s).exp();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x6a55);
        let mut bias: [f64; 3] = std::array::from_fn(|_| standard_normal(&mut rng));
        for sample in &mut table.samples {
            for a in 0..3 {
                bias[a] = phi * bias[a] + (1.0 - phi * phi).sqrt() * standard_normal(&mut rng);
                sample[a] += sigma_mg * mg * bias[a];
            }
        }
        table
    }

    /// A clean simulated log rounded to a step `steps` times its per-reading noise: the readings
    /// stay on one level for most of each hold and flip to the next only where the true value lies
    /// near a rounding boundary.
    pub(crate) fn coarsely_rounded(seed: u64, steps: f64) -> Table {
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "rounded").unwrap();
        let noise: super::math::V3 = std::array::from_fn(|a| {
            let d: Vec<f64> = table.samples.windows(2).map(|w| (w[1][a] - w[0][a]).abs()).collect();
            super::math::median(&d) / 0.6745 / std::f64::consts::SQRT_2
        });
        for sample in &mut table.samples {
            (0..3).for_each(|a| sample[a] = (sample[a] / (steps * noise[a])).round() * steps * noise[a]);
        }
        table
    }

    /// `table` through a moving average of `width` readings: a digital low-pass filter of about
    /// `rate / (2 width)` Hz (a MEMS part's, correlating successive readings; the noise of a mean
    /// keeps its level while the per-reading variance falls by `width`).
    pub(crate) fn low_passed(mut table: Table, width: usize) -> Table {
        let raw = table.samples.clone();
        for (i, s) in table.samples.iter_mut().enumerate() {
            let window = &raw[i.saturating_sub(width - 1)..=i];
            *s = std::array::from_fn(|a| window.iter().map(|r| r[a]).sum::<f64>() / window.len() as f64);
        }
        table
    }
}

#[cfg(test)]
mod tests {
    use super::math::{Model, lstsq};
    use super::*;
    use crate::sim::knocked::knocked_log;
    use accelcal::model::Params;

    /// A bias step placed before pose `step_before` (or inside its hold), with `heldout_gain`.
    fn step_probe(step_before: usize, heldout_gain: f64) -> Probe {
        Probe {
            shape: "bias-step",
            heldout_gain,
            detail: String::new(),
            in_sample_ratio: 1.0,
            veto_margin: 0.0,
            jump_in_hold: true,
            columns: 3,
            step_before: Some(step_before),
        }
    }

    #[test]
    fn a_hold_a_bias_step_explains_is_not_left_out_as_handling() {
        // On a blindgen4 log a 0.8 mg offset step 4 s into a 5 s hold moved it after its first
        // third: the second look left it out as a knock and named the later poses' shift drift.
        let dropped = |i: usize| (0..12).map(|p| p == i).collect::<Vec<bool>>();
        let step = [step_probe(5, 0.8)];
        assert!(step_where_dropped(&step, &dropped(5)), "inside the moving hold");
        assert!(step_where_dropped(&step, &dropped(4)), "at the end of the moving hold");
        assert!(!step_where_dropped(&step, &dropped(7)), "a knock elsewhere is handling");
        assert!(!step_where_dropped(&[step_probe(5, MIN_GAIN - 0.01)], &dropped(5)), "a step that explains nothing");
        let one_pose = Probe { shape: "one-pose", step_before: None, ..step_probe(5, 0.8) };
        assert!(!step_where_dropped(&[one_pose], &dropped(5)), "not a step");
    }

    #[test]
    fn lstsq_recovers_a_line() {
        let rows: Vec<Vec<f64>> = (0..10).map(|i| vec![1.0, i as f64]).collect();
        let r: Vec<f64> = (0..10).map(|i| -(2.0 + 0.5 * i as f64)).collect();
        let idx: Vec<usize> = (0..10).collect();
        let x = lstsq(&rows, &r, &idx).unwrap();
        assert!((x[0] - 2.0).abs() < 1e-9 && (x[1] - 0.5).abs() < 1e-9, "{x:?}");
    }

    #[test]
    fn the_tail_of_a_move_in_a_few_pose_starts_is_trimmed_and_a_transient_in_every_one_is_settling() {
        // The hand still settling the part after a lift: 12 mg along the vertical decaying in 0.3 s
        // at the start of a hold (the detector's variance test barely sees it).
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let clean = to_table(&generate(&random_scenario(EffectClass::None, 5)), "sim").unwrap();
        let opts = DiagnoseOptions::DEFAULT;
        let m = gap::measure(&clean, &opts).unwrap();
        let tailed = |chosen: &dyn Fn(usize) -> bool| {
            let mut table = clean.clone();
            let mg = table.median_magnitude * 1e-3;
            for (p, pose) in m.poses.iter().enumerate().filter(|(p, _)| chosen(*p)) {
                let up = m.directions[p];
                for row in pose.rows.clone() {
                    let t = gap::row_time(&table, row, m.rate) - pose.t_start;
                    let b = 12.0 * (-t / 0.3).exp() * mg;
                    table.samples[row] = std::array::from_fn(|a| table.samples[row][a] - up[a] * b);
                }
            }
            table
        };
        // Two holds, the two longest after the first rest (the longer the hold, the more of the tail
        // its first sixth holds): trimmed, and the log is clean (without the trim it is not).
        let mut by_length: Vec<usize> = (1..m.poses.len()).collect();
        by_length.sort_by(|a, b| m.poses[*b].duration().total_cmp(&m.poses[*a].duration()));
        let d = diagnose(&tailed(&|p| by_length[..2].contains(&p)), &opts).unwrap();
        assert_eq!(d.tails_trimmed, 2, "{}", d.to_text());
        assert_eq!(d.verdict, "none", "{}", d.to_text());
        assert!(d.to_text().contains("2 poses trimmed"), "{}", d.to_text());
        // Every pose: the part's settling, left to the settling family. The sixths test does not take
        // it whole; the edge test takes the first tenths of a second where they differ from the
        // second after them beyond noise, and the rest of the transient stays for the family.
        let d = diagnose(&tailed(&|_| true), &opts).unwrap();
        assert_eq!(d.verdict, "settling", "{}", d.to_text());
        let settling = d.candidates.iter().find(|c| c.effect == "settling").unwrap();
        assert!(settling.heldout_gain >= MIN_GAIN, "{}", d.to_text());
    }

    #[test]
    fn a_pose_a_move_began_in_is_left_out_and_the_others_named() {
        // Only z bows (k2 2 mg, k3 -1.5 mg at 1 g); in the longest hold a move begins in the last
        // 40 % of the pose (a slow turn about the vertical: gravity stays, the lever arm's
        // acceleration grows to 10-20 mg by the pose's end, too slowly for the trim of a move's
        // tail). That pose's mean is the move's, not the sensor's: left out, the others show the
        // bow. Of seeds 11-16 with 5, 10 and 20 mg, the diagnosis of every pose named 15 of 18
        // right; these three it named `unexplained`, `motion` and colored-noise. With the pose left
        // out, 18 of 18.
        for (seed, lean_mg) in [(12, 10.0), (12, 20.0), (16, 10.0)] {
            let mut table = testing::z_bowed(seed);
            let opts = DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
            let m = gap::measure(&table, &opts).unwrap();
            let longest = (1..m.poses.len()).max_by(|a, b| m.poses[*a].duration().total_cmp(&m.poses[*b].duration()));
            let pose = &m.poses[longest.unwrap()];
            let mg = table.median_magnitude * 1e-3;
            for row in pose.rows.clone() {
                let to_end = pose.t_end - gap::row_time(&table, row, m.rate);
                let b = lean_mg * (1.0 - to_end / (0.4 * pose.duration())).max(0.0) * mg;
                table.samples[row] = std::array::from_fn(|a| table.samples[row][a] + [0.6, 0.8, 0.0][a] * b);
            }
            let d = diagnose(&table, &opts).unwrap();
            assert_eq!(d.verdict, "scale-nonlinearity", "seed {seed}, {lean_mg} mg: {}", d.to_text());
            let note = d.disturbed_left_out.as_deref().unwrap_or_default();
            assert!(note.contains("a pose moving within its hold left out"), "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_log_whose_clock_starts_late_is_diagnosed_as_from_its_first_row() {
        // A warm-up drift logged against a host clock that had run 4321 s before the log began: the
        // effects' shapes in time (the warm-up's exponential, the periods the probe searches) are
        // measured from the log's start.
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let table = to_table(&generate(&random_scenario(EffectClass::Drift, 7)), "drift").unwrap();
        let mut late = table.clone();
        late.times_s = table.times_s.as_ref().map(|t| t.iter().map(|s| s + 4321.0).collect());
        let opts = DiagnoseOptions::DEFAULT;
        let (d, d_late) = (diagnose(&table, &opts).unwrap(), diagnose(&late, &opts).unwrap());
        assert_eq!(d.verdict, d_late.verdict);
        for (c, c_late) in d.candidates.iter().zip(&d_late.candidates) {
            assert_eq!(c.detail, c_late.detail, "{}", c.effect);
            assert!((c.heldout_ratio - c_late.heldout_ratio).abs() <= 1e-6 * c.heldout_ratio, "{c:?}\n{c_late:?}");
        }
        let (p, p_late) = (&d.probes, &d_late.probes);
        assert!(p.iter().zip(p_late).all(|(a, b)| a.detail == b.detail), "{p:?}\n{p_late:?}");
    }

    #[test]
    fn the_short_still_fragments_of_a_knocked_hold_are_counted_and_left_out() {
        // One knock in every fourth hold, mid-hold: a 0.45 s fragment pressed, then the hold resumes.
        let table = knocked_log(4, 0.5, 0.45, 1);
        let opts = DiagnoseOptions::DEFAULT;
        let all =
            gap::measure_with(&table, &opts, &AccumulateOptions { min_pose_s: 0.0, ..AccumulateOptions::default() })
                .unwrap();
        let full = gap::measure(&table, &opts).unwrap();
        assert!(full.short_poses >= 3, "{} short of {} still intervals", full.short_poses, all.poses.len());
        assert_eq!(all.poses.len(), full.poses.len() + full.short_poses);
        // The fragments' 30 mg make a gap; without them there is none.
        assert!(all.gap.significant, "{:?}", all.gap);
        let d = diagnose(&table, &opts).unwrap();
        assert!(!d.gap.significant && d.verdict == "none", "{}", d.to_text());
        assert_eq!(d.short_poses, full.short_poses);
        assert!(d.to_text().contains("shorter than 0.5 s left out"), "{}", d.to_text());
    }

    #[test]
    fn holds_the_first_settings_cut_into_fragments_are_diagnosed_whole_as_calibrate_finds_them() {
        // A clean simulated log through a moving average of 8 readings (a sensor's digital filter):
        // the default settings keep enough poses to calibrate among far more fragments of holds.
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let clean = to_table(&generate(&random_scenario(EffectClass::None, 1)), "filtered").unwrap();
        let table = testing::low_passed(clean, 8);
        let opts = DiagnoseOptions::DEFAULT;
        let first = gap::measure(&table, &opts).unwrap();
        assert!(first.fragmented, "{} poses", first.poses.len());
        let whole =
            crate::poses::accumulate_holds(&table, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
        assert!(!crate::poses::fragmented(&whole) && whole.poses.len() > first.poses.len());
        let d = diagnose(&table, &opts).unwrap();
        assert_eq!(d.poses.len(), whole.poses.len(), "{}", d.to_text());
        assert_eq!(d.mean_change_widened, whole.mean_change_widened);
        assert_eq!(d.verdict, "none", "{}", d.to_text());
    }

    #[test]
    fn still_poses_that_calibrate_but_determine_no_gap_are_answered() {
        use crate::blindgen::{Family, generate, random_spec};
        use crate::csvio::{ReadOptions, read_csv_str};
        // A Gauss-Markov bias of 13 mg (tau 9 s) at 500 Hz, a held-out log of the first generator: the
        // detector finds ten fragments of 0.26 s still, calibrate fits them (a FAIL verdict, six
        // parameters undetermined), and no simulated repeat of that experiment refits.
        let log = generate(&random_spec(Family::ColoredNoise, 1_008_112));
        let table = read_csv_str("markov.csv", &log.to_csv_string(), &ReadOptions::default()).unwrap();
        let opts = DiagnoseOptions::DEFAULT;
        assert!(matches!(
            gap::measure_with(&table, &opts, &AccumulateOptions { min_pose_s: 0.0, ..AccumulateOptions::default() }),
            Err(gap::Refusal::Undetermined { .. })
        ));
        let d = diagnose(&table, &opts).unwrap();
        assert_eq!(d.verdict, "unexplained", "{}", d.to_text());
        assert!(!d.explained && d.not_calibrated.as_deref().is_some_and(|r| r.contains("no gap measured")));
    }

    #[test]
    fn a_log_of_short_holds_only_is_still_answered() {
        // Every hold knocked from its start: still intervals of 0.4 s only, which calibrate accepts.
        let table = knocked_log(1, 0.0, 0.4, 1000);
        let opts = DiagnoseOptions::DEFAULT;
        assert!(matches!(gap::measure(&table, &opts), Err(gap::Refusal::NotCalibrated { .. })));
        assert!(
            gap::measure_with(&table, &opts, &AccumulateOptions { min_pose_s: 0.0, ..AccumulateOptions::default() })
                .is_ok()
        );
        let d = diagnose(&table, &opts).unwrap();
        assert!(!d.verdict.is_empty(), "{}", d.to_text());
    }

    #[test]
    fn a_clean_log_has_no_gap_and_the_report_has_the_documented_fields() {
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        // A clean log's gap is significant about once in 40 seeds (1/40 on seeds 0..39 with the
        // simulator's rand_distr noise, ratio median 1.03): seed 5 is that one, seed 0 is not.
        let log = generate(&random_scenario(EffectClass::None, 0));
        let table = to_table(&log, "clean").unwrap();
        let report = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
        assert!(!report.gap.significant, "{}", report.to_text());
        assert_eq!(report.verdict, "none");
        let json = report.to_json();
        for key in ["real_rmse_mg", "sim_rmse_mg", "ratio_before", "ratio_after"] {
            assert!(json["gap"][key].is_number(), "{key}");
        }
        assert!(json["poses"].as_u64().unwrap() >= 24);
        assert!(json["where"].is_object());
        let names: Vec<&str> =
            json["candidates"].as_array().unwrap().iter().map(|c| c["effect"].as_str().unwrap()).collect();
        assert_eq!(names, EFFECT_NAMES);
        assert_eq!(json["verdict"]["effect"], "none");
        assert!(json["verdict"]["shrink"].is_number());
        assert!(report.to_text().contains("4. ratio"));
    }

    #[test]
    fn too_few_poses_is_an_error_not_a_panic() {
        let text: String = std::iter::once("t,ax,ay,az\n".to_string())
            .chain((0..2000).map(|i| format!("{},0.0,0.0,1.0\n", i as f64 * 0.01)))
            .collect();
        let table = crate::csvio::read_csv_str("still", &text, &crate::csvio::ReadOptions::default()).unwrap();
        let e = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap_err();
        assert!(e.to_string().contains("static poses"), "{e}");
        assert!(diagnose(&table, &DiagnoseOptions { gravity: f64::NAN, ..DiagnoseOptions::DEFAULT }).is_err());
    }

    #[test]
    fn a_certain_gap_within_the_noise_models_own_error_is_not_significant() {
        // Every hold of a clean simulated log (seed 1) offset along its reading by 1.4 times the
        // simulated pose scatter, up or down in a fixed pattern: ratio 1.47 at z 3.9, certain but
        // within the 1.5 the noise model errs by on other generators' clean logs.
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, 1)), "scattered").unwrap();
        let sim_rmse_mg = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap().gap.sim_rmse_mg;
        let spans = crate::csvio::accumulate(&table, &crate::csvio::AccumulateOptions::default()).unwrap().spans;
        let mg = table.median_magnitude / 1000.0;
        for (i, h) in spans.iter().enumerate() {
            let offset = if (i * 7 + 3) % 5 < 2 { -1.4 } else { 1.4 } * sim_rmse_mg * mg;
            for sample in &mut table.samples[h.first_row..=h.last_row] {
                let along = crate::vec3::norm(*sample);
                (0..3).for_each(|a| sample[a] += offset * sample[a] / along);
            }
        }
        let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
        assert!(d.gap.z >= SIGNIFICANT_Z && d.gap.ratio_before < SIGNIFICANT_RATIO, "{:?}", d.gap);
        assert_eq!(d.verdict, "none", "{}", d.to_text());
        assert!(d.to_text().contains("not significant (ratio below 1.5"), "{}", d.to_text());
    }

    #[test]
    fn a_table_whose_columns_disagree_in_length_is_an_error_not_a_panic() {
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let mut table = to_table(&generate(&random_scenario(EffectClass::Temperature, 1)), "cut").unwrap();
        assert!(table.temps_c.is_some() && table.times_s.is_some());
        let rows = table.samples.len();
        table.temps_c.as_mut().unwrap().truncate(rows / 2);
        let e = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap_err();
        assert!(e.to_string().contains("one value per row"), "{e}");
        table.truncate(rows / 2);
        assert!(table.columns_agree() && table.samples.len() == rows / 2);
        assert!(diagnose(&table, &DiagnoseOptions::DEFAULT).is_ok());
    }

    #[test]
    fn holds_that_move_too_much_to_calibrate_are_answered_motion_quiet_ones_are_not() {
        // Ten holds, eight with a 2 Hz sway of 20 mg (the detector keeps the two still ones).
        let table = holds::tests::log(10, |k, t| if k % 5 == 0 { 0.0 } else { 0.020 * (12.57 * t).sin() });
        let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
        assert_eq!(d.verdict, "motion", "{}", d.to_text());
        assert!(d.not_calibrated.is_some() && d.candidates[0].detail.contains("8 of them move"), "{}", d.to_text());
        assert!(d.to_json()["not_calibrated"].is_string());
        // Three still holds: too few, and nothing moves: the detector's error stays.
        let e = diagnose(&holds::tests::log(3, |_, _| 0.0), &DiagnoseOptions::DEFAULT).unwrap_err();
        assert!(e.to_string().contains("static poses"), "{e}");
    }

    #[test]
    fn a_log_held_by_a_swaying_trembling_hand_is_answered_motion() {
        // Every hold sways by 60 mg at 0.7 Hz (too much for the holds scan to find holds) with a
        // 10 mg tremor at 9 Hz: no still poses, no holds, but the log's spectrum rises to 8-12 Hz.
        let hand = |_: usize, t: f64| 0.060 * (4.4 * t).sin() + 0.010 * (56.5 * t).sin();
        let table = holds::tests::log(10, hand);
        assert!(holds::scan(&table, 100.0).is_none_or(|m| !m.explains_few_poses()));
        let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
        assert_eq!(d.verdict, "motion", "{}", d.to_text());
        assert!(d.candidates[0].detail.contains("8-12 Hz"), "{}", d.to_text());
        // The same sway without the tremor: the detector's error stays.
        let e = diagnose(&holds::tests::log(10, |_, t| 0.060 * (4.4 * t).sin()), &DiagnoseOptions::DEFAULT);
        assert!(e.is_err(), "{:?}", e.map(|d| d.to_text()));
    }

    #[test]
    fn a_bias_step_at_one_time_is_unexplained_and_located_not_given_a_catalogue_name() {
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, 0)), "step").unwrap();
        // A 4 mg step of every axis half way through (the table's unit: its median |a| is 1 g).
        let step = 0.004 * table.median_magnitude;
        let half = table.samples.len() / 2;
        for s in &mut table.samples[half..] {
            s.iter_mut().for_each(|v| *v += step);
        }
        let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
        assert_eq!(d.verdict, "unexplained", "{}", d.to_text());
        assert!(d.located.as_deref().is_some_and(|w| w.contains("bias step")), "{}", d.to_text());
    }

    #[test]
    fn an_unexplained_gap_on_few_poses_says_which_shapes_could_not_be_tested() {
        use crate::sim::scenario::{SimLog, to_table};
        use crate::sim::{Plan, SimConfig, simulate_with};
        // A 4 mg step of every axis from the middle pose on: out of the catalogue on 12 and 30 poses.
        for (poses, widest) in [(12, Some(2)), (30, None)] {
            let cfg = SimConfig { plan: Plan::Random(poses), ..SimConfig::paper(5) };
            let g = cfg.gravity;
            let mut step = |_t: f64, p: Option<usize>, r: &mut [f64; 3]| {
                if p.is_some_and(|p| p >= poses / 2) {
                    r.iter_mut().for_each(|v| *v += 0.004 * g);
                }
            };
            let recording = simulate_with(&cfg, &mut [&mut step]);
            let temps_c = vec![25.0; recording.samples.len()];
            let table = to_table(&SimLog { recording, temps_c }, "step").unwrap();
            let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
            assert_eq!((d.poses.len(), d.verdict), (poses, "unexplained"), "{}", d.to_text());
            let located = d.located.unwrap_or_default();
            match widest {
                Some(k) => {
                    let note = format!("with {poses} poses no shape of more than {k} parameters could be tested");
                    assert!(located.contains(&note), "{located}");
                }
                None => assert!(!located.contains("could be tested"), "{located}"),
            }
        }
    }

    #[test]
    fn model_inverts() {
        let p = Params { bias: [0.1, -0.2, 0.05], scale: [0.98, 1.01, 1.02], nonorth: [0.01, -0.02, 0.005] };
        let m = Model::from_params(&p);
        let f = [1.0, -9.0, 3.0];
        let back = m.apply(m.invert(f));
        assert!((0..3).all(|a| (back[a] - f[a]).abs() < 1e-12));
    }
}
