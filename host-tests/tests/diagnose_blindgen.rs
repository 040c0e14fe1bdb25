//! The blind test on the independent generator (`accelcal_host::blindgen`, written without sight
//! of the detectors): 8 logs per family (64 logs, random orientations, every shape, magnitudes
//! from barely visible to obvious) from a seed range the detectors were not tuned on.
//!
//! Asserted at the goals: false alarms on clean logs <= 5 %, out-of-catalogue logs answered
//! `none` or `unexplained` >= 90 %, no log refused that `calibrate` accepts, median shrink when
//! right >= 0.7. The share right where the effect is clearly visible is asserted as a regression
//! floor (measured 24/30 = 80 % on these seeds; the goal of 90 % is not met yet).
//! `cargo run --release -p accelcal-host --example blind_eval -- --per-family 8 --first-seed 500`
//! prints the same figures with the per-family table.

use accelcal_host::blind_eval::{self, Outcome};
use accelcal_host::blindgen::{self, Family};

/// First seed of the range (log i of family k: FIRST_SEED + 1000 k + i, as the example).
const FIRST_SEED: u64 = 500;

/// Logs per family.
const PER_FAMILY: u64 = 8;

/// Regression floor of the share right where the effect is clearly visible (goal 0.9).
const VISIBLE_FLOOR: f64 = 0.7;

#[test]
fn the_diagnosis_holds_on_logs_it_has_never_seen() {
    let mut outcomes: Vec<Outcome> = Vec::new();
    for (k, family) in Family::ALL.iter().enumerate() {
        for i in 0..PER_FAMILY {
            let spec = blindgen::random_spec(*family, FIRST_SEED + 1000 * k as u64 + i);
            outcomes.push(blind_eval::evaluate(&spec));
        }
    }
    println!("{}", blind_eval::table(&blind_eval::summarize(&outcomes)));
    let all = blind_eval::overall(&outcomes);
    println!("{}", all.to_text());
    println!("{}", blind_eval::by_poses_text(&outcomes));
    assert!(all.clean.0 >= PER_FAMILY as usize && all.clean.1 * 20 <= all.clean.0, "false alarms: {all:?}");
    assert!(all.outside.1 * 10 >= all.outside.0 * 9, "out-of-catalogue logs given a catalogue name: {all:?}");
    assert_eq!(all.wrongly_refused, 0, "a log calibrate accepts was refused");
    assert!(all.median_shrink >= 0.7, "median shrink {}", all.median_shrink);
    assert!(all.visible.0 >= 20, "too few clearly visible logs to judge: {all:?}");
    let share = all.visible.1 as f64 / all.visible.0 as f64;
    assert!(share >= VISIBLE_FLOOR, "right where clearly visible {share:.2} < {VISIBLE_FLOOR}: {all:?}");
}
