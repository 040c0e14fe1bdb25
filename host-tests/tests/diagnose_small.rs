//! `diagnose` answers every log `calibrate` accepts: a free-hand log of only ten poses (too few to
//! withhold any for the catalogue) gets its gap measured and a verdict, not a refusal.

use accelcal_host::csvio::{self, ReadOptions};
use accelcal_host::diagnose::{DiagnoseOptions, diagnose};
use accelcal_host::sim::{self, Plan, SimConfig};

#[test]
fn a_ten_pose_free_hand_log_is_answered() {
    for seed in [2, 5] {
        let cfg = SimConfig { truth: sim::random_truth(seed), ..SimConfig::for_plan(Plan::FreeHand(10), seed) };
        let mut text = Vec::new();
        sim::write_csv(&sim::simulate(&cfg), &mut text).unwrap();
        let table = csvio::read_csv_bytes("ten poses", &text, &ReadOptions::default()).unwrap();
        let report = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap_or_else(|e| panic!("seed {seed}: {e}"));
        assert_eq!(report.poses.len(), 10, "seed {seed}");
        assert!(report.gap.ratio_before.is_finite(), "seed {seed}: {:?}", report.gap);
        // A clean simulated log: no significant gap, so `none`.
        assert_eq!(report.verdict, "none", "seed {seed}: {:?}", report.gap);
        assert!(report.candidates.is_empty(), "no catalogue candidate can be tested on ten poses");
    }
}
