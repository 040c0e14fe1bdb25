//! The blind test of the diagnosis: logs from the independent generator ([`crate::blindgen`], written
//! without sight of the detectors) are written as CSV, read back and diagnosed; each answer is scored
//! against the family the generator injected.
//!
//! Scoring: a catalogue family must be named (its verdict name, [`expected_verdict`]); a clean log
//! must be `none`; an out-of-catalogue effect must be `none` or `unexplained`. A log's *visibility* is
//! the gap ratio the diagnosis measures with the nominal model (real / simulated modulus RMSE): below
//! about 1.5 an effect hides in the noise, above 2 it is clearly visible.

use std::time::Instant;

use crate::blindgen::{self, Family, LogSpec};
use crate::csvio::{ReadOptions, read_csv_str};
use crate::diagnose::{DiagnoseOptions, diagnose};
use crate::stats::median;

/// Gap ratio from which an effect counts as clearly visible.
pub const CLEARLY_VISIBLE: f64 = 2.0;

/// Visibility thresholds at which the share of right answers is tabulated.
pub const VISIBILITY_LADDER: [f64; 8] = [1.0, 1.25, 1.5, 2.0, 3.0, 5.0, 10.0, 30.0];

/// What the diagnosis should answer for a family.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expected {
    /// `none` (a clean log).
    Nothing,
    /// This catalogue verdict.
    Named(&'static str),
    /// `none` or `unexplained` (an effect outside the catalogue).
    Honest,
}

/// The expected answer for a generator family (by its manifest name).
pub fn expected_verdict(family: Family) -> Expected {
    match family.name() {
        "clean" => Expected::Nothing,
        "drift" => Expected::Named("drift"),
        "temperature" => Expected::Named("temperature"),
        "nonlinearity" => Expected::Named("scale-nonlinearity"),
        "settling" => Expected::Named("settling"),
        "motion" => Expected::Named("motion"),
        "colored_noise" => Expected::Named("colored-noise"),
        _ => Expected::Honest,
    }
}

/// One diagnosed log.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Generator family and shape.
    pub family: Family,
    /// Shape within the family.
    pub shape: String,
    /// Generator seed.
    pub seed: u64,
    /// The effect's magnitude (generator units), 0 for none.
    pub magnitude: f64,
    /// Gap ratio before (the visibility); NaN when refused.
    pub visibility: f64,
    /// The verdict, or `refused: <error>`.
    pub verdict: String,
    /// The answer is the expected one.
    pub right: bool,
    /// Share of the gap the diagnosis removes (1 - ratio after / ratio before, as the report gives it).
    pub shrink: f64,
    /// Samples in the log.
    pub samples: usize,
    /// Seconds the diagnosis took (reading excluded).
    pub seconds: f64,
    /// For a refused log: `calibrate` accepts it (its poses calibrate), which a refusal must not be.
    pub calibrate_accepts: bool,
    /// Poses the diagnosis found (`None` when refused).
    pub poses: Option<usize>,
}

impl Outcome {
    /// The effect is clearly visible (gap ratio >= [`CLEARLY_VISIBLE`]).
    pub fn visible(&self) -> bool {
        self.visibility >= CLEARLY_VISIBLE
    }

    /// A catalogue family's effect, clearly visible: what "right where clearly visible" counts.
    pub fn visible_catalogue_effect(&self) -> bool {
        matches!(expected_verdict(self.family), Expected::Named(_)) && self.visible()
    }
}

/// Generates, writes, reads back and diagnoses the log of `spec`.
pub fn evaluate(spec: &LogSpec) -> Outcome {
    let log = blindgen::generate(spec);
    let name = format!("{}-{}-{}.csv", spec.family.name(), spec.shape, spec.seed);
    let magnitude = spec.effect.as_ref().map_or(0.0, |e| e.model().magnitude().value);
    let mut outcome = Outcome {
        family: spec.family,
        shape: spec.shape.clone(),
        seed: spec.seed,
        magnitude,
        visibility: f64::NAN,
        verdict: String::new(),
        right: false,
        shrink: f64::NAN,
        samples: log.samples.len(),
        seconds: 0.0,
        calibrate_accepts: false,
        poses: None,
    };
    let table = match read_csv_str(&name, &log.to_csv_string(), &ReadOptions::default()) {
        Ok(t) => t,
        Err(e) => {
            outcome.verdict = format!("refused: {e}");
            return outcome;
        }
    };
    let started = Instant::now();
    let result = diagnose(&table, &DiagnoseOptions { seed: spec.seed, ..DiagnoseOptions::DEFAULT });
    outcome.seconds = started.elapsed().as_secs_f64();
    match result {
        Ok(d) => {
            outcome.visibility = d.gap.ratio_before;
            outcome.verdict = d.verdict.to_string();
            outcome.shrink = d.shrink;
            outcome.right = is_right(expected_verdict(spec.family), d.verdict);
            outcome.poses = Some(d.poses.len());
        }
        Err(e) => {
            outcome.verdict = format!("refused: {}", e.0);
            outcome.calibrate_accepts = calibrate_accepts(&table, spec.seed);
        }
    }
    outcome
}

/// `calibrate`'s path (the reader's poses, the library's calibration) succeeds on `table`.
fn calibrate_accepts(table: &crate::csvio::Table, seed: u64) -> bool {
    let opts = crate::csvio::AccumulateOptions::default();
    let config = accelcal::calibrate::CalibrationConfig::DEFAULT;
    let enough = |poses: &[accelcal::accumulator::Pose]| crate::calib::enough_poses(poses, &config);
    let Ok(acc) = crate::csvio::accumulate_until(table, &opts, enough) else { return false };
    acc.poses.len() >= crate::calib::MIN_POSES && crate::calib::run(&acc.poses, &config, seed).is_ok()
}

/// `verdict` is the answer `expected` asks for.
pub fn is_right(expected: Expected, verdict: &str) -> bool {
    match expected {
        Expected::Nothing => verdict == "none",
        Expected::Named(name) => verdict == name,
        Expected::Honest => matches!(verdict, "none" | "unexplained"),
    }
}

/// Per-family figures of a set of outcomes.
#[derive(Debug, Clone, PartialEq)]
pub struct FamilySummary {
    /// The family.
    pub family: Family,
    /// Logs.
    pub logs: usize,
    /// Right answers among all logs.
    pub right: usize,
    /// Logs clearly visible, and right among them.
    pub visible: (usize, usize),
    /// Refused logs, and among them logs `calibrate` accepts.
    pub refused: (usize, usize),
    /// Smallest ladder visibility from which >= 80 % of the logs at or above it are right (with at
    /// least 3 logs there); `None` if none.
    pub visibility_80: Option<f64>,
    /// Median shrink of the right, visible answers.
    pub median_shrink: f64,
    /// Answers given, with counts.
    pub answers: Vec<(String, usize)>,
}

/// Summaries per family, in the order of first appearance.
pub fn summarize(outcomes: &[Outcome]) -> Vec<FamilySummary> {
    let mut families: Vec<Family> = Vec::new();
    for o in outcomes {
        if !families.contains(&o.family) {
            families.push(o.family);
        }
    }
    families.into_iter().map(|f| summarize_family(f, outcomes)).collect()
}

fn summarize_family(family: Family, outcomes: &[Outcome]) -> FamilySummary {
    let mine: Vec<&Outcome> = outcomes.iter().filter(|o| o.family == family).collect();
    let visible: Vec<&&Outcome> = mine.iter().filter(|o| o.visible()).collect();
    let shrinks: Vec<f64> = visible.iter().filter(|o| o.right).map(|o| o.shrink).collect();
    let mut answers: Vec<(String, usize)> = Vec::new();
    for o in &mine {
        let key = if o.verdict.starts_with("refused") { "refused".to_string() } else { o.verdict.clone() };
        match answers.iter_mut().find(|(a, _)| *a == key) {
            Some((_, n)) => *n += 1,
            None => answers.push((key, 1)),
        }
    }
    answers.sort_by_key(|a| std::cmp::Reverse(a.1));
    FamilySummary {
        family,
        logs: mine.len(),
        right: mine.iter().filter(|o| o.right).count(),
        visible: (visible.len(), visible.iter().filter(|o| o.right).count()),
        refused: (
            mine.iter().filter(|o| o.verdict.starts_with("refused")).count(),
            mine.iter().filter(|o| o.calibrate_accepts).count(),
        ),
        visibility_80: visibility_80(&mine),
        median_shrink: median(&shrinks),
        answers,
    }
}

/// The smallest ladder visibility from which >= 80 % of the logs at or above it are right.
fn visibility_80(outcomes: &[&Outcome]) -> Option<f64> {
    VISIBILITY_LADDER.into_iter().find(|&v| {
        let above: Vec<&&Outcome> = outcomes.iter().filter(|o| o.visibility >= v).collect();
        above.len() >= 3 && above.iter().filter(|o| o.right).count() * 5 >= above.len() * 4
    })
}

/// The markdown table of the summaries.
pub fn table(summaries: &[FamilySummary]) -> String {
    let mut out = String::from(
        "| family | logs | right | right where visible (ratio >= 2) | visibility for 80 % right | median shrink | refused (calibrate accepts) | answers |\n|---|---:|---:|---:|---:|---:|---:|---|\n",
    );
    for s in summaries {
        let v80 = s.visibility_80.map_or("never".to_string(), |v| format!(">= {v}"));
        let answers: Vec<String> = s.answers.iter().map(|(a, n)| format!("{a} {n}")).collect();
        out += &format!(
            "| {} | {} | {} | {}/{} | {} | {:.2} | {} ({}) | {} |\n",
            s.family.name(),
            s.logs,
            s.right,
            s.visible.1,
            s.visible.0,
            v80,
            s.median_shrink,
            s.refused.0,
            s.refused.1,
            answers.join(", ")
        );
    }
    out
}

/// Bins of the poses the diagnosis found, first and last in each (`None`: no last): a 9-parameter
/// calibration leaves 12 poses 3 degrees of freedom, so the catalogue's terms per axis (3-6
/// parameters) cannot all be tested on withheld poses of the first bins (as the Python sets'
/// `score.py --by-poses`).
pub const POSE_BINS: [(usize, Option<usize>); 4] = [(6, Some(13)), (14, Some(16)), (17, Some(24)), (25, None)];

/// Catalogue-family logs clearly visible, and right among them, per [`POSE_BINS`] bin (refused logs
/// found no poses and are in none).
pub fn visible_by_poses(outcomes: &[Outcome]) -> [(usize, usize); POSE_BINS.len()] {
    std::array::from_fn(|b| {
        let (first, last) = POSE_BINS[b];
        let inside = |o: &&Outcome| o.poses.is_some_and(|n| n >= first && last.is_none_or(|l| n <= l));
        let bin: Vec<&Outcome> = outcomes.iter().filter(|o| o.visible_catalogue_effect()).filter(inside).collect();
        (bin.len(), bin.iter().filter(|o| o.right).count())
    })
}

/// [`visible_by_poses`] as one line.
pub fn by_poses_text(outcomes: &[Outcome]) -> String {
    let bins: Vec<String> = POSE_BINS
        .iter()
        .zip(visible_by_poses(outcomes))
        .map(|((first, last), (n, right))| match last {
            Some(last) => format!("{first}-{last} poses {right}/{n}"),
            None => format!("{first}+ poses {right}/{n}"),
        })
        .collect();
    format!("right where clearly visible, by poses found: {}\n", bins.join(", "))
}

/// The figures the targets are stated in, over every family.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Overall {
    /// Catalogue-family logs clearly visible, and right among them.
    pub visible: (usize, usize),
    /// Clean logs, and those given an effect (false alarms).
    pub clean: (usize, usize),
    /// Out-of-catalogue logs, and those answered `none` or `unexplained`.
    pub outside: (usize, usize),
    /// Logs refused although `calibrate` accepts them.
    pub wrongly_refused: usize,
    /// Median shrink of the right, visible catalogue answers.
    pub median_shrink: f64,
}

/// [`Overall`] of a set of outcomes.
pub fn overall(outcomes: &[Outcome]) -> Overall {
    let visible: Vec<&Outcome> = outcomes.iter().filter(|o| o.visible_catalogue_effect()).collect();
    let count = |e: Expected| outcomes.iter().filter(|o| expected_verdict(o.family) == e).count();
    let right = |e: Expected| outcomes.iter().filter(|o| expected_verdict(o.family) == e && o.right).count();
    let shrinks: Vec<f64> = visible.iter().filter(|o| o.right).map(|o| o.shrink).collect();
    Overall {
        visible: (visible.len(), visible.iter().filter(|o| o.right).count()),
        clean: (count(Expected::Nothing), count(Expected::Nothing) - right(Expected::Nothing)),
        outside: (count(Expected::Honest), right(Expected::Honest)),
        wrongly_refused: outcomes.iter().filter(|o| o.calibrate_accepts).count(),
        median_shrink: median(&shrinks),
    }
}

impl Overall {
    /// One line per target, with the goal beside the figure.
    pub fn to_text(&self) -> String {
        let pct = |a: usize, b: usize| if b == 0 { f64::NAN } else { 100.0 * a as f64 / b as f64 };
        format!(
            "right where clearly visible: {}/{} ({:.0} %, goal >= 90 %)\n\
             false alarms on clean logs: {}/{} ({:.0} %, goal <= 5 %)\n\
             out-of-catalogue answered none/unexplained: {}/{} ({:.0} %, goal >= 90 %)\n\
             refused although calibrate accepts: {} (goal 0)\n\
             median shrink when right: {:.2} (goal >= 0.7)\n",
            self.visible.1,
            self.visible.0,
            pct(self.visible.1, self.visible.0),
            self.clean.1,
            self.clean.0,
            pct(self.clean.1, self.clean.0),
            self.outside.1,
            self.outside.0,
            pct(self.outside.1, self.outside.0),
            self.wrongly_refused,
            self.median_shrink
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A drift or clean log's outcome on `poses` poses (none: refused) at `visibility`.
    fn outcome(family: Family, poses: Option<usize>, visibility: f64, right: bool) -> Outcome {
        Outcome {
            family,
            shape: String::new(),
            seed: 0,
            magnitude: 1.0,
            visibility,
            verdict: String::new(),
            right,
            shrink: 1.0,
            samples: 0,
            seconds: 0.0,
            calibrate_accepts: false,
            poses,
        }
    }

    #[test]
    fn visible_catalogue_logs_are_binned_by_the_poses_found_at_the_bins_edges() {
        let d = Family::Drift;
        let outcomes = [
            outcome(d, Some(13), 3.0, false),
            outcome(d, Some(14), 3.0, true),
            outcome(d, Some(16), 3.0, false),
            outcome(d, Some(24), 2.0, true),
            outcome(d, Some(25), 9.0, true),
            // Not counted: not clearly visible, a clean log, a refused log.
            outcome(d, Some(30), 1.9, false),
            outcome(Family::Clean, Some(30), 5.0, false),
            outcome(d, None, f64::NAN, false),
        ];
        assert_eq!(visible_by_poses(&outcomes), [(1, 0), (2, 1), (1, 1), (1, 1)]);
        assert_eq!(
            by_poses_text(&outcomes),
            "right where clearly visible, by poses found: 6-13 poses 0/1, 14-16 poses 1/2, 17-24 poses 1/1, 25+ poses 1/1\n"
        );
    }
}
