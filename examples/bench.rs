//! Size and cycle benchmark image: the library's hot paths, each in its own never-inlined function
//! with a stable symbol name, fed the paper's 24-position simulation (`common/sim_sensor.rs`).
//!
//! `tools/cyclecount.py` runs this image in an instruction-set emulator, counts the instructions and
//! estimated Cortex-M4 cycles of every call to the functions below and measures the stack of
//! `full_calibration`; `accelcal report` (host-tests/src/report.rs) turns
//! that into the size and cycle report with its budgets. The image also runs in QEMU
//! (`cargo run --release --target thumbv7em-none-eabihf --example bench`): it prints what it measured
//! over semihosting and exits with 0 when the calibration succeeded.
//!
//! | symbol | what one call does |
//! |---|---|
//! | `accumulate_fifo` | `Accumulator<i16, 24, 32>::push` of each sample of one FIFO read (`FIFO_SAMPLES` samples, push inlined in the loop as in a firmware's read loop; the report gives cycles per sample) |
//! | `accumulate_sample` | `Accumulator<i16, 24, 32>::push` of one raw sample through a call (a second accumulator fed the same stream sample by sample) |
//! | `apply_sample` | `Params::apply_in_place` of a batch of `APPLY_BATCH` samples (the pose means; the report gives cycles per sample) |
//! | `taga_generation` | one `Ga::step` on the normalised 24-pose problem, population `POP` (called `GENERATIONS` = 10 times) |
//! | `lm` | `levenberg_marquardt` from the coarse start (deviation 0) |
//! | `full_calibration` | `calibrate::<_, POP, 24>` with `CalibrationConfig::DEFAULT`: coarse, TAGA, LM, verdict |
//!
//! On the host this example is an empty stub, so that `cargo test` can build it.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    // On the host the firmware example is an empty stub, so that `cargo test` can build it.
}

#[cfg(target_os = "none")]
#[path = "common/sim_sensor.rs"]
mod sim_sensor;

#[cfg(target_os = "none")]
mod firmware {
    use accelcal::accumulator::{Accumulator, AccumulatorConfig, AccumulatorError, Event, Pose};
    use accelcal::calibrate::{
        Calibration, CalibrationConfig, CalibrationError, NormalizedPoses, calibrate, ga_solver,
    };
    use accelcal::frame::{Deviation, NormPose, objective};
    use accelcal::ga::Ga;
    use accelcal::model::{PARAM_COUNT, Params};
    use accelcal::sensor::AccelSensor;
    use accelcal::solve::{LmConfig, SolveError, SolveReport, levenberg_marquardt};
    use core::hint::black_box;
    use cortex_m_semihosting::{debug, hprintln};
    use panic_semihosting as _;
    use rand_core::SeedableRng;
    use rand_xoshiro::Xoshiro128PlusPlus;
    // Links the device interrupt table that cortex-m-rt's `device` feature asks for (see
    // examples/qemu_calibrate.rs); no interrupt is enabled.
    use stm32f4xx_hal as _;

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

    /// One raw sample into the accumulator.
    #[unsafe(no_mangle)]
    #[inline(never)]
    pub fn accumulate_sample(acc: &mut Acc, sample: [i16; 3]) -> Result<Option<Event>, AccumulatorError> {
        acc.push(sample)
    }

    /// One FIFO read of samples into the accumulator; the last event, or the first error.
    #[unsafe(no_mangle)]
    #[inline(never)]
    pub fn accumulate_fifo(acc: &mut Acc, samples: &[[i16; 3]]) -> Result<Option<Event>, AccumulatorError> {
        let mut last = None;
        for &sample in samples {
            if let Some(event) = acc.push(sample)? {
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

    fn fail(what: &str) -> ! {
        hprintln!("bench: error: {}", what);
        debug::exit(debug::EXIT_FAILURE);
        #[allow(clippy::empty_loop)]
        loop {}
    }

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let acc = accumulate_stream();
        let poses = acc.poses();
        bench_apply(poses);
        bench_ga_and_lm(poses);
        if !initial_estimate(poses) {
            fail("initial estimate");
        }
        bench_full_calibration(poses);
        hprintln!(
            "bench: sizes accumulator {} ga {} normalized_poses {} population {}",
            core::mem::size_of::<Acc>(),
            core::mem::size_of::<Taga>(),
            core::mem::size_of::<NormalizedPoses<POSES>>(),
            POP
        );
        debug::exit(debug::EXIT_SUCCESS);
        #[allow(clippy::empty_loop)]
        loop {}
    }

    /// The simulated sensor's whole stream through `accumulate_fifo` in reads of `FIFO_SAMPLES`, and
    /// through `accumulate_sample` one by one into a second accumulator: both must find the same poses.
    fn accumulate_stream() -> Acc {
        let mut sensor = SimSensor::new(SIM_SEED);
        let (mut acc, mut one_by_one) =
            match (Acc::new(AccumulatorConfig::DEFAULT), Acc::new(AccumulatorConfig::DEFAULT)) {
                (Ok(a), Ok(b)) => (a, b),
                _ => fail("accumulator config"),
            };
        let (mut fifo, mut samples) = ([[0i16; 3]; FIFO_SAMPLES], 0usize);
        loop {
            let read = fill_fifo(&mut sensor, &mut fifo);
            for &sample in &fifo[..read] {
                if black_box(accumulate_sample(&mut one_by_one, sample)).is_err() {
                    fail("accumulate");
                }
            }
            if black_box(accumulate_fifo(&mut acc, black_box(&fifo[..read]))).is_err() {
                fail("accumulate");
            }
            samples += read;
            if read < FIFO_SAMPLES {
                break;
            }
        }
        if acc.finish().is_err() || one_by_one.finish().is_err() || acc.poses() != one_by_one.poses() {
            fail("finish");
        }
        let rate_hz = sim_sensor::SAMPLE_RATE_HZ as u32;
        hprintln!("bench: samples {} at {} Hz, poses {}", samples, rate_hz, acc.poses().len());
        hprintln!("bench: accumulate samples_per_call {}", FIFO_SAMPLES);
        acc
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
    fn bench_apply(poses: &[Pose]) {
        let gain = sim_sensor::LSB_PER_G / accelcal::model::STANDARD_GRAVITY_MPS2;
        let params = Params { scale: [1.0 / gain; 3], ..Params::IDENTITY };
        let mut batch = [[0.0f32; 3]; APPLY_BATCH];
        for (b, p) in batch.iter_mut().zip(poses) {
            *b = p.mean;
        }
        apply_sample(black_box(&params), black_box(&mut batch));
        black_box(&batch);
        hprintln!("bench: apply samples_per_call {}", APPLY_BATCH);
    }

    /// `GENERATIONS` TAGA generations, then LM alone, on the six-position normalised problem.
    fn bench_ga_and_lm(poses: &[Pose]) {
        let config = CalibrationConfig::DEFAULT;
        let normalized = match NormalizedPoses::<POSES>::new(poses, config.gravity) {
            Ok(n) => n,
            Err(_) => fail("normalise"),
        };
        let norm = normalized.poses();
        let rng = Xoshiro128PlusPlus::seed_from_u64(GA_SEED);
        let start = normalized.start();
        let mut ga: Taga = match ga_solver(norm, &start, &accelcal::coarse::SearchWidths::DEFAULT, config.ga, rng) {
            Ok(ga) => ga,
            Err(_) => fail("ga"),
        };
        for _ in 0..GENERATIONS {
            taga_generation(&mut ga, norm);
        }
        hprintln!("bench: taga_generation {} evaluations {}", ga.generation(), ga.evaluations());
        match lm(norm) {
            Ok(r) => hprintln!("bench: lm iterations {}", r.iterations),
            Err(_) => fail("lm"),
        }
    }

    /// The whole calibration from the same seed.
    fn bench_full_calibration(poses: &[Pose]) {
        let rng = Xoshiro128PlusPlus::seed_from_u64(GA_SEED);
        match full_calibration(poses, rng) {
            Ok(cal) => hprintln!(
                "bench: full_calibration generations {} evaluations {} iterations {} pass {} objective_bits {}",
                cal.generations,
                cal.evaluations,
                cal.iterations,
                cal.verdict.pass() as u8,
                cal.objective.to_bits()
            ),
            Err(_) => fail("calibrate"),
        }
    }
}
