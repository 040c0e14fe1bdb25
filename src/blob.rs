//! The calibration as a fixed-size byte array for flash: what was fitted, against which sensor set-up
//! and at which temperature, with optional effect terms, protected by a CRC-32 and checked for
//! plausibility when read back.
//!
//! Layout version 2 (little-endian, [`BLOB_LEN`] bytes):
//!
//! | offset | field |
//! |---|---|
//! | 0 | `b"ACAL"` |
//! | 4 | version `u8` = 2 |
//! | 5 | flags `u8`: bit 0 sensor set-up, bit 1 temperature, bit 2 effect terms; other bits zero |
//! | 6 | 2 reserved zero bytes |
//! | 8 | 9 x `f32` parameters ([`Params::to_array`] order) |
//! | 44 | `f32` gravity (output unit) |
//! | 48 | `f32` full scale (g), `f32` LSB per g, `u32` sensor id |
//! | 60 | `f32` temperature at calibration (deg C) |
//! | 64 | 3 x `f32` bias temperature coefficients, 3 x `f32` scale temperature coefficients, 3 x `f32` square terms |
//! | 100 | CRC-32 (IEEE) of bytes 0..100 |
//!
//! A field whose flag is clear is stored as zero bytes. Version 1 blobs ([`BLOB_V1_LEN`] bytes: magic,
//! version, 3 reserved bytes, parameters, gravity, CRC) still decode, with no sensor set-up, temperature
//! or effect terms. CRC-32 detects every single-bit and every burst error up to 32 bits.
//!
//! ```
//! use accelcal::blob::{Blob, SensorSetup, decode, encode};
//! use accelcal::model::Params;
//! let bytes = encode(&Params::IDENTITY, 9.80665);
//! assert_eq!(decode(&bytes), Ok((Params::IDENTITY, 9.80665)));
//!
//! let mut blob = Blob::new(Params::IDENTITY, 9.80665);
//! blob.sensor = Some(SensorSetup { full_scale_g: 4.0, lsb_per_g: 8192.0, sensor_id: 0x68 });
//! blob.temperature_c = Some(24.5);
//! assert_eq!(Blob::from_bytes(&blob.to_bytes()), Ok(blob));
//! ```

use crate::model::{PARAM_COUNT, Params};

/// Magic bytes at the start of every blob.
pub const MAGIC: [u8; 4] = *b"ACAL";
/// The layout version this crate writes.
pub const VERSION: u8 = 2;
/// Length of a version 2 blob (the one [`encode`] writes) in bytes.
pub const BLOB_LEN: usize = 104;
/// Length of a version 1 blob in bytes.
pub const BLOB_V1_LEN: usize = 4 + 4 + 4 * PARAM_COUNT + 4 + 4;

const FLAG_SENSOR: u8 = 1;
const FLAG_TEMPERATURE: u8 = 2;
const FLAG_EFFECTS: u8 = 4;
const AT_PARAMS: usize = 8;
const AT_GRAVITY: usize = AT_PARAMS + 4 * PARAM_COUNT;
const AT_SENSOR: usize = AT_GRAVITY + 4;
const AT_TEMPERATURE: usize = AT_SENSOR + 12;
const AT_EFFECTS: usize = AT_TEMPERATURE + 4;
const AT_CRC: usize = AT_EFFECTS + 36;

/// A field of the blob, named in [`BlobError::NotFinite`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Field {
    /// [`Params::bias`].
    Bias,
    /// [`Params::scale`].
    Scale,
    /// [`Params::nonorth`].
    Nonorth,
    /// [`Blob::gravity`].
    Gravity,
    /// [`SensorSetup::full_scale_g`].
    FullScale,
    /// [`SensorSetup::lsb_per_g`].
    LsbPerG,
    /// [`Blob::temperature_c`].
    Temperature,
    /// [`Effects::bias_per_c`].
    BiasTempco,
    /// [`Effects::scale_per_c`].
    ScaleTempco,
    /// [`Effects::square`].
    Square,
}

/// Why a blob could not be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BlobError {
    /// The input is neither [`BLOB_LEN`] nor [`BLOB_V1_LEN`] bytes long.
    WrongLength {
        /// Bytes given.
        got: usize,
    },
    /// The magic bytes are wrong: this is not a calibration blob (e.g. erased flash).
    BadMagic,
    /// The CRC does not match: the blob is corrupted.
    BadChecksum,
    /// Written by a layout version this crate does not read, or a version whose length differs.
    UnsupportedVersion {
        /// The version found.
        found: u8,
    },
    /// Reserved bytes or unknown flag bits are set, or a field whose flag is clear is not zero.
    ReservedBitsSet,
    /// A value is NaN or infinite.
    NotFinite {
        /// Which one.
        field: Field,
    },
    /// A scale factor (`Sxx`, `Syy`, `Szz`) is zero or negative.
    NonPositiveScale {
        /// Axis index (0 = x).
        axis: u8,
    },
    /// Gravity is zero or negative.
    NonPositiveGravity,
    /// The full scale or the LSB per g is zero or negative.
    NonPositiveSensorSetup,
    /// A bias is larger than the sensor's full scale (`full_scale_g * gravity`).
    BiasBeyondFullScale {
        /// Axis index (0 = x).
        axis: u8,
    },
    /// Effect terms are present without the temperature they are relative to.
    EffectsWithoutTemperature,
}

impl core::fmt::Display for BlobError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::WrongLength { got } => {
                write!(f, "calibration blob is {got} bytes, expected {BLOB_LEN} (or {BLOB_V1_LEN} for version 1)")
            }
            Self::BadMagic => f.write_str("not a calibration blob (bad magic)"),
            Self::BadChecksum => f.write_str("calibration blob is corrupted (CRC mismatch)"),
            Self::UnsupportedVersion { found } => write!(f, "calibration blob version {found} is not supported"),
            Self::ReservedBitsSet => f.write_str("calibration blob has reserved bits set"),
            Self::NotFinite { field } => write!(f, "calibration blob field {field:?} is not finite"),
            Self::NonPositiveScale { axis } => {
                write!(f, "calibration blob scale of axis {} is not positive", crate::axis_name(*axis))
            }
            Self::NonPositiveGravity => f.write_str("calibration blob gravity is not positive"),
            Self::NonPositiveSensorSetup => f.write_str("calibration blob full scale or LSB per g is not positive"),
            Self::BiasBeyondFullScale { axis } => {
                write!(f, "calibration blob bias of axis {} exceeds the full scale", crate::axis_name(*axis))
            }
            Self::EffectsWithoutTemperature => f.write_str("calibration blob has effect terms but no temperature"),
        }
    }
}

impl core::error::Error for BlobError {}

/// The sensor set-up the calibration was made with.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SensorSetup {
    /// Full scale, g (e.g. 4.0 for +-4 g). Must be positive.
    pub full_scale_g: f32,
    /// Sensitivity, LSB per g (e.g. 8192.0). Must be positive.
    pub lsb_per_g: f32,
    /// Which sensor: a part id (e.g. WHO_AM_I) or a serial number, as the firmware chooses.
    pub sensor_id: u32,
}

/// Optional effect terms beyond the 9-parameter model, used by [`Blob::apply`].
///
/// With `dT = T - T_cal` (deg C), axis `i` is corrected as
/// `f_b[i] = (1 + scale_per_c[i] dT) (Ka f_s)[i] + square[i] f_s[i]^2 - (B[i] + bias_per_c[i] dT)`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Effects {
    /// Temperature coefficient of the bias, output unit per deg C.
    pub bias_per_c: [f32; 3],
    /// Relative temperature coefficient of the scale, 1 per deg C.
    pub scale_per_c: [f32; 3],
    /// Per-axis square term, output unit per input unit squared.
    pub square: [f32; 3],
}

/// Everything a blob holds.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Blob {
    /// The fitted parameters.
    pub params: Params,
    /// The gravity they were fitted against (output unit).
    pub gravity: f32,
    /// Full scale, sensitivity and sensor id, when known.
    pub sensor: Option<SensorSetup>,
    /// Temperature at calibration, deg C, when known.
    pub temperature_c: Option<f32>,
    /// Temperature and square terms, when fitted (they need `temperature_c`).
    pub effects: Option<Effects>,
}

impl Blob {
    /// Parameters and gravity only.
    pub const fn new(params: Params, gravity: f32) -> Self {
        Self { params, gravity, sensor: None, temperature_c: None, effects: None }
    }

    /// Calibrates one sample, with the effect terms when present. `temperature_c` is the sensor's
    /// temperature now; `None` (or a blob without temperature) applies no temperature correction.
    pub fn apply(&self, f_s: [f32; 3], temperature_c: Option<f32>) -> [f32; 3] {
        let Some(e) = self.effects else { return self.params.apply(f_s) };
        let dt = match (temperature_c, self.temperature_c) {
            (Some(now), Some(then)) => now - then,
            _ => 0.0,
        };
        let k = self.params.ka_times(f_s);
        let mut out = [0.0; 3];
        for i in 0..3 {
            let bias = self.params.bias[i] + e.bias_per_c[i] * dt;
            out[i] = (1.0 + e.scale_per_c[i] * dt) * k[i] + e.square[i] * f_s[i] * f_s[i] - bias;
        }
        out
    }

    /// The version 2 bytes.
    pub fn to_bytes(&self) -> [u8; BLOB_LEN] {
        let mut out = [0u8; BLOB_LEN];
        out[..4].copy_from_slice(&MAGIC);
        out[4] = VERSION;
        put_f32s(&mut out, AT_PARAMS, &self.params.to_array());
        put_f32s(&mut out, AT_GRAVITY, &[self.gravity]);
        if let Some(s) = self.sensor {
            out[5] |= FLAG_SENSOR;
            put_f32s(&mut out, AT_SENSOR, &[s.full_scale_g, s.lsb_per_g]);
            out[AT_SENSOR + 8..AT_TEMPERATURE].copy_from_slice(&s.sensor_id.to_le_bytes());
        }
        if let Some(t) = self.temperature_c {
            out[5] |= FLAG_TEMPERATURE;
            put_f32s(&mut out, AT_TEMPERATURE, &[t]);
        }
        if let Some(e) = self.effects {
            out[5] |= FLAG_EFFECTS;
            put_f32s(&mut out, AT_EFFECTS, &e.bias_per_c);
            put_f32s(&mut out, AT_EFFECTS + 12, &e.scale_per_c);
            put_f32s(&mut out, AT_EFFECTS + 24, &e.square);
        }
        let crc = crc32(&out[..AT_CRC]);
        out[AT_CRC..].copy_from_slice(&crc.to_le_bytes());
        out
    }

    /// Reads a version 2 or version 1 blob and checks that it is a plausible calibration.
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, BlobError> {
        let blob = if let Ok(v2) = <&[u8; BLOB_LEN]>::try_from(bytes) {
            check_frame(v2)?;
            match v2[4] {
                VERSION => read_v2(v2)?,
                found => return Err(BlobError::UnsupportedVersion { found }),
            }
        } else if let Ok(v1) = <&[u8; BLOB_V1_LEN]>::try_from(bytes) {
            check_frame(v1)?;
            match v1[4] {
                1 => read_v1(v1)?,
                found => return Err(BlobError::UnsupportedVersion { found }),
            }
        } else {
            return Err(BlobError::WrongLength { got: bytes.len() });
        };
        blob.check()?;
        Ok(blob)
    }

    /// The plausibility checks of [`Blob::from_bytes`]: finite values, positive scales, gravity and
    /// sensor set-up, biases within the full scale, effect terms only with a temperature.
    pub fn check(&self) -> Result<(), BlobError> {
        check_params(&self.params)?;
        check_positive(self.gravity, Field::Gravity, BlobError::NonPositiveGravity)?;
        if let Some(s) = self.sensor {
            check_sensor(&s, &self.params, self.gravity)?;
        }
        if let Some(t) = self.temperature_c {
            check_finite(&[t], Field::Temperature)?;
        }
        if let Some(e) = self.effects {
            if self.temperature_c.is_none() {
                return Err(BlobError::EffectsWithoutTemperature);
            }
            check_finite(&e.bias_per_c, Field::BiasTempco)?;
            check_finite(&e.scale_per_c, Field::ScaleTempco)?;
            check_finite(&e.square, Field::Square)?;
        }
        Ok(())
    }
}

fn check_finite(values: &[f32], field: Field) -> Result<(), BlobError> {
    if values.iter().all(|v| v.is_finite()) { Ok(()) } else { Err(BlobError::NotFinite { field }) }
}

fn check_positive(value: f32, field: Field, not_positive: BlobError) -> Result<(), BlobError> {
    check_finite(&[value], field)?;
    if value > 0.0 { Ok(()) } else { Err(not_positive) }
}

fn check_params(p: &Params) -> Result<(), BlobError> {
    check_finite(&p.bias, Field::Bias)?;
    check_finite(&p.scale, Field::Scale)?;
    check_finite(&p.nonorth, Field::Nonorth)?;
    match p.scale.iter().position(|&s| !(s > 0.0)) {
        Some(axis) => Err(BlobError::NonPositiveScale { axis: axis as u8 }),
        None => Ok(()),
    }
}

fn check_sensor(s: &SensorSetup, p: &Params, gravity: f32) -> Result<(), BlobError> {
    check_positive(s.full_scale_g, Field::FullScale, BlobError::NonPositiveSensorSetup)?;
    check_positive(s.lsb_per_g, Field::LsbPerG, BlobError::NonPositiveSensorSetup)?;
    let full_scale = s.full_scale_g * gravity;
    match p.bias.iter().position(|b| b.abs() > full_scale) {
        Some(axis) => Err(BlobError::BiasBeyondFullScale { axis: axis as u8 }),
        None => Ok(()),
    }
}

/// CRC and magic of a blob whose last 4 bytes are the CRC of the others.
fn check_frame<const N: usize>(bytes: &[u8; N]) -> Result<(), BlobError> {
    let Some((body, crc)) = bytes.split_last_chunk::<4>() else { return Err(BlobError::WrongLength { got: N }) };
    let magic_ok = body.first_chunk::<4>() == Some(&MAGIC);
    if crc32(body) != u32::from_le_bytes(*crc) {
        return Err(if magic_ok { BlobError::BadChecksum } else { BlobError::BadMagic });
    }
    if !magic_ok {
        return Err(BlobError::BadMagic);
    }
    Ok(())
}

fn read_v1(bytes: &[u8; BLOB_V1_LEN]) -> Result<Blob, BlobError> {
    if bytes[5..8] != [0, 0, 0] {
        return Err(BlobError::ReservedBitsSet);
    }
    Ok(Blob::new(read_params(bytes), read_f32(bytes, AT_GRAVITY)))
}

fn read_v2(bytes: &[u8; BLOB_LEN]) -> Result<Blob, BlobError> {
    let flags = bytes[5];
    if flags & !(FLAG_SENSOR | FLAG_TEMPERATURE | FLAG_EFFECTS) != 0 || bytes[6..8] != [0, 0] {
        return Err(BlobError::ReservedBitsSet);
    }
    for (flag, range) in [
        (FLAG_SENSOR, AT_SENSOR..AT_TEMPERATURE),
        (FLAG_TEMPERATURE, AT_TEMPERATURE..AT_EFFECTS),
        (FLAG_EFFECTS, AT_EFFECTS..AT_CRC),
    ] {
        if flags & flag == 0 && bytes.get(range).is_some_and(|field| field.iter().any(|&b| b != 0)) {
            return Err(BlobError::ReservedBitsSet);
        }
    }
    let mut blob = Blob::new(read_params(bytes), read_f32(bytes, AT_GRAVITY));
    if flags & FLAG_SENSOR != 0 {
        let id = [bytes[AT_SENSOR + 8], bytes[AT_SENSOR + 9], bytes[AT_SENSOR + 10], bytes[AT_SENSOR + 11]];
        let (full_scale_g, lsb_per_g) = (read_f32(bytes, AT_SENSOR), read_f32(bytes, AT_SENSOR + 4));
        blob.sensor = Some(SensorSetup { full_scale_g, lsb_per_g, sensor_id: u32::from_le_bytes(id) });
    }
    if flags & FLAG_TEMPERATURE != 0 {
        blob.temperature_c = Some(read_f32(bytes, AT_TEMPERATURE));
    }
    if flags & FLAG_EFFECTS != 0 {
        let three = |at| [read_f32(bytes, at), read_f32(bytes, at + 4), read_f32(bytes, at + 8)];
        let (bias_per_c, scale_per_c, square) = (three(AT_EFFECTS), three(AT_EFFECTS + 12), three(AT_EFFECTS + 24));
        blob.effects = Some(Effects { bias_per_c, scale_per_c, square });
    }
    Ok(blob)
}

fn read_params(bytes: &[u8]) -> Params {
    let mut values = [0.0; PARAM_COUNT];
    for (i, v) in values.iter_mut().enumerate() {
        *v = read_f32(bytes, AT_PARAMS + 4 * i);
    }
    Params::from_array(values)
}

fn put_f32s(out: &mut [u8], at: usize, values: &[f32]) {
    for (i, v) in values.iter().enumerate() {
        if let Some(dst) = out.get_mut(at + 4 * i..at + 4 * i + 4) {
            dst.copy_from_slice(&v.to_le_bytes());
        }
    }
}

fn read_f32(bytes: &[u8], at: usize) -> f32 {
    let mut word = [0u8; 4];
    if let Some(src) = bytes.get(at..at + 4) {
        word.copy_from_slice(src);
    }
    f32::from_le_bytes(word)
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), bitwise: no table in flash.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            let mask = (crc & 1).wrapping_neg();
            crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
        }
    }
    !crc
}

/// Encodes parameters and the gravity they were calibrated against as a version 2 blob with no
/// sensor set-up, temperature or effect terms (see [`Blob::to_bytes`] for those).
pub fn encode(params: &Params, gravity: f32) -> [u8; BLOB_LEN] {
    Blob::new(*params, gravity).to_bytes()
}

/// Decodes a version 2 or version 1 blob into `(params, gravity)` (see [`Blob::from_bytes`]).
pub fn decode(bytes: &[u8]) -> Result<(Params, f32), BlobError> {
    Blob::from_bytes(bytes).map(|b| (b.params, b.gravity))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_matches_the_standard_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn layout_offsets_add_up() {
        assert_eq!(AT_CRC + 4, BLOB_LEN);
        assert_eq!(BLOB_V1_LEN, 52);
    }
}
