//! Effects outside the catalogue (a bad pose, cross-axis coupling, hysteresis, a slow periodic
//! bias) must not be given a catalogue name: the diagnosis answers `none` or `unexplained`.
//! Requires at least [`MIN_HONEST`] of the logs answered so (the periodic bias is a known miss,
//! its test ignored with the reason). `ACCELCAL_OUTSIDE_LOGS` sets the logs
//! per kind; run with `--nocapture` for the table.

use accelcal_host::diagnose::{DiagnoseOptions, diagnose};
use accelcal_host::sim::scenario::{Outside, generate_outside, to_table};

/// Base seed of the logs.
const BASE_SEED: u64 = 40_261_123;

/// Logs per kind (override with `ACCELCAL_OUTSIDE_LOGS`).
const LOGS_PER_KIND: usize = 4;

/// Required fraction answered `none` or `unexplained`.
const MIN_HONEST: f64 = 0.9;

#[test]
fn out_of_catalogue_effects_are_not_given_a_catalogue_name() {
    check_kinds(&[Outside::OneBadPose, Outside::CrossAxis, Outside::Hysteresis]);
}

#[test]
#[ignore = "known miss: a periodic bias with a period near the length of the longest rest is taken for colored noise"]
fn a_periodic_bias_is_not_given_a_catalogue_name() {
    check_kinds(&[Outside::PeriodicBias]);
}

fn check_kinds(kinds: &[Outside]) {
    let logs = std::env::var("ACCELCAL_OUTSIDE_LOGS").ok().and_then(|v| v.parse().ok()).unwrap_or(LOGS_PER_KIND);
    let (mut honest, mut total) = (0usize, 0usize);
    for &kind in kinds {
        let k = Outside::ALL.iter().position(|o| *o == kind).unwrap_or(0);
        let mut answers = Vec::new();
        for i in 0..logs {
            let seed = BASE_SEED + (k * 100 + i) as u64;
            let table = to_table(&generate_outside(kind, seed), kind.name()).expect("simulated CSV reads back");
            let report = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT })
                .unwrap_or_else(|e| panic!("{} seed {seed}: {e}", kind.name()));
            total += 1;
            if matches!(report.verdict, "none" | "unexplained") {
                honest += 1;
            }
            let best = |v: Vec<f64>| v.into_iter().fold(f64::NEG_INFINITY, f64::max);
            let family_gain = best(report.candidates.iter().map(|c| c.heldout_gain).collect());
            let probe_gain = best(report.probes.iter().map(|p| p.heldout_gain).collect());
            answers.push(format!(
                "{} (ratio {:.1}, gains: family {family_gain:.2}, probe {probe_gain:.2})",
                report.verdict, report.gap.ratio_before
            ));
            if let Some(w) = &report.located {
                println!("    {} seed {seed}: {}, {w}", kind.name(), report.verdict);
            }
        }
        println!("{:<14} {}", kind.name(), answers.join(", "));
    }
    let share = honest as f64 / total as f64;
    println!("none/unexplained: {honest}/{total}");
    assert!(share >= MIN_HONEST, "only {honest}/{total} out-of-catalogue logs answered none/unexplained");
}
