//! Random scenarios for `accelcal diagnose` and its tests: a hand-placed session with a
//! temperature column and one effect of the catalogue ([`super::effects`]) injected as physics, or an
//! effect outside the catalogue ([`Outside`]), or another shape of a catalogue effect ([`Shape`]).
//!
//! Every scenario has a temperature profile that is *not* monotonic in time (two slow sinusoids),
//! written to the `temp` column whether or not the temperature acts on the sensor. Magnitudes are
//! realistic: each effect moves the pose means by one to a few mg.
//!
//! ```
//! use accelcal_host::sim::scenario::{EffectClass, random_scenario, generate};
//! let scenario = random_scenario(EffectClass::Drift, 3);
//! let log = generate(&scenario);
//! assert_eq!(log.temps_c.len(), log.recording.samples.len());
//! assert_eq!(log.recording.poses.len(), scenario.sim.plan.pose_count());
//! ```

use std::fmt::Write as _;

use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::csvio::{self, CsvError, ReadOptions, Table, Units};
use crate::sim::effects::{
    ColoredBias, ScaleNonlinearity, Settling, SlowMotion, TemperatureEffect, TemperatureProfile, WarmUpDrift,
};
use crate::sim::random::{random_sign, uniform_in, unit_vector};
use crate::sim::{self, OutputUnits, Plan, Recording, SimConfig};

/// The effect a scenario injects (the diagnosis classes).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum EffectClass {
    /// Nothing beyond the 9-parameter model and white noise.
    None,
    /// Bias warming up with time: `A (1 - exp(-t / tau))` per axis.
    Drift,
    /// Bias and/or scale linear in the temperature.
    Temperature,
    /// `k2 a^2` per axis.
    ScaleNonlinearity,
    /// A transient toward the previous pose's reading at the start of each pose.
    Settling,
    /// Some poses disturbed by a slow movement that the static detector accepts.
    Motion,
    /// A bias random walk on top of the white noise.
    ColoredNoise,
}

impl EffectClass {
    /// Every class, `None` first.
    pub const ALL: [Self; 7] = [
        Self::None,
        Self::Drift,
        Self::Temperature,
        Self::ScaleNonlinearity,
        Self::Settling,
        Self::Motion,
        Self::ColoredNoise,
    ];

    /// The name `accelcal diagnose` reports (`none`, `drift`, `temperature`, `scale-nonlinearity`,
    /// `settling`, `motion`, `colored-noise`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::None => "none",
            Self::Drift => "drift",
            Self::Temperature => "temperature",
            Self::ScaleNonlinearity => "scale-nonlinearity",
            Self::Settling => "settling",
            Self::Motion => "motion",
            Self::ColoredNoise => "colored-noise",
        }
    }
}

/// The injected effect with its true magnitudes (m/s^2 convention).
#[derive(Debug, Clone, PartialEq)]
pub enum Injected {
    /// Nothing.
    None,
    /// Warm-up drift: final bias change per axis (m/s^2) and time constant (s).
    Drift {
        /// Final bias change per axis, m/s^2.
        amplitude: [f64; 3],
        /// Time constant, s.
        tau_s: f64,
    },
    /// Temperature: bias (m/s^2 per deg C) and relative scale (per deg C) coefficients around
    /// `reference_c`.
    Temperature {
        /// Bias coefficient per axis, m/s^2 / deg C.
        bias_per_c: [f64; 3],
        /// Relative scale coefficient per axis, 1 / deg C.
        scale_per_c: [f64; 3],
        /// Reference temperature, deg C.
        reference_c: f64,
    },
    /// Second-order term per axis, 1 / (m/s^2).
    ScaleNonlinearity {
        /// `k2` per axis.
        k2: [f64; 3],
    },
    /// Settling: fraction of the previous pose's reading change left at the start of a pose,
    /// per axis, and its decay time, s.
    Settling {
        /// Lag fraction per axis.
        lag: [f64; 3],
        /// Decay time, s.
        tau_s: f64,
    },
    /// Slow motion: `(pose index, unit direction in sensor axes, peak m/s^2)` per disturbed pose.
    Motion {
        /// The disturbed poses.
        poses: Vec<(usize, [f64; 3], f64)>,
    },
    /// Bias random walk (m/s^2 per sqrt(s) per axis) and/or bias instability (a first-order
    /// Gauss-Markov bias of standard deviation m/s^2 per axis and correlation time s).
    ColoredNoise {
        /// Random-walk coefficient per axis.
        walk: [f64; 3],
        /// Bias-instability standard deviation per axis.
        instability: [f64; 3],
        /// Bias-instability correlation time, s.
        correlation_s: f64,
    },
}

/// One random log to diagnose.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// The class injected.
    pub class: EffectClass,
    /// The simulator settings (plan, noise, truth, units, seed).
    pub sim: SimConfig,
    /// The temperature profile (always written, acts only for [`EffectClass::Temperature`]).
    pub temperature: TemperatureProfile,
    /// The effect and its magnitudes.
    pub injected: Injected,
}

/// A simulated log with its temperature column.
#[derive(Debug, Clone, PartialEq)]
pub struct SimLog {
    /// The recording.
    pub recording: Recording,
    /// Temperature per sample, deg C.
    pub temps_c: Vec<f64>,
}

/// `true` when every axis points within 20 deg of up and of down in some direction.
pub(crate) fn covers_every_axis(directions: &[[f64; 3]]) -> bool {
    (0..3).all(|a| [1.0, -1.0].iter().all(|s| directions.iter().any(|d| s * d[a] > 0.94)))
}

/// A random scenario of `class`, deterministic by `seed`: hand-placed random orientations (24 to 44
/// poses of 4 to 8 s, a 40 to 90 s first rest), 100 or 200 Hz, 0.5 to 2 mg white noise, random
/// sensor errors and output units, a non-monotonic temperature profile, and the effect with a
/// random magnitude of one to a few mg.
pub fn random_scenario(class: EffectClass, seed: u64) -> Scenario {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5EED_D1A6_0000_0000);
    let poses = 24 + (rng.next_u64() % 21) as usize;
    // Hand-placed orientations that point every axis up and down once (the coarse calibration needs
    // it): the geometry seed is advanced until they do.
    let mut sim_seed = seed;
    while !covers_every_axis(&sim::plan_directions(&Plan::Random(poses), sim_seed)) {
        sim_seed = sim_seed.wrapping_add(0x1_0000_0000);
    }
    let units = match rng.next_u64() % 3 {
        0 => OutputUnits::Mps2,
        1 => OutputUnits::G,
        _ => OutputUnits::MPU6050_2G,
    };
    let cfg = SimConfig {
        plan: Plan::Random(poses),
        seed: sim_seed,
        rate_hz: if rng.next_u64() & 1 == 0 { 100.0 } else { 200.0 },
        seconds_per_pose: uniform_in(&mut rng, 4.0, 8.0),
        move_seconds: uniform_in(&mut rng, 1.5, 3.0),
        initial_rest_s: uniform_in(&mut rng, 40.0, 90.0),
        noise_mg: uniform_in(&mut rng, 0.5, 2.0),
        truth: sim::random_truth(seed),
        units,
        ..SimConfig::paper(sim_seed)
    };
    let duration = cfg.initial_rest_s + poses as f64 * (cfg.seconds_per_pose + cfg.move_seconds) - cfg.move_seconds;
    // Two slow waves: at least one full period of the faster one fits in the log (not monotonic).
    let temperature = TemperatureProfile {
        base_c: uniform_in(&mut rng, 20.0, 35.0),
        waves: [
            (uniform_in(&mut rng, 1.5, 4.0), duration * uniform_in(&mut rng, 0.3, 0.7), uniform_in(&mut rng, 0.0, 6.3)),
            (
                uniform_in(&mut rng, 0.5, 1.5),
                duration * uniform_in(&mut rng, 0.1, 0.25),
                uniform_in(&mut rng, 0.0, 6.3),
            ),
        ],
    };
    let injected = random_injected(class, &mut rng, poses, duration);
    Scenario { class, sim: cfg, temperature, injected }
}

/// The effect of `class` with random magnitudes for a log of `poses` poses lasting `duration` s.
fn random_injected(class: EffectClass, rng: &mut Xoshiro256PlusPlus, poses: usize, duration: f64) -> Injected {
    let g = sim::STANDARD_GRAVITY_MPS2;
    let mg = g * 1e-3;
    match class {
        EffectClass::None => Injected::None,
        EffectClass::Drift => Injected::Drift {
            amplitude: std::array::from_fn(|_| random_sign(rng) * uniform_in(rng, 1.5, 5.0) * mg),
            tau_s: duration * uniform_in(rng, 0.15, 0.6),
        },
        EffectClass::Temperature => {
            let which = rng.next_u64() % 3; // bias, scale or both
            let bias = which != 1;
            let scale = which != 0;
            Injected::Temperature {
                bias_per_c: std::array::from_fn(|_| {
                    if bias { random_sign(rng) * uniform_in(rng, 0.4, 1.2) * mg } else { 0.0 }
                }),
                scale_per_c: std::array::from_fn(|_| {
                    if scale { random_sign(rng) * uniform_in(rng, 300e-6, 1000e-6) } else { 0.0 }
                }),
                reference_c: 25.0,
            }
        }
        EffectClass::ScaleNonlinearity => Injected::ScaleNonlinearity {
            k2: std::array::from_fn(|_| random_sign(rng) * uniform_in(rng, 1.5, 5.0) * 1e-3 / g),
        },
        EffectClass::Settling => Injected::Settling {
            lag: std::array::from_fn(|_| uniform_in(rng, 0.002, 0.006)),
            tau_s: uniform_in(rng, 0.5, 2.0),
        },
        EffectClass::Motion => {
            let count = ((poses as f64 * uniform_in(rng, 0.12, 0.3)).round() as usize).max(2);
            let mut chosen: Vec<usize> = Vec::new();
            while chosen.len() < count {
                let i = 1 + (rng.next_u64() % (poses as u64 - 1)) as usize;
                if !chosen.contains(&i) {
                    chosen.push(i);
                }
            }
            chosen.sort_unstable();
            Injected::Motion {
                poses: chosen.into_iter().map(|i| (i, unit_vector(rng), uniform_in(rng, 3.0, 10.0) * mg)).collect(),
            }
        }
        EffectClass::ColoredNoise => {
            let kind = rng.next_u64() % 3; // random walk, bias instability or both
            Injected::ColoredNoise {
                walk: std::array::from_fn(|_| if kind != 1 { uniform_in(rng, 0.05, 0.2) * mg } else { 0.0 }),
                instability: std::array::from_fn(|_| if kind != 0 { uniform_in(rng, 0.5, 2.0) * mg } else { 0.0 }),
                correlation_s: uniform_in(rng, 20.0, 200.0),
            }
        }
    }
}

/// Simulates the scenario's log: the recording with its effect and the temperature per sample.
pub fn generate(scenario: &Scenario) -> SimLog {
    let cfg = &scenario.sim;
    let recording = match &scenario.injected {
        Injected::None => sim::simulate(cfg),
        Injected::Drift { amplitude, tau_s } => {
            sim::simulate_with(cfg, &mut [&mut WarmUpDrift { amplitude: *amplitude, tau_s: *tau_s }])
        }
        Injected::Temperature { bias_per_c, scale_per_c, reference_c } => sim::simulate_with(
            cfg,
            &mut [&mut TemperatureEffect {
                profile: scenario.temperature,
                bias_per_c: *bias_per_c,
                scale_per_c: *scale_per_c,
                reference_c: *reference_c,
            }],
        ),
        Injected::ScaleNonlinearity { k2 } => sim::simulate_with(cfg, &mut [&mut ScaleNonlinearity { k2: *k2 }]),
        Injected::Settling { lag, tau_s } => sim::simulate_with(cfg, &mut [&mut Settling::new(*lag, *tau_s)]),
        Injected::Motion { poses } => {
            sim::simulate_with(cfg, &mut [&mut SlowMotion::new(poses.clone(), cfg.seconds_per_pose)])
        }
        Injected::ColoredNoise { walk, instability, correlation_s } => {
            sim::simulate_with(cfg, &mut [&mut ColoredBias::new(*walk, *instability, *correlation_s, cfg.seed)])
        }
    };
    with_thermometer(recording, &scenario.temperature)
}

/// The recording with the thermometer's column: `profile` at every sample time, to 0.01 deg C.
fn with_thermometer(recording: Recording, profile: &TemperatureProfile) -> SimLog {
    let temps_c = recording.times_s.iter().map(|&t| (profile.at(t) * 100.0).round() / 100.0).collect();
    SimLog { recording, temps_c }
}

/// Effects outside the diagnosis catalogue (a diagnosis should answer `none` or `unexplained`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Outside {
    /// One pose offset by 5 to 15 mg along a random direction (a bad pose).
    OneBadPose,
    /// Cross-axis coupling: `c a_b a_c / g` added to axis `a` (products of two other axes).
    CrossAxis,
    /// Hysteresis: a bias that follows the direction of the last rotation (the change from the
    /// previous pose), not the orientation itself.
    Hysteresis,
    /// A slow periodic bias (a few periods over the log, e.g. pickup from a cyclic heater).
    PeriodicBias,
}

impl Outside {
    /// Every kind.
    pub const ALL: [Self; 4] = [Self::OneBadPose, Self::CrossAxis, Self::Hysteresis, Self::PeriodicBias];

    /// A short name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::OneBadPose => "one-bad-pose",
            Self::CrossAxis => "cross-axis",
            Self::Hysteresis => "hysteresis",
            Self::PeriodicBias => "periodic-bias",
        }
    }
}

/// A clean random scenario (as [`random_scenario`] with [`EffectClass::None`]) with an
/// out-of-catalogue effect applied.
pub fn generate_outside(kind: Outside, seed: u64) -> SimLog {
    let scenario = random_scenario(EffectClass::None, seed);
    let cfg = &scenario.sim;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x0075_1DE0);
    let mg = sim::STANDARD_GRAVITY_MPS2 * 1e-3;
    let poses = cfg.plan.pose_count();
    let recording = match kind {
        Outside::OneBadPose => {
            let bad = 1 + (rng.next_u64() % (poses as u64 - 1)) as usize;
            let offset = unit_vector(&mut rng).map(|c| c * uniform_in(&mut rng, 5.0, 15.0) * mg);
            sim::simulate_with(
                cfg,
                &mut [&mut |_t: f64, pose: Option<usize>, r: &mut [f64; 3]| {
                    if pose == Some(bad) {
                        (0..3).for_each(|a| r[a] += offset[a]);
                    }
                }],
            )
        }
        Outside::CrossAxis => {
            let c: [f64; 3] = std::array::from_fn(|_| random_sign(&mut rng) * uniform_in(&mut rng, 3.0, 8.0) * 1e-3);
            let g = sim::STANDARD_GRAVITY_MPS2;
            sim::simulate_with(
                cfg,
                &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    let x = *r;
                    r[0] += c[0] * x[1] * x[2] / g;
                    r[1] += c[1] * x[0] * x[2] / g;
                    r[2] += c[2] * x[0] * x[1] / g;
                }],
            )
        }
        Outside::Hysteresis => {
            let h: [f64; 3] = std::array::from_fn(|_| uniform_in(&mut rng, 3.0, 8.0) * mg);
            let (mut last, mut previous_pose, mut bias) = (None::<[f64; 3]>, None, [0.0; 3]);
            sim::simulate_with(
                cfg,
                &mut [&mut |_t: f64, pose: Option<usize>, r: &mut [f64; 3]| {
                    if pose.is_some() && pose != previous_pose {
                        if let Some(l) = last {
                            bias = std::array::from_fn(|a| h[a] * (r[a] - l[a]).signum());
                        }
                        last = Some(*r);
                        previous_pose = pose;
                    }
                    (0..3).for_each(|a| r[a] += bias[a]);
                }],
            )
        }
        Outside::PeriodicBias => {
            let amp: [f64; 3] = std::array::from_fn(|_| uniform_in(&mut rng, 2.0, 5.0) * mg);
            let period = uniform_in(&mut rng, 40.0, 90.0);
            let phase = uniform_in(&mut rng, 0.0, 6.3);
            sim::simulate_with(
                cfg,
                &mut [&mut |t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    let k = (std::f64::consts::TAU * t / period + phase).sin();
                    (0..3).for_each(|a| r[a] += amp[a] * k);
                }],
            )
        }
    };
    with_thermometer(recording, &scenario.temperature)
}

/// Other shapes of the catalogue's effects than [`random_scenario`] injects (the diagnosis should
/// still name the family).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Shape {
    /// Drift: a warm-up with two time constants (fast and slow, opposite signs possible).
    TwoStageDrift,
    /// Drift: a slow smooth wander, quadratic in time.
    CurvedDrift,
    /// Temperature: bias linear in the temperature the sensor sees, which lags the thermometer
    /// by a first-order lag of 60 to 300 s.
    LaggedTemperature,
    /// Scale non-linearity: an odd, cubic term per axis.
    CubicNonlinearity,
}

impl Shape {
    /// Every shape.
    pub const ALL: [Self; 4] =
        [Self::TwoStageDrift, Self::CurvedDrift, Self::LaggedTemperature, Self::CubicNonlinearity];

    /// The family the diagnosis should name.
    pub const fn family(self) -> EffectClass {
        match self {
            Self::TwoStageDrift | Self::CurvedDrift => EffectClass::Drift,
            Self::LaggedTemperature => EffectClass::Temperature,
            Self::CubicNonlinearity => EffectClass::ScaleNonlinearity,
        }
    }

    /// A short name.
    pub const fn name(self) -> &'static str {
        match self {
            Self::TwoStageDrift => "two-stage-drift",
            Self::CurvedDrift => "curved-drift",
            Self::LaggedTemperature => "lagged-temperature",
            Self::CubicNonlinearity => "cubic-nonlinearity",
        }
    }
}

/// A clean random scenario (as [`random_scenario`] with [`EffectClass::None`]) with one of the
/// other shapes applied.
pub fn generate_shape(shape: Shape, seed: u64) -> SimLog {
    let scenario = random_scenario(EffectClass::None, seed);
    let cfg = &scenario.sim;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x05A4_E000);
    let g = sim::STANDARD_GRAVITY_MPS2;
    let mg = g * 1e-3;
    let poses = cfg.plan.pose_count();
    let duration = cfg.initial_rest_s + poses as f64 * (cfg.seconds_per_pose + cfg.move_seconds);
    let amp = |rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64| -> [f64; 3] {
        std::array::from_fn(|_| random_sign(rng) * uniform_in(rng, lo, hi) * mg)
    };
    let recording = match shape {
        Shape::TwoStageDrift => {
            let (a1, a2) = (amp(&mut rng, 1.5, 4.0), amp(&mut rng, 1.5, 4.0));
            let (t1, t2) = (duration * uniform_in(&mut rng, 0.03, 0.1), duration * uniform_in(&mut rng, 0.4, 1.0));
            sim::simulate_with(
                cfg,
                &mut [&mut |t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    let (k1, k2) = (1.0 - (-t / t1).exp(), 1.0 - (-t / t2).exp());
                    (0..3).for_each(|a| r[a] += a1[a] * k1 + a2[a] * k2);
                }],
            )
        }
        Shape::CurvedDrift => {
            let (a1, a2) = (amp(&mut rng, 0.0, 2.0), amp(&mut rng, 2.0, 5.0));
            sim::simulate_with(
                cfg,
                &mut [&mut |t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    let x = t / duration;
                    (0..3).for_each(|a| r[a] += a1[a] * x + a2[a] * x * x);
                }],
            )
        }
        Shape::LaggedTemperature => {
            let bias = amp(&mut rng, 0.6, 1.5);
            let lag = uniform_in(&mut rng, 60.0, 300.0);
            let profile = scenario.temperature;
            let (mut sensor_c, mut last_t) = (None::<f64>, 0.0);
            sim::simulate_with(
                cfg,
                &mut [&mut |t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    let seen = sensor_c.get_or_insert(profile.at(t));
                    *seen += (1.0 - (-(t - last_t).max(0.0) / lag).exp()) * (profile.at(t) - *seen);
                    last_t = t;
                    let dt = *seen - profile.base_c;
                    (0..3).for_each(|a| r[a] += bias[a] * dt);
                }],
            )
        }
        Shape::CubicNonlinearity => {
            let k3: [f64; 3] = std::array::from_fn(|_| random_sign(&mut rng) * uniform_in(&mut rng, 1.5, 5.0) * 1e-3);
            sim::simulate_with(
                cfg,
                &mut [&mut |_t: f64, _p: Option<usize>, r: &mut [f64; 3]| {
                    (0..3).for_each(|a| r[a] += k3[a] * g * (r[a] / g).powi(3));
                }],
            )
        }
    };
    with_thermometer(recording, &scenario.temperature)
}

/// The log as `t,ax,ay,az,temp` CSV text (counts as integers, other units with 10 significant
/// digits, temperatures with 2 decimals).
pub fn to_csv_string(log: &SimLog) -> String {
    let rec = &log.recording;
    let mut out = String::with_capacity(rec.samples.len() * 48);
    out.push_str("t,ax,ay,az,temp\n");
    for ((t, s), temp) in rec.times_s.iter().zip(&rec.samples).zip(&log.temps_c) {
        if rec.units.is_counts() {
            let _ = writeln!(out, "{t:.6},{},{},{},{temp:.2}", s[0] as i64, s[1] as i64, s[2] as i64);
        } else {
            let _ = writeln!(out, "{t:.6},{:.9e},{:.9e},{:.9e},{temp:.2}", s[0], s[1], s[2]);
        }
    }
    out
}

/// The log read back through the CSV reader (units declared), as `accelcal diagnose` would see the
/// file.
pub fn to_table(log: &SimLog, name: &str) -> Result<Table, CsvError> {
    let units = match log.recording.units {
        OutputUnits::Counts { .. } => Units::Counts,
        OutputUnits::G => Units::G,
        OutputUnits::Mps2 => Units::Mps2,
    };
    csvio::read_csv_str(name, &to_csv_string(log), &ReadOptions { units, ..ReadOptions::default() })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn temperature_profiles_are_not_monotonic() {
        for seed in 0..50 {
            let s = random_scenario(EffectClass::None, seed);
            let log = generate(&s);
            let t = &log.temps_c;
            let (first, last) = (t[0], t[t.len() - 1]);
            let (lo, hi) = t.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| (l.min(*v), h.max(*v)));
            // An interior extreme at least 0.1 deg C beyond both ends.
            assert!(hi > first.max(last) + 0.1 || lo < first.min(last) - 0.1, "seed {seed}");
        }
    }

    #[test]
    fn effects_change_the_pose_readings_by_a_few_mg() {
        for class in EffectClass::ALL {
            let s = random_scenario(class, 11);
            let clean = sim::simulate(&SimConfig { noise_mg: 0.0, ..s.sim.clone() });
            let log = generate(&Scenario { sim: SimConfig { noise_mg: 0.0, ..s.sim.clone() }, ..s.clone() });
            let g_unit =
                s.sim.units.from_mps2(s.sim.gravity, s.sim.gravity) - s.sim.units.from_mps2(0.0, s.sim.gravity);
            let mut largest = 0.0f64;
            for p in &clean.poses {
                for i in p.start..p.end {
                    for a in 0..3 {
                        let d = (log.recording.samples[i][a] - clean.samples[i][a]).abs() / g_unit * 1000.0;
                        largest = largest.max(d);
                    }
                }
            }
            if class == EffectClass::None {
                assert!(largest < 0.1, "{largest}");
            } else {
                assert!((0.5..40.0).contains(&largest), "{}: {largest} mg", class.name());
            }
        }
    }

    #[test]
    fn csv_round_trip_keeps_the_temperature() {
        let log = generate(&random_scenario(EffectClass::Temperature, 2));
        let table = to_table(&log, "sim").unwrap();
        assert_eq!(table.samples.len(), log.recording.samples.len());
        assert_eq!(table.temps_c.as_ref().map(Vec::len), Some(log.temps_c.len()));
    }
}
