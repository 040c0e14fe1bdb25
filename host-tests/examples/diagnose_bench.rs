//! Times `accelcal diagnose` on a simulated 50 000-sample log (cube26 plan at 200 Hz with a 70 s
//! first rest, warm-up drift injected, temperature column): CSV parsing and the diagnosis,
//! separately, over a few runs.
//!
//! `cargo run --release -p accelcal-host --example diagnose_bench`

use std::time::Instant;

use accelcal_host::csvio::{ReadOptions, read_csv_str};
use accelcal_host::diagnose::{DiagnoseOptions, diagnose};
use accelcal_host::sim::scenario::{EffectClass, Scenario, generate, random_scenario, to_csv_string};
use accelcal_host::sim::{Plan, SimConfig};

/// Runs timed.
const RUNS: usize = 5;

fn main() {
    let base = random_scenario(EffectClass::Drift, 7);
    let sim = SimConfig {
        plan: Plan::Cube26,
        rate_hz: 200.0,
        seconds_per_pose: 5.0,
        move_seconds: 2.0,
        initial_rest_s: 70.0,
        ..base.sim.clone()
    };
    let scenario = Scenario { sim, ..base };
    let log = generate(&scenario);
    let text = to_csv_string(&log);
    let read = ReadOptions::default();
    let mut parse_s = Vec::new();
    let mut diagnose_s = Vec::new();
    let mut verdict = "";
    for _ in 0..RUNS {
        let start = Instant::now();
        let table = read_csv_str("bench.csv", &text, &read).expect("simulated CSV reads");
        parse_s.push(start.elapsed().as_secs_f64());
        let start = Instant::now();
        let report = diagnose(&table, &DiagnoseOptions::DEFAULT).expect("diagnosis runs");
        diagnose_s.push(start.elapsed().as_secs_f64());
        verdict = report.verdict;
    }
    parse_s.sort_by(f64::total_cmp);
    diagnose_s.sort_by(f64::total_cmp);
    let profile = if cfg!(debug_assertions) { "debug" } else { "release" };
    println!(
        "diagnose bench ({profile}, {} {}): {} samples, verdict {verdict}; median of {RUNS} runs: CSV parse {:.3} s, diagnose {:.3} s (worst {:.3} s)",
        std::env::consts::ARCH,
        std::env::consts::OS,
        log.recording.samples.len(),
        parse_s[RUNS / 2],
        diagnose_s[RUNS / 2],
        diagnose_s[RUNS - 1]
    );
}
