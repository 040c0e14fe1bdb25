//! The guided session in an Embassy task (feature `async`): the sensor is read with `.await` and the
//! solve yields to the executor after every GA generation, so other tasks keep running while the
//! board is calibrated. The sensor here is the simulated MPU-6050 of the QEMU example
//! (`common/sim_sensor.rs`) behind [`AsyncAccelSensor`]; a real driver awaits its I2C transfer there.
//!
//! ```text
//! cargo build --release --target thumbv7em-none-eabihf --features async --example embassy_session
//! qemu-system-arm -M netduinoplus2 -cpu cortex-m4 -nographic -semihosting-config enable=on,target=native \
//!     -kernel target/thumbv7em-none-eabihf/release/examples/embassy_session
//! ```
//! On the host this example is an empty stub, so that `cargo test` can build it.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    // On the host the firmware example is an empty stub, so that `cargo test` can build it.
}

#[cfg(target_os = "none")]
#[path = "common/sim_sensor.rs"]
#[allow(dead_code)] // shared with the QEMU example, which uses all of it
mod sim_sensor;

#[cfg(target_os = "none")]
mod firmware {
    use core::ops::ControlFlow;

    use accelcal::calibrate::DefaultRng;
    use accelcal::sensor::AccelSensor;
    use accelcal::session::{RunLimits, Session, SessionConfig};
    use accelcal::session_async::{AsyncAccelSensor, yield_now};
    use cortex_m_semihosting::{debug, hprintln};
    use embassy_executor::Spawner;
    use panic_semihosting as _;
    use rand_core::SeedableRng;
    use stm32f4xx_hal as _;

    use crate::sim_sensor::{self, SimSensor};

    /// The simulated sensor, read as a bus transfer would be: the task yields on every read.
    struct AsyncSim(SimSensor);

    impl AsyncAccelSensor for AsyncSim {
        type Error = sim_sensor::End;
        async fn read_raw(&mut self) -> Result<[i16; 3], sim_sensor::End> {
            yield_now().await;
            self.0.read_raw()
        }
    }

    #[embassy_executor::task]
    async fn calibrate() {
        let mut session: Session<i16, 24, 32, 40> = match Session::new(SessionConfig::DEFAULT) {
            Ok(s) => s,
            Err(e) => {
                hprintln!("session: {}", e);
                debug::exit(debug::EXIT_FAILURE);
                return;
            }
        };
        let mut imu = AsyncSim(SimSensor::new(0x5EED_2020));
        let rng = DefaultRng::seed_from_u64(24);
        let limits = RunLimits::DEFAULT;
        // The end of the stream: the first failed read is skipped, the second closes the last pose.
        let result = session.run_with_sensor_async(&mut imu, rng, &limits, |p| {
            if p.sensor_errors > 1 { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
        });
        match result.await {
            Ok(r) => {
                hprintln!(
                    "embassy: {} poses, verdict pass {}, RMSE {} mg",
                    r.poses,
                    r.calibration.verdict.pass(),
                    r.calibration.verdict.rmse_after_mg
                );
                debug::exit(if r.calibration.verdict.pass() { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE });
            }
            Err(e) => {
                hprintln!("embassy: {}", e);
                debug::exit(debug::EXIT_FAILURE);
            }
        }
    }

    #[embassy_executor::main]
    async fn main(spawner: Spawner) {
        spawner.spawn(calibrate().expect("the task is spawned once"));
    }
}
