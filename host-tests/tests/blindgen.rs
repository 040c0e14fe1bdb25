//! Physics checks of the blind-test log generator (`accelcal_host::blindgen`): each injected
//! effect changes the log the way its physics says, the clean sensor reads g at rest, generation is
//! deterministic per seed and the twin differs only by the effect.

use accelcal_host::blindgen::drift::{Drift, DriftShape};
use accelcal_host::blindgen::nonlinear::Nonlinear;
use accelcal_host::blindgen::sensor::Units;
use accelcal_host::blindgen::session::G_MPS2;
use accelcal_host::blindgen::temperature::{TempEffect, TempProfile};
use accelcal_host::blindgen::vec3::{V3, norm, scale, sub};
use accelcal_host::blindgen::{Effect, Family, Log, LogSpec, Magnitude, generate, random_small_spec};

const MG: f64 = 1e-3 * G_MPS2;

/// A small spec of `family` in m/s^2 (no quantisation).
fn small(family: Family, seed: u64) -> LogSpec {
    let mut spec = random_small_spec(family, seed);
    spec.units = Units::Mps2;
    spec
}

/// Calibrated hold means (truth applied) minus the true specific force `g up` (m/s^2).
fn residuals(spec: &LogSpec, log: &Log, margin_s: f64) -> Vec<V3> {
    let means = log.hold_means_mps2(margin_s);
    means.iter().zip(&log.holds).map(|(m, h)| sub(spec.truth.apply(*m), scale(h.up_body, G_MPS2))).collect()
}

/// Log hold means minus twin hold means (m/s^2).
fn effect_on_means(log: &Log, twin: &Log, margin_s: f64) -> Vec<V3> {
    log.hold_means_mps2(margin_s).iter().zip(twin.hold_means_mps2(margin_s)).map(|(a, b)| sub(*a, b)).collect()
}

fn mid(log: &Log, i: usize) -> f64 {
    0.5 * (log.holds[i].start_s + log.holds[i].end_s)
}

#[test]
fn clean_sensor_reads_g_at_rest_within_noise() {
    for seed in 1..=4 {
        let spec = small(Family::Clean, seed);
        let log = generate(&spec);
        let sigma_mps2 = spec.noise_mg * MG;
        let mut moduli = Vec::new();
        for (i, s) in log.samples.iter().enumerate() {
            if log.holds.iter().any(|h| s.t_s >= h.start_s && s.t_s < h.end_s) {
                moduli.push(norm(spec.truth.apply(log.accel_mps2(i))) - G_MPS2);
            }
        }
        let n = moduli.len() as f64;
        let mean = moduli.iter().sum::<f64>() / n;
        let std = (moduli.iter().map(|m| (m - mean) * (m - mean)).sum::<f64>() / n).sqrt();
        assert!(mean.abs() < 5.0 * sigma_mps2 / n.sqrt(), "seed {seed}: mean {mean} sigma {sigma_mps2}");
        assert!((std / sigma_mps2 - 1.0).abs() < 0.1, "seed {seed}: std {std} vs noise {sigma_mps2}");
    }
}

#[test]
fn clean_hold_means_lie_on_the_sphere_in_every_unit() {
    for (units, seed) in [(Units::G, 11), (Units::Counts { lsb_per_g: 16384.0, bits: 16 }, 12), (Units::COARSE, 13)] {
        let mut spec = small(Family::Clean, seed);
        spec.units = units;
        let log = generate(&spec);
        let lsb_mps2 = units.lsb_per_g().map_or(0.0, |l| G_MPS2 / l);
        for r in residuals(&spec, &log, 0.0) {
            // Quantisation with noise below one LSB can bias a mean by up to half an LSB per axis.
            let tolerance = 1.0 * MG + 0.5 * lsb_mps2 * 3f64.sqrt();
            assert!(norm(r) < tolerance, "{units:?}: residual {r:?}");
        }
    }
}

#[test]
fn generation_is_deterministic_per_seed() {
    for family in [Family::Clean, Family::Drift, Family::Temperature, Family::Nonlinearity] {
        assert_eq!(random_small_spec(family, 5), random_small_spec(family, 5));
        let spec = random_small_spec(family, 5);
        assert_eq!(generate(&spec), generate(&spec), "{family:?}");
        assert_ne!(random_small_spec(family, 5).truth, random_small_spec(family, 6).truth);
    }
}

#[test]
fn twin_differs_only_by_the_effect() {
    for family in [Family::Drift, Family::Temperature, Family::Nonlinearity] {
        let spec = small(family, 21);
        let (log, twin) = (generate(&spec), generate(&spec.twin()));
        assert!(spec.effect.is_some() && twin.holds == log.holds);
        assert_eq!(log.samples.len(), twin.samples.len());
        let same_times = log.samples.iter().zip(&twin.samples).all(|(a, b)| a.t_s == b.t_s && a.temp_c == b.temp_c);
        assert!(same_times, "{family:?}: time or temperature columns differ");
        assert!(log.rms_difference_mg(&twin) > 0.0, "{family:?}: the effect changed nothing");
        let clean = small(Family::Clean, 21);
        assert_eq!(generate(&clean), generate(&clean.twin()));
    }
}

fn with_drift(seed: u64, shape: DriftShape) -> LogSpec {
    let mut spec = small(Family::Drift, seed);
    spec.set_effect(Effect::Drift(Drift { shape, peak_mg: 20.0 }));
    spec
}

#[test]
fn drift_moves_the_bias_of_later_holds_as_its_time_course_says() {
    let spec = small(Family::Drift, 31);
    let total_s = spec.session.total_s();
    let c1 = [20.0 * MG / total_s, -10.0 * MG / total_s, 5.0 * MG / total_s];
    let shapes = [
        DriftShape::Polynomial { c1, c2: [0.0; 3] },
        DriftShape::Polynomial { c1: [0.0; 3], c2: scale(c1, 1.0 / total_s) },
        DriftShape::WarmUp { a1: scale(c1, total_s), tau1_s: 10.0, a2: scale(c1, -0.5 * total_s), tau2_s: 80.0 },
    ];
    for shape in shapes {
        let spec = with_drift(31, shape.clone());
        let log = generate(&spec);
        let res = residuals(&spec, &log, 0.0);
        let n = res.len();
        for i in 0..n {
            let h = log.holds[i];
            let expected = average(|t| shape.at(t), h.start_s, h.end_s);
            assert!(norm(sub(res[i], expected)) < 1.0 * MG, "{}: hold {i} {:?} vs {expected:?}", shape.name(), res[i]);
        }
        assert!(norm(sub(res[n - 1], res[0])) > 5.0 * MG, "{}: late holds should differ", shape.name());
    }
}

/// Mean of `f` over `[a, b]` (midpoint rule).
fn average(f: impl Fn(f64) -> V3, a: f64, b: f64) -> V3 {
    let k = 400;
    let sum = (0..k)
        .map(|j| f(a + (b - a) * (j as f64 + 0.5) / k as f64))
        .fold([0.0; 3], |s, v| [s[0] + v[0], s[1] + v[1], s[2] + v[2]]);
    scale(sum, 1.0 / k as f64)
}

fn temp_spec(seed: u64, profile: TempProfile, effect: TempEffect) -> LogSpec {
    let mut spec = small(Family::Temperature, seed);
    spec.session.temperature = Some(profile);
    spec.set_effect(Effect::Temperature(effect));
    spec
}

fn temp_effect(bias_per_c: V3, scale_per_c: V3, lag_tau_s: Option<f64>) -> TempEffect {
    TempEffect {
        shape: "test".into(),
        bias_per_c,
        bias_per_c2: [0.0; 3],
        scale_per_c,
        scale_per_c2: [0.0; 3],
        lag_tau_s,
        magnitude: Magnitude { value: 1.0, unit: "mg", what: "test" },
    }
}

#[test]
fn temperature_bias_follows_the_thermometer() {
    let profile = TempProfile::Ramp { start_c: 20.0, rate_c_per_s: 0.05 };
    let b = [1.0 * MG, -0.5 * MG, 0.3 * MG];
    let spec = temp_spec(41, profile, temp_effect(b, [0.0; 3], None));
    let log = generate(&spec);
    for (i, r) in residuals(&spec, &log, 0.0).iter().enumerate() {
        let delta_c = profile.at(mid(&log, i)) - 20.0;
        assert!(norm(sub(*r, scale(b, delta_c))) < 0.5 * MG, "hold {i}: {r:?} at +{delta_c} C");
    }
}

#[test]
fn temperature_scale_multiplies_the_axis_input() {
    let profile = TempProfile::Cycling { mean_c: 25.0, amp_c: 8.0, period_s: 60.0 };
    let s = [2e-3, -1e-3, 1.5e-3];
    let spec = temp_spec(42, profile, temp_effect([0.0; 3], s, None));
    let (log, twin) = (generate(&spec), generate(&spec.twin()));
    let bias_s = spec.truth.ka_inv(spec.truth.bias_mps2);
    let diffs = effect_on_means(&log, &twin, 0.0);
    let means = twin.hold_means_mps2(0.0);
    for (i, d) in diffs.iter().enumerate() {
        let h = log.holds[i];
        let delta_c = average(|t| [profile.at(t) - profile.at(0.0); 3], h.start_s, h.end_s)[0];
        let input = sub(means[i], bias_s);
        let expected: V3 = core::array::from_fn(|k| s[k] * delta_c * input[k]);
        assert!(norm(sub(*d, expected)) < 0.05 * MG, "hold {i}: {d:?} vs {expected:?}");
    }
}

#[test]
fn nonlinearity_error_grows_with_the_square_and_cube_of_the_input() {
    let (k2, k3) = ([0.01, -0.005, 0.0], [0.0, 0.004, -0.008]);
    let mut spec = small(Family::Nonlinearity, 51);
    spec.set_effect(Effect::Nonlinear(Nonlinear { k2_per_g: k2, k3_per_g2: k3, at_1g_mg: 10.0 }));
    let (log, twin) = (generate(&spec), generate(&spec.twin()));
    let bias_s = spec.truth.ka_inv(spec.truth.bias_mps2);
    let means = twin.hold_means_mps2(0.0);
    for (i, d) in effect_on_means(&log, &twin, 0.0).iter().enumerate() {
        let a = scale(sub(means[i], bias_s), 1.0 / G_MPS2);
        for k in 0..3 {
            let expected_mps2 = (k2[k] * a[k] * a[k] + k3[k] * a[k].powi(3)) * G_MPS2;
            assert!((d[k] - expected_mps2).abs() < 0.02 * MG, "hold {i} axis {k}: {} vs {expected_mps2}", d[k]);
        }
    }
}

#[test]
fn random_effects_have_the_drawn_strength_order() {
    for family in [Family::Drift, Family::Temperature, Family::Nonlinearity] {
        for seed in 60..64 {
            let spec = small(family, seed);
            let (log, twin) = (generate(&spec), generate(&spec.twin()));
            let magnitude = spec.effect.as_ref().map(|e| e.model().magnitude()).expect("an effect");
            let rms = log.rms_difference_mg(&twin);
            assert!(rms > 0.0 && magnitude.value > 0.0, "{family:?} seed {seed}: rms {rms} mg, {magnitude:?}");
            if magnitude.unit == "mg" {
                assert!(rms < 3.0 * magnitude.value, "{family:?} seed {seed}: rms {rms} mg > 3x {magnitude:?}");
            }
        }
    }
}
