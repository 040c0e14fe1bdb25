//! The sensor path: anything that gives one raw triaxial sample.
//!
//! Implement [`AccelSensor`] for a driver (or wrap an existing embedded-hal driver crate); the
//! calibration code only ever asks for the next sample. Drivers give their bus back with their own
//! `release()` (see [`crate::mpu6050`]).
//!
//! ```
//! use accelcal::sensor::AccelSensor;
//! struct Fixed;
//! impl AccelSensor for Fixed {
//!     type Error = core::convert::Infallible;
//!     fn read_raw(&mut self) -> Result<[i16; 3], Self::Error> { Ok([0, 0, 16384]) }
//! }
//! assert_eq!(Fixed.read_raw(), Ok([0, 0, 16384]));
//! ```

/// A source of raw accelerometer samples (counts, x/y/z).
pub trait AccelSensor {
    /// The driver's error (typically wrapping an `embedded_hal::i2c::Error`).
    type Error;
    /// Reads one sample.
    fn read_raw(&mut self) -> Result<[i16; 3], Self::Error>;

    /// Reads one sample as micromath's `I16x3`.
    fn read_vector(&mut self) -> Result<micromath::vector::I16x3, Self::Error> {
        self.read_raw().map(|[x, y, z]| micromath::vector::I16x3 { x, y, z })
    }
}

impl<T: AccelSensor + ?Sized> AccelSensor for &mut T {
    type Error = T::Error;
    fn read_raw(&mut self) -> Result<[i16; 3], Self::Error> {
        (**self).read_raw()
    }
}

/// Errors of a calibration fed by a sensor: the sensor's own, or the calibration's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Error<E> {
    /// The sensor failed to deliver a sample.
    Sensor(E),
    /// The accumulator refused the sample.
    Accumulator(crate::accumulator::AccumulatorError),
}

impl<E> From<crate::accumulator::AccumulatorError> for Error<E> {
    fn from(e: crate::accumulator::AccumulatorError) -> Self {
        Self::Accumulator(e)
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Sensor(e) => write!(f, "sensor error: {e:?}"),
            Self::Accumulator(e) => write!(f, "{e}"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}
