//! Physics checks of the blind-test log generator (`accelcal_host::blindgen`): each injected
//! effect changes the log the way its physics says, the clean sensor reads g at rest, generation is
//! deterministic per seed and the twin differs only by the effect.

use accelcal_host::blindgen::colored::Colored;
use accelcal_host::blindgen::drift::{Drift, DriftShape};
use accelcal_host::blindgen::motion::{Bump, Motion, Tap};
use accelcal_host::blindgen::nonlinear::Nonlinear;
use accelcal_host::blindgen::outlier::Outlier;
use accelcal_host::blindgen::sensor::Units;
use accelcal_host::blindgen::session::G_MPS2;
use accelcal_host::blindgen::settling::{Creep, Ringing, Settling};
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
    for family in Family::ALL {
        assert_eq!(random_small_spec(family, 5), random_small_spec(family, 5));
        let spec = random_small_spec(family, 5);
        assert_eq!(generate(&spec), generate(&spec), "{family:?}");
        assert_ne!(random_small_spec(family, 5).truth, random_small_spec(family, 6).truth);
    }
}

#[test]
fn twin_differs_only_by_the_effect() {
    for family in Family::ALL.into_iter().skip(1) {
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
    for family in Family::ALL.into_iter().skip(1) {
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

/// Per-sample `Ka (log - twin)`: the effect in the body frame (m/s^2).
fn body_difference(spec: &LogSpec, log: &Log, twin: &Log) -> Vec<V3> {
    (0..log.samples.len())
        .map(|i| sub(spec.truth.apply(log.accel_mps2(i)), spec.truth.apply(twin.accel_mps2(i))))
        .collect()
}

/// Per-sample `log - twin` in the sensor frame (m/s^2).
fn sensor_difference(log: &Log, twin: &Log) -> Vec<V3> {
    (0..log.samples.len()).map(|i| sub(log.accel_mps2(i), twin.accel_mps2(i))).collect()
}

fn with_effect(family: Family, seed: u64, effect: Effect) -> (LogSpec, Log, Log) {
    let mut spec = small(family, seed);
    spec.set_effect(effect);
    let (log, twin) = (generate(&spec), generate(&spec.twin()));
    (spec, log, twin)
}

fn magnitude() -> Magnitude {
    Magnitude { value: 1.0, unit: "mg", what: "test" }
}

#[test]
fn settling_creep_decays_exponentially_within_each_hold() {
    let creep = Creep { lag_fraction: [0.02, -0.01, 0.015], tau_s: [0.2, 0.4, 0.3] };
    let effect = Settling { creep: Some(creep.clone()), ringing: None, magnitude: magnitude() };
    let (_, log, twin) = with_effect(Family::Settling, 71, Effect::Settling(effect));
    let d = sensor_difference(&log, &twin);
    let mut lagging = 0;
    for (p, h) in log.holds.iter().enumerate().skip(1) {
        let change = sub(h.up_body, log.holds[p - 1].up_body);
        let first = log.samples.iter().position(|s| s.t_s >= h.start_s).expect("a sample in the hold");
        for k in 0..3 {
            // The reading lags its input: the transient opposes the change.
            if change[k].abs() > 0.5 && -creep.lag_fraction[k] * change[k] * d[first][k] > 0.0 {
                lagging += 1;
            }
            for (i, s) in log.samples.iter().enumerate().filter(|(_, s)| s.t_s >= h.start_s && s.t_s < h.end_s) {
                let expected = d[first][k] * (-(s.t_s - log.samples[first].t_s) / creep.tau_s[k]).exp();
                assert!(
                    (d[i][k] - expected).abs() < 1e-4 * MG,
                    "hold {p} axis {k} t {}: {} vs {expected}",
                    s.t_s,
                    d[i][k]
                );
            }
        }
        let late = sub(log.window_mean_mps2(h.end_s - 1.0, h.end_s), twin.window_mean_mps2(h.end_s - 1.0, h.end_s));
        assert!(norm(late) < 0.01 * MG, "hold {p}: the creep should be gone by the end of the hold");
    }
    assert!(lagging >= 8, "only {lagging} transients oppose a change above 0.5 g");
}

#[test]
fn settling_ringing_oscillates_at_its_frequency_and_decays() {
    let poses = small(Family::Settling, 72).session.poses.len();
    let ringing = Ringing {
        dir_body: [0.6, 0.0, 0.8],
        freq_hz: 7.0,
        decay_s: 0.4,
        amp_mps2: vec![50.0 * MG; poses],
        phase_rad: vec![0.3; poses],
    };
    let effect = Settling { creep: None, ringing: Some(ringing), magnitude: magnitude() };
    let (spec, log, twin) = with_effect(Family::Settling, 72, Effect::Settling(effect));
    let d = body_difference(&spec, &log, &twin);
    for h in log.holds.iter().skip(1) {
        let along: Vec<f64> = log
            .samples
            .iter()
            .zip(&d)
            .filter(|(s, _)| s.t_s >= h.start_s && s.t_s < h.start_s + 2.0)
            .map(|(_, v)| v[0] * 0.6 + v[2] * 0.8)
            .collect();
        let crossings = along.windows(2).take(100).filter(|w| w[0].signum() != w[1].signum()).count();
        assert!((13..=15).contains(&crossings), "{crossings} zero crossings in 1 s at 7 Hz");
        let early = along[..20].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let late = along[150..].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(early > 30.0 * MG && late < early * 0.05, "early {early} late {late}");
    }
}

#[test]
fn taps_are_short_and_only_inside_their_window() {
    let tap = Tap { pose: 3, at_s: 1.0, width_s: 0.03, accel_mps2: [0.0, 0.0, 5.0] };
    let (spec, log, twin) = with_effect(Family::Motion, 81, Effect::Motion(Motion::Taps(vec![tap])));
    let start = log.holds[3].start_s + 1.0;
    for (s, v) in log.samples.iter().zip(body_difference(&spec, &log, &twin)) {
        let inside = s.t_s >= start - 1e-9 && s.t_s <= start + 0.03 + 1e-9;
        assert!(inside || norm(v) < 1e-9, "t {}: {v:?} outside the tap", s.t_s);
        assert!(norm(v) <= 5.0 + 1e-6, "t {}: {v:?} above the tap peak", s.t_s);
    }
}

#[test]
fn a_bump_turns_the_gravity_vector_mid_hold_and_keeps_its_modulus() {
    let angle = 3f64.to_radians();
    let bump = Bump { pose: 4, at_s: 2.0, rise_s: 0.1, rotvec_rad: [angle, 0.0, 0.0] };
    let (spec, log, twin) = with_effect(Family::Motion, 82, Effect::Motion(Motion::Bumps(vec![bump])));
    let h = log.holds[4];
    assert!(h.end_s - h.start_s > 2.6, "the hold must outlast the bump");
    let before = spec.truth.apply(log.window_mean_mps2(h.start_s, h.start_s + 1.9));
    let after = spec.truth.apply(log.window_mean_mps2(h.start_s + 2.2, h.end_s));
    let turned = (accelcal_host::blindgen::vec3::dot(before, after) / (norm(before) * norm(after))).acos();
    assert!((turned - angle).abs() < 0.05 * angle, "turned {} deg", turned.to_degrees());
    assert!((norm(after) - G_MPS2).abs() < 1.0 * MG, "modulus {}", norm(after));
    let other = effect_on_means(&log, &twin, 0.0);
    assert!(other.iter().enumerate().all(|(i, d)| i == 4 || norm(*d) < 1e-9), "only hold 4 moves");
}

#[test]
fn sway_tilts_the_reading_at_its_frequency() {
    let poses = small(Family::Motion, 83).session.poses.len();
    let sway = Motion::Sway { freq_hz: 1.0, amp_rad: 2f64.to_radians(), lever_m: 0.0, azimuth_rad: vec![0.5; poses] };
    let (spec, log, twin) = with_effect(Family::Motion, 83, Effect::Motion(sway));
    let d = body_difference(&spec, &log, &twin);
    for h in &log.holds {
        let in_hold = |t: f64| t >= h.start_s + 0.5 && t < h.end_s - 0.5;
        let peak = log.samples.iter().zip(&d).filter(|(s, _)| in_hold(s.t_s)).fold(0.0f64, |m, (_, v)| m.max(norm(*v)));
        // A tilt of theta moves the gravity vector by 2 g sin(theta / 2).
        assert!(peak <= G_MPS2 * 2f64.to_radians() * 1.001 && peak > 0.5 * G_MPS2 * 2f64.to_radians(), "peak {peak}");
    }
}

fn colored_bias(seed: u64, effect: Colored) -> Vec<V3> {
    let mut spec = small(Family::ColoredNoise, seed);
    spec.session.rate_hz = 50.0;
    spec.set_effect(Effect::Colored(effect));
    let (log, twin) = (generate(&spec), generate(&spec.twin()));
    body_difference(&spec, &log, &twin)
}

/// Variance over samples and axes of `b[i + lag] - b[i]`.
fn increment_variance(b: &[V3], lag: usize) -> f64 {
    let n = b.len() - lag;
    (0..n).map(|i| sub(b[i + lag], b[i]).iter().map(|v| v * v).sum::<f64>()).sum::<f64>() / (3 * n) as f64
}

#[test]
fn random_walk_variance_grows_linearly_with_lag() {
    let sigma = 1.0 * MG;
    let b = colored_bias(91, Colored::RandomWalk { sigma_mps2_per_rt_s: sigma });
    let one_step = increment_variance(&b, 1) / (sigma * sigma / 50.0);
    assert!((one_step - 1.0).abs() < 0.05, "step variance ratio {one_step}");
    let ratio = increment_variance(&b, 50) / increment_variance(&b, 5);
    assert!((ratio - 10.0).abs() < 2.0, "variance(1 s) / variance(0.1 s) = {ratio}");
}

#[test]
fn gauss_markov_has_its_deviation_and_correlation_time() {
    let (sigma, tau_s) = (2.0 * MG, 0.5);
    let b = colored_bias(92, Colored::GaussMarkov { sigma_mps2: sigma, tau_s });
    let mean = scale(b.iter().fold([0.0; 3], |s, v| [s[0] + v[0], s[1] + v[1], s[2] + v[2]]), 1.0 / b.len() as f64);
    let variance =
        b.iter().map(|v| sub(*v, mean).iter().map(|x| x * x).sum::<f64>()).sum::<f64>() / (3 * b.len()) as f64;
    assert!((variance.sqrt() / sigma - 1.0).abs() < 0.1, "std {} vs {sigma}", variance.sqrt());
    // Structure function 2 sigma^2 (1 - exp(-lag / tau)) at lag = tau.
    let at_tau = increment_variance(&b, 25) / (2.0 * sigma * sigma);
    assert!((at_tau - (1.0 - (-1f64).exp())).abs() < 0.1, "structure function at tau {at_tau}");
}

#[test]
fn flicker_grows_slower_than_a_random_walk_and_faster_than_white() {
    let b = colored_bias(93, Colored::Flicker { sigma_each_mps2: 1.0 * MG });
    let ratio = increment_variance(&b, 500) / increment_variance(&b, 50);
    assert!((1.5..4.0).contains(&ratio), "variance(10 s) / variance(1 s) = {ratio}");
}

#[test]
fn a_bad_pose_offsets_only_its_own_hold() {
    let offset = [0.0, 50.0 * MG, -30.0 * MG];
    let (spec, log, _) =
        with_effect(Family::OutOfCatalogue, 101, Effect::Outlier(Outlier::BadPose { pose: 5, offset_mps2: offset }));
    for (i, r) in residuals(&spec, &log, 0.0).iter().enumerate() {
        let expected = if i == 5 { offset } else { [0.0; 3] };
        assert!(norm(sub(*r, expected)) < 1.0 * MG, "hold {i}: {r:?}");
    }
}

fn mains_hold_effect(rate_hz: f64, freq_hz: f64) -> (f64, f64) {
    let mut spec = small(Family::OutOfCatalogue, 102);
    spec.session.rate_hz = rate_hz;
    let amp = [10.0 * MG, 0.0, 0.0];
    spec.set_effect(Effect::Outlier(Outlier::Mains { freq_hz, amp_mps2: amp, third: 0.0, phase_rad: 0.2 }));
    let (log, twin) = (generate(&spec), generate(&spec.twin()));
    let d = body_difference(&spec, &log, &twin);
    let rms = (d.iter().map(|v| v[0] * v[0]).sum::<f64>() / d.len() as f64).sqrt();
    let means = effect_on_means(&log, &twin, 0.0);
    (rms, means.iter().map(|m| norm(*m)).fold(0.0, f64::max))
}

#[test]
fn mains_pickup_averages_out_unless_the_sample_rate_aliases_it() {
    let (rms, hold_peak) = mains_hold_effect(200.0, 50.02);
    assert!((rms / (10.0 * MG / 2f64.sqrt()) - 1.0).abs() < 0.02, "rms {rms}");
    assert!(hold_peak < 0.2 * MG, "hold means at 200 Hz: {hold_peak}");
    let (_, aliased_peak) = mains_hold_effect(50.0, 50.02);
    assert!(aliased_peak > 3.0 * MG, "hold means at 50 Hz (alias 0.02 Hz): {aliased_peak}");
}

#[test]
fn hysteresis_bias_follows_the_direction_of_the_last_rotation() {
    let h = [5.0 * MG, -4.0 * MG, 3.0 * MG];
    let (spec, log, _) =
        with_effect(Family::OutOfCatalogue, 103, Effect::Outlier(Outlier::Hysteresis { h_mps2: h, width_g: 0.05 }));
    let res = residuals(&spec, &log, 0.0);
    let mut checked = 0;
    for p in 1..log.holds.len() {
        let change = sub(log.holds[p].up_body, log.holds[p - 1].up_body);
        let bias = spec.truth.ka_inv(res[p]);
        for k in 0..3 {
            if change[k].abs() > 0.3 {
                let expected = h[k] * change[k].signum();
                assert!(((bias[k] - expected) / expected).abs() < 0.2, "hold {p} axis {k}: {} vs {expected}", bias[k]);
                checked += 1;
            }
        }
    }
    assert!(checked >= 10, "only {checked} axis changes above 0.3 g");
}

#[test]
fn cross_axis_error_is_the_product_of_the_other_axes() {
    let k = [0.01, -0.02, 0.015];
    let (spec, log, twin) =
        with_effect(Family::OutOfCatalogue, 104, Effect::Outlier(Outlier::CrossAxis { k_per_g: k }));
    let bias_s = spec.truth.ka_inv(spec.truth.bias_mps2);
    let means = twin.hold_means_mps2(0.0);
    for (i, d) in effect_on_means(&log, &twin, 0.0).iter().enumerate() {
        let a = scale(sub(means[i], bias_s), 1.0 / G_MPS2);
        let expected = [k[0] * a[1] * a[2], k[1] * a[2] * a[0], k[2] * a[0] * a[1]];
        assert!(norm(sub(scale(*d, 1.0 / G_MPS2), expected)) < 2e-5, "hold {i}: {d:?} vs {expected:?} g");
    }
}

#[test]
fn a_lagged_sensor_temperature_trails_the_thermometer() {
    let (rate, tau_s) = (0.05, 60.0);
    let profile = TempProfile::Ramp { start_c: 20.0, rate_c_per_s: rate };
    let b = [2.0 * MG, 0.0, -MG];
    let spec = temp_spec(43, profile, temp_effect(b, [0.0; 3], Some(tau_s)));
    let log = generate(&spec);
    let res = residuals(&spec, &log, 0.0);
    for (i, r) in res.iter().enumerate() {
        let h = log.holds[i];
        // A first-order lag behind a ramp from equilibrium: rate (t - tau (1 - exp(-t / tau))).
        let lagged = average(|t| [rate * (t - tau_s * (1.0 - (-t / tau_s).exp())); 3], h.start_s, h.end_s)[0];
        assert!(norm(sub(*r, scale(b, lagged))) < 0.3 * MG, "hold {i}: {r:?} vs {:?}", scale(b, lagged));
    }
    let last = log.holds.len() - 1;
    let unlagged = rate * mid(&log, last);
    assert!(norm(sub(res[last], scale(b, unlagged))) > 2.0 * MG, "the lag should show by the last hold");
}

#[test]
fn hand_rotations_are_smooth_with_no_jump_at_either_end() {
    let mut spec = small(Family::Clean, 111);
    spec.session.rate_hz = 1000.0;
    spec.session.poses.truncate(6);
    spec.noise_mg = 0.0;
    let log = generate(&spec);
    let worst = (1..log.samples.len())
        .map(|i| norm(sub(spec.truth.apply(log.accel_mps2(i)), spec.truth.apply(log.accel_mps2(i - 1)))))
        .fold(0.0, f64::max);
    assert!(worst < 30.0 * MG, "largest step between 1 ms samples: {} mg", worst / MG);
}

#[test]
fn a_face_aligned_session_points_each_body_axis_up_and_down_within_its_tilt() {
    let mut spec = small(Family::Clean, 121);
    let mut rng = accelcal_host::blindgen::noise::Rng::new(1, 2);
    spec.session.align_to_faces(&mut rng);
    let log = generate(&spec);
    assert!([12, 18, 24].contains(&log.holds.len()), "{} poses", log.holds.len());
    let mut faces = [0usize; 6];
    for h in &log.holds {
        let (k, v) = (0..3).map(|k| (k, h.up_body[k])).max_by(|a, b| a.1.abs().total_cmp(&b.1.abs())).unwrap();
        let tilt_deg = v.abs().acos().to_degrees();
        assert!((0.4..2.1).contains(&tilt_deg), "tilt {tilt_deg} deg");
        faces[2 * k + usize::from(v < 0.0)] += 1;
    }
    assert!(faces.iter().all(|&n| n == log.holds.len() / 6), "faces {faces:?}");
    for r in residuals(&spec, &log, 0.0) {
        assert!(norm(r) < 1.0 * MG, "residual {r:?}");
    }
}

#[test]
fn quadratic_temperature_bias_grows_with_the_square_of_the_change() {
    let profile = TempProfile::Cycling { mean_c: 25.0, amp_c: 8.0, period_s: 90.0 };
    let b2 = [0.05 * MG, -0.1 * MG, 0.0];
    let mut effect = temp_effect([0.0; 3], [0.0; 3], None);
    effect.bias_per_c2 = b2;
    let spec = temp_spec(44, profile, effect);
    let log = generate(&spec);
    for (i, r) in residuals(&spec, &log, 0.0).iter().enumerate() {
        let h = log.holds[i];
        let square = average(|t| [(profile.at(t) - 25.0).powi(2); 3], h.start_s, h.end_s)[0];
        assert!(norm(sub(*r, scale(b2, square))) < 0.3 * MG, "hold {i}: {r:?} vs {:?}", scale(b2, square));
    }
}

#[test]
fn random_attitudes_are_uniform_on_the_sphere_of_up_directions() {
    use accelcal_host::blindgen::orientation::Quat;
    let mut rng = accelcal_host::blindgen::noise::Rng::new(3, 4);
    let n = 4000;
    let ups: Vec<V3> = (0..n).map(|_| Quat::random(&mut rng).rotate_inv([0.0, 0.0, 1.0])).collect();
    for k in 0..3 {
        let mean = ups.iter().map(|u| u[k]).sum::<f64>() / n as f64;
        let second = ups.iter().map(|u| u[k] * u[k]).sum::<f64>() / n as f64;
        // Uniform on the sphere: mean 0 (sd 1/sqrt(3n)), second moment 1/3 (sd sqrt(4/45/n)).
        assert!(mean.abs() < 4.0 / (3.0 * n as f64).sqrt(), "axis {k}: mean {mean}");
        assert!((second - 1.0 / 3.0).abs() < 4.0 * (4.0 / 45.0 / n as f64).sqrt(), "axis {k}: second moment {second}");
    }
    let faces = ups.iter().filter(|u| u.iter().any(|c| c.abs() > 0.9998)).count();
    assert!(faces < 10, "{faces} of {n} attitudes within 1 deg of a face");
}

#[test]
fn every_shape_of_every_family_is_drawn() {
    let expected: [(Family, &[&str]); 8] = [
        (Family::Clean, &["plain", "quantised", "face_aligned", "temperature_column"]),
        (Family::Drift, &["linear", "quadratic", "warm_up", "wander"]),
        (
            Family::Temperature,
            &["bias_linear", "bias_quadratic_lagged", "scale_linear", "scale_quadratic", "bias_and_scale_lagged"],
        ),
        (Family::Nonlinearity, &["square", "cube", "square_and_cube"]),
        (Family::Settling, &["exponential", "ringing", "exponential_and_ringing"]),
        (Family::Motion, &["taps", "sway", "bump"]),
        (Family::ColoredNoise, &["random_walk", "gauss_markov", "flicker"]),
        (Family::OutOfCatalogue, &["bad_pose", "mains", "hysteresis", "cross_axis"]),
    ];
    for (family, shapes) in expected {
        let drawn: Vec<String> = (0..60).map(|seed| random_small_spec(family, seed).shape).collect();
        for shape in shapes {
            assert!(drawn.iter().any(|d| d == shape), "{family:?}: {shape} never drawn in 60 seeds");
        }
        let specs = (0..60).map(|seed| random_small_spec(family, seed));
        assert!(specs.clone().all(|s| s.family == family && s.effect.is_some() == (family != Family::Clean)));
        let with_temp = specs.filter(|s| s.session.temperature.is_some()).count();
        assert!(
            family == Family::Temperature || (10..50).contains(&with_temp),
            "{family:?}: {with_temp}/60 with a thermometer"
        );
    }
}

#[test]
fn the_csv_reads_back_through_the_cli_reader_in_its_unit() {
    use accelcal_host::csvio::{self, ReadOptions};
    let cases = [(Units::Mps2, csvio::Units::Mps2), (Units::G, csvio::Units::G), (Units::COARSE, csvio::Units::Counts)];
    for (units, read_as) in cases {
        let mut spec = small(Family::Temperature, 131);
        spec.units = units;
        let log = generate(&spec);
        let table = csvio::read_csv_str("blind.csv", &log.to_csv_string(), &ReadOptions::default()).expect("readable");
        assert_eq!(table.units, read_as);
        assert_eq!(table.samples.len(), log.samples.len());
        let temps = table.temps_c.expect("a temperature column");
        let times = table.times_s.expect("a time column");
        for (i, s) in log.samples.iter().enumerate().step_by(97) {
            assert!(sub(table.samples[i], s.accel).iter().all(|d| d.abs() < 1e-5), "row {i}");
            assert!((times[i] - s.t_s).abs() < 1e-6 && (temps[i] - s.temp_c.unwrap()).abs() < 0.006, "row {i}");
        }
    }
}

#[test]
fn slow_bias_effects_come_with_a_steady_thermometer() {
    for family in [Family::Drift, Family::ColoredNoise] {
        for seed in 0..30 {
            let spec = random_small_spec(family, seed);
            if let Some(profile) = spec.session.temperature {
                assert_eq!(profile.span_c(spec.session.total_s()), 0.0, "{family:?} seed {seed}: {profile:?}");
            }
        }
    }
    let varying = (0..30).filter(|&seed| {
        let spec = random_small_spec(Family::Nonlinearity, seed);
        spec.session.temperature.is_some_and(|p| p.span_c(spec.session.total_s()) > 0.1)
    });
    assert!(varying.count() > 0, "other families keep a drifting room thermometer");
}
