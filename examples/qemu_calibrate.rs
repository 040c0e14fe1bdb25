//! The paper's 24-position simulation, calibrated on an emulated Cortex-M4F; then a guided session
//! from a free-hand start whose early finish fails its verdict, keeps its poses, and passes after the
//! poses the guidance asks for (`common/guided.rs`).
//!
//! A simulated MPU-6050 with the paper's table 1 errors (`common/sim_sensor.rs`) is read through
//! [`AccelSensor`](accelcal::sensor::AccelSensor) into an `Accumulator<i16, 32, 32>`, calibrated with
//! TAGA + LM and encoded as a flash blob (`common/pipeline.rs`); the report goes out over semihosting and
//! QEMU exits with 0 only if the verdict passes and every parameter is within tolerance of the truth.
//! `tests/qemu_parity.rs` runs the same code on the host; `.ci/qemu.sh` checks the two reports match.
//!
//! ```text
//! cargo build --release --target thumbv7em-none-eabihf --example qemu_calibrate
//! qemu-system-arm -M netduinoplus2 -cpu cortex-m4 -nographic \
//!     -semihosting-config enable=on,target=native \
//!     -kernel target/thumbv7em-none-eabihf/release/examples/qemu_calibrate
//! ```
//! (or `cargo qemu`, see `.cargo/config.toml`). On the host this example is an empty stub, so that
//! `cargo test` can build it.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    // On the host the firmware example is an empty stub, so that `cargo test` can build it.
}

#[cfg(target_os = "none")]
#[path = "common/guided.rs"]
mod guided;
#[cfg(target_os = "none")]
#[path = "common/pipeline.rs"]
mod pipeline;
#[cfg(target_os = "none")]
#[path = "common/sim_sensor.rs"]
mod sim_sensor;

#[cfg(target_os = "none")]
mod firmware {
    use cortex_m_semihosting::{debug, hprintln};
    // A panic prints its message over semihosting and exits QEMU with a failure.
    use panic_semihosting as _;
    // The F411 HAL (dev-dependency of the other example) turns on cortex-m-rt's `device` feature for
    // every example, which wants a device's interrupt table: link that one. QEMU's STM32F405 never
    // takes an interrupt here (none is enabled), so only the core exceptions of the table matter.
    use stm32f4xx_hal as _;

    #[cortex_m_rt::entry]
    fn main() -> ! {
        let mut pass = crate::pipeline::run(&mut |line| hprintln!("{}", line));
        pass &= crate::guided::run(&mut |line| hprintln!("{}", line));
        debug::exit(if pass { debug::EXIT_SUCCESS } else { debug::EXIT_FAILURE });
        #[allow(clippy::empty_loop)]
        loop {}
    }
}
