//! The sample-level simulation: a [`Recording`] of every sample, poses joined by the hand's moves,
//! with [`Effect`]s, white noise and the output unit applied per sample; and its CSV form.

use std::io::{self, Write};

use glam::DQuat;
use rand_xoshiro::Xoshiro256PlusPlus;

use super::config::SimConfig;
use super::effects::Effect;
use super::model::Model64;
use super::motion::HandMove;
use super::plan::{placement_rotations, up_in_body};
use super::random::{Stream, standard_normal, stream_rng};
use super::units::OutputUnits;

/// One simulated static interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimPose {
    /// Index of the first sample of the static interval.
    pub start: usize,
    /// Index one past the last sample of the static interval.
    pub end: usize,
    /// True `f_b / g`, body frame (unit vector).
    pub direction: [f64; 3],
    /// The noise-free reading the 9-parameter model predicts, output unit (unrounded, without
    /// [`Effect`]s).
    pub true_reading: [f64; 3],
}

/// A simulated recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    /// Sample times, s (`index / rate_hz`).
    pub times_s: Vec<f64>,
    /// Readings `[x, y, z]`, output unit (whole numbers for counts).
    pub samples: Vec<[f64; 3]>,
    /// The unit of `samples`.
    pub units: OutputUnits,
    /// The static intervals, in time order.
    pub poses: Vec<SimPose>,
}

/// Simulates a recording (no extra effects). Deterministic by `cfg.seed`. An invalid configuration
/// (see [`SimConfig::validate`]) gives an empty recording.
pub fn simulate(cfg: &SimConfig) -> Recording {
    simulate_with(cfg, &mut [])
}

/// Simulates a recording with `effects` applied in order to every noise-free reading. Deterministic
/// by `cfg.seed` (given deterministic effects). An invalid configuration gives an empty recording.
pub fn simulate_with(cfg: &SimConfig, effects: &mut [&mut dyn Effect]) -> Recording {
    if cfg.validate().is_err() {
        return Recording { times_s: Vec::new(), samples: Vec::new(), units: cfg.units, poses: Vec::new() };
    }
    let rotations = placement_rotations(&cfg.plan, cfg.seed, cfg.tilt_deg, cfg.flip_deg);
    let layout = Layout::new(cfg, rotations.len());
    let mut motion_rng = stream_rng(cfg.seed, Stream::Motion);
    let mut sensor = Sensor::new(cfg, effects, layout.total_samples);
    for (i, &rotation) in rotations.iter().enumerate() {
        if i > 0 {
            sensor.carry(&HandMove::new(rotations[i - 1], rotation, &mut motion_rng), layout.move_samples);
        }
        debug_assert_eq!(sensor.recording.samples.len(), layout.pose_ranges[i].0);
        let (start, end) = layout.pose_ranges[i];
        sensor.hold(rotation, i, end - start);
    }
    sensor.recording
}

/// The simulated sensor writing the recording: the model, the effects, the noise and the unit.
struct Sensor<'c, 'e, 'f> {
    cfg: &'c SimConfig,
    model: Model64,
    effects: &'e mut [&'f mut dyn Effect],
    noise: Xoshiro256PlusPlus,
    /// White-noise standard deviation, m/s^2.
    sigma_mps2: f64,
    recording: Recording,
}

impl<'c, 'e, 'f> Sensor<'c, 'e, 'f> {
    fn new(cfg: &'c SimConfig, effects: &'e mut [&'f mut dyn Effect], samples: usize) -> Self {
        let recording = Recording {
            times_s: Vec::with_capacity(samples),
            samples: Vec::with_capacity(samples),
            units: cfg.units,
            poses: Vec::new(),
        };
        Self {
            cfg,
            model: Model64::from(&cfg.truth),
            effects,
            noise: stream_rng(cfg.seed, Stream::Noise),
            sigma_mps2: cfg.noise_mg * 1e-3 * cfg.gravity,
            recording,
        }
    }

    /// One sample of the noise-free reading `f_s` (m/s^2): effects, noise, unit.
    fn push(&mut self, f_s: [f64; 3], pose_index: Option<usize>) {
        let t_s = self.recording.samples.len() as f64 / self.cfg.rate_hz;
        let mut reading = f_s;
        for effect in self.effects.iter_mut() {
            effect.apply(t_s, pose_index, &mut reading);
        }
        let (units, gravity) = (self.cfg.units, self.cfg.gravity);
        let sample = std::array::from_fn(|a| {
            let noisy = reading[a] + self.sigma_mps2 * standard_normal(&mut self.noise);
            units.quantize(units.from_mps2(noisy, gravity))
        });
        self.recording.times_s.push(t_s);
        self.recording.samples.push(sample);
    }

    /// The `steps` samples of one move.
    fn carry(&mut self, hand_move: &HandMove, steps: usize) {
        for step in 0..steps {
            let elapsed_s = (step + 1) as f64 / self.cfg.rate_hz;
            let progress = (step + 1) as f64 / (steps + 1) as f64;
            let landing = step + 1 == steps;
            let f_b = hand_move.specific_force(progress, elapsed_s, self.cfg.gravity, landing);
            self.push(self.model.reading(f_b), None);
        }
    }

    /// The `samples` samples of static pose `index` held at `rotation`.
    fn hold(&mut self, rotation: DQuat, index: usize, samples: usize) {
        let direction = up_in_body(rotation).to_array();
        let f_s = self.model.reading(direction.map(|c| c * self.cfg.gravity));
        let start = self.recording.samples.len();
        for _ in 0..samples {
            self.push(f_s, Some(index));
        }
        let true_reading = f_s.map(|v| self.cfg.units.from_mps2(v, self.cfg.gravity));
        self.recording.poses.push(SimPose { start, end: self.recording.samples.len(), direction, true_reading });
    }
}

/// Writes `t,ax,ay,az` CSV: times with 6 decimals, counts as integers, other units with 9
/// significant digits.
pub fn write_csv(rec: &Recording, w: impl Write) -> io::Result<()> {
    let mut w = io::BufWriter::new(w);
    writeln!(w, "t,ax,ay,az")?;
    for (t, s) in rec.times_s.iter().zip(&rec.samples) {
        if rec.units.is_counts() {
            writeln!(w, "{t:.6},{},{},{}", s[0] as i64, s[1] as i64, s[2] as i64)?;
        } else {
            writeln!(w, "{t:.6},{},{},{}", significant(s[0], 9), significant(s[1], 9), significant(s[2], 9))?;
        }
    }
    w.flush()
}

/// `value` with `digits` significant digits in plain decimal notation (at most 15 decimals).
fn significant(value: f64, digits: i32) -> String {
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    let magnitude = value.abs().log10().floor() as i32;
    let decimals = (digits - 1 - magnitude).clamp(0, 15) as usize;
    format!("{value:.decimals$}")
}

/// Sample layout: pose 0 at index 0, then (move, pose) pairs.
pub(crate) struct Layout {
    /// `[start, end)` of every static interval.
    pub(crate) pose_ranges: Vec<(usize, usize)>,
    /// Samples per move.
    pub(crate) move_samples: usize,
    /// All samples.
    pub(crate) total_samples: usize,
}

impl Layout {
    pub(crate) fn new(cfg: &SimConfig, pose_count: usize) -> Self {
        let samples = |seconds: f64| (seconds * cfg.rate_hz).round().max(0.0) as usize;
        let first = samples(cfg.initial_rest_s + cfg.seconds_per_pose);
        let per_pose = samples(cfg.seconds_per_pose);
        let move_samples = samples(cfg.move_seconds);
        let mut pose_ranges = Vec::with_capacity(pose_count);
        let mut next = 0usize;
        for i in 0..pose_count {
            let (start, len) = if i == 0 { (0, first) } else { (next.saturating_add(move_samples), per_pose) };
            let end = start.saturating_add(len);
            pose_ranges.push((start, end));
            next = end;
        }
        Self { pose_ranges, move_samples, total_samples: next }
    }
}

#[cfg(test)]
#[allow(clippy::needless_range_loop)] // per-axis loops over several arrays read best indexed
mod tests {
    use super::*;
    use crate::sim::{Plan, random_truth, simulate_pose_means};
    use accelcal::accumulator::{Accumulator, AccumulatorConfig};
    use accelcal::model::Params;

    fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }

    #[test]
    fn layout_matches_config() {
        let cfg = SimConfig { initial_rest_s: 10.0, ..SimConfig::for_plan(Plan::Random(3), 1) };
        assert_eq!(cfg.initial_rest_s, 10.0);
        let rec = simulate(&cfg);
        let ranges: Vec<_> = rec.poses.iter().map(|p| (p.start, p.end)).collect();
        assert_eq!(ranges, vec![(0, 3000), (3400, 4400), (4800, 5800)]);
        assert_eq!(rec.samples.len(), 5800);
        assert_eq!(rec.times_s.len(), 5800);
        assert!((rec.times_s[200] - 1.0).abs() < 1e-12);
    }

    #[test]
    fn same_seed_same_output_different_seed_different() {
        let cfg = SimConfig { plan: Plan::Cube26, ..SimConfig::paper(42) };
        let a = simulate(&cfg);
        assert_eq!(a, simulate(&cfg));
        let b = simulate(&SimConfig { seed: 43, ..cfg.clone() });
        assert_eq!(a.samples.len(), b.samples.len());
        assert_ne!(a.samples, b.samples);
        assert_ne!(a.poses[0].direction, b.poses[0].direction);
        assert_eq!(simulate_pose_means(&cfg), simulate_pose_means(&cfg));
        assert_ne!(simulate_pose_means(&cfg), simulate_pose_means(&SimConfig { seed: 43, ..cfg }));
        assert_eq!(random_truth(5), random_truth(5));
        assert_ne!(random_truth(5), random_truth(6));
    }

    #[test]
    fn noise_does_not_change_geometry_or_motion() {
        let quiet = simulate(&SimConfig { noise_mg: 0.0, ..SimConfig::paper(8) });
        let noisy = simulate(&SimConfig::paper(8));
        assert_eq!(
            quiet.poses.iter().map(|p| p.direction).collect::<Vec<_>>(),
            noisy.poses.iter().map(|p| p.direction).collect::<Vec<_>>()
        );
        let i = quiet.poses[0].end + 10; // inside the first move
        for a in 0..3 {
            assert!((quiet.samples[i][a] - noisy.samples[i][a]).abs() < 0.1);
        }
    }

    #[test]
    fn noiseless_static_readings_are_the_inverted_truth() {
        for (plan, units) in
            [(Plan::Paper24, OutputUnits::Mps2), (Plan::Cube26, OutputUnits::G), (Plan::Random(10), OutputUnits::Mps2)]
        {
            let cfg = SimConfig { noise_mg: 0.0, units, truth: random_truth(3), ..SimConfig::for_plan(plan, 4) };
            let rec = simulate(&cfg);
            let model = Model64::from(&cfg.truth);
            let to_mps2 = if units == OutputUnits::G { cfg.gravity } else { 1.0 };
            assert_eq!(rec.poses.len(), plan.pose_count());
            for pose in &rec.poses {
                let f_b = model.apply(pose.true_reading.map(|c| c * to_mps2));
                assert!((dot(f_b, f_b).sqrt() - cfg.gravity).abs() < 1e-9, "{f_b:?}");
                for a in 0..3 {
                    assert!((f_b[a] - cfg.gravity * pose.direction[a]).abs() < 1e-9);
                }
                for sample in &rec.samples[pose.start..pose.end] {
                    assert_eq!(*sample, pose.true_reading);
                }
            }
        }
    }

    #[test]
    fn moves_differ_from_the_poses_around_them() {
        let rec = simulate(&SimConfig { noise_mg: 0.0, ..SimConfig::paper(2) });
        for pair in rec.poses.windows(2) {
            let (before, after) = (&pair[0], &pair[1]);
            // The samples right next to each static interval are moving (abrupt start and stop).
            for (index, pose) in [(before.end, before), (after.start - 1, after)] {
                let d = (0..3).map(|a| (rec.samples[index][a] - pose.true_reading[a]).abs()).fold(0.0, f64::max);
                assert!(d > 1e-4, "sample {index}: {d}");
            }
            let mid = (before.end + after.start) / 2;
            let d = (0..3).map(|a| (rec.samples[mid][a] - before.true_reading[a]).abs()).fold(0.0, f64::max);
            assert!(d > 0.05, "mid-move sample {mid}: {d}");
        }
    }

    #[test]
    fn counts_are_rounded_and_clamped() {
        let signed = SimConfig { units: OutputUnits::MPU6050_2G, ..SimConfig::paper(1) };
        let unsigned =
            SimConfig { units: OutputUnits::Counts { lsb_per_g: 16384.0, offset: 32768.0 }, ..signed.clone() };
        let tiny_range = SimConfig { units: OutputUnits::Counts { lsb_per_g: 40000.0, offset: 0.0 }, ..signed.clone() };
        for (cfg, low, high) in
            [(&signed, -32768.0, 32767.0), (&unsigned, 0.0, 65535.0), (&tiny_range, -32768.0, 32767.0)]
        {
            let rec = simulate(cfg);
            for s in &rec.samples {
                for v in s {
                    assert_eq!(v.fract(), 0.0);
                    assert!((low..=high).contains(v));
                }
            }
            if cfg == &tiny_range {
                assert!(rec.samples.iter().any(|s| s.contains(&32767.0)), "1 g = 40000 LSB must clip");
            }
        }
        let a = simulate(&signed);
        let b = simulate(&unsigned);
        assert!(a.samples.iter().zip(&b.samples).all(|(x, y)| (0..3).all(|i| y[i] - x[i] == 32768.0)));
    }

    #[test]
    fn effects_are_applied_before_noise_and_units() {
        let cfg = SimConfig { noise_mg: 0.0, units: OutputUnits::G, ..SimConfig::paper(3) };
        let mut calls = 0usize;
        let mut drift = |t_s: f64, pose: Option<usize>, reading: &mut [f64; 3]| {
            calls += 1;
            if pose.is_some() {
                reading[0] += 0.01 * t_s; // 10 mm/s^2 per second
            }
        };
        let rec = simulate_with(&cfg, &mut [&mut drift]);
        assert_eq!(calls, rec.samples.len());
        let pose = rec.poses[3];
        let i = pose.start + 17;
        let expected = pose.true_reading[0] + 0.01 * rec.times_s[i] / cfg.gravity;
        assert!((rec.samples[i][0] - expected).abs() < 1e-12);
        assert_eq!(rec.samples[i][1], pose.true_reading[1]);
    }

    #[test]
    fn static_noise_has_the_configured_std() {
        for units in [OutputUnits::Mps2, OutputUnits::MPU6050_2G] {
            let cfg = SimConfig { noise_mg: 2.0, units, ..SimConfig::paper(12) };
            let rec = simulate(&cfg);
            let sigma = units.noise_std(cfg.noise_mg, cfg.gravity);
            let expected = sigma * sigma + if units.is_counts() { 1.0 / 12.0 } else { 0.0 };
            let (mut sum_sq, mut count) = (0.0, 0.0);
            for pose in &rec.poses {
                for s in &rec.samples[pose.start..pose.end] {
                    for a in 0..3 {
                        sum_sq += (s[a] - pose.true_reading[a]).powi(2);
                        count += 1.0;
                    }
                }
            }
            let variance = sum_sq / count; // 72000 values: relative std 0.5 %
            assert!((variance / expected - 1.0).abs() < 0.03, "{units}: {variance} vs {expected}");
        }
    }

    #[test]
    fn invalid_configs_are_rejected_without_panicking() {
        let bad = [
            SimConfig { rate_hz: 0.0, ..SimConfig::default() },
            SimConfig { rate_hz: f64::NAN, ..SimConfig::default() },
            SimConfig { seconds_per_pose: 0.0, ..SimConfig::default() },
            SimConfig { move_seconds: -1.0, ..SimConfig::default() },
            SimConfig { noise_mg: f64::INFINITY, ..SimConfig::default() },
            SimConfig { gravity: 0.0, ..SimConfig::default() },
            SimConfig { truth: Params { scale: [1.0, 0.0, 1.0], ..Params::IDENTITY }, ..SimConfig::default() },
            SimConfig { units: OutputUnits::Counts { lsb_per_g: 0.0, offset: 0.0 }, ..SimConfig::default() },
            SimConfig { plan: Plan::Random(0), ..SimConfig::default() },
            SimConfig { rate_hz: 1e12, ..SimConfig::default() },
        ];
        for cfg in bad {
            assert!(cfg.validate().is_err(), "{cfg:?}");
            assert!(simulate(&cfg).samples.is_empty());
            assert!(simulate_pose_means(&cfg).is_empty());
        }
        assert_eq!(SimConfig::default().validate(), Ok(()));
        let error = SimConfig { rate_hz: -1.0, ..SimConfig::default() }.validate().unwrap_err();
        assert!(error.to_string().contains("rate_hz"));
    }

    #[test]
    fn csv_has_header_and_formats() {
        let cfg =
            SimConfig { plan: Plan::Random(1), initial_rest_s: 0.0, seconds_per_pose: 0.02, ..SimConfig::default() };
        let rec = simulate(&cfg);
        let mut out = Vec::new();
        write_csv(&rec, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let lines: Vec<_> = text.lines().collect();
        assert_eq!(lines.len(), 5);
        assert_eq!(lines[0], "t,ax,ay,az");
        assert!(lines[2].starts_with("0.005000,"), "{}", lines[2]);
        let values: Vec<f64> = lines[1].split(',').map(|v| v.parse().unwrap()).collect();
        for a in 0..3 {
            let digits = lines[1].split(',').nth(a + 1).unwrap().chars().filter(char::is_ascii_digit).count();
            assert!((9..=10).contains(&digits) || values[a + 1].abs() < 1e-3, "{}", lines[1]);
            assert!((values[a + 1] - rec.samples[0][a]).abs() <= 1e-8 * rec.samples[0][a].abs().max(1.0));
        }
        let counts = simulate(&SimConfig { units: OutputUnits::MPU6050_2G, ..cfg });
        let mut out = Vec::new();
        write_csv(&counts, &mut out).unwrap();
        let text = String::from_utf8(out).unwrap();
        let row: Vec<i64> = text.lines().nth(1).unwrap().split(',').skip(1).map(|v| v.parse().unwrap()).collect();
        assert_eq!(row, counts.samples[0].map(|v| v as i64).to_vec());
        assert_eq!(significant(0.000123456789123, 9), "0.000123456789");
        assert_eq!(significant(-9.80665, 9), "-9.80665000");
    }

    #[test]
    fn accumulator_finds_every_paper24_pose() {
        for seed in 0..8 {
            let rec = simulate(&SimConfig::paper(seed));
            let mut acc: Accumulator<f32, 64, 32> = Accumulator::new(AccumulatorConfig::default()).unwrap();
            for s in &rec.samples {
                acc.push(s.map(|v| v as f32)).unwrap();
            }
            acc.finish().unwrap();
            let found = acc.poses();
            assert_eq!(
                found.len(),
                24,
                "seed {seed}: rejections {:?}, noise variance {}",
                acc.rejections(),
                acc.noise_variance()
            );
            for (pose, sim_pose) in found.iter().zip(&rec.poses) {
                let (start, end) = (pose.start_index as usize, pose.end_index as usize);
                assert!(
                    sim_pose.start <= start && end <= sim_pose.end,
                    "seed {seed}: found {start}..{end} in {}..{}",
                    sim_pose.start,
                    sim_pose.end
                );
                assert!(end - start >= 800, "seed {seed}: only {} samples", end - start);
            }
        }
    }
}
