//! Calibration of the real recordings in `../shared/data/real` (relative to the workspace root).
//!
//! Each test reads one recording with [`accelcal_host::csvio`], gets its poses (the library's static
//! detector on raw samples, or one pose per row of a means file), runs the library's TAGA+LM
//! calibration and checks:
//! - (a) enough poses were found (at least 9, and about as many as the folder's README counts);
//! - (b) the modulus RMSE after calibration is below the RMSE before;
//! - (c) the library's objective is within 0.1 % of the least-squares optimum found by an independent
//!   reference written here: a plain `f64` Levenberg-Marquardt on the paper's objective
//!   `fE = mean((|Ka f_s - B|^2 - g^2)^2)` in the paper's parametrisation, started both from the
//!   library's result and from a six-position-style estimate computed here.
//!
//! Gravity: data in g are calibrated against `g = 1` (output in g), data in m/s^2 and raw counts
//! against 9.80665 (output in m/s^2); see [`Units::calibration_gravity`]. The "before" RMSE uses no
//! correction for data in g or m/s^2 and the coarse calibration for counts.
//!
//! The data are not part of the repository: when the folder is absent every test prints a message
//! and passes. Run with `cargo test -p accelcal-host --release --test real_data -- --nocapture` to
//! see the table.

use std::path::{Path, PathBuf};

use accelcal::accumulator::Pose;
use accelcal::calibrate::{Calibration, CalibrationConfig, calibrate};
use accelcal::model::{PARAM_COUNT, Params};
use accelcal_host::csvio::{
    AccumulateOptions, Accumulation, ColumnSpec, ReadOptions, Table, Units, accumulate, read_csv, to_poses_from_means,
};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

/// Largest relative excess of the library's objective over the reference optimum.
const OBJECTIVE_TOLERANCE_REL: f64 = 1e-3;

/// Per-pose modulus error `E = |f_b|^2 - g^2`, relative to `g^2`, that the library's `f32` arithmetic
/// cannot resolve. Only matters when the optimum is (nearly) zero, i.e. exactly 9 poses for 9
/// parameters; real residuals are >= 1e-5 g^2 (0.005 mg).
const F32_ERROR_FLOOR_REL: f64 = 1e-6;

/// The objective comparison tolerance: 0.1 % of the optimum, plus the `f32` floor `(1e-6 g^2)^2`.
fn objective_tolerance(reference_objective: f64, g: f64) -> f64 {
    OBJECTIVE_TOLERANCE_REL * reference_objective + (F32_ERROR_FLOOR_REL * g * g).powi(2)
}

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/real")
}

/// The recording. Fails (never passes unchecked) when the data folder or the file is absent.
fn data_file(relative: &str) -> PathBuf {
    let dir = data_dir();
    assert!(
        dir.is_dir(),
        "the real recordings are missing: {} is not a folder. These tests need the workplace's shared/ folder \
         beside the repository (../shared/data/real, see the README)",
        dir.display()
    );
    let path = dir.join(relative);
    assert!(path.is_file(), "{} is missing from the data folder", path.display());
    path
}

// ---------------------------------------------------------------------------------------------
// Independent f64 reference: Levenberg-Marquardt on the paper's objective, paper parametrisation.
// ---------------------------------------------------------------------------------------------

/// `[Bx, By, Bz, Sxx, Syy, Szz, Mxx, Myy, Mzz]` (the order of [`Params::to_array`]).
type P64 = [f64; PARAM_COUNT];

/// `f_b = Ka f_s - B` with `Ka = [[Sxx, 0, 0], [Mxx, Syy, 0], [Myy, Mzz, Szz]]`.
fn apply64(p: &P64, f: &[f64; 3]) -> [f64; 3] {
    [p[3] * f[0] - p[0], p[6] * f[0] + p[4] * f[1] - p[1], p[7] * f[0] + p[8] * f[1] + p[5] * f[2] - p[2]]
}

/// `E = |f_b|^2 - g^2` per pose.
fn residuals64(p: &P64, means: &[[f64; 3]], g: f64) -> Vec<f64> {
    means
        .iter()
        .map(|f| {
            let b = apply64(p, f);
            b[0] * b[0] + b[1] * b[1] + b[2] * b[2] - g * g
        })
        .collect()
}

/// The paper's objective `fE = mean(E^2)`, output unit to the fourth.
fn objective64(p: &P64, means: &[[f64; 3]], g: f64) -> f64 {
    let r = residuals64(p, means, g);
    r.iter().map(|e| e * e).sum::<f64>() / r.len() as f64
}

/// Modulus RMSE `sqrt(mean((|f_b| - g)^2))` in milli-g.
fn rmse64_mg(p: &P64, means: &[[f64; 3]], g: f64) -> f64 {
    let sum: f64 = means
        .iter()
        .map(|f| {
            let b = apply64(p, f);
            let m = (b[0] * b[0] + b[1] * b[1] + b[2] * b[2]).sqrt();
            (m - g) * (m - g)
        })
        .sum();
    (sum / means.len() as f64).sqrt() / g * 1000.0
}

/// `dE/dp` for one pose.
fn gradient64(p: &P64, f: &[f64; 3]) -> P64 {
    let b = apply64(p, f);
    [
        -2.0 * b[0],
        -2.0 * b[1],
        -2.0 * b[2],
        2.0 * b[0] * f[0],
        2.0 * b[1] * f[1],
        2.0 * b[2] * f[2],
        2.0 * b[1] * f[0],
        2.0 * b[2] * f[0],
        2.0 * b[2] * f[1],
    ]
}

/// Solves `a x = b` by Gaussian elimination with partial pivoting; `None` if singular.
fn solve64(mut a: [[f64; PARAM_COUNT]; PARAM_COUNT], mut b: P64) -> Option<P64> {
    const N: usize = PARAM_COUNT;
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[pivot][col].abs() < 1e-300 || !a[pivot][col].is_finite() {
            return None;
        }
        a.swap(col, pivot);
        b.swap(col, pivot);
        let pivot_row = a[col];
        for row in col + 1..N {
            let factor = a[row][col] / pivot_row[col];
            for (value, above) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *value -= factor * above;
            }
            b[row] -= factor * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let mut s = b[row];
        for k in row + 1..N {
            s -= a[row][k] * x[k];
        }
        x[row] = s / a[row][row];
    }
    Some(x)
}

/// Levenberg-Marquardt with Marquardt's diagonal scaling (so the raw-count scale of the paper's
/// parameters does not matter). Returns the parameters and their objective.
/// With `held` parameters (paper convention) fixed at their start values: the library holds the
/// non-orthogonality terms the poses cannot determine at 0, and the reference solves the same problem.
fn reference_lm(start: P64, means: &[[f64; 3]], g: f64, held: &[bool; PARAM_COUNT]) -> (P64, f64) {
    let mut p = start;
    let mut cost = objective64(&p, means, g);
    let mut lambda = 1e-3;
    for _ in 0..500 {
        let r = residuals64(&p, means, g);
        let mut jtj = [[0.0; PARAM_COUNT]; PARAM_COUNT];
        let mut jtr = [0.0; PARAM_COUNT];
        for (f, e) in means.iter().zip(&r) {
            let j = gradient64(&p, f);
            for a in 0..PARAM_COUNT {
                jtr[a] += j[a] * e;
                for b in 0..PARAM_COUNT {
                    jtj[a][b] += j[a] * j[b];
                }
            }
        }
        let mut improved = false;
        while lambda < 1e12 {
            let mut m = jtj;
            for (a, row) in m.iter_mut().enumerate() {
                row[a] += lambda * jtj[a][a].max(1e-300);
            }
            let mut rhs = jtr.map(|v| -v);
            for a in (0..PARAM_COUNT).filter(|&a| held[a]) {
                for b in 0..PARAM_COUNT {
                    m[a][b] = f64::from(u8::from(a == b));
                    m[b][a] = f64::from(u8::from(a == b));
                }
                rhs[a] = 0.0;
            }
            let Some(step) = solve64(m, rhs) else {
                lambda *= 10.0;
                continue;
            };
            let mut trial = p;
            for a in 0..PARAM_COUNT {
                trial[a] += step[a];
            }
            let trial_cost = objective64(&trial, means, g);
            if trial_cost.is_finite() && trial_cost < cost {
                let decrease = (cost - trial_cost) / cost;
                p = trial;
                cost = trial_cost;
                lambda = (lambda / 3.0).max(1e-15);
                improved = decrease > 1e-15;
                break;
            }
            lambda *= 4.0;
        }
        if !improved {
            break;
        }
    }
    (p, cost)
}

/// A start independent of the library: per axis, the largest and smallest pose reading give the
/// offset and the gain (`S = 2g / (max - min)`, `B = S (max + min) / 2`), no cross-axis terms.
fn extremes_start(means: &[[f64; 3]], g: f64) -> P64 {
    let mut p = [0.0; PARAM_COUNT];
    for a in 0..3 {
        let hi = means.iter().map(|m| m[a]).fold(f64::NEG_INFINITY, f64::max);
        let lo = means.iter().map(|m| m[a]).fold(f64::INFINITY, f64::min);
        let scale = 2.0 * g / (hi - lo);
        p[3 + a] = scale;
        p[a] = scale * 0.5 * (hi + lo);
    }
    p
}

// ---------------------------------------------------------------------------------------------
// One real set end to end.
// ---------------------------------------------------------------------------------------------

/// Where the poses come from.
enum Source {
    /// Raw samples through the static detector.
    Raw(AccumulateOptions),
    /// One pose per row.
    Means,
}

struct Case {
    name: &'static str,
    file: &'static str,
    /// The command-line options that reproduce this reading (for the printed table).
    cli: &'static str,
    read: ReadOptions,
    source: Source,
    expected_units: Units,
    /// Static positions the folder's README counts (printed next to the poses found).
    readme_positions: usize,
    /// Inclusive range of the number of poses that must be found (at least 9 everywhere).
    poses: (usize, usize),
}

struct Outcome {
    table: Table,
    accumulation: Option<Accumulation>,
    poses: Vec<Pose>,
    calibration: Calibration,
    gravity: f64,
    library_objective64: f64,
    reference_objective: f64,
    reference_params: P64,
}

fn run(case: &Case) -> Outcome {
    let path = data_file(case.file);
    let table = read_csv(&path, &case.read).unwrap_or_else(|e| panic!("{}: {e}", case.name));
    assert_eq!(table.units, case.expected_units, "{}: units {}", case.name, table.units_summary());
    for w in &table.warnings {
        println!("{}: warning: {w}", case.name);
    }
    let (poses, accumulation) = match &case.source {
        Source::Means => (to_poses_from_means(&table), None),
        Source::Raw(opts) => {
            let acc = accumulate(&table, opts).unwrap_or_else(|e| panic!("{}: {e}", case.name));
            (acc.poses.clone(), Some(acc))
        }
    };
    let (lo, hi) = case.poses;
    assert!(
        poses.len() >= 9 && (lo..=hi).contains(&poses.len()),
        "{}: {} poses found, expected {lo}..={hi} (rejections {:?})",
        case.name,
        poses.len(),
        accumulation.as_ref().map(|a| a.rejections)
    );

    let gravity = table.units.calibration_gravity();
    let config = CalibrationConfig { gravity, before: table.units.before_model(), ..CalibrationConfig::DEFAULT };
    let calibration = calibrate::<_, 40, 512>(&poses, &config, Xoshiro128PlusPlus::seed_from_u64(1))
        .unwrap_or_else(|e| panic!("{}: calibration failed: {e}", case.name));

    let g = f64::from(gravity);
    // The reference solves the library's problem: the poses it kept, the parameters it fitted.
    let warnings = calibration.verdict.warnings;
    assert!(warnings.held[..6].iter().all(|h| !h), "{}: only non-orthogonality is ever held here", case.name);
    let left_out = warnings.excluded.as_slice();
    let means: Vec<[f64; 3]> =
        (0..poses.len()).filter(|i| !left_out.contains(&(*i as u16))).map(|i| poses[i].mean.map(f64::from)).collect();
    let library: P64 = calibration.params.to_array().map(f64::from);
    let library_objective64 = objective64(&library, &means, g);
    let from_library = reference_lm(library, &means, g, &warnings.held);
    let mut extremes = extremes_start(&means, g);
    (6..PARAM_COUNT).filter(|&i| warnings.held[i]).for_each(|i| extremes[i] = 0.0);
    let from_extremes = reference_lm(extremes, &means, g, &warnings.held);
    let (reference_params, reference_objective) =
        if from_library.1 <= from_extremes.1 { from_library } else { from_extremes };
    Outcome {
        table,
        accumulation,
        poses,
        calibration,
        gravity: g,
        library_objective64,
        reference_objective,
        reference_params,
    }
}

/// Runs a case, prints its summary row and checks (a)-(c).
fn check(case: &Case) -> Outcome {
    let out = run(case);
    let v = &out.calibration.verdict;
    let means: Vec<[f64; 3]> = out.poses.iter().map(|p| p.mean.map(f64::from)).collect();
    let ratio_reported = f64::from(out.calibration.objective) / out.reference_objective;
    let ratio64 = out.library_objective64 / out.reference_objective;
    println!(
        "| {} | `{}` | {} | `{}` | {} ({}) | {:.2} | {:.3} | {:.3} | {:.6e} | {:.6e} | {:.6} | {:.6} |",
        case.name,
        case.file,
        out.table.units_summary(),
        case.cli,
        out.poses.len(),
        case.readme_positions,
        v.rmse_before_mg,
        v.rmse_after_mg,
        rmse64_mg(&out.reference_params, &means, out.gravity),
        out.calibration.objective,
        out.reference_objective,
        ratio_reported,
        ratio64,
    );
    if let Some(acc) = &out.accumulation {
        println!(
            "{}: block {} samples, rate {:?} Hz, stale repeats skipped {}, noise var {:.3e} (floor {:.3e}), \
             rejections {:?}, gaps {}",
            case.name,
            acc.block_samples,
            acc.sample_rate_hz.map(|r| (r * 10.0).round() / 10.0),
            acc.skipped_repeats,
            acc.noise_variance,
            acc.min_noise_variance,
            acc.rejections,
            acc.interruptions
        );
    }
    println!(
        "{}: library params {:?}; reference params {:?}; verdict pass {}",
        case.name,
        out.calibration.params.to_array(),
        out.reference_params,
        v.pass()
    );
    assert!(
        v.rmse_after_mg < v.rmse_before_mg,
        "{}: RMSE after {} mg is not below before {} mg",
        case.name,
        v.rmse_after_mg,
        v.rmse_before_mg
    );
    let tolerance = objective_tolerance(out.reference_objective, out.gravity);
    assert!(
        out.library_objective64 <= out.reference_objective + tolerance,
        "{}: library parameters give fE = {:e}, the f64 reference reaches {:e} (ratio {ratio64})",
        case.name,
        out.library_objective64,
        out.reference_objective
    );
    assert!(
        (f64::from(out.calibration.objective) - out.reference_objective).abs() <= tolerance,
        "{}: library reports fE = {:e}, the f64 reference optimum is {:e} (ratio {ratio_reported})",
        case.name,
        out.calibration.objective,
        out.reference_objective
    );
    out
}

fn raw(opts: AccumulateOptions) -> Source {
    Source::Raw(opts)
}

fn means_options() -> ReadOptions {
    ReadOptions { means: true, ..ReadOptions::default() }
}

#[test]
fn imu_tk_xsens_mti() {
    let case = Case {
        name: "imu_tk_xsens_mti",
        file: "imu_tk_xsens_mti/xsens_acc.csv",
        cli: "(none)",
        read: ReadOptions::default(),
        source: raw(AccumulateOptions::default()),
        expected_units: Units::Counts,
        readme_positions: 38,
        poses: (35, 41),
    };
    let out = check(&case);
    assert_eq!(out.table.samples.len(), 51_175);
    let acc = out.accumulation.as_ref().unwrap();
    assert_eq!(acc.block_samples, 16);
    // The first pose is the ~51 s initial rest.
    let first = acc.spans[0];
    let (start_s, end_s) = (first.start_s.unwrap(), first.end_s.unwrap());
    assert!(start_s < 2.0 && end_s > 50.0 && end_s < 53.0, "first pose {start_s}..{end_s} s");
}

#[test]
fn hassan_lis3dh_30pos_raw() {
    check(&Case {
        name: "hassan_lis3dh_30pos (raw)",
        file: "hassan_lis3dh_30pos/MobileAccData30orientationRawSample01.csv",
        cli: "(none)",
        read: ReadOptions::default(),
        source: raw(AccumulateOptions::default()),
        expected_units: Units::Mps2,
        readme_positions: 30,
        poses: (9, 512),
    });
}

#[test]
fn hassan_lis3dh_30pos_author_windows() {
    check(&Case {
        name: "hassan_lis3dh_30pos (author windows)",
        file: "hassan_lis3dh_30pos/author_interval_means.csv",
        cli: "--means",
        read: means_options(),
        source: Source::Means,
        expected_units: Units::Mps2,
        readme_positions: 30,
        poses: (30, 30),
    });
}

#[test]
fn hassan_49_means() {
    check(&Case {
        name: "hassan 49-position means",
        file: "hassan_lis3dh_30pos/CalibrationOfLowCostTriaxialInertialSensors50.csv",
        cli: "--means",
        read: means_options(),
        source: Source::Means,
        expected_units: Units::G,
        readme_positions: 49,
        poses: (49, 49),
    });
}

#[test]
fn fastahrs_fxos8700_data_sample() {
    check(&Case {
        name: "fastahrs_fxos8700 data_sample",
        file: "fastahrs_fxos8700/data_sample.clean.csv",
        cli: "(none)",
        read: ReadOptions::default(),
        source: raw(AccumulateOptions::default()),
        expected_units: Units::Mps2,
        readme_positions: 18,
        poses: (9, 512),
    });
}

#[test]
fn fastahrs_fxos8700_data_sample2() {
    check(&Case {
        name: "fastahrs_fxos8700 data_sample2",
        file: "fastahrs_fxos8700/data_sample2.clean.csv",
        cli: "(none)",
        read: ReadOptions::default(),
        source: raw(AccumulateOptions::default()),
        expected_units: Units::Mps2,
        readme_positions: 20,
        poses: (9, 512),
    });
}

#[test]
fn ck_explorer_acc_sphere_raw() {
    // No time column; holds of 100 readings: found with the pose finder's last attempt for short
    // holds (poses of 4 blocks, 64 readings; `calibrate` reaches it through its retries).
    let untimed = AccumulateOptions {
        min_pose_s: 0.0,
        short_min_pose_blocks: Some(accelcal_host::poses::SHORT_MIN_POSE_BLOCKS),
        ..AccumulateOptions::default()
    };
    check(&Case {
        name: "ck_explorer_acc_sphere (raw)",
        file: "ck_explorer_acc_sphere/acc_log.csv",
        cli: "(none)",
        read: ReadOptions::default(),
        source: raw(untimed),
        expected_units: Units::G,
        readme_positions: 160,
        poses: (50, 160),
    });
}

#[test]
fn ck_explorer_acc_sphere_block_means() {
    check(&Case {
        name: "ck_explorer_acc_sphere (block means)",
        file: "ck_explorer_acc_sphere/derived_block_means.csv",
        cli: "--means",
        read: means_options(),
        source: Source::Means,
        expected_units: Units::G,
        readme_positions: 160,
        poses: (160, 160),
    });
}

#[test]
fn michaelwro_178pos() {
    check(&Case {
        name: "michaelwro_178pos",
        file: "michaelwro_178pos/acceldata-example.csv",
        cli: "--means",
        read: means_options(),
        source: Source::Means,
        expected_units: Units::G,
        readme_positions: 178,
        poses: (178, 178),
    });
}

#[test]
fn imutk_windows_20pos() {
    check(&Case {
        name: "imutk_windows_20pos",
        file: "imutk_windows_20pos/imu.csv",
        cli: "(none)",
        read: ReadOptions::default(),
        source: raw(AccumulateOptions::default()),
        expected_units: Units::Mps2,
        readme_positions: 20,
        // All 20 holds, including the noisier ones a running-minimum noise level shut out (15 found).
        poses: (20, 20),
    });
}

#[test]
fn tomisuarez_mpu6050_10pos() {
    check(&Case {
        name: "tomisuarez_mpu6050_10pos",
        file: "tomisuarez_mpu6050_10pos/example_data_calibration.plain.csv",
        cli: "(none)",
        read: ReadOptions::default(),
        source: raw(AccumulateOptions::default()),
        expected_units: Units::Counts,
        readme_positions: 10,
        // All 10, including the hand-held hold 3 (z std 185 LSB against about 77 elsewhere).
        poses: (10, 10),
    });
}

#[test]
fn tomisuarez_mpu6050_10pos_intervals() {
    check(&Case {
        name: "tomisuarez_mpu6050_10pos (interval means)",
        file: "tomisuarez_mpu6050_10pos/derived_static_intervals.csv",
        cli: "--means",
        read: means_options(),
        source: Source::Means,
        expected_units: Units::Counts,
        readme_positions: 10,
        poses: (10, 10),
    });
}

#[test]
fn fastahrs_fxos8700_chunk_means() {
    for (file, positions) in [
        ("fastahrs_fxos8700/derived_chunk_means_data_sample.csv", 18),
        ("fastahrs_fxos8700/derived_chunk_means_data_sample2.csv", 20),
    ] {
        check(&Case {
            name: "fastahrs_fxos8700 (chunk means)",
            file,
            cli: "--means",
            read: means_options(),
            source: Source::Means,
            expected_units: Units::Mps2,
            readme_positions: positions,
            poses: (positions, positions),
        });
    }
}

/// The folders the survey found unusable for a full 9-parameter fit still read cleanly; the
/// calibration fits what they determine and says what it could not, or refuses with a clear error.
#[test]
fn unusable_sets_read_and_are_refused() {
    let path = data_file("avrlabs_mpu6050/derived_notebook_26pos_means.csv");
    let table = read_csv(&path, &means_options()).unwrap();
    assert_eq!(table.units, Units::Counts);
    let poses = to_poses_from_means(&table);
    assert_eq!(poses.len(), 26);
    let config = CalibrationConfig { gravity: table.units.calibration_gravity(), ..CalibrationConfig::DEFAULT };
    let result = calibrate::<_, 40, 512>(&poses, &config, Xoshiro128PlusPlus::seed_from_u64(1));
    println!("avrlabs notebook (two quarter circles): {:?}", result.as_ref().map(|c| c.verdict));
    // Two quarter circles (x+ to z-, y+ to z-): the cross term between the two planes is free.
    let cal = result.expect("two quarter circles give a partial fit, not an error");
    assert_eq!(cal.initial.kind, accelcal::calibrate::Init::Ellipsoid);
    assert!(cal.verdict.warnings.held[6], "Mxx (the x-y cross term) is held: {:?}", cal.verdict);
    assert!(cal.verdict.rmse_after_mg < 0.5 * cal.verdict.rmse_before_mg, "{:?}", cal.verdict);
    assert!(!cal.verdict.pass(), "biases and scales this poorly determined fail the default bounds");

    let path = data_file("willward_mpu9250/final_trial__six_position_data.csv");
    let table = read_csv(&path, &means_options()).unwrap();
    assert_eq!(table.units, Units::G);
    let poses = to_poses_from_means(&table);
    assert_eq!(poses.len(), 6);
    let config = CalibrationConfig { gravity: 1.0, before: Some(Params::IDENTITY), ..CalibrationConfig::DEFAULT };
    let result = calibrate::<_, 40, 512>(&poses, &config, Xoshiro128PlusPlus::seed_from_u64(1));
    // Six faces: the biases and scale factors (as ArduPilot and PX4 fit them); the non-orthogonality
    // is invisible to them and held at 0, said so.
    let cal = result.expect("six faces fit six parameters");
    assert_eq!(cal.verdict.warnings.held, [false, false, false, false, false, false, true, true, true]);
    assert!(cal.verdict.rmse_after_mg < cal.verdict.rmse_before_mg, "{:?}", cal.verdict);

    // Raw z-up log: a title line, then a header with two names run together ("time (s)x (g)").
    // The title is skipped as a preamble; the columns must be given by index.
    let path = data_file("willward_mpu9250/final_trial__six_position_final_test_data.csv");
    let err = read_csv(&path, &ReadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("`time (s)x (g)`"), "{err}");
    let spec: ColumnSpec = "0,1,2,3".parse().unwrap();
    let table = read_csv(&path, &ReadOptions { columns: Some(spec), ..ReadOptions::default() }).unwrap();
    assert_eq!((table.samples.len(), table.units), (53_966, Units::G));
    let acc = accumulate(&table, &AccumulateOptions::default()).unwrap();
    assert_eq!(acc.poses.len(), 1, "one 300 s z-up hold");

    // The avrlabs notebook raw file concatenates captures (time restarts per position).
    let path = data_file("avrlabs_mpu6050/notebook_26pos_clean.csv");
    let err = read_csv(&path, &ReadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("time goes backwards"), "{err}");
    let spec: ColumnSpec = "-,ax_raw,ay_raw,az_raw,temp_C".parse().unwrap();
    let table = read_csv(&path, &ReadOptions { columns: Some(spec), ..ReadOptions::default() }).unwrap();
    assert_eq!(table.temps_c.as_ref().map(Vec::len), Some(table.samples.len()));
}

/// `--pose-column`: the avrlabs notebook log names its hold on every row; segmenting by that label gives
/// the 26 holds of the authors' means file (same counts, same means) and the same partial fit.
#[test]
fn avrlabs_notebook_segmented_by_its_position_column() {
    let path = data_file("avrlabs_mpu6050/notebook_26pos_clean.csv");
    let spec: ColumnSpec = "-,ax_raw,ay_raw,az_raw,temp_C".parse().unwrap();
    let table = read_csv(&path, &ReadOptions { columns: Some(spec), ..ReadOptions::default() }).unwrap();
    let poses = accelcal_host::labelled::poses_by_label(&table, &path, "position").unwrap();
    let means = read_csv(&data_file("avrlabs_mpu6050/derived_notebook_26pos_means.csv"), &means_options()).unwrap();
    let reference = to_poses_from_means(&means);
    assert_eq!(poses.len(), 26);
    for (p, r) in poses.iter().zip(&reference) {
        assert!((87..=259).contains(&p.n), "{p:?}");
        assert!((0..3).all(|a| (p.mean[a] - r.mean[a]).abs() < 0.01), "{p:?} vs {r:?}");
    }
    let err = accelcal_host::labelled::poses_by_label(&table, &path, "label").unwrap_err();
    assert!(err.contains("no such column") && err.contains("position"), "{err}");
}
