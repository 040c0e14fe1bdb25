//! End-to-end numerics of the library on synthetic poses with known parameters.

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, Init, InitError, Method, NormalizedPoses, calibrate};
use accelcal::frame::objective;
use accelcal::model::{PARAM_COUNT, Params};
use accelcal::solve::{LmConfig, NewtonConfig, levenberg_marquardt, newton};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

const G: f64 = 9.80665;

/// The paper's Table 1 truth.
const PAPER_TRUTH: [f64; PARAM_COUNT] =
    [0.124886392, 0.124886392, 0.124886392, 0.97, 0.970119681, 0.970239377, -0.01523798, -0.01500048, -0.01523986];

/// Sensor reading `Ka^-1 (f_b + B)` in f64 (an independent inverse of the model).
fn reading(truth: &[f64; PARAM_COUNT], f_b: [f64; 3]) -> [f64; 3] {
    let y = [f_b[0] + truth[0], f_b[1] + truth[1], f_b[2] + truth[2]];
    let x0 = y[0] / truth[3];
    let x1 = (y[1] - truth[6] * x0) / truth[4];
    let x2 = (y[2] - truth[7] * x0 - truth[8] * x1) / truth[5];
    [x0, x1, x2]
}

/// `n` well-spread unit directions: the 6 faces, then the 8 cube vertices, then the 12 edges.
fn cube_directions(n: usize) -> Vec<[f64; 3]> {
    let s = 1.0 / 3f64.sqrt();
    let e = 1.0 / 2f64.sqrt();
    let mut d =
        vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    for sx in [-1.0, 1.0] {
        for sy in [-1.0, 1.0] {
            for sz in [-1.0, 1.0] {
                d.push([sx * s, sy * s, sz * s]);
            }
        }
    }
    for (a, b) in [(0, 1), (0, 2), (1, 2)] {
        for sa in [-1.0, 1.0] {
            for sb in [-1.0, 1.0] {
                let mut v = [0.0; 3];
                v[a] = sa * e;
                v[b] = sb * e;
                d.push(v);
            }
        }
    }
    d.truncate(n);
    d
}

/// Noiseless poses of `truth` at `dirs`, in a unit given by `to_unit` (value per m/s^2) plus `offset`.
fn poses(truth: &[f64; PARAM_COUNT], dirs: &[[f64; 3]], per_mps2: f64, offset: f64) -> Vec<Pose> {
    dirs.iter()
        .map(|d| {
            let r = reading(truth, [d[0] * G, d[1] * G, d[2] * G]);
            Pose::from_mean(r.map(|v| (v * per_mps2 + offset) as f32), 1000)
        })
        .collect()
}

/// Truth in the units of poses made with `per_mps2` and `offset`: `Ka' = Ka / per`, `B' = B + Ka' offset`.
fn truth_in_units(truth: &[f64; PARAM_COUNT], per_mps2: f64, offset: f64) -> [f64; PARAM_COUNT] {
    let mut t = *truth;
    for v in &mut t[3..] {
        *v /= per_mps2;
    }
    t[0] += t[3] * offset;
    t[1] += (t[6] + t[4]) * offset;
    t[2] += (t[7] + t[8] + t[5]) * offset;
    t
}

fn max_rel_err(params: &Params, truth: &[f64; PARAM_COUNT]) -> (f64, usize) {
    let p = params.to_array();
    let mut worst = (0.0, 0);
    for i in 0..PARAM_COUNT {
        let r = ((p[i] as f64 - truth[i]) / truth[i]).abs();
        if r > worst.0 {
            worst = (r, i);
        }
    }
    worst
}

fn config(method: Method) -> CalibrationConfig {
    CalibrationConfig { method, ..CalibrationConfig::DEFAULT }
}

#[test]
fn noiseless_poses_recover_all_nine_parameters_to_1e_5() {
    // m/s^2 readings, and raw counts near 33 000 (offset 32 768, 836 counts per m/s^2).
    for (per, offset) in [(1.0, 0.0), (836.0, 32768.0)] {
        let truth = truth_in_units(&PAPER_TRUTH, per, offset);
        for n in [12, 14, 20, 26] {
            let poses = poses(&PAPER_TRUTH, &cube_directions(n), per, offset);
            for method in [Method::Lm, Method::TagaLm, Method::Newton] {
                let rng = Xoshiro128PlusPlus::seed_from_u64(n as u64);
                let cal = calibrate::<_, 40, 32>(&poses, &config(method), rng).unwrap();
                let (err, which) = max_rel_err(&cal.params, &truth);
                assert!(err < 1e-5, "{method:?} {n} poses unit {per}: param {which} rel err {err:e}");
            }
        }
    }
}

#[test]
fn lm_from_the_coarse_start_reaches_the_optimum_it_reaches_from_the_truth() {
    // Noisy poses: the optimum is not the truth, and both starts must land on the same point.
    let dirs = cube_directions(26);
    let mut rng_state = 12345u64;
    let mut noise = || {
        rng_state = rng_state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((rng_state >> 40) as f64 / (1u64 << 24) as f64 - 0.5) * 2e-3
    };
    let poses: Vec<Pose> = dirs
        .iter()
        .map(|d| {
            let r = reading(&PAPER_TRUTH, [d[0] * G, d[1] * G, d[2] * G]);
            Pose::from_mean([(r[0] + noise()) as f32, (r[1] + noise()) as f32, (r[2] + noise()) as f32], 1000)
        })
        .collect();
    let norm = NormalizedPoses::<32>::new(&poses, G as f32).unwrap();
    let frame = norm.frame();
    let truth = Params::from_array(PAPER_TRUTH.map(|v| v as f32));
    let from_coarse = levenberg_marquardt([0.0; PARAM_COUNT], norm.poses(), &LmConfig::DEFAULT).unwrap();
    let from_truth = levenberg_marquardt(frame.to_deviation(&truth), norm.poses(), &LmConfig::DEFAULT).unwrap();
    let (a, b) = (frame.to_params(&from_coarse.x).to_array(), frame.to_params(&from_truth.x).to_array());
    for i in 0..PARAM_COUNT {
        assert!((a[i] - b[i]).abs() <= 1e-5 * b[i].abs().max(1e-2), "param {i}: {} vs {}", a[i], b[i]);
    }
    let rel = (from_coarse.cost - from_truth.cost).abs() / from_truth.cost;
    assert!(rel < 1e-3, "{} vs {}", from_coarse.cost, from_truth.cost);
    // Newton from the coarse start lands there too.
    let nt = newton([0.0; PARAM_COUNT], norm.poses(), &NewtonConfig::DEFAULT).unwrap();
    assert!((objective(&nt.x, norm.poses()) - from_truth.cost).abs() / from_truth.cost < 1e-3);
}

#[test]
fn too_few_poses_and_missing_axes_are_typed_errors() {
    use accelcal::calibrate::CalibrationError;
    use accelcal::coarse::CoarseError;
    let all = poses(&PAPER_TRUTH, &cube_directions(26), 1.0, 0.0);
    let rng = || Xoshiro128PlusPlus::seed_from_u64(1);
    // Six faces only: six poses fit the biases and scale factors; the non-orthogonality is held.
    let cal = calibrate::<_, 40, 32>(&all[..6], &config(Method::TagaLm), rng()).unwrap();
    assert_eq!(cal.verdict.warnings.held, [false, false, false, false, false, false, true, true, true]);
    // Five poses: too few for even that.
    let r = calibrate::<_, 40, 32>(&all[..5], &config(Method::TagaLm), rng());
    let too_few = accelcal::ellipsoid::EllipsoidError::TooFewPoses { got: 5 };
    assert_eq!(r.err(), Some(CalibrationError::Init(InitError::Ellipsoid(too_few))));
    // No pose with z down: the paper's six-position start refuses, the ellipsoid start needs no face.
    let no_z_down: Vec<Pose> = all.iter().copied().filter(|p| p.mean[2] > -9.0).collect();
    let six = CalibrationConfig { init: Init::SixPosition, ..config(Method::Lm) };
    let r = calibrate::<_, 40, 32>(&no_z_down, &six, rng());
    let missing = CoarseError::MissingAxisPair { axis: 2, up: false };
    assert_eq!(r.err(), Some(CalibrationError::Init(InitError::Coarse(missing))));
    let cal = calibrate::<_, 40, 32>(&no_z_down, &config(Method::Lm), rng()).unwrap();
    assert_eq!(cal.initial.kind, Init::Ellipsoid);
    assert!(max_rel_err(&cal.params, &PAPER_TRUTH).0 < 1e-4, "{cal:?}");
    // x never points down (a hemisphere only): named as such by the six-position start.
    let half: Vec<Pose> = all.iter().copied().filter(|p| p.mean[0] > -0.5).collect();
    let r = calibrate::<_, 40, 32>(&half, &six, rng());
    let not_reversed =
        matches!(r.err(), Some(CalibrationError::Init(InitError::Coarse(CoarseError::NotReversed { axis: 0, .. }))));
    assert!(not_reversed, "{r:?}");
    // More poses than the buffer.
    let r = calibrate::<_, 40, 8>(&all, &config(Method::Lm), rng());
    assert_eq!(r.err(), Some(CalibrationError::TooManyPoses { got: 26, capacity: 8 }));
}

#[test]
fn verdict_reports_the_noise_floor_and_determined_parameters() {
    let mut poses = poses(&PAPER_TRUTH, &cube_directions(26), 1.0, 0.0);
    // 1 mg per sample, 1000 samples: the poses say so.
    for p in &mut poses {
        p.variance = [(1e-3 * G as f32).powi(2); 3];
    }
    let cal = calibrate::<_, 40, 32>(&poses, &config(Method::TagaLm), Xoshiro128PlusPlus::seed_from_u64(2)).unwrap();
    let v = cal.verdict;
    let floor = v.noise_floor_mg.unwrap();
    // sigma of |f| per pose = 1 mg / sqrt(1000) = 0.0316 mg; times sqrt((26 - 9) / 26).
    assert!((floor - 0.0316 * (17.0f32 / 26.0).sqrt()).abs() < 2e-3, "{floor}");
    assert!(v.rmse_after_mg < 1e-2 && v.pass(), "{v:?}");
    assert!(v.param_std.iter().all(|s| s.is_finite() && *s > 0.0));
    // The same noise, but a tight bound on the bias std: fails on exactly the biases.
    let strict = CalibrationConfig {
        bounds: accelcal::verdict::VerdictBounds { max_bias_std_mg: 1e-4, ..Default::default() },
        ..config(Method::Lm)
    };
    let v = calibrate::<_, 40, 32>(&poses, &strict, Xoshiro128PlusPlus::seed_from_u64(2)).unwrap().verdict;
    assert!(!v.pass());
    assert_eq!(v.failures.undetermined, [true, true, true, false, false, false, false, false, false]);
}

#[test]
fn axis_aligned_poses_fit_what_they_determine_and_hold_the_rest() {
    // 24 poses but only the 6 exact face directions: the non-orthogonality terms are invisible.
    let faces = cube_directions(6);
    let dirs: Vec<[f64; 3]> = faces.iter().cycle().take(24).copied().collect();
    let poses = poses(&PAPER_TRUTH, &dirs, 1.0, 0.0);
    let cal = calibrate::<_, 40, 32>(&poses, &config(Method::TagaLm), Xoshiro128PlusPlus::seed_from_u64(1)).unwrap();
    let expected = [false, false, false, false, false, false, true, true, true];
    assert_eq!(cal.verdict.warnings.held, expected, "{:?}", cal.verdict);
    assert_eq!(cal.params.nonorth, [0.0; 3], "held at nominal");
    assert!(cal.verdict.pass() && !cal.verdict.complete(), "{:?}", cal.verdict);
    // Biases and scale factors are still fitted: six directions, six parameters, an exact fit.
    assert!(cal.verdict.rmse_after_mg < 1e-3, "{:?}", cal.verdict);
    // One corner adds one combination of the three terms: two stay held.
    let corners = &cube_directions(9)[6..9];
    let mut dirs = dirs;
    dirs.push(corners[0]);
    let cal = calibrate::<_, 40, 32>(&poses_with(&dirs), &config(Method::Lm), Xoshiro128PlusPlus::seed_from_u64(1));
    let which = cal.unwrap().verdict.warnings.held;
    assert_eq!(which[..6], [false; 6]);
    assert_eq!(which[6..].iter().filter(|u| **u).count(), 2, "{which:?}");
    // Three corners with independent sign patterns: everything is determined and recovered.
    dirs.extend_from_slice(&corners[1..]);
    let cal = calibrate::<_, 40, 32>(&poses_with(&dirs), &config(Method::Lm), Xoshiro128PlusPlus::seed_from_u64(1));
    let (err, which) = max_rel_err(&cal.unwrap().params, &PAPER_TRUTH);
    assert!(err < 1e-5, "param {which}: {err:e}");
}

fn poses_with(dirs: &[[f64; 3]]) -> Vec<Pose> {
    poses(&PAPER_TRUTH, dirs, 1.0, 0.0)
}

#[test]
fn zero_negative_or_nan_gravity_is_a_typed_error() {
    use accelcal::calibrate::CalibrationError;
    use accelcal::coarse::CoarseError;
    use accelcal::ellipsoid::EllipsoidError;
    let poses = poses(&PAPER_TRUTH, &cube_directions(14), 1.0, 0.0);
    for gravity in [0.0, -9.80665, f32::NAN, f32::INFINITY] {
        let config = CalibrationConfig { gravity, ..config(Method::TagaLm) };
        let r = calibrate::<_, 40, 32>(&poses, &config, Xoshiro128PlusPlus::seed_from_u64(1));
        let expected = CalibrationError::Init(InitError::Ellipsoid(EllipsoidError::InvalidGravity));
        assert_eq!(r.err(), Some(expected), "gravity {gravity}");
        let six = CalibrationConfig { init: Init::SixPosition, ..config };
        let r = calibrate::<_, 40, 32>(&poses, &six, Xoshiro128PlusPlus::seed_from_u64(1));
        assert_eq!(r.err(), Some(CalibrationError::Init(InitError::Coarse(CoarseError::InvalidGravity))));
    }
}

#[test]
fn a_solve_that_does_not_converge_or_lands_far_away_fails_its_verdict() {
    let mut poses = poses(&PAPER_TRUTH, &cube_directions(26), 1.0, 0.0);
    for p in &mut poses {
        p.variance = [1e-4; 3];
    }
    // One LM iteration from the coarse start cannot converge: said, not hidden.
    let mut short = config(Method::Lm);
    short.lm.max_iterations = 1;
    let cal = calibrate::<_, 40, 32>(&poses, &short, Xoshiro128PlusPlus::seed_from_u64(1)).unwrap();
    assert!(cal.verdict.failures.not_converged && !cal.verdict.pass(), "{:?}", cal.verdict);
    // A deviation far outside the plausible range is judged implausible, whatever its fit.
    let norm = NormalizedPoses::<32>::new(&poses, G as f32).unwrap();
    let frame = norm.frame();
    let far = [0.9; PARAM_COUNT];
    let set = norm.pose_set(&poses);
    let v = accelcal::verdict::judge(
        &far,
        frame,
        &set,
        &Params::IDENTITY,
        &Default::default(),
        accelcal::linalg::Held::NONE,
        accelcal::ellipsoid::PoseList::EMPTY,
    );
    assert!(v.failures.implausible && !v.pass());
    // The converged solve passes.
    let cal = calibrate::<_, 40, 32>(&poses, &config(Method::Lm), Xoshiro128PlusPlus::seed_from_u64(1)).unwrap();
    assert!(cal.verdict.pass(), "{:?}", cal.verdict);
}
