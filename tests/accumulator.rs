//! The accumulator's poses are the exact means of static samples; motion, saturation and short
//! intervals are rejected; thresholds follow the measured noise.

use accelcal::accumulator::{Accumulator, AccumulatorConfig, AccumulatorError, Event, Rejection};

/// A deterministic noise source: uniform integers in `[-a, a]`.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self, a: i32) -> i32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 33) % (2 * a as u64 + 1)) as i32 - a
    }
}

/// Static segments at `levels` (counts) of `len` samples with noise `a`, joined by ramps of `ramp`.
fn stream(levels: &[[i32; 3]], len: usize, ramp: usize, a: i32, seed: u64) -> (Vec<[i16; 3]>, Vec<(usize, usize)>) {
    let mut rng = Lcg(seed);
    let mut out = Vec::new();
    let mut segments = Vec::new();
    let mut last = levels[0];
    for (k, level) in levels.iter().enumerate() {
        if k > 0 {
            for i in 0..ramp {
                let f = i as f64 / ramp as f64;
                let v: [i16; 3] = core::array::from_fn(|j| {
                    (last[j] as f64 + (level[j] - last[j]) as f64 * f) as i16 + rng.next(40) as i16
                });
                out.push(v);
            }
        }
        let start = out.len();
        for _ in 0..len {
            out.push(core::array::from_fn(|j| (level[j] + rng.next(a)) as i16));
        }
        segments.push((start, out.len()));
        last = *level;
    }
    (out, segments)
}

const LEVELS: [[i32; 3]; 6] =
    [[16384, 10, -20], [-16300, 5, 30], [0, 16500, 0], [40, -16200, 12], [-8, 30, 16390], [3, -1, -16370]];

#[test]
fn poses_are_the_exact_means_of_static_samples() {
    let (samples, segments) = stream(&LEVELS, 2500, 300, 6, 1);
    let mut acc: Accumulator<i16, 16, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    for s in &samples {
        acc.push(*s).unwrap();
    }
    acc.finish().unwrap();
    assert_eq!(acc.poses().len(), LEVELS.len(), "{:?}", acc.rejections());
    for (pose, (start, end)) in acc.poses().iter().zip(&segments) {
        let (s, e) = (pose.start_index as usize, pose.end_index as usize);
        assert!(s >= *start && e <= *end, "pose {s}..{e} outside static {start}..{end}");
        assert!(e - s >= (end - start) * 9 / 10, "pose {s}..{e} misses much of {start}..{end}");
        assert_eq!(pose.n as usize, e - s);
        for axis in 0..3 {
            let sum: i64 = samples[s..e].iter().map(|v| i64::from(v[axis])).sum();
            let mean = sum as f64 / (e - s) as f64;
            assert_eq!(pose.mean[axis], mean as f32, "axis {axis}");
            let var = samples[s..e].iter().map(|v| (f64::from(v[axis]) - mean).powi(2)).sum::<f64>() / (e - s) as f64;
            assert!((f64::from(pose.variance[axis]) - var).abs() <= 1e-6 * var.max(1.0));
        }
    }
}

#[test]
fn long_pose_sums_do_not_drift() {
    // 60 000 samples of one pose near full scale: integer sums stay exact.
    let mut rng = Lcg(7);
    let mut acc: Accumulator<i16, 4, 64> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    let mut sums = [0i64; 3];
    let mut all = Vec::new();
    for _ in 0..60_000 {
        let v: [i16; 3] = [30000 + rng.next(3) as i16, -29000 + rng.next(3) as i16, 123 + rng.next(3) as i16];
        all.push(v);
        acc.push(v).unwrap();
    }
    acc.finish().unwrap();
    let pose = acc.poses()[0];
    for v in &all[pose.start_index as usize..pose.end_index as usize] {
        for a in 0..3 {
            sums[a] += i64::from(v[a]);
        }
    }
    for (mean, sum) in pose.mean.iter().zip(sums) {
        assert_eq!(*mean, (sum as f64 / f64::from(pose.n)) as f32);
    }
    assert!(pose.n > 59_000);
}

#[test]
fn float_samples_average_exactly_too() {
    let (samples, segments) = stream(&LEVELS, 1500, 200, 4, 3);
    let to_g = |v: i16| f32::from(v) / 16384.0;
    let mut acc: Accumulator<f32, 16, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    for s in &samples {
        acc.push(s.map(to_g)).unwrap();
    }
    acc.finish().unwrap();
    assert_eq!(acc.poses().len(), segments.len());
    for pose in acc.poses() {
        let range = pose.start_index as usize..pose.end_index as usize;
        for a in 0..3 {
            let mean = samples[range.clone()].iter().map(|v| f64::from(to_g(v[a]))).sum::<f64>() / f64::from(pose.n);
            assert_eq!(pose.mean[a], mean as f32);
        }
    }
}

#[test]
fn thresholds_follow_the_noise_of_the_sensor() {
    // The same motion pattern at 10x the noise still yields the poses: nothing is tuned to one sensor.
    for a in [2, 20, 200] {
        let (samples, _) = stream(&LEVELS, 2000, 400, a, 11);
        let mut acc: Accumulator<i16, 16, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
        for s in &samples {
            acc.push(*s).unwrap();
        }
        acc.finish().unwrap();
        assert_eq!(acc.poses().len(), LEVELS.len(), "noise +-{a}: {:?}", acc.rejections());
        // Uniform noise on [-a, a]: variance a(a+1)/3 per axis.
        let expected = 3.0 * (a * (a + 1)) as f32 / 3.0;
        let ratio = acc.noise_variance() / expected;
        assert!((0.4..=1.1).contains(&ratio), "noise estimate {} vs {expected}", acc.noise_variance());
    }
}

#[test]
fn short_saturated_and_slowly_turning_intervals_are_not_poses() {
    let mut rng = Lcg(5);
    let mut acc: Accumulator<i16, 16, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    let mut events = Vec::new();
    let mut feed = |acc: &mut Accumulator<i16, 16, 32>, v: [i16; 3]| {
        if let Some(e) = acc.push(v).unwrap() {
            events.push(e);
        }
    };
    let still =
        |rng: &mut Lcg, level: [i16; 3]| -> [i16; 3] { core::array::from_fn(|j| level[j] + rng.next(5) as i16) };
    // A good pose first (sets the noise), then motion.
    for _ in 0..2000 {
        feed(&mut acc, still(&mut rng, [0, 0, 16384]));
    }
    for i in 0..200 {
        feed(&mut acc, [i * 80, 0, 16384 - i * 40]);
    }
    // Too short: 80 samples still.
    for _ in 0..80 {
        feed(&mut acc, still(&mut rng, [16000, 0, 8000]));
    }
    for i in 0..200 {
        feed(&mut acc, [16000 - i * 80, i * 80, 8000]);
    }
    // A slow turn (0.5 count per sample, variance within a block close to the noise): no pose.
    for i in 0..2000 {
        let v = still(&mut rng, [16000 - 3200, 3200, 8000]);
        feed(&mut acc, [v[0] + (i / 2) as i16, v[1], v[2] - (i / 4) as i16]);
    }
    // Saturated: rails.
    for _ in 0..1000 {
        feed(&mut acc, [i16::MAX, 16000, 0]);
    }
    for i in 0..200 {
        feed(&mut acc, [32000 - i * 100, 16000 - i * 50, 0]);
    }
    acc.finish().unwrap();
    let r = acc.rejections();
    assert_eq!(acc.poses().len(), 1, "{r:?} {events:?}");
    assert_eq!((r.too_short, r.saturated), (1, 1), "{r:?}");
    assert!(events.contains(&Event::PoseRejected(Rejection::Saturated)));
}

#[test]
fn full_capacity_is_an_error_and_keeps_what_was_captured() {
    let (samples, _) = stream(&LEVELS, 1000, 300, 4, 9);
    let mut acc: Accumulator<i16, 3, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    let mut full = 0;
    for s in &samples {
        if acc.push(*s) == Err(AccumulatorError::Full) {
            full += 1;
        }
    }
    assert_eq!(acc.finish(), Err(AccumulatorError::Full));
    assert_eq!(acc.poses().len(), 3);
    assert_eq!(full, 2);
}

#[test]
fn non_finite_samples_are_skipped_with_an_error() {
    let mut acc: Accumulator<f32, 4, 16> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    assert_eq!(acc.push([f32::NAN, 0.0, 1.0]), Err(AccumulatorError::NonFiniteSample));
    assert_eq!(acc.push([0.0, f32::INFINITY, 1.0]), Err(AccumulatorError::NonFiniteSample));
    assert_eq!(acc.samples_seen(), 2);
    assert!(acc.push([0.0, 0.0, 1.0]).is_ok());
    let bad = AccumulatorConfig { exit_factor: 1.0, ..AccumulatorConfig::DEFAULT };
    assert!(matches!(Accumulator::<f32, 4, 16>::new(bad), Err(AccumulatorError::InvalidConfig)));
}

#[test]
fn micromath_vectors_feed_the_same_poses() {
    use micromath::vector::{F32x3, I16x3};
    let (samples, _) = stream(&LEVELS, 1500, 200, 4, 21);
    let mut by_array: Accumulator<i16, 16, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    let mut by_vector: Accumulator<i16, 16, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    for s in &samples {
        by_array.push(*s).unwrap();
        by_vector.push_vector(I16x3 { x: s[0], y: s[1], z: s[2] }).unwrap();
    }
    assert_eq!(by_array.poses(), by_vector.poses());
    let p = accelcal::model::Params { bias: [0.1, 0.2, 0.3], scale: [1.0, 2.0, 3.0], nonorth: [0.0; 3] };
    let v = p.apply_vector(F32x3 { x: 1.0, y: 1.0, z: 1.0 });
    assert_eq!([v.x, v.y, v.z], p.apply([1.0, 1.0, 1.0]));
}

#[test]
fn block_sums_are_exact_at_full_scale() {
    use accelcal::accumulator::Reading;
    // Rail to rail (i16 sums are raw: every square at most 2^30).
    let mut rng = Lcg(3);
    let mut samples: Vec<[i16; 3]> = (0..4096)
        .map(|i| if i % 2 == 0 { [i16::MIN, i16::MAX, i16::MIN] } else { [i16::MAX, i16::MIN, i16::MAX] })
        .collect();
    samples.extend((0..4096).map(|_| [rng.next(32767) as i16, rng.next(32767) as i16, i16::MIN]));
    for len in [4, 32, 33, 4096, samples.len()] {
        let block = &samples[..len];
        let sums = i16::block_sums(axes(block).each_ref().map(Vec::as_slice), 40_000);
        for a in 0..3 {
            let r = i128::from(i16::block_reference(block[0][a]));
            let sum: i128 = block.iter().map(|v| i128::from(v[a]) - r).sum();
            let sum_sq: i128 = block.iter().map(|v| (i128::from(v[a]) - r).pow(2)).sum();
            assert_eq!((i128::from(sums.sum[a]), i128::from(sums.sum_sq[a])), (sum, sum_sq), "len {len} axis {a}");
        }
        assert!(sums.saturated, "rails are saturated");
    }
    // Near full scale but inside a limit: not saturated, by the bound or by the check.
    let inside: Vec<[i16; 3]> = (0..64).map(|i| [32_000 + (i % 7) as i16, -32_000, 0]).collect();
    let inside = axes(&inside);
    assert!(!i16::block_sums(inside.each_ref().map(Vec::as_slice), 32_767).saturated);
    assert!(i16::block_sums(inside.each_ref().map(Vec::as_slice), 32_006).saturated);
    // The longest block (2^16 samples) at the negative rail: the raw 32-bit sum reaches -2^31 exactly.
    let rail = [vec![i16::MIN; 1 << 16], vec![i16::MAX; 1 << 16], vec![0; 1 << 16]];
    let sums = i16::block_sums(rail.each_ref().map(Vec::as_slice), 40_000);
    let n = 1i64 << 16;
    assert_eq!(sums.sum, [-32_768 * n, 32_767 * n, 0]);
    assert_eq!(sums.sum_sq, [32_768 * 32_768 * n, 32_767 * 32_767 * n, 0]);
}

/// Samples split axis by axis (the accumulator's block layout).
fn axes(samples: &[[i16; 3]]) -> [Vec<i16>; 3] {
    [0, 1, 2].map(|a| samples.iter().map(|v| v[a]).collect())
}

#[test]
fn pose_end_index_counts_skipped_samples() {
    let mut acc: Accumulator<f32, 4, 16> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
    let mut rng = Lcg(11);
    let mut skipped = Vec::new();
    for i in 0..1000 {
        if i % 100 == 50 {
            skipped.push(acc.samples_seen());
            assert!(acc.push([f32::NAN, 0.0, 1.0]).is_err());
        }
        acc.push([rng.next(2) as f32 * 0.01, 0.0, 1.0]).unwrap();
    }
    acc.finish().unwrap();
    assert_eq!(acc.samples_seen(), 1010);
    let pose = acc.poses()[0];
    let inside = skipped.iter().filter(|&&k| (pose.start_index..pose.end_index).contains(&k)).count() as u32;
    assert!(inside >= 9, "{pose:?}");
    assert_eq!(pose.end_index - pose.start_index, pose.n + inside, "{pose:?}");
}
