//! Feature `serde`: the result types serialise (here to JSON) with the values they hold.

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, calibrate};
use accelcal::model::Params;
use accelcal::seeded_rng;

/// 26 cube directions read by a sensor with a known truth.
fn poses(truth: &Params) -> Vec<Pose> {
    let g = 9.80665f32;
    let mut out = Vec::new();
    for x in -1i32..=1 {
        for y in -1i32..=1 {
            for z in -1i32..=1 {
                if (x, y, z) == (0, 0, 0) {
                    continue;
                }
                let n = ((x * x + y * y + z * z) as f32).sqrt();
                let f_b = [x as f32 * g / n, y as f32 * g / n, z as f32 * g / n];
                out.push(Pose::from_mean(truth.invert(f_b).expect("invertible truth"), 500));
            }
        }
    }
    out
}

#[test]
fn a_calibration_serialises_with_its_values() {
    let truth = Params { bias: [0.1, -0.2, 0.05], scale: [1.01, 0.99, 1.02], nonorth: [0.01, -0.005, 0.002] };
    let poses = poses(&truth);
    let cal = calibrate::<_, 24, 32>(&poses, &CalibrationConfig::DEFAULT, seeded_rng(1)).expect("calibrates");
    let params: serde_json::Value = serde_json::to_value(cal.params).unwrap();
    for (k, v) in [("bias", cal.params.bias), ("scale", cal.params.scale), ("nonorth", cal.params.nonorth)] {
        let got: Vec<f32> = params[k].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        assert_eq!(got, v, "{k}");
    }
    let verdict: serde_json::Value = serde_json::to_value(cal.verdict).unwrap();
    assert_eq!(verdict["param_std"].as_array().unwrap().len(), 9);
    assert!(verdict["failures"]["undetermined"].is_array());
    assert_eq!(verdict["warnings"]["excluded"], serde_json::json!([]), "a pose list is its indices");
    let pose: serde_json::Value = serde_json::to_value(poses[0]).unwrap();
    assert_eq!(pose["n"], 500);
}
