//! The QEMU example's simulated calibration, run on the host: the same generator and pipeline
//! (`examples/common/`), the same seeds, so its report must equal the one `examples/qemu_calibrate.rs`
//! prints over semihosting line for line (`.ci/qemu.sh` compares the two).
//!
//! The report is written to `$QEMU_PARITY_OUT` when set, else to `qemu_parity.txt` in Cargo's
//! per-target temporary directory (under `target/`).

#[path = "../examples/common/guided.rs"]
mod guided;
#[path = "../examples/common/pipeline.rs"]
mod pipeline;
#[path = "../examples/common/sim_sensor.rs"]
mod sim_sensor;

use std::fmt::Write as _;

#[test]
fn simulated_24_position_calibration_recovers_the_truth() {
    let mut report = String::new();
    let mut pass = pipeline::run(&mut |line| {
        let _ = writeln!(report, "{line}");
    });
    pass &= guided::run(&mut |line| {
        let _ = writeln!(report, "{line}");
    });
    print!("{report}");
    let path = std::env::var_os("QEMU_PARITY_OUT")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join("qemu_parity.txt"));
    std::fs::write(&path, &report).unwrap();
    println!("report written to {}", path.display());
    assert!(pass, "the simulated calibration failed:\n{report}");
    assert!(report.contains("poses: 24 captured"), "{report}");
    assert!(report.contains("guided: result PASS"), "{report}");
}

#[test]
fn the_stream_has_the_documented_length_and_stays_in_range() {
    use accelcal::sensor::AccelSensor;
    let mut sensor = sim_sensor::SimSensor::new(pipeline::SIM_SEED);
    let mut n = 0;
    let mut largest = 0i16;
    while let Ok(s) = sensor.read_raw() {
        n += 1;
        largest = largest.max(s.iter().map(|v| v.saturating_abs()).max().unwrap());
    }
    assert_eq!(n, sim_sensor::TOTAL_SAMPLES);
    // Well inside +-2 g: nothing is clipped.
    assert!(largest < 30_000, "{largest}");
    // The 24 positions are distinct directions (the turns are told apart by the tilt and set-down errors).
    let p = sim_sensor::positions();
    for i in 0..p.len() {
        for j in 0..i {
            let d: f32 = (0..3).map(|a| (p[i][a] - p[j][a]).powi(2)).sum::<f32>().sqrt();
            assert!(d > 0.1, "positions {i} and {j} coincide");
        }
    }
}
