//! `accelcal diagnose` from the command line: a simulated log with a temperature column is
//! diagnosed (exit 0, JSON with the documented fields, SVG plots); bad input exits with 2.
//! Files are written under Cargo's target temporary directory, never into the source tree.

use std::path::PathBuf;
use std::process::Command;

use accelcal_host::sim::scenario::{EffectClass, generate, random_scenario, to_csv_string};

fn scratch(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("diagnose_cli");
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

#[test]
fn diagnose_reports_json_and_plots_and_exits_0() {
    let csv = scratch("temperature.csv");
    let log = generate(&random_scenario(EffectClass::Temperature, 42));
    std::fs::write(&csv, to_csv_string(&log)).unwrap();
    let plots = scratch("plots");
    let out = Command::new(env!("CARGO_BIN_EXE_accelcal"))
        .arg("diagnose")
        .arg(&csv)
        .args(["--json", "--seed", "3", "--plots"])
        .arg(&plots)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let json: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(json["poses"].as_u64().unwrap() >= 12);
    for key in ["real_rmse_mg", "sim_rmse_mg", "ratio_before", "ratio_after"] {
        assert!(json["gap"][key].is_number(), "{key}");
    }
    assert!(json["where"]["temperature"].is_object());
    for c in json["candidates"].as_array().unwrap() {
        assert!(c["effect"].is_string() && c["heldout_gain"].is_number() && c["ratio_after"].is_number());
    }
    assert_eq!(json["verdict"]["effect"], "temperature");
    assert!(json["verdict"]["shrink"].as_f64().unwrap() > 0.5);
    for svg in ["residual_per_pose.svg", "residual_vs_time.svg", "residual_vs_temperature.svg", "allan_deviation.svg"] {
        assert!(plots.join(svg).is_file(), "{svg}");
    }
}

#[test]
fn diagnose_bad_input_exits_2() {
    let csv = scratch("still.csv");
    let text: String = std::iter::once("t,ax,ay,az\n".to_string())
        .chain((0..3000).map(|i| format!("{:.3},0.01,0.02,0.99\n", f64::from(i) * 0.01)))
        .collect();
    std::fs::write(&csv, text).unwrap();
    for extra in [&[][..], &["--means"][..]] {
        let out = Command::new(env!("CARGO_BIN_EXE_accelcal")).arg("diagnose").arg(&csv).args(extra).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{extra:?}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("error"));
    }
}
