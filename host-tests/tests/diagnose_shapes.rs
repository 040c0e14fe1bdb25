//! Other shapes of the catalogue's effects than the blind test's (a two-stage warm-up, a curved
//! drift, temperature through a lag, a cubic non-linearity): the diagnosis must still name the
//! family on at least [`MIN_RIGHT`] of the logs. `ACCELCAL_SHAPES_LOGS` sets the logs per shape;
//! run with `--nocapture` for the table.

use accelcal_host::diagnose::{DiagnoseOptions, diagnose};
use accelcal_host::sim::scenario::{Shape, generate_shape, to_table};

/// Base seed of the logs.
const BASE_SEED: u64 = 50_261_123;

/// Logs per shape (override with `ACCELCAL_SHAPES_LOGS`).
const LOGS_PER_SHAPE: usize = 4;

/// Required fraction of right families.
const MIN_RIGHT: f64 = 0.9;

#[test]
fn other_shapes_are_given_their_family() {
    let logs = std::env::var("ACCELCAL_SHAPES_LOGS").ok().and_then(|v| v.parse().ok()).unwrap_or(LOGS_PER_SHAPE);
    let (mut right, mut total) = (0usize, 0usize);
    for (k, shape) in Shape::ALL.into_iter().enumerate() {
        let mut answers = Vec::new();
        for i in 0..logs {
            let seed = BASE_SEED + (k * 100 + i) as u64;
            let table = to_table(&generate_shape(shape, seed), shape.name()).expect("simulated CSV reads back");
            let report = diagnose(&table, &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT })
                .unwrap_or_else(|e| panic!("{} seed {seed}: {e}", shape.name()));
            total += 1;
            right += usize::from(report.verdict == shape.family().name());
            let detail =
                report.candidates.iter().find(|c| c.effect == report.verdict).map_or("", |c| c.detail.as_str());
            answers.push(format!("{} [{detail}] (ratio {:.1})", report.verdict, report.gap.ratio_before));
        }
        println!("{:<19} {}", shape.name(), answers.join("; "));
    }
    println!("right: {right}/{total}");
    assert!(right as f64 >= MIN_RIGHT * total as f64, "only {right}/{total} right");
}
