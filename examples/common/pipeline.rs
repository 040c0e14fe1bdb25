//! The simulated calibration run and its report, shared by `examples/qemu_calibrate.rs` (printed over
//! semihosting) and `tests/qemu_parity.rs` (printed on the host): same seeds, same samples, same code,
//! so the two reports must be identical line for line (`.ci/qemu.sh` compares them).
//!
//! sensor ([`SimSensor`], raw counts) -> [`Accumulator<i16, 32, 32>`] -> [`calibrate`] (TAGA + LM,
//! population 40) -> [`blob::encode`].

use core::fmt;

use accelcal::accumulator::{Accumulator, AccumulatorConfig};
use accelcal::blob;
use accelcal::calibrate::{CalibrationConfig, calibrate};
use accelcal::model::{PARAM_COUNT, PARAM_NAMES, Params, STANDARD_GRAVITY_MPS2};
use accelcal::sensor::AccelSensor;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

use crate::sim_sensor::{self, SimSensor};

/// Seed of the simulated sensor's noise.
pub const SIM_SEED: u64 = 0x5EED_2020;
/// Seed of the genetic algorithm.
pub const GA_SEED: u64 = 24;

/// Largest accepted error against [`sim_sensor::TRUTH`], per parameter ([`PARAM_NAMES`] order, truth
/// units: m/s^2 for B, per m/s^2 of reading for S and M): 1e-3 m/s^2 (0.1 mg) for the biases, 8e-5 for
/// the scale factors, 2e-3 for the non-orthogonality terms: 4.5 to 8 times the RMS error over 60 noise
/// and GA seeds with this stream (1 mg noise, 5 s per position), and at least 1.4 times the largest seen.
pub const TOLERANCE: [f32; PARAM_COUNT] = [1e-3, 1e-3, 1e-3, 8e-5, 8e-5, 8e-5, 2e-3, 2e-3, 2e-3];

/// Parameters for raw counts converted to the truth's convention (reading in m/s^2): `Ka` scaled by
/// the counts per m/s^2, the bias unchanged.
pub fn to_truth_units(p: &Params) -> Params {
    let k = sim_sensor::LSB_PER_G / STANDARD_GRAVITY_MPS2;
    Params { bias: p.bias, scale: p.scale.map(|s| s * k), nonorth: p.nonorth.map(|m| m * k) }
}

/// Runs the simulated experiment, writes the report line by line to `out` and returns `true` when the
/// verdict passes and every parameter is within [`TOLERANCE`] of the truth.
pub fn run(out: &mut dyn FnMut(fmt::Arguments<'_>)) -> bool {
    out(format_args!(
        "run: 24-position simulation, sim seed {SIM_SEED:#x}, GA seed {GA_SEED}, {} samples at {} Hz, noise {} mg, {} LSB/g",
        sim_sensor::TOTAL_SAMPLES,
        sim_sensor::SAMPLE_RATE_HZ,
        sim_sensor::NOISE_MG,
        sim_sensor::LSB_PER_G
    ));
    let mut sensor = SimSensor::new(SIM_SEED);
    let mut acc = match Accumulator::<i16, 32, 32>::new(AccumulatorConfig::DEFAULT) {
        Ok(acc) => acc,
        Err(e) => {
            out(format_args!("error: accumulator: {e}"));
            return false;
        }
    };
    while let Ok(sample) = sensor.read_raw() {
        if let Err(e) = acc.push(sample) {
            out(format_args!("error: sample {}: {e}", acc.samples_seen()));
            return false;
        }
    }
    if let Err(e) = acc.finish() {
        out(format_args!("error: finish: {e}"));
        return false;
    }
    let r = acc.rejections();
    out(format_args!(
        "poses: {} captured, rejected {} too short / {} saturated / {} moving, noise variance {} LSB^2",
        acc.poses().len(),
        r.too_short,
        r.saturated,
        r.moving,
        acc.noise_variance()
    ));
    for (i, p) in acc.poses().iter().enumerate() {
        out(format_args!(
            "pose {i:2}: samples {:5}..{:5} mean [{:.3}, {:.3}, {:.3}] LSB",
            p.start_index, p.end_index, p.mean[0], p.mean[1], p.mean[2]
        ));
    }

    let rng = Xoshiro128PlusPlus::seed_from_u64(GA_SEED);
    let cal = match calibrate::<_, 40, 32>(acc.poses(), &CalibrationConfig::DEFAULT, rng) {
        Ok(cal) => cal,
        Err(e) => {
            out(format_args!("error: calibrate: {e}"));
            return false;
        }
    };
    out(format_args!(
        "method: {}, {} generations, {} evaluations, {} LM iterations",
        cal.method.name(),
        cal.generations,
        cal.evaluations,
        cal.iterations
    ));
    let got = to_truth_units(&cal.params).to_array();
    let truth = sim_sensor::TRUTH.to_array();
    let std = cal.verdict.param_std;
    let k = sim_sensor::LSB_PER_G / STANDARD_GRAVITY_MPS2;
    let mut within = true;
    for i in 0..PARAM_COUNT {
        let error = got[i] - truth[i];
        let ok = error.abs() <= TOLERANCE[i];
        within &= ok;
        // The standard deviation of S and M scales with them (per count -> per m/s^2).
        let sigma = if i < 3 { std[i] } else { std[i] * k };
        out(format_args!(
            "param {:3} = {:>13} (truth {:>12}, error {:>10.3e}, std {:>9.2e}, tolerance {:.0e}) {}",
            PARAM_NAMES[i],
            got[i],
            truth[i],
            error,
            sigma,
            TOLERANCE[i],
            if ok { "ok" } else { "OUT OF TOLERANCE" }
        ));
    }
    let v = &cal.verdict;
    out(format_args!(
        "verdict: rmse before {:.4} mg, after {:.4} mg, noise floor {:.4} mg, pass {}",
        v.rmse_before_mg,
        v.rmse_after_mg,
        v.noise_floor_mg.unwrap_or(f32::NAN),
        v.pass()
    ));
    let bytes = blob::encode(&cal.params, STANDARD_GRAVITY_MPS2);
    out(format_args!("blob: {} bytes, crc32 {:#010x}", bytes.len(), blob::crc32(&bytes[..blob::BLOB_LEN - 4])));
    let pass = v.pass() && within;
    out(format_args!("result: {}", if pass { "PASS" } else { "FAIL" }));
    pass
}
