//! Property tests: arbitrary input never panics, and what comes out is typed and finite.

use accelcal::accumulator::{Accumulator, AccumulatorConfig, Pose};
use accelcal::blob::{BLOB_LEN, decode, encode};
use accelcal::calibrate::{CalibrationConfig, Method, NormalizedPoses, calibrate};
use accelcal::frame::NormPose;
use accelcal::model::Params;
use accelcal::solve::{LmConfig, NewtonConfig, levenberg_marquardt, newton};
use proptest::prelude::*;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

/// Any f32, with the special values well represented.
fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        4 => -2.0e4f32..2.0e4,
        1 => Just(f32::NAN),
        1 => Just(f32::INFINITY),
        1 => Just(f32::NEG_INFINITY),
        1 => Just(0.0f32),
        1 => any::<f32>(),
    ]
}

/// Mostly still, sometimes jumping, occasionally at the rails: the shapes of real streams.
fn i16_stream() -> impl Strategy<Value = Vec<[i16; 3]>> {
    prop::collection::vec((0u8..8, any::<[i16; 3]>(), -3i16..3), 0..3000).prop_map(|steps| {
        let mut level = [0i16, 0, 16384];
        steps
            .into_iter()
            .map(|(kind, jump, noise)| {
                if kind == 0 {
                    level = jump;
                }
                level.map(|v| v.saturating_add(noise))
            })
            .collect()
    })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn accumulator_never_panics_on_counts(stream in i16_stream()) {
        let mut acc: Accumulator<i16, 8, 16> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
        for s in &stream {
            let _ = acc.push(*s);
        }
        let _ = acc.finish();
        for p in acc.poses() {
            prop_assert!(p.n > 0 && p.start_index < p.end_index);
            prop_assert!(p.mean.iter().chain(&p.variance).all(|v| v.is_finite()));
        }
    }

    #[test]
    fn accumulator_never_panics_on_floats(stream in prop::collection::vec([any_f32(), any_f32(), any_f32()], 0..2000)) {
        let mut acc: Accumulator<f32, 8, 16> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
        for s in &stream {
            let _ = acc.push(*s);
            if s[0] == 0.0 {
                let _ = acc.interrupt();
            }
        }
        let _ = acc.finish();
        prop_assert!(acc.poses().iter().all(|p| p.mean.iter().all(|v| v.is_finite())));
    }

    #[test]
    fn blob_decoder_never_panics(bytes in prop::collection::vec(any::<u8>(), 0..80)) {
        let _ = decode(&bytes);
    }

    #[test]
    fn blob_round_trips_any_plausible_calibration(
        bias in prop::array::uniform3(-100.0f32..100.0),
        scale in prop::array::uniform3(1e-6f32..100.0),
        nonorth in prop::array::uniform3(-1.0f32..1.0),
        gravity in 0.1f32..100.0,
        flip in 0usize..BLOB_LEN * 8,
    ) {
        let p = Params { bias, scale, nonorth };
        let bytes = encode(&p, gravity);
        prop_assert_eq!(decode(&bytes), Ok((p, gravity)));
        let mut bad = bytes;
        bad[flip / 8] ^= 1 << (flip % 8);
        prop_assert!(decode(&bad).is_err());
    }

    #[test]
    fn solvers_never_panic(
        poses in prop::collection::vec((prop::array::uniform3(any_f32()), any_f32()), 0..30),
        start in prop::array::uniform9(prop_oneof![4 => -1.0f32..1.0, 1 => any_f32()]),
    ) {
        let norm: Vec<NormPose> = poses.iter().map(|(u, q)| NormPose { u: *u, q: *q }).collect();
        let results = [levenberg_marquardt(start, &norm, &LmConfig::DEFAULT), newton(start, &norm, &NewtonConfig::DEFAULT)];
        for report in results.iter().flatten() {
            prop_assert!(report.x.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn calibrate_never_panics(
        means in prop::collection::vec(prop::array::uniform3(any_f32()), 0..40),
        gravity in prop_oneof![4 => 0.5f32..20.0, 1 => any_f32()],
        method in 0usize..4,
    ) {
        let poses: Vec<Pose> = means.iter().map(|m| Pose::from_mean(*m, 100)).collect();
        let method = [Method::Newton, Method::Lm, Method::Taga, Method::TagaLm][method];
        let mut config = CalibrationConfig { gravity, method, ..CalibrationConfig::DEFAULT };
        config.ga.max_generations = 5;
        let _ = NormalizedPoses::<64>::new(&poses, gravity);
        if let Ok(cal) = calibrate::<_, 8, 64>(&poses, &config, Xoshiro128PlusPlus::seed_from_u64(0)) {
            // A result that is not usable must say so in its verdict, never come back as garbage.
            prop_assert!(cal.params.is_finite() || !cal.verdict.pass());
        }
    }
}
