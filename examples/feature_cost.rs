//! The flash cost of each opt-in feature: one minimal Cortex-M4F firmware whose body is a single probe, chosen
//! at compile time by the environment variable `ACCELCAL_FEATURE_COST_PROBE` (unset: `none`, the baseline).
//!
//! `cargo xtask report` builds this example once per probe (release, LTO, one target dir) and gives each
//! feature's cost as the flash difference between its probe image and its baseline image. Probes:
//!
//! - `none`: the baseline, an empty cortex-m-rt image (vector table, reset, a parking loop);
//! - `blob`: blob v2 encode + decode (`Blob::to_bytes`, `Blob::from_bytes`);
//! - `storage`: `storage::CalibrationStore` new + store + load on a stand-in NorFlash (needs feature `storage`);
//! - `accelerometer`: one sample read through the `accelerometer` adapter from a stand-in `RawAccelerometer`
//!   driver (needs feature `accelerometer`);
//! - `mpu6050`: the MPU-6050 driver's init + one sample read on a stand-in I2C bus (needs feature `mpu6050`);
//! - `calibrate`: the calibration path (accumulator + coarse/TAGA/LM calibration) with a stand-in RNG, built
//!   once with and once without the default features.
//!
//! The stand-ins (flash, driver, bus, RNG) read and write through `black_box`, so nothing is optimised away;
//! they are a few dozen bytes of the figures. Build one by hand: `ACCELCAL_FEATURE_COST_PROBE=blob cargo build
//! -p accelcal --release --target thumbv7em-none-eabihf --example feature_cost --no-default-features`. Not meant
//! to run.
#![cfg_attr(target_os = "none", no_std, no_main)]

#[cfg(not(target_os = "none"))]
fn main() {
    // On the host the firmware example is an empty stub, so that `cargo test` can build it.
}

#[cfg(target_os = "none")]
mod firmware {
    use cortex_m_rt::entry;
    // The chip crate's interrupt table: cortex-m-rt's `device` feature is on for every example.
    use stm32f4xx_hal as _;

    /// The probe this image is built with.
    const PROBE: &str = match option_env!("ACCELCAL_FEATURE_COST_PROBE") {
        Some(p) => p,
        None => "none",
    };

    const fn is(name: &str) -> bool {
        let (a, b) = (PROBE.as_bytes(), name.as_bytes());
        if a.len() != b.len() {
            return false;
        }
        let mut i = 0;
        while i < a.len() {
            if a[i] != b[i] {
                return false;
            }
            i += 1;
        }
        true
    }

    /// A probe name this example does not know is a build error, not a silent baseline.
    const _: () = assert!(
        is("none") || is("blob") || is("storage") || is("accelerometer") || is("mpu6050") || is("calibrate"),
        "ACCELCAL_FEATURE_COST_PROBE: none, blob, storage, accelerometer, mpu6050 or calibrate"
    );

    #[entry]
    fn main() -> ! {
        if is("blob") {
            probes::blob();
        }
        if is("calibrate") {
            probes::calibrate();
        }
        #[cfg(feature = "storage")]
        if is("storage") {
            probes::storage();
        }
        #[cfg(feature = "accelerometer")]
        if is("accelerometer") {
            probes::accelerometer();
        }
        #[cfg(feature = "mpu6050")]
        if is("mpu6050") {
            probes::mpu6050();
        }
        loop {
            cortex_m::asm::wfi();
        }
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        loop {
            cortex_m::asm::wfi();
        }
    }

    /// Stand-ins for the hardware and the RNG: every value they give is opaque to the optimiser.
    mod stand_ins {
        use core::convert::Infallible;
        use core::hint::black_box;

        /// An RNG the calibration path uses with and without the default features.
        pub struct FakeRng(pub u64);

        impl accelcal::rand_core::TryRng for FakeRng {
            type Error = Infallible;
            fn try_next_u32(&mut self) -> Result<u32, Infallible> {
                self.0 = black_box(self.0.wrapping_add(1));
                Ok(self.0 as u32)
            }
            fn try_next_u64(&mut self) -> Result<u64, Infallible> {
                self.0 = black_box(self.0.wrapping_add(1));
                Ok(self.0)
            }
            fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
                dst.fill(black_box(0));
                Ok(())
            }
        }

        /// A NorFlash of 4 KiB, write size 4, erase size 2 KiB, whose reads are opaque.
        #[cfg(feature = "storage")]
        pub struct FakeFlash;

        #[cfg(feature = "storage")]
        mod flash {
            use core::hint::black_box;
            use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};

            impl ErrorType for super::FakeFlash {
                type Error = NorFlashErrorKind;
            }
            impl ReadNorFlash for super::FakeFlash {
                const READ_SIZE: usize = 1;
                fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
                    bytes.fill(black_box(offset as u8));
                    black_box(Ok(()))
                }
                fn capacity(&self) -> usize {
                    4096
                }
            }
            impl NorFlash for super::FakeFlash {
                const WRITE_SIZE: usize = 4;
                const ERASE_SIZE: usize = 2048;
                fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
                    black_box((from, to));
                    black_box(Ok(()))
                }
                fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
                    black_box((offset, bytes));
                    black_box(Ok(()))
                }
            }
        }

        /// An `accelerometer` crate driver whose samples are opaque.
        #[cfg(feature = "accelerometer")]
        pub struct FakeDriver;

        #[cfg(feature = "accelerometer")]
        impl accelerometer::RawAccelerometer<accelerometer::vector::I16x3> for FakeDriver {
            type Error = ();
            fn accel_raw(&mut self) -> Result<accelerometer::vector::I16x3, accelerometer::Error<()>> {
                if black_box(false) {
                    return Err(accelerometer::Error::new(accelerometer::ErrorKind::Bus));
                }
                Ok(accelerometer::vector::I16x3::new(black_box(1), black_box(2), black_box(3)))
            }
        }

        /// An I2C bus whose reads are opaque.
        #[cfg(feature = "mpu6050")]
        pub struct FakeBus;

        #[cfg(feature = "mpu6050")]
        mod bus {
            use core::hint::black_box;
            use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, Operation};

            impl ErrorType for super::FakeBus {
                type Error = ErrorKind;
            }
            impl I2c for super::FakeBus {
                fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), ErrorKind> {
                    for op in operations {
                        match op {
                            Operation::Read(bytes) => bytes.fill(black_box(address)),
                            Operation::Write(bytes) => drop(black_box(bytes)),
                        }
                    }
                    black_box(Ok(()))
                }
            }
        }
    }

    mod probes {
        #[allow(unused_imports)]
        use super::stand_ins::*;
        use accelcal::Params;
        use accelcal::blob::Blob;
        #[allow(unused_imports)]
        use accelcal::sensor::AccelSensor;
        use core::hint::black_box;

        /// A blob with every v2 field present, opaque to the optimiser.
        fn full_blob() -> Blob {
            let mut blob = Blob::new(black_box(Params::IDENTITY), black_box(9.806_65));
            blob.sensor =
                black_box(Some(accelcal::blob::SensorSetup { full_scale_g: 2.0, lsb_per_g: 16384.0, sensor_id: 0x68 }));
            blob.temperature_c = black_box(Some(25.0));
            blob.effects = black_box(Some(accelcal::blob::Effects::default()));
            blob
        }

        pub fn blob() {
            let bytes = full_blob().to_bytes();
            black_box(Blob::from_bytes(black_box(&bytes[..])).ok());
        }

        pub fn calibrate() {
            use accelcal::accumulator::{Accumulator, AccumulatorConfig};
            use accelcal::calibrate::{CalibrationConfig, calibrate};
            let Ok(mut acc) = Accumulator::<i16, 24, 32>::new(black_box(AccumulatorConfig::DEFAULT)) else {
                return;
            };
            while black_box(true) {
                let _ = acc.push(black_box([0i16; 3]));
            }
            let _ = acc.finish();
            let config = black_box(CalibrationConfig::DEFAULT);
            if let Ok(cal) = calibrate::<_, 40, 24>(acc.poses(), &config, FakeRng(black_box(1))) {
                black_box(cal.params);
            }
        }

        #[cfg(feature = "storage")]
        pub fn storage() {
            use accelcal::storage::CalibrationStore;
            let Ok(mut store) = CalibrationStore::new(FakeFlash, black_box(0), black_box(2048)) else { return };
            black_box(store.store(&full_blob()).ok());
            black_box(store.load().ok());
        }

        #[cfg(feature = "accelerometer")]
        pub fn accelerometer() {
            black_box(FakeDriver.read_raw().ok());
        }

        #[cfg(feature = "mpu6050")]
        pub fn mpu6050() {
            use accelcal::mpu6050::{Address, Mpu6050};
            let mut mpu = Mpu6050::new(FakeBus, black_box(Address::Ad0Low));
            if mpu.init().is_ok() {
                black_box(mpu.read_raw().ok());
            }
        }
    }
}
