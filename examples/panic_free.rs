//! Link-time proof that the calibration path has no reachable panic.
//!
//! `panic-never` makes any panic that the optimiser cannot remove a link error, so this example
//! links only if accumulating samples, coarse + TAGA + LM calibration, the verdict, blob encoding and
//! decoding, applying the result and the guided calibration session contain no panicking branch, whatever the input (every input here
//! is opaque to the optimiser through `black_box`). Build: `cargo build --release --target
//! thumbv7em-none-eabihf --example panic_free` (CI does). It is not meant to run.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    // On the host the firmware example is an empty stub, so that `cargo test` can build it.
}

#[cfg(target_os = "none")]
mod firmware {
    use accelcal::accumulator::{Accumulator, AccumulatorConfig};
    use accelcal::blob;
    use accelcal::calibrate::{CalibrationConfig, DefaultRng, calibrate};
    use accelcal::session::{Session, SessionConfig};
    use core::hint::black_box;
    use cortex_m_rt::entry;
    use panic_never as _;
    use rand_core::SeedableRng;
    // The chip crate's interrupt table: cortex-m-rt's `device` feature is on for every example.
    use stm32f4xx_hal as _;

    #[entry]
    fn main() -> ! {
        let Ok(mut acc) = Accumulator::<i16, 24, 32>::new(black_box(AccumulatorConfig::DEFAULT)) else { park() };
        while black_box(true) {
            let _ = acc.push(black_box([0i16; 3]));
            if black_box(false) {
                let _ = acc.interrupt();
            }
        }
        let _ = acc.finish();
        let config = black_box(CalibrationConfig::DEFAULT);
        let rng = DefaultRng::seed_from_u64(black_box(1));
        if let Ok(cal) = calibrate::<_, 40, 24>(acc.poses(), &config, rng) {
            let bytes = blob::encode(&cal.params, config.gravity);
            if let Ok((params, _)) = blob::decode(black_box(&bytes[..])) {
                black_box(params.apply(black_box([1.0, 2.0, 3.0])));
            }
            black_box(cal.verdict.pass());
        }
        // The guided session: samples, a sensor error, guidance at each capture, the solve.
        if let Ok(mut session) = Session::<i16, 24, 32, 40>::new(black_box(SessionConfig::DEFAULT)) {
            while black_box(true) {
                let _ = session.push(black_box([0i16; 3]));
                if black_box(false) {
                    let _ = session.sensor_error();
                }
            }
            if let Ok(result) = session.finish(DefaultRng::seed_from_u64(black_box(2))) {
                black_box(result.blob);
            }
        }
        park()
    }

    /// Where the proof ends: wait for interrupts forever.
    fn park() -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }
}
