//! Blind test of `accelcal diagnose`: for each of the 7 classes (the 6 candidate effects and none),
//! random logs (random seed, truth, units, pose count, durations, noise, effect magnitude; a
//! non-monotonic temperature column in every log) are simulated with the effect injected, diagnosed
//! without being told the effect, and the verdicts are scored. Requires at least
//! [`MIN_ACCURACY`] right verdicts overall and a median shrink of at least [`MIN_MEDIAN_SHRINK`] on
//! the right verdicts of the effect classes.
//!
//! The seeds of every log derive from one documented base seed, [`BASE_SEED`], so CI is
//! deterministic; nothing is tuned to it: set `ACCELCAL_BLIND_SEED` to run with another base seed
//! (several were checked, see `host-tests/FINDINGS.md`) and `ACCELCAL_BLIND_LOGS` for more logs per
//! class. Run with `--nocapture` to see the table.

use accelcal_host::diagnose::{DiagnoseOptions, diagnose};
use accelcal_host::sim::scenario::{EffectClass, generate, random_scenario, to_table};
use accelcal_host::stats::median;

/// Base seed of the logs (override with `ACCELCAL_BLIND_SEED`).
const BASE_SEED: u64 = 20_261_121;

/// Logs per class (override with `ACCELCAL_BLIND_LOGS`).
const LOGS_PER_CLASS: usize = 8;

/// Required fraction of right verdicts over all logs.
const MIN_ACCURACY: f64 = 0.9;

/// Required median shrink over the right verdicts of the effect classes.
const MIN_MEDIAN_SHRINK: f64 = 0.7;

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[test]
fn diagnose_names_the_withheld_effect() {
    let base = env_or("ACCELCAL_BLIND_SEED", BASE_SEED);
    let logs = env_or("ACCELCAL_BLIND_LOGS", LOGS_PER_CLASS);
    println!("blind diagnose test: base seed {base}, {logs} logs per class");
    let (mut right, mut total) = (0usize, 0usize);
    let mut all_shrinks = Vec::new();
    for (c, class) in EffectClass::ALL.into_iter().enumerate() {
        let mut class_right = 0;
        let mut shrinks = Vec::new();
        let mut wrong = Vec::new();
        let mut min_gain = f64::INFINITY;
        for k in 0..logs {
            let seed = base.wrapping_mul(1_000).wrapping_add((c * 100 + k) as u64);
            let scenario = random_scenario(class, seed);
            let log = generate(&scenario);
            let table = to_table(&log, &format!("{}-{seed}", class.name())).expect("simulated CSV reads back");
            let opts = DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
            let report = match diagnose(&table, &opts) {
                Ok(r) => r,
                Err(e) => {
                    wrong.push(format!("seed {seed}: error {e}"));
                    total += 1;
                    continue;
                }
            };
            total += 1;
            if report.verdict == class.name() {
                right += 1;
                class_right += 1;
                if class != EffectClass::None {
                    shrinks.push(report.shrink);
                    let gain = report
                        .candidates
                        .iter()
                        .find(|c| c.effect == report.verdict)
                        .map_or(f64::NAN, |c| c.heldout_gain);
                    min_gain = min_gain.min(gain);
                }
            } else {
                let gains: Vec<String> =
                    report.candidates.iter().map(|c| format!("{}={:.2}", c.effect, c.heldout_gain)).collect();
                wrong.push(format!(
                    "seed {seed}: said {} (ratio {:.1}, z {:.1}; {})",
                    report.verdict,
                    report.gap.ratio_before,
                    report.gap.z,
                    gains.join(" ")
                ));
            }
        }
        all_shrinks.extend(shrinks.iter().copied());
        let fmt = |v: f64| if v.is_finite() { format!("{v:.2}") } else { "-".to_string() };
        println!(
            "{:<19} right {class_right}/{logs}  median shrink {}  smallest winning gain {}",
            class.name(),
            fmt(median(&shrinks)),
            fmt(min_gain)
        );
        for w in wrong {
            println!("    {w}");
        }
    }
    let accuracy = right as f64 / total as f64;
    let shrink = median(&all_shrinks);
    println!("overall: {right}/{total} right ({:.1} %), median shrink {shrink:.2}", 100.0 * accuracy);
    assert!(accuracy >= MIN_ACCURACY, "accuracy {accuracy}");
    assert!(shrink >= MIN_MEDIAN_SHRINK, "median shrink {shrink}");
}
