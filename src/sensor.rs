//! The sensor path: anything that gives one raw triaxial sample.
//!
//! Implement [`AccelSensor`] for a driver; the calibration code only ever asks for the next sample.
//! With the `accelerometer` feature every `accelerometer::RawAccelerometer<I16x3>` driver already is
//! one (`accelcal::accelerometer`). Drivers give their bus back with their own `release()` (see
//! `accelcal::mpu6050`, feature `mpu6050`). [`RawFormat`] describes the register encoding (full scale,
//! resolution, justification) and where a reading saturates.
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
    #[cfg(feature = "micromath")]
    fn read_vector(&mut self) -> Result<micromath::vector::I16x3, Self::Error> {
        self.read_raw().map(|[x, y, z]| micromath::vector::I16x3 { x, y, z })
    }
}

/// How a sensor's raw `i16` registers encode acceleration: full scale and resolution.
///
/// A `resolution_bits`-bit converter whose value is left-justified in the 16-bit register (as many
/// ST parts deliver 10-, 12- or 14-bit data) reads in steps of `2^(16 - bits)` counts and saturates at
/// `+-(2^(bits-1) - 1) << (16 - bits)`, not at the `i16` limits: a 12-bit part at `+-2047 << 4`.
///
/// ```
/// use accelcal::sensor::RawFormat;
/// let lis3dh_normal = RawFormat { full_scale_g: 2.0, resolution_bits: 12, left_justified: true };
/// assert_eq!(lis3dh_normal.saturation_counts(), 2047 << 4);
/// assert_eq!(lis3dh_normal.lsb_per_g(), 16384.0); // counts of the i16 register per g
/// assert_eq!(RawFormat::MPU6050_2G.saturation_counts(), i16::MAX);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RawFormat {
    /// Full scale, g (the `+-` range). Defaults to 2.0.
    pub full_scale_g: f32,
    /// Converter resolution, bits, 1 to 16. Defaults to 16.
    pub resolution_bits: u8,
    /// `true` when a narrower value sits in the high bits of the register. Defaults to `false`.
    pub left_justified: bool,
}

/// Why a [`RawFormat`] is unusable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum RawFormatError {
    /// `full_scale_g` is not a positive finite number.
    FullScale,
    /// `resolution_bits` is 0 or above 16.
    Resolution,
}

impl core::fmt::Display for RawFormatError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::FullScale => f.write_str("full scale must be a positive number of g"),
            Self::Resolution => f.write_str("resolution must be 1 to 16 bits"),
        }
    }
}

impl core::error::Error for RawFormatError {}

impl RawFormat {
    /// A 16-bit sensor at +-2 g (the MPU-6050 at power-on).
    pub const MPU6050_2G: Self = Self { full_scale_g: 2.0, resolution_bits: 16, left_justified: false };

    /// Checks the fields.
    pub fn validate(&self) -> Result<(), RawFormatError> {
        if !(self.full_scale_g > 0.0 && self.full_scale_g.is_finite()) {
            return Err(RawFormatError::FullScale);
        }
        if !(1..=16).contains(&self.resolution_bits) {
            return Err(RawFormatError::Resolution);
        }
        Ok(())
    }

    /// Resolution in bits, values outside 1 to 16 taken as 16.
    const fn bits(&self) -> u32 {
        if self.resolution_bits >= 1 && self.resolution_bits <= 16 { self.resolution_bits as u32 } else { 16 }
    }

    /// Bits the value is shifted left in the register (0 unless left-justified).
    const fn shift_bits(&self) -> u32 {
        if self.left_justified { 16 - self.bits() } else { 0 }
    }

    /// Largest positive reading in register counts; also the magnitude at which a reading counts as
    /// saturated (both signs). Resolutions outside 1 to 16 bits are taken as 16.
    pub const fn saturation_counts(&self) -> i16 {
        (((1u32 << (self.bits() - 1)) - 1) << self.shift_bits()) as i16
    }

    /// Register counts per g: `2^(bits-1) / full_scale_g`, times `2^shift` when left-justified.
    pub fn lsb_per_g(&self) -> f32 {
        (1u32 << (self.bits() - 1 + self.shift_bits())) as f32 / self.full_scale_g
    }

    /// The value for [`AccumulatorConfig::full_scale`](crate::accumulator::AccumulatorConfig::full_scale)
    /// with `i16` counts: samples at or beyond [`RawFormat::saturation_counts`] are flagged saturated.
    pub fn accumulator_full_scale(&self) -> f32 {
        f32::from(self.saturation_counts())
    }

    /// A raw sample in g.
    pub fn to_g(&self, raw: [i16; 3]) -> [f32; 3] {
        let lsb_per_g = self.lsb_per_g();
        raw.map(|v| f32::from(v) / lsb_per_g)
    }
}

impl Default for RawFormat {
    fn default() -> Self {
        Self::MPU6050_2G
    }
}
