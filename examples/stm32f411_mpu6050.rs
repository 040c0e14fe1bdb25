//! Calibrates a real MPU-6050 on an STM32F411 "Black Pill" (WeAct, 25 MHz crystal).
//!
//! Wiring: MPU-6050 SCL to PB8, SDA to PB9 (I2C1, 400 kHz; most breakout boards carry the pull-ups),
//! AD0 low (address 0x68), VCC 3.3 V. Output goes over RTT:
//!
//! ```text
//! cargo build --release --target thumbv7em-none-eabihf --example stm32f411_mpu6050
//! probe-rs run --chip STM32F411CEUx target/thumbv7em-none-eabihf/release/examples/stm32f411_mpu6050
//! ```
//!
//! Hold the board still in at least 12 clearly different orientations (every face up and down, and some
//! tilted ones in between; the paper's 24: each face up, turned by 90 degrees four times), about 5 s
//! each, moving it between them. Samples are read at 200 Hz through
//! [`AccelSensor`](accelcal::sensor::AccelSensor) into an `Accumulator<i16, 32, 32>` that finds the
//! still intervals; after [`POSES_WANTED`] poses (or [`MAX_SECONDS`]) the board is calibrated
//! (TAGA + LM) and the blob to store in flash is printed. Writing it to a flash sector is left to the
//! application (the F411's last 128 KiB sector, 0x0806_0000, is outside this example's `memory.x`).
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    // On the host the firmware example is an empty stub, so that `cargo test` can build it.
}

/// Poses to collect before calibrating.
#[cfg(target_os = "none")]
const POSES_WANTED: usize = 24;
/// Give up collecting after this long and calibrate with what there is.
#[cfg(target_os = "none")]
const MAX_SECONDS: u32 = 600;

#[cfg(target_os = "none")]
mod firmware {
    use accelcal::accumulator::{Accumulator, AccumulatorConfig, Event};
    use accelcal::blob;
    use accelcal::calibrate::{CalibrationConfig, calibrate};
    use accelcal::model::{PARAM_NAMES, STANDARD_GRAVITY_MPS2};
    use accelcal::mpu6050::{AccelRange, Address, Mpu6050};
    use accelcal::sensor::AccelSensor;
    use rand_core::SeedableRng;
    use rand_xoshiro::Xoshiro128PlusPlus;
    use rtt_target::{rprintln, rtt_init_print};
    use stm32f4xx_hal::{block, i2c::I2c, pac, prelude::*, rcc::Config};

    use super::{MAX_SECONDS, POSES_WANTED};

    /// The GA's seed (printed, so a run can be repeated from the same poses).
    const GA_SEED: u64 = 2020;
    /// Sample rate, Hz.
    const RATE_HZ: u32 = 200;

    #[cortex_m_rt::entry]
    fn main() -> ! {
        rtt_init_print!();
        if let Err(message) = run() {
            rprintln!("error: {}", message);
        }
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// The accumulator: up to 32 poses, blocks of 32 samples.
    type Poses = Accumulator<i16, 32, 32>;
    /// The MPU-6050 on I2C1.
    type Imu = Mpu6050<I2c<pac::I2C1>>;
    /// The sample-rate tick.
    type Ticker = stm32f4xx_hal::timer::SysCounterHz;

    fn run() -> Result<(), &'static str> {
        let dp = pac::Peripherals::take().ok_or("device peripherals already taken")?;
        let cp = cortex_m::Peripherals::take().ok_or("core peripherals already taken")?;
        let mut rcc = dp.RCC.freeze(Config::hse(25.MHz()).sysclk(100.MHz()));
        let gpiob = dp.GPIOB.split(&mut rcc);
        let i2c = I2c::new(dp.I2C1, (gpiob.pb8, gpiob.pb9), 400.kHz(), &mut rcc);
        let mut ticker = cp.SYST.counter_hz(&rcc.clocks);
        ticker.start(RATE_HZ.Hz()).map_err(|_| "cannot start the 200 Hz tick")?;

        let mut imu = Mpu6050::new(i2c, Address::Ad0Low);
        if let Err(e) = imu.init() {
            rprintln!("MPU-6050: {}", e);
            return Err("no MPU-6050 at 0x68 on I2C1 (PB8/PB9)");
        }
        if let Err(e) = imu.set_full_scale(AccelRange::G2) {
            rprintln!("MPU-6050: {}", e);
            return Err("cannot set the full scale");
        }
        rprintln!("MPU-6050 ready, +-2 g, {} LSB/g; hold still in {} orientations", imu.lsb_per_g(), POSES_WANTED);

        let acc = collect_poses(&mut imu, &mut ticker)?;
        report_calibration(&acc)?;
        // The bus is free again for the application.
        let _i2c = imu.release();
        Ok(())
    }

    /// Samples at the tick into the accumulator until enough poses (or the time limit).
    fn collect_poses(imu: &mut Imu, ticker: &mut Ticker) -> Result<Poses, &'static str> {
        let mut acc: Poses =
            Accumulator::new(AccumulatorConfig::DEFAULT).map_err(|_| "bad accumulator configuration")?;
        let mut read_errors = 0u32;
        let limit = MAX_SECONDS * RATE_HZ;
        for _ in 0..limit {
            let _ = block!(ticker.wait());
            let event = match imu.read_raw() {
                Ok(sample) => acc.push(sample),
                Err(e) => {
                    read_errors += 1;
                    rprintln!("read error: {}", e);
                    // A gap in the stream: close what was open rather than average across it.
                    acc.interrupt()
                }
            };
            match event {
                Ok(Some(Event::StillnessDetected)) => rprintln!("still..."),
                Ok(Some(Event::PoseCaptured(i))) => {
                    let p = acc.poses().get(usize::from(i)).copied().unwrap_or_default();
                    rprintln!(
                        "pose {}: mean [{:.1}, {:.1}, {:.1}] LSB, {} samples",
                        i,
                        p.mean[0],
                        p.mean[1],
                        p.mean[2],
                        p.n
                    );
                    rprintln!("move to the next orientation");
                }
                Ok(Some(Event::PoseRejected(why))) => rprintln!("pose rejected: {:?}", why),
                Ok(None) => {}
                Err(e) => rprintln!("accumulator: {}", e),
            }
            if acc.poses().len() >= POSES_WANTED {
                break;
            }
        }
        let _ = acc.finish();
        let r = acc.rejections();
        rprintln!(
            "{} poses, rejected {} short / {} saturated / {} moving, {} read errors",
            acc.poses().len(),
            r.too_short,
            r.saturated,
            r.moving,
            read_errors
        );
        Ok(acc)
    }

    /// Calibrates the poses and prints the parameters, the verdict and the blob.
    fn report_calibration(acc: &Poses) -> Result<(), &'static str> {
        let rng = Xoshiro128PlusPlus::seed_from_u64(GA_SEED);
        let cal = match calibrate::<_, 40, 32>(acc.poses(), &CalibrationConfig::DEFAULT, rng) {
            Ok(cal) => cal,
            Err(e) => {
                rprintln!("calibration: {}", e);
                return Err("calibration failed");
            }
        };
        rprintln!("GA seed {}, {} generations, {} LM iterations", GA_SEED, cal.generations, cal.iterations);
        for (name, (value, std)) in PARAM_NAMES.iter().zip(cal.params.to_array().iter().zip(cal.verdict.param_std)) {
            rprintln!("{} = {:e} (std {:e})", name, value, std);
        }
        let v = &cal.verdict;
        rprintln!("rmse before {} mg, after {} mg, pass {}", v.rmse_before_mg, v.rmse_after_mg, v.pass());
        if !v.pass() {
            rprintln!("failures: {:?}", v.failures);
            return Err("the calibration did not pass: not stored");
        }
        let bytes = blob::encode(&cal.params, STANDARD_GRAVITY_MPS2);
        rprintln!("blob ({} bytes, store in flash): {:02x?}", bytes.len(), bytes);
        Ok(())
    }

    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        rprintln!("{}", info);
        loop {
            cortex_m::asm::wfi();
        }
    }
}
