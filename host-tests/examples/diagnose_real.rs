//! Runs `accelcal diagnose` on every real recording in `../shared/data/real` (relative to the
//! workspace root; another folder can be given as the first argument) that has raw samples, and
//! prints the findings as a Markdown table.
//!
//! `cargo run --release -p accelcal-host --example diagnose_real`

use std::path::PathBuf;

use accelcal_host::csvio::{ColumnSpec, ReadOptions, read_csv};
use accelcal_host::diagnose::{DiagnoseOptions, diagnose};

/// `(file under the data folder, column spec or "")`: every raw-sample recording.
const SETS: [(&str, &str); 10] = [
    ("imu_tk_xsens_mti/xsens_acc.csv", ""),
    ("hassan_lis3dh_30pos/MobileAccData30orientationRawSample01.csv", ""),
    ("fastahrs_fxos8700/data_sample.clean.csv", ""),
    ("fastahrs_fxos8700/data_sample2.clean.csv", ""),
    ("imutk_windows_20pos/imu.csv", ""),
    ("ck_explorer_acc_sphere/acc_log.csv", ""),
    ("tomisuarez_mpu6050_10pos/example_data_calibration.plain.csv", ""),
    ("sunsided_mpu6050_temp/set-2__full-sphere.csv", ""),
    ("avrlabs_mpu6050/notebook_26pos_clean.csv", "-,ax_raw,ay_raw,az_raw,temp_C"),
    ("willward_mpu9250/final_trial__six_position_final_test_data.csv", "0,1,2,3"),
];

fn main() {
    let dir = std::env::args()
        .nth(1)
        .map_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/real"), PathBuf::from);
    let options = DiagnoseOptions::DEFAULT;
    println!(
        "| recording | poses | real / simulated RMSE (mg) | gap ratio (z) | where it lies | effect | gain on withheld poses | ratio after | shrink |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let mut drift_shapes = Vec::new();
    for (file, columns) in SETS {
        let path = dir.join(file);
        let read = ReadOptions {
            columns: (!columns.is_empty()).then(|| columns.parse::<ColumnSpec>().expect("valid column spec")),
            ..ReadOptions::default()
        };
        let table = match read_csv(&path, &read) {
            Ok(t) => t,
            Err(e) => {
                println!("| `{file}` | - | - | - | not read: {e} | - | - | - | - |");
                continue;
            }
        };
        match diagnose(&table, &options) {
            Ok(r) => {
                let best =
                    r.candidates.iter().filter(|c| c.applicable).max_by(|a, b| a.evidence().total_cmp(&b.evidence()));
                let effect = if r.explained {
                    format!("**{}**", r.verdict)
                } else if r.gap.significant && r.verdict != "unexplained" {
                    // Named from the holds alone: the pose means do not follow it (no shrink).
                    format!("{} (in the holds: {})", r.verdict, r.located.as_deref().unwrap_or("-"))
                } else if r.gap.significant {
                    format!(
                        "unexplained: {} (best family {})",
                        r.located.as_deref().unwrap_or("-"),
                        best.map_or("-", |c| c.effect)
                    )
                } else {
                    "none (no significant gap)".to_string()
                };
                let gain = best.map_or("-".into(), |c| format!("{:.2} ({})", c.evidence(), c.effect));
                drift_shapes.push((file, curved_vs_exponential(&r)));
                println!(
                    "| `{file}` | {} | {:.3} / {:.3} | {:.2} ({:.0}) | {} | {effect} | {gain} | {:.2} | {:.2} |",
                    r.poses.len(),
                    r.gap.real_rmse_mg,
                    r.gap.sim_rmse_mg,
                    r.gap.ratio_before,
                    r.gap.z,
                    r.where_summary(),
                    r.gap.ratio_after,
                    r.shrink
                );
            }
            Err(e) => {
                let reason = e.to_string();
                let reason = reason.rsplit(": ").next().unwrap_or(&reason).to_string();
                println!("| `{file}` | - | - | - | not diagnosable: {reason} | - | - | - | - |");
            }
        }
    }
    println!(
        "\nseed {}, {} simulated repeats, cross-validation over the poses leaving one out up to {} poses, in {} folds beyond",
        options.seed,
        options.repeats,
        accelcal_host::diagnose::LEAVE_ONE_OUT_UP_TO,
        options.folds
    );
    println!("\ndrift shape on withheld poses (penalised held-out ratio, smaller is better; 1 = explained):\n");
    println!(
        "| recording | best curved bias (polynomial) | best single exponential bias | best scale in time |\n|---|---|---|---|"
    );
    for (file, shapes) in drift_shapes {
        if let Some(((curved, c), (exponential, e), scale)) = shapes {
            let scale = scale.map_or("-".to_string(), |(d, r)| format!("{r:.2} ({d})"));
            println!("| `{file}` | {c:.2} ({curved}) | {e:.2} ({exponential}) | {scale} |");
        }
    }
}

/// A drift variant and its held-out ratio.
type Shape = (String, f64);

/// The drift family's best bias polynomial and best single-exponential bias variants, and its best
/// scale changing with time (per axis or common; none when a thermometer moved a kelvin).
fn curved_vs_exponential(r: &accelcal_host::diagnose::Diagnosis) -> Option<(Shape, Shape, Option<Shape>)> {
    let drift = r.candidates.iter().find(|c| c.effect == "drift")?;
    let best = |pattern: &str| {
        drift.variants.iter().filter(|(d, _)| d.starts_with(pattern)).min_by(|a, b| a.1.total_cmp(&b.1)).cloned()
    };
    Some((best("bias polynomial")?, best("bias (1 - exp")?, best("scale")))
}
