//! The firmware path on the host, exactly as a board runs it: a simulated MPU-6050 on the I2C bus
//! ([`accelcal_host::sim::i2c`]) -> the [`accelcal::mpu6050`] driver -> a [`Session`] (accumulator,
//! guidance, coarse, TAGA, LM, verdict, blob).
//!
//! The truth in the session's units (counts in, m/s^2 out against 9.80665) is
//! [`sim::equivalent_params`] of the simulator's truth. Run with `-- --nocapture` to see the
//! per-parameter errors in reported standard deviations, the guidance sequence and the time per push.

use std::ops::ControlFlow;
use std::time::{Duration, Instant};

use accelcal::blob;
use accelcal::model::{PARAM_COUNT, PARAM_NAMES, Params, STANDARD_GRAVITY_MPS2};
use accelcal::mpu6050::{AccelRange, Address, Mpu6050};
use accelcal::sensor::AccelSensor;
use accelcal::session::{
    DirectionKind, GuidanceBasis, Progress, RunLimits, Session, SessionConfig, SessionResult, State,
};
use accelcal_host::sim::i2c::SimMpu6050;
use accelcal_host::sim::random::standard_normal;
use accelcal_host::sim::{self, OutputUnits, PAPER_TRUTH, Recording, SimConfig, simulate};
use rand_core::SeedableRng;
use rand_xoshiro::{Xoshiro128PlusPlus, Xoshiro256PlusPlus};

/// What firmware would instantiate: `i16` counts, 32 poses, blocks of 32 samples, GA population 40.
type FirmwareSession = Session<i16, 32, 32, 40>;

/// The GA seed (printed with every result).
const GA_SEED: u64 = 2020;
/// Parameters must match the truth within this many reported standard deviations.
const MAX_SIGMAS: f32 = 4.0;
/// The simulator's recording seed.
const SIM_SEED: u64 = 11;

fn units() -> OutputUnits {
    OutputUnits::Counts { lsb_per_g: 16384.0, offset: 0.0 }
}

/// The truth in the units the session calibrates: counts in, m/s^2 out.
fn truth_in_counts(truth: &Params) -> Params {
    let g = f64::from(STANDARD_GRAVITY_MPS2);
    sim::equivalent_params(truth, units(), g, g)
}

/// The paper's 24 positions (Table 1 truth, 1 mg noise, 1.5 deg tilt, 2 deg flip error) in counts.
fn paper_recording() -> Recording {
    simulate(&SimConfig { units: units(), ..SimConfig::paper(SIM_SEED) })
}

fn driver(bus: SimMpu6050) -> Mpu6050<SimMpu6050> {
    let mut imu = Mpu6050::new(bus, Address::Ad0Low);
    imu.init().unwrap();
    imu.set_full_scale(AccelRange::G2).unwrap();
    imu
}

/// A firmware run: `run_with_sensor` until the sensor has failed `injected + 1` times (the end of the
/// stream closes the last pose), then finish. Returns the session, the result and every progress
/// report that was not a plain capturing/waiting sample.
fn firmware_run(bus: SimMpu6050, injected: u32) -> (FirmwareSession, SessionResult, Vec<Progress>) {
    let mut imu = driver(bus);
    let mut session = FirmwareSession::new(SessionConfig::DEFAULT).unwrap();
    let mut events = Vec::new();
    let rng = Xoshiro128PlusPlus::seed_from_u64(GA_SEED);
    let result = session
        .run_with_sensor(&mut imu, rng, &RunLimits::DEFAULT, |p| {
            if matches!(p.state, State::PoseCaptured { .. } | State::PoseRejected(_) | State::Interrupted) {
                events.push(*p);
            }
            // The end of the stream: the first failed read is skipped, the second closes the last pose.
            if p.sensor_errors > injected + 1 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        })
        .unwrap();
    (session, result, events)
}

/// Asserts the verdict passes, the blob round-trips and every parameter is within
/// [`MAX_SIGMAS`] reported standard deviations of `truth`; prints the table.
fn check_result(label: &str, result: &SessionResult, truth: &Params) {
    let cal = &result.calibration;
    let verdict = &cal.verdict;
    println!(
        "{label}: {} poses ({} duplicates), RMSE {:.3} mg (noise floor {:?} mg), {} generations, {} LM \
         iterations, GA seed {GA_SEED}",
        result.poses, result.duplicates, verdict.rmse_after_mg, verdict.noise_floor_mg, cal.generations, cal.iterations
    );
    assert!(verdict.pass(), "{label}: verdict failed: {verdict:?}");
    let got = cal.params.to_array();
    let want = truth.to_array();
    for i in 0..PARAM_COUNT {
        let z = (got[i] - want[i]) / verdict.param_std[i];
        println!(
            "  {:>4}: {:>14.8} truth {:>14.8} std {:.3e} ({z:+.2} sigma)",
            PARAM_NAMES[i], got[i], want[i], verdict.param_std[i]
        );
        assert!(z.abs() <= MAX_SIGMAS, "{label}: {} is {z:.2} sigma off", PARAM_NAMES[i]);
    }
    assert_eq!(blob::decode(&result.blob), Ok((cal.params, STANDARD_GRAVITY_MPS2)));
}

#[test]
fn the_papers_24_positions_through_the_bus_calibrate_and_pass() {
    let rec = paper_recording();
    let bus = SimMpu6050::from_recording(&rec).unwrap();
    let start = Instant::now();
    let (session, result, events) = firmware_run(bus, 0);
    let elapsed = start.elapsed();
    assert_eq!(result.poses, 24);
    assert_eq!(session.poses().len(), 24);
    assert_eq!(session.state(), State::Done);
    assert_eq!(session.result(), Some(&result));
    // Each face is held four times (turned by 90 deg on a 1.5 deg tilted platform): three repeats.
    assert_eq!(result.duplicates, 18);
    let captured: Vec<_> = events.iter().filter(|p| matches!(p.state, State::PoseCaptured { .. })).collect();
    assert_eq!(captured.len(), 24);
    for (i, p) in captured.iter().enumerate() {
        let State::PoseCaptured { index, duplicate_of } = p.state else { unreachable!() };
        assert_eq!(index, i);
        assert_eq!(duplicate_of.is_some(), i % 4 != 0, "pose {i}");
    }
    // The session saw the poses where the simulator put them.
    for (pose, sim_pose) in session.poses().iter().zip(&rec.poses) {
        assert!(pose.start_index as usize >= sim_pose.start && pose.end_index as usize <= sim_pose.end);
    }
    let last = captured.last().unwrap();
    assert!(last.ready, "{:?}", last.guidance);
    println!("24 positions: {} samples, {elapsed:?} for the whole run including the calibration", rec.samples.len());
    check_result("paper 24", &result, &truth_in_counts(&PAPER_TRUTH));
}

#[test]
fn an_i2c_error_in_the_middle_of_pose_10_is_a_skipped_sample() {
    let rec = paper_recording();
    let (clean, _, _) = firmware_run(SimMpu6050::from_recording(&rec).unwrap(), 0);

    let mut bus = SimMpu6050::from_recording(&rec).unwrap();
    let pose10 = rec.poses[9];
    let fail_at = (pose10.start + pose10.end) / 2;
    bus.fail_at(fail_at);
    let (session, result, events) = firmware_run(bus, 1);

    // One failed read is one sample lost, not a gap: pose 10 is not split, nothing is lost.
    let first_after = events.iter().find(|p| p.sensor_errors == 1).unwrap();
    assert_eq!(first_after.state, State::PoseCaptured { index: 9, duplicate_of: Some(8) });
    assert!(session.poses()[9].end_index as usize > fail_at, "the pose goes on past the failed read");
    assert_eq!(&session.poses()[..9], &clean.poses()[..9]);
    assert_eq!(session.poses().len(), clean.poses().len());
    let (p, c) = (&session.poses()[9], &clean.poses()[9]);
    assert!(p.start_index == c.start_index && p.n + 32 >= c.n, "{p:?} vs {c:?}");
    // After it, the same poses as the clean run (block boundaries shifted: means within 2 LSB).
    for (p, c) in session.poses()[9..].iter().zip(&clean.poses()[9..]) {
        assert!((0..3).all(|a| (p.mean[a] - c.mean[a]).abs() < 2.0), "{p:?} vs {c:?}");
    }
    assert_eq!((result.poses, result.duplicates), (24, 18));
    assert_eq!(session.progress().sensor_errors, 3); // the injected one and two at the end of the stream
    check_result("paper 24, I2C error in pose 10", &result, &truth_in_counts(&PAPER_TRUTH));
}

// ---------------------------------------------------------------------------------------------
// Guidance: the person follows the suggestions
// ---------------------------------------------------------------------------------------------

/// One placement in counts: `direction` (unit, sensor axes) up for 5 s at 200 Hz with 1 mg (16 LSB)
/// noise, then a 1 s move (a swinging reading the static detector must not average).
fn placement(truth_counts: &Params, direction: [f32; 3], noise: &mut Xoshiro256PlusPlus) -> Vec<[i16; 3]> {
    let g = STANDARD_GRAVITY_MPS2;
    let reading = truth_counts.invert(direction.map(|d| d * g)).unwrap();
    let mut out = Vec::new();
    for _ in 0..1000 {
        out.push(std::array::from_fn(|a| (f64::from(reading[a]) + 16.0 * standard_normal(noise)).round() as i16));
    }
    for i in 0..200 {
        let swing = 3000.0 * (i as f64 * 0.2).sin();
        out.push(std::array::from_fn(|a| (f64::from(reading[a]) + swing * (a as f64 - 1.0)).round() as i16));
    }
    out
}

/// Feeds one placement through a fresh bus and driver, as firmware reading until the stream ends
/// (one sensor error, with nothing open). Returns the capture report and the push times.
fn hold(session: &mut FirmwareSession, counts: &[[i16; 3]], times: &mut PushTimes) -> Progress {
    let mut imu = driver(SimMpu6050::from_counts(counts, 16384.0));
    let mut captured = None;
    loop {
        match imu.read_raw() {
            Ok(sample) => {
                let t = Instant::now();
                let p = session.push(sample).unwrap();
                let dt = t.elapsed();
                if matches!(p.state, State::PoseCaptured { .. }) {
                    times.capture.push(dt);
                    captured = Some(p);
                } else {
                    times.sample.push(dt);
                }
            }
            Err(_) => {
                let p = session.sensor_error().unwrap();
                assert_eq!(p.state, State::Interrupted);
                return captured.expect("the placement was not captured");
            }
        }
    }
}

#[derive(Default)]
struct PushTimes {
    sample: Vec<Duration>,
    capture: Vec<Duration>,
}

fn mean(d: &[Duration]) -> Duration {
    d.iter().sum::<Duration>() / d.len().max(1) as u32
}

#[test]
fn guidance_asks_for_the_faces_then_off_axis_orientations_and_following_it_calibrates() {
    let truth = sim::random_truth(5);
    let truth_counts = truth_in_counts(&truth);
    let mut noise = Xoshiro256PlusPlus::seed_from_u64(17);
    let mut times = PushTimes::default();
    let mut session = FirmwareSession::new(SessionConfig::DEFAULT).unwrap();

    // From scratch the most informative orientations are the faces (provisional frame until there is
    // an initial estimate).
    for i in 0..6 {
        let g = session.progress().guidance;
        assert_eq!(g.next.kind(), DirectionKind::Face, "pose {i}");
        if i < 5 {
            assert_eq!(g.basis, GuidanceBasis::Provisional, "pose {i}");
        }
        let p = hold(&mut session, &placement(&truth_counts, g.next.unit(), &mut noise), &mut times);
        assert_eq!(p.state, State::PoseCaptured { index: i, duplicate_of: None });
        println!(
            "pose {i}: {} captured; next {} (worst std/bound {:.3})",
            g.next, p.guidance.next, p.guidance.worst_std
        );
    }
    let after_faces = session.progress().guidance;
    assert_eq!(after_faces.basis, GuidanceBasis::Information);
    assert_ne!(after_faces.next.kind(), DirectionKind::Face, "after the faces: {}", after_faces.next);
    assert_eq!(&after_faces.poorly_determined[6..], &[true; 3], "non-orthogonality undetermined by faces");

    // Follow the guidance: every capture changes the suggestion, and it is ready in a few poses.
    let mut previous = after_faces;
    while !session.progress().ready {
        let n = session.poses().len();
        assert!(n < 24, "not ready after {n} poses: {:?}", session.progress().guidance);
        let p = hold(&mut session, &placement(&truth_counts, previous.next.unit(), &mut noise), &mut times);
        println!(
            "pose {n}: {} captured; worst std/bound {:.3} (predicted {:.3}); next {}; ready {}",
            previous.next, p.guidance.worst_std, previous.worst_std_after_next, p.guidance.next, p.ready
        );
        assert_eq!(p.state, State::PoseCaptured { index: n, duplicate_of: None });
        assert_ne!(p.guidance.next, previous.next, "the suggestion did not change after pose {n}");
        assert!(p.guidance.worst_std < previous.worst_std);
        previous = p.guidance;
    }
    let poses = session.poses().len();
    assert!(poses >= SessionConfig::DEFAULT.min_poses);
    println!(
        "push time (host, {} samples): mean {:?}, max {:?}; at a capture (guidance): mean {:?}, max {:?}",
        times.sample.len(),
        mean(&times.sample),
        times.sample.iter().max().unwrap(),
        mean(&times.capture),
        times.capture.iter().max().unwrap()
    );
    let result = session.finish(Xoshiro128PlusPlus::seed_from_u64(GA_SEED)).unwrap();
    assert_eq!(result.poses, poses);
    check_result("guided", &result, &truth_counts);
}
