//! The calibration as a fixed-size byte array for flash: magic, version, parameters, gravity, CRC-32.
//!
//! Layout (little-endian, [`BLOB_LEN`] bytes): `b"ACAL"`, version `u8`, 3 reserved zero bytes,
//! 9 x `f32` parameters ([`Params::to_array`] order), `f32` gravity, CRC-32 (IEEE) of everything before.
//! CRC-32 detects every single-bit and every burst error up to 32 bits.
//!
//! ```
//! use accelcal::blob::{decode, encode};
//! use accelcal::model::Params;
//! let bytes = encode(&Params::IDENTITY, 9.80665);
//! assert_eq!(decode(&bytes), Ok((Params::IDENTITY, 9.80665)));
//! ```

use crate::model::{PARAM_COUNT, Params};

/// Magic bytes at the start of every blob.
pub const MAGIC: [u8; 4] = *b"ACAL";
/// The layout version this crate writes and reads.
pub const VERSION: u8 = 1;
/// Length of a blob in bytes.
pub const BLOB_LEN: usize = 4 + 4 + 4 * PARAM_COUNT + 4 + 4;

/// Why a blob could not be decoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum BlobError {
    /// The input is not [`BLOB_LEN`] bytes long.
    WrongLength {
        /// Bytes given.
        got: usize,
    },
    /// The magic bytes are wrong: this is not a calibration blob (e.g. erased flash).
    BadMagic,
    /// The CRC does not match: the blob is corrupted.
    BadChecksum,
    /// Written by another layout version.
    UnsupportedVersion {
        /// The version found.
        found: u8,
    },
    /// The stored values are not a usable calibration (non-finite, non-positive scale or gravity,
    /// reserved bytes set).
    InvalidContent,
}

impl core::fmt::Display for BlobError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::WrongLength { got } => write!(f, "calibration blob is {got} bytes, expected {BLOB_LEN}"),
            Self::BadMagic => f.write_str("not a calibration blob (bad magic)"),
            Self::BadChecksum => f.write_str("calibration blob is corrupted (CRC mismatch)"),
            Self::UnsupportedVersion { found } => {
                write!(f, "calibration blob version {found} is not supported (expected {VERSION})")
            }
            Self::InvalidContent => f.write_str("calibration blob holds no usable calibration"),
        }
    }
}

impl core::error::Error for BlobError {}

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

/// Encodes parameters and the gravity they were calibrated against.
pub fn encode(params: &Params, gravity: f32) -> [u8; BLOB_LEN] {
    let mut out = [0u8; BLOB_LEN];
    out[..4].copy_from_slice(&MAGIC);
    out[4] = VERSION;
    let values = params.to_array();
    let at = 8 + 4 * (PARAM_COUNT + 1);
    for (word, v) in out[8..at].chunks_exact_mut(4).zip(values.iter().chain(core::iter::once(&gravity))) {
        word.copy_from_slice(&v.to_le_bytes());
    }
    let crc = crc32(&out[..at]);
    out[at..].copy_from_slice(&crc.to_le_bytes());
    out
}

fn read_f32(bytes: &[u8], at: usize) -> f32 {
    let mut word = [0u8; 4];
    if let Some(src) = bytes.get(at..at + 4) {
        word.copy_from_slice(src);
    }
    f32::from_le_bytes(word)
}

/// Decodes a blob into `(params, gravity)`.
pub fn decode(bytes: &[u8]) -> Result<(Params, f32), BlobError> {
    if bytes.len() != BLOB_LEN {
        return Err(BlobError::WrongLength { got: bytes.len() });
    }
    let body = BLOB_LEN - 4;
    let stored = u32::from_le_bytes([bytes[body], bytes[body + 1], bytes[body + 2], bytes[body + 3]]);
    if crc32(&bytes[..body]) != stored {
        return Err(if bytes[..4] == MAGIC { BlobError::BadChecksum } else { BlobError::BadMagic });
    }
    if bytes[..4] != MAGIC {
        return Err(BlobError::BadMagic);
    }
    if bytes[4] != VERSION {
        return Err(BlobError::UnsupportedVersion { found: bytes[4] });
    }
    if bytes[5..8] != [0, 0, 0] {
        return Err(BlobError::InvalidContent);
    }
    let mut values = [0.0; PARAM_COUNT];
    for (i, v) in values.iter_mut().enumerate() {
        *v = read_f32(bytes, 8 + 4 * i);
    }
    let gravity = read_f32(bytes, 8 + 4 * PARAM_COUNT);
    let params = Params::from_array(values);
    if !params.is_finite() || params.scale.iter().any(|&s| !(s > 0.0)) || !(gravity > 0.0 && gravity.is_finite()) {
        return Err(BlobError::InvalidContent);
    }
    Ok((params, gravity))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc_matches_the_standard_check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
    }

    #[test]
    fn round_trip_and_every_single_bit_flip_is_rejected() {
        let p = Params { bias: [0.1, -0.2, 0.3], scale: [0.97, 1.01, 0.99], nonorth: [-0.01, 0.02, 0.005] };
        let blob = encode(&p, 9.80665);
        assert_eq!(decode(&blob), Ok((p, 9.80665)));
        for bit in 0..BLOB_LEN * 8 {
            let mut bad = blob;
            bad[bit / 8] ^= 1 << (bit % 8);
            assert!(decode(&bad).is_err(), "bit {bit} flip accepted");
        }
    }

    #[test]
    fn wrong_length_version_and_erased_flash() {
        let blob = encode(&Params::IDENTITY, 9.81);
        assert_eq!(decode(&blob[..10]), Err(BlobError::WrongLength { got: 10 }));
        assert_eq!(decode(&[0xFF; BLOB_LEN]), Err(BlobError::BadMagic));
        let mut v2 = blob;
        v2[4] = 2;
        let crc = crc32(&v2[..BLOB_LEN - 4]);
        v2[BLOB_LEN - 4..].copy_from_slice(&crc.to_le_bytes());
        assert_eq!(decode(&v2), Err(BlobError::UnsupportedVersion { found: 2 }));
    }
}
