//! The target-independent core of the bench image (`examples/bench.rs`): the library's hot paths, each in
//! its own never-inlined function with a stable symbol name, fed the paper's 24-position simulation
//! (`sim_sensor.rs`), and the run that calls them and prints what it measured on a [`Console`].
//!
//! | symbol | what one call does |
//! |---|---|
//! | `accumulate_fifo` | `Accumulator<i16, 24, 32>::push_slice` of one FIFO read (`FIFO_SAMPLES` samples: whole blocks are summed where they lie, as a firmware with a sensor FIFO does; the report gives cycles per sample) |
//! | `accumulate_sample` | `Accumulator<i16, 24, 32>::push` of one raw sample through a call (a second accumulator fed the same stream sample by sample) |
//! | `apply_sample` | `Params::apply_in_place` of a batch of `APPLY_BATCH` samples (the pose means; the report gives cycles per sample) |
//! | `taga_generation` | one `Ga::step` on the normalised 24-pose problem, population `POP` (called `GENERATIONS` = 10 times) |
//! | `lm` | `levenberg_marquardt` from the coarse start (deviation 0) |
//! | `initial_estimate` | the robust ellipsoid fit of the 24 pose means, and the poses normalised in its frame |
//! | `full_calibration` | `calibrate::<_, POP, 24>` with `CalibrationConfig::DEFAULT`: coarse, TAGA, LM, verdict |

use accelcal::accumulator::{Accumulator, AccumulatorConfig, AccumulatorError, Event, Pose};
use accelcal::calibrate::{Calibration, CalibrationConfig, CalibrationError, NormalizedPoses, calibrate, ga_solver};
use accelcal::frame::{Deviation, NormPose, objective};
use accelcal::ga::Ga;
use accelcal::model::{PARAM_COUNT, Params};
use accelcal::sensor::AccelSensor;
use accelcal::solve::{LmConfig, SolveError, SolveReport, levenberg_marquardt};
use core::fmt::Write;
use core::hint::black_box;
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

use crate::sim_sensor::{self, SimSensor};

/// Seed of the simulated sensor's noise (as in examples/common/pipeline.rs).
const SIM_SEED: u64 = 0x5EED_2020;
/// Seed of the genetic algorithm.
const GA_SEED: u64 = 24;
/// Poses the accumulator holds: the paper's 24.
const POSES: usize = 24;
/// Samples per static-detection block.
const BLOCK: usize = 32;
/// GA population of the device: 24 reaches the same optimum as the host's 40 (objective bit-identical
/// on this bench, measured with tools/cyclecount.py) at 1.24 M instead of 1.68 M cycles and a smaller
/// GA state (1976 B instead of 3192 B).
const POP: usize = 24;
/// Samples per `accumulate_fifo` call: one read of a sensor FIFO (the LIS3DH's holds 32).
pub const FIFO_SAMPLES: usize = 32;
/// Samples per `apply_sample` call (a stream is calibrated in batches: the parameters stay in
/// registers).
pub const APPLY_BATCH: usize = 24;
/// Calls of `taga_generation` (one generation each); the report gives the mean.
pub const GENERATIONS: u32 = 10;

type Acc = Accumulator<i16, POSES, BLOCK>;
type Taga = Ga<Xoshiro128PlusPlus, POP, PARAM_COUNT>;

/// Where the bench prints (semihosting on ARM, a UART on RISC-V) and how it ends.
pub trait Console: Write {
    /// Ends the program: exit code 0 when `success`, 1 otherwise.
    fn exit(&mut self, success: bool) -> !;
}

/// One raw sample into the accumulator.
#[unsafe(no_mangle)]
#[inline(never)]
pub fn accumulate_sample(acc: &mut Acc, sample: [i16; 3]) -> Result<Option<Event>, AccumulatorError> {
    acc.push(sample)
}

/// One FIFO read of samples into the accumulator (`push_slice` until all are taken); the last event,
/// or the first error.
#[unsafe(no_mangle)]
#[inline(never)]
pub fn accumulate_fifo(acc: &mut Acc, mut samples: &[[i16; 3]]) -> Result<Option<Event>, AccumulatorError> {
    let mut last = None;
    while !samples.is_empty() {
        let (taken, event) = acc.push_slice(samples);
        samples = samples.get(taken..).unwrap_or_default();
        if let Some(event) = event? {
            last = Some(event);
        }
    }
    Ok(last)
}

/// A batch of samples through the calibration model, in place.
#[unsafe(no_mangle)]
#[inline(never)]
pub fn apply_sample(params: &Params, samples: &mut [[f32; 3]]) {
    params.apply_in_place(samples);
}

/// One TAGA generation on the normalised problem.
#[unsafe(no_mangle)]
#[inline(never)]
pub fn taga_generation(ga: &mut Taga, norm: &[NormPose]) {
    ga.step(&|x: &Deviation| objective(x, norm));
}

/// Levenberg-Marquardt alone, from the coarse estimate.
#[unsafe(no_mangle)]
#[inline(never)]
pub fn lm(norm: &[NormPose]) -> Result<SolveReport, SolveError> {
    levenberg_marquardt([0.0; PARAM_COUNT], norm, &LmConfig::DEFAULT)
}

/// The any-orientation initial estimate: the ellipsoid fit of the pose means (robust), and the
/// poses normalised in its frame.
#[unsafe(no_mangle)]
#[inline(never)]
pub fn initial_estimate(poses: &[Pose]) -> bool {
    let rule = accelcal::ellipsoid::OutlierRule::DEFAULT;
    let init = accelcal::calibrate::Init::Ellipsoid;
    NormalizedPoses::<POSES>::prepare(poses, init, CalibrationConfig::DEFAULT.gravity, &rule).is_ok()
}

/// The whole calibration as firmware runs it.
#[unsafe(no_mangle)]
#[inline(never)]
pub fn full_calibration(poses: &[Pose], rng: Xoshiro128PlusPlus) -> Result<Calibration, CalibrationError> {
    calibrate::<_, POP, POSES>(poses, &CalibrationConfig::DEFAULT, rng)
}

/// The whole bench: prints its figures, then exits with 0 when every step succeeded.
pub fn run(console: &mut impl Console) -> ! {
    let success = match bench(console) {
        Ok(()) => true,
        Err(what) => {
            let _ = writeln!(console, "bench: error: {what}");
            false
        }
    };
    console.exit(success)
}

/// Every phase in turn; the name of the step that failed.
fn bench(out: &mut impl Write) -> Result<(), &'static str> {
    let acc = accumulate_stream(out)?;
    let poses = acc.poses();
    bench_apply(out, poses);
    bench_ga_and_lm(out, poses)?;
    if !initial_estimate(poses) {
        return Err("initial estimate");
    }
    bench_full_calibration(out, poses)?;
    let _ = writeln!(
        out,
        "bench: sizes accumulator {} ga {} normalized_poses {} population {}",
        core::mem::size_of::<Acc>(),
        core::mem::size_of::<Taga>(),
        core::mem::size_of::<NormalizedPoses<POSES>>(),
        POP
    );
    Ok(())
}

/// The simulated sensor's whole stream through `accumulate_fifo` in reads of `FIFO_SAMPLES`, and
/// through `accumulate_sample` one by one into a second accumulator: both must find the same poses.
fn accumulate_stream(out: &mut impl Write) -> Result<Acc, &'static str> {
    let mut sensor = SimSensor::new(SIM_SEED);
    let mut acc = Acc::new(AccumulatorConfig::DEFAULT).map_err(|_| "accumulator config")?;
    let mut one_by_one = Acc::new(AccumulatorConfig::DEFAULT).map_err(|_| "accumulator config")?;
    let (mut fifo, mut samples) = ([[0i16; 3]; FIFO_SAMPLES], 0usize);
    loop {
        let read = fill_fifo(&mut sensor, &mut fifo);
        for &sample in &fifo[..read] {
            black_box(accumulate_sample(&mut one_by_one, sample)).map_err(|_| "accumulate")?;
        }
        black_box(accumulate_fifo(&mut acc, black_box(&fifo[..read]))).map_err(|_| "accumulate")?;
        samples += read;
        if read < FIFO_SAMPLES {
            break;
        }
    }
    if acc.finish().is_err() || one_by_one.finish().is_err() || acc.poses() != one_by_one.poses() {
        return Err("finish");
    }
    let rate_hz = sim_sensor::SAMPLE_RATE_HZ as u32;
    let _ = writeln!(out, "bench: samples {} at {} Hz, poses {}", samples, rate_hz, acc.poses().len());
    let _ = writeln!(out, "bench: accumulate samples_per_call {FIFO_SAMPLES}");
    Ok(acc)
}

/// Reads up to a FIFO's worth of samples; fewer only at the end of the stream.
fn fill_fifo(sensor: &mut SimSensor, fifo: &mut [[i16; 3]; FIFO_SAMPLES]) -> usize {
    for (i, slot) in fifo.iter_mut().enumerate() {
        match sensor.read_raw() {
            Ok(sample) => *slot = sample,
            Err(_) => return i,
        }
    }
    FIFO_SAMPLES
}

/// One `apply_sample` call on a batch of the pose means.
fn bench_apply(out: &mut impl Write, poses: &[Pose]) {
    let gain = sim_sensor::LSB_PER_G / accelcal::model::STANDARD_GRAVITY_MPS2;
    let params = Params { scale: [1.0 / gain; 3], ..Params::IDENTITY };
    let mut batch = [[0.0f32; 3]; APPLY_BATCH];
    for (b, p) in batch.iter_mut().zip(poses) {
        *b = p.mean;
    }
    apply_sample(black_box(&params), black_box(&mut batch));
    black_box(&batch);
    let _ = writeln!(out, "bench: apply samples_per_call {APPLY_BATCH}");
}

/// `GENERATIONS` TAGA generations, then LM alone, on the six-position normalised problem.
fn bench_ga_and_lm(out: &mut impl Write, poses: &[Pose]) -> Result<(), &'static str> {
    let config = CalibrationConfig::DEFAULT;
    let normalized = NormalizedPoses::<POSES>::new(poses, config.gravity).map_err(|_| "normalise")?;
    let norm = normalized.poses();
    let rng = Xoshiro128PlusPlus::seed_from_u64(GA_SEED);
    let start = normalized.start();
    let widths = accelcal::coarse::SearchWidths::DEFAULT;
    let mut ga: Taga = ga_solver(norm, &start, &widths, config.ga, rng).map_err(|_| "ga")?;
    for _ in 0..GENERATIONS {
        taga_generation(&mut ga, norm);
    }
    let _ = writeln!(out, "bench: taga_generation {} evaluations {}", ga.generation(), ga.evaluations());
    let report = lm(norm).map_err(|_| "lm")?;
    let _ = writeln!(out, "bench: lm iterations {}", report.iterations);
    Ok(())
}

/// The whole calibration from the same seed.
fn bench_full_calibration(out: &mut impl Write, poses: &[Pose]) -> Result<(), &'static str> {
    let rng = Xoshiro128PlusPlus::seed_from_u64(GA_SEED);
    let cal = full_calibration(poses, rng).map_err(|_| "calibrate")?;
    let _ = writeln!(
        out,
        "bench: full_calibration generations {} evaluations {} iterations {} pass {} objective_bits {}",
        cal.generations,
        cal.evaluations,
        cal.iterations,
        cal.verdict.pass() as u8,
        cal.objective.to_bits()
    );
    Ok(())
}
