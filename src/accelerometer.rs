//! Any [`accelerometer`] crate driver is an [`AccelSensor`]: every `RawAccelerometer<I16x3>` reads
//! raw samples for the accumulator and the session with no glue code.
//!
//! The `accelerometer` crate (0.12) is built on micromath 1, this crate on micromath 2.1: its `I16x3`
//! is another type than `micromath::vector::I16x3`, so the sample is converted field by field here.
//! Its error type has no `PartialEq` or `defmt::Format`; [`AccelerometerError`] carries the same kind
//! and cause with both.
//!
//! ```
//! use accelcal::accelerometer::AccelerometerError;
//! use accelcal::sensor::AccelSensor;
//! use accelerometer::{Error, ErrorKind, RawAccelerometer, vector::I16x3};
//! struct Lis3dh; // stands in for a driver crate's type
//! impl RawAccelerometer<I16x3> for Lis3dh {
//!     type Error = ();
//!     fn accel_raw(&mut self) -> Result<I16x3, Error<()>> { Ok(I16x3::new(16, -32, 16384)) }
//! }
//! assert_eq!(Lis3dh.read_raw(), Ok([16, -32, 16384]));
//! ```

use accelerometer::{ErrorKind, RawAccelerometer, vector::I16x3};

use crate::sensor::AccelSensor;

/// What went wrong, as `accelerometer::ErrorKind` says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AccelerometerErrorKind {
    /// The bus failed.
    Bus,
    /// The device failed or is not the expected one.
    Device,
    /// The device is in the wrong mode.
    Mode,
    /// A parameter was invalid.
    Param,
}

/// An `accelerometer::Error` of a driver: its kind and the driver's own error, when it gave one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AccelerometerError<E> {
    /// The kind.
    pub kind: AccelerometerErrorKind,
    /// The driver's error.
    pub cause: Option<E>,
}

impl<E: core::fmt::Debug> From<accelerometer::Error<E>> for AccelerometerError<E> {
    fn from(e: accelerometer::Error<E>) -> Self {
        let kind = match e.kind() {
            ErrorKind::Bus => AccelerometerErrorKind::Bus,
            ErrorKind::Device => AccelerometerErrorKind::Device,
            ErrorKind::Mode => AccelerometerErrorKind::Mode,
            ErrorKind::Param => AccelerometerErrorKind::Param,
        };
        // `into_cause` is only called when there is a cause, so it cannot panic.
        let cause = if e.cause().is_some() { Some(e.into_cause()) } else { None };
        Self { kind, cause }
    }
}

impl<E: core::fmt::Debug> core::fmt::Display for AccelerometerError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match &self.cause {
            Some(cause) => write!(f, "accelerometer {:?} error: {cause:?}", self.kind),
            None => write!(f, "accelerometer {:?} error", self.kind),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for AccelerometerError<E> {}

impl<T: RawAccelerometer<I16x3>> AccelSensor for T {
    type Error = AccelerometerError<T::Error>;

    fn read_raw(&mut self) -> Result<[i16; 3], Self::Error> {
        let v = self.accel_raw()?;
        Ok([v.x, v.y, v.z])
    }
}
