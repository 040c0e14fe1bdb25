//! An `accelerometer` crate driver used as the library's sensor with no glue code.

use accelcal::accelerometer::{AccelerometerError, AccelerometerErrorKind};
use accelcal::sensor::{AccelSensor, RawFormat};
use accelerometer::vector::I16x3;
use accelerometer::{Error, ErrorKind, RawAccelerometer};

/// A driver as a driver crate writes it: a left-justified 12-bit part at +-2 g, then a bus failure.
struct ScriptedDriver {
    readings: Vec<Result<[i16; 3], Error<u8>>>,
}

impl RawAccelerometer<I16x3> for ScriptedDriver {
    type Error = u8;

    fn accel_raw(&mut self) -> Result<I16x3, Error<u8>> {
        self.readings.remove(0).map(|[x, y, z]| I16x3::new(x, y, z))
    }
}

/// Generic over the library's trait only, as the session and the examples are.
fn read<S: AccelSensor>(sensor: &mut S) -> Result<[i16; 3], S::Error> {
    sensor.read_raw()
}

#[test]
fn raw_accelerometer_driver_is_an_accel_sensor() {
    let mut driver = ScriptedDriver {
        readings: vec![
            Ok([16, -32, 1024 << 4]),
            Err(Error::new_with_cause(ErrorKind::Bus, 7)),
            Err(Error::new(ErrorKind::Device)),
        ],
    };
    assert_eq!(read(&mut driver), Ok([16, -32, 1024 << 4]));
    let bus = AccelerometerError { kind: AccelerometerErrorKind::Bus, cause: Some(7) };
    assert_eq!(read(&mut driver), Err(bus));
    let device = AccelerometerError { kind: AccelerometerErrorKind::Device, cause: None };
    assert_eq!(read(&mut driver), Err(device));
    assert_eq!(bus.to_string(), "accelerometer Bus error: 7");
}

#[test]
fn saturation_follows_the_raw_format() {
    let twelve_bit = RawFormat { full_scale_g: 2.0, resolution_bits: 12, left_justified: true };
    assert_eq!(twelve_bit.validate(), Ok(()));
    assert_eq!(twelve_bit.saturation_counts(), 2047 << 4);
    assert_eq!(twelve_bit.accumulator_full_scale(), 32752.0);
    assert_eq!(twelve_bit.to_g([0, 1024 << 4, -(1024 << 4)]), [0.0, 1.0, -1.0]);
    let right_justified = RawFormat { left_justified: false, ..twelve_bit };
    assert_eq!(right_justified.saturation_counts(), 2047);
    assert_eq!(right_justified.lsb_per_g(), 1024.0);
    let mpu_16g = RawFormat { full_scale_g: 16.0, ..RawFormat::MPU6050_2G };
    assert_eq!(mpu_16g.saturation_counts(), i16::MAX);
    assert_eq!(mpu_16g.lsb_per_g(), 2048.0);
    assert_eq!(
        RawFormat { resolution_bits: 0, ..twelve_bit }.validate(),
        Err(accelcal::sensor::RawFormatError::Resolution)
    );
    assert_eq!(
        RawFormat { resolution_bits: 17, ..twelve_bit }.validate(),
        Err(accelcal::sensor::RawFormatError::Resolution)
    );
    assert_eq!(
        RawFormat { full_scale_g: f32::NAN, ..twelve_bit }.validate(),
        Err(accelcal::sensor::RawFormatError::FullScale)
    );
}

/// A 12-bit left-justified part held with x on its rail (2047 << 4, below the i16 limit): counted as
/// saturated only when the accumulator is configured from the sensor's `RawFormat`.
fn saturated_poses(config: accelcal::accumulator::AccumulatorConfig) -> (usize, u32) {
    let mut acc: accelcal::accumulator::Accumulator<i16, 16, 32> =
        accelcal::accumulator::Accumulator::new(config).unwrap();
    let mut noise = 1u32;
    for _ in 0..1500 {
        noise = noise.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        let step = ((noise >> 28) as i16 - 8) * 16; // +-8 steps of the 12-bit converter
        acc.push([2047 << 4, 2000 + step, 3000 - step]).unwrap();
    }
    for i in 0..200 {
        acc.push([30000 - i * 100, 2000 + i * 50, 3000]).unwrap();
    }
    acc.finish().unwrap();
    (acc.poses().len(), acc.rejections().saturated)
}

#[test]
fn accumulator_flags_saturation_at_the_format_rail() {
    use accelcal::accumulator::AccumulatorConfig;
    let twelve_bit = RawFormat { full_scale_g: 2.0, resolution_bits: 12, left_justified: true };
    assert_eq!(saturated_poses(AccumulatorConfig::DEFAULT), (1, 0), "i16 limits only: the rail is a pose");
    let config = AccumulatorConfig { full_scale: twelve_bit.accumulator_full_scale(), ..AccumulatorConfig::DEFAULT };
    assert_eq!(saturated_poses(config), (0, 1));
}
