//! Calibrates a real LIS3DH on an STM32F411 "Black Pill" (WeAct, 25 MHz crystal): the guided session
//! ([`accelcal::ImuSession`]), the crates.io `lis3dh` driver used as the sensor with no glue (feature
//! `accelerometer`: any `accelerometer::RawAccelerometer<I16x3>` is an `AccelSensor`), and defmt
//! logging over RTT. This is the file to copy into a firmware.
//!
//! Wiring: LIS3DH SCL to PB8, SDA to PB9 (I2C1, 400 kHz; breakout boards carry the pull-ups), SDO/SA0
//! high (address 0x19, the driver's `SlaveAddr::Default`), VIN 3.3 V. Build and flash:
//!
//! ```text
//! cargo build --release --target thumbv7em-none-eabihf --example stm32f411_lis3dh --features accelerometer,defmt
//! cargo board    # the alias in .cargo/config.toml: the same build, flashed and logged with
//!                # probe-rs run --chip STM32F411CEUx (defmt output decoded on the host)
//! ```
//!
//! The session asks for the next orientation (any start, any order): turn the board until that
//! direction points up, hold it still [`HOLD_S`] seconds, turn it on to the next one when the log says
//! `MoveOn`. When the predicted parameter uncertainties are within the verdict's bounds it calibrates
//! (TAGA + LM) and logs the verdict and the blob to store in flash. A failed verdict (or a sensor that
//! stopped answering) keeps every pose: the loop captures more and finishes again, until the session's
//! 24 poses are full. Not yet run on hardware here: built for the target and linked with defmt only.
//!
//! The calibration loop in `calibrate` is 20 lines, counted from `let mut session` to the blob's log
//! line (rustfmt's layout); `board` is the board and sensor set-up.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    // On the host the firmware example is an empty stub, so that `cargo test` can build it.
}

/// Sample rate, Hz: the LIS3DH's output data rate and the loop's tick.
#[cfg(target_os = "none")]
const RATE_HZ: u32 = 200;
/// Seconds a pose is held before the session says `MoveOn`.
#[cfg(target_os = "none")]
const HOLD_S: f32 = 3.0;
/// Still intervals shorter than this, seconds, are not kept as poses.
#[cfg(target_os = "none")]
const MIN_STILL_S: f32 = 0.5;

#[cfg(target_os = "none")]
mod firmware {
    use core::fmt::Debug;
    use core::mem::discriminant;
    use core::ops::ControlFlow;

    use accelcal::sensor::AccelSensor;
    use accelcal::{ImuSession, RunLimits, SessionConfig, State, seeded_rng};
    use defmt::{Display2Format, error, info, warn};
    use lis3dh::{Configuration, DataRate, Lis3dh, Mode, Range, SlaveAddr};
    use stm32f4xx_hal::{block, i2c::I2c, pac, prelude::*, rcc::Config, timer::SysCounterHz};
    use {defmt_rtt as _, panic_probe as _};

    use super::{HOLD_S, MIN_STILL_S, RATE_HZ};

    /// The GA's seed (fixed, so a run can be repeated from the same poses).
    const GA_SEED: u64 = 2020;
    /// Poses an [`ImuSession`] holds (`Session<i16, 24, ..>`): once full, a failed verdict is final.
    const SESSION_POSES: usize = 24;
    /// Saturation, raw counts: high-resolution mode is 12 bits left-justified in an `i16`, so the
    /// largest reading at +-2 g is 2047 * 16 (not `i16::MAX`).
    const FULL_SCALE_LSB: f32 = 32_752.0;

    #[cortex_m_rt::entry]
    fn main() -> ! {
        if let Err(message) = board().and_then(|(mut imu, mut tick)| calibrate(&mut imu, &mut tick)) {
            error!("{}", message);
        }
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// The LIS3DH on I2C1 (+-2 g, high resolution, [`RATE_HZ`]) and the tick that paces its reads.
    fn board() -> Result<(impl AccelSensor<Error: Debug>, SysCounterHz), &'static str> {
        let dp = pac::Peripherals::take().ok_or("device peripherals already taken")?;
        let cp = cortex_m::Peripherals::take().ok_or("core peripherals already taken")?;
        let mut rcc = dp.RCC.freeze(Config::hse(25.MHz()).sysclk(100.MHz()));
        let gpiob = dp.GPIOB.split(&mut rcc);
        let i2c = I2c::new(dp.I2C1, (gpiob.pb8, gpiob.pb9), 400.kHz(), &mut rcc);
        let mut tick = cp.SYST.counter_hz(&rcc.clocks);
        tick.start(RATE_HZ.Hz()).map_err(|_| "cannot start the sample tick")?;
        let lis3dh = Configuration { mode: Mode::HighResolution, datarate: DataRate::Hz_200, ..Default::default() };
        let mut imu = Lis3dh::new_i2c_with_config(i2c, SlaveAddr::Default, lis3dh)
            .map_err(|_| "no LIS3DH at 0x19 on I2C1 (PB8/PB9)")?;
        imu.set_range(Range::G2).map_err(|_| "cannot set the LIS3DH's range")?;
        info!("LIS3DH ready: +-2 g, {} Hz; follow the guidance", RATE_HZ);
        Ok((imu, tick))
    }

    /// The guided session on any sensor (here the `lis3dh` driver itself), logged over defmt: the
    /// calibration loop, from `let mut session` to the blob's log line.
    fn calibrate<S: AccelSensor<Error: Debug>>(imu: &mut S, tick: &mut SysCounterHz) -> Result<(), &'static str> {
        let mut config = SessionConfig::at_rate(RATE_HZ as f32, HOLD_S, MIN_STILL_S);
        config.accumulator.full_scale = FULL_SCALE_LSB;
        let mut session = ImuSession::new(config).map_err(|_| "bad session configuration")?;
        let mut last = discriminant(&State::Done);
        let result = loop {
            let run = session.run_with_sensor(imu, seeded_rng(GA_SEED), &RunLimits::DEFAULT, |p| {
                if core::mem::replace(&mut last, discriminant(&p.state)) != discriminant(&p.state) {
                    let next = Display2Format(&p.guidance.next);
                    info!("{}: {} poses, next turn {} up, ready {}", p.state, p.poses, next, p.ready);
                }
                let _ = block!(tick.wait()); // paces the reads at RATE_HZ
                if p.ready { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
            });
            match run {
                // A failed verdict or a loose wire: the poses are kept, capture more and finish again.
                Err(e) if session.poses().len() < SESSION_POSES => warn!("{}: capture more", Display2Format(&e)),
                run => break run.map_err(|e| error!("{}: no room for more poses", Display2Format(&e))),
            }
        };
        let result = result.map_err(|()| "no calibration")?;
        info!("verdict {}", result.calibration.verdict);
        info!("blob ({} bytes, store in flash): {=[u8]:02x}", result.blob.len(), result.blob);
        Ok(())
    }
}
