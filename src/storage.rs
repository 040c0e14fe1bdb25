//! The calibration in NOR flash, safe against power loss: two slots, written alternately, each record
//! with a sequence number and a CRC-32, so a write cut short leaves the previous calibration readable.
//!
//! A record is `b"ACSR"`, the sequence number (`u32`, little-endian), the [`Blob`] bytes
//! ([`BLOB_LEN`]) and a CRC-32 of all of that ([`RECORD_LEN`] bytes), padded with `0xFF` to a
//! multiple of the flash's write size. [`CalibrationStore::store`] erases and writes the slot that
//! does not hold the newest record; [`CalibrationStore::load`] returns the newest record whose CRC and
//! blob checks pass. Each slot is a whole number of erase sectors.
//!
//! ```
//! # use embedded_storage::nor_flash::{ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash};
//! # struct Ram([u8; 2048]);
//! # impl ErrorType for Ram { type Error = NorFlashErrorKind; }
//! # impl ReadNorFlash for Ram {
//! #     const READ_SIZE: usize = 1;
//! #     fn read(&mut self, at: u32, out: &mut [u8]) -> Result<(), Self::Error> {
//! #         out.copy_from_slice(&self.0[at as usize..at as usize + out.len()]); Ok(())
//! #     }
//! #     fn capacity(&self) -> usize { self.0.len() }
//! # }
//! # impl NorFlash for Ram {
//! #     const WRITE_SIZE: usize = 4;
//! #     const ERASE_SIZE: usize = 512;
//! #     fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
//! #         self.0[from as usize..to as usize].fill(0xFF); Ok(())
//! #     }
//! #     fn write(&mut self, at: u32, data: &[u8]) -> Result<(), Self::Error> {
//! #         self.0[at as usize..at as usize + data.len()].copy_from_slice(data); Ok(())
//! #     }
//! # }
//! use accelcal::blob::Blob;
//! use accelcal::model::Params;
//! use accelcal::storage::CalibrationStore;
//! let flash = Ram([0xFF; 2048]);
//! let mut store = CalibrationStore::new(flash, 1024, 512).unwrap(); // slots at 1024 and 1536
//! assert_eq!(store.load(), Ok(None));
//! let blob = Blob::new(Params::IDENTITY, 9.80665);
//! assert_eq!(store.store(&blob), Ok(1));
//! assert_eq!(store.load().unwrap().map(|r| r.blob), Some(blob));
//! ```

use embedded_storage::nor_flash::NorFlash;

use crate::blob::{BLOB_LEN, Blob, BlobError, crc32};

/// Magic bytes at the start of every record.
pub const RECORD_MAGIC: [u8; 4] = *b"ACSR";
/// Length of a record before padding: magic, sequence number, blob, CRC-32.
pub const RECORD_LEN: usize = 4 + 4 + BLOB_LEN + 4;
/// Largest padded record: flash whose write (or read) size pads a record beyond this is refused.
pub const MAX_PADDED_LEN: usize = 256;

/// Why the calibration could not be stored or loaded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum StorageError<E> {
    /// The flash driver failed.
    Flash(E),
    /// The slots do not fit this flash: base or slot length not a multiple of the erase size, a slot
    /// shorter than a padded record, the two slots beyond the capacity, or a write/read size that pads
    /// a record beyond [`MAX_PADDED_LEN`].
    Geometry,
    /// [`CalibrationStore::store`] was given a blob that fails [`Blob::check`].
    Blob(BlobError),
}

impl<E: core::fmt::Debug> core::fmt::Display for StorageError<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::Flash(e) => write!(f, "flash error: {e:?}"),
            Self::Geometry => f.write_str("calibration slots do not fit the flash geometry"),
            Self::Blob(e) => write!(f, "{e}"),
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for StorageError<E> {}

/// A record read back: the blob and the sequence number it was written with.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StoredCalibration {
    /// The calibration.
    pub blob: Blob,
    /// 1 for the first store, one more for each store after it (wrapping).
    pub sequence: u32,
}

/// Two flash slots holding the calibration.
#[derive(Debug)]
pub struct CalibrationStore<F> {
    flash: F,
    base: u32,
    slot_len: u32,
}

#[cfg(feature = "defmt")]
impl<F> defmt::Format for CalibrationStore<F> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "CalibrationStore {{ base: {=u32:#x}, slot_len: {=u32} }}", self.base, self.slot_len)
    }
}

/// `true` when sequence `a` was written after `b` (serial-number arithmetic, wraps at `u32::MAX`).
pub const fn is_newer(a: u32, b: u32) -> bool {
    (a.wrapping_sub(b) as i32) > 0
}

impl<F: NorFlash> CalibrationStore<F> {
    /// Uses slots `[base, base + slot_len)` and `[base + slot_len, base + 2 slot_len)` (bytes from
    /// the start of `flash`). Reads and writes nothing yet.
    pub fn new(flash: F, base: u32, slot_len: u32) -> Result<Self, StorageError<F::Error>> {
        let store = Self { flash, base, slot_len };
        let padded = Self::padded_len().ok_or(StorageError::Geometry)?;
        let (base, slot_len) = (base as usize, slot_len as usize);
        let end = slot_len.checked_mul(2).and_then(|two| two.checked_add(base));
        let fits = end.is_some_and(|end| end <= store.flash.capacity());
        if F::ERASE_SIZE == 0
            || base % F::ERASE_SIZE != 0
            || slot_len % F::ERASE_SIZE != 0
            || slot_len < padded
            || !fits
        {
            return Err(StorageError::Geometry);
        }
        Ok(store)
    }

    /// [`RECORD_LEN`] rounded up to the write size; `None` when that is not a multiple of the read
    /// size or exceeds [`MAX_PADDED_LEN`].
    fn padded_len() -> Option<usize> {
        let (write, read) = (F::WRITE_SIZE, F::READ_SIZE);
        if write == 0 || read == 0 {
            return None;
        }
        let padded = RECORD_LEN.div_ceil(write) * write;
        (padded % read == 0 && padded <= MAX_PADDED_LEN).then_some(padded)
    }

    fn slot_offset(&self, slot: u32) -> u32 {
        self.base + slot * self.slot_len
    }

    /// The newest record whose CRC and blob checks pass; `None` when neither slot holds one (new or
    /// erased flash).
    pub fn load(&mut self) -> Result<Option<StoredCalibration>, StorageError<F::Error>> {
        let first = self.read_slot(0)?;
        let second = self.read_slot(1)?;
        Ok(match (first, second) {
            (Some(a), Some(b)) => Some(if is_newer(b.sequence, a.sequence) { b } else { a }),
            (a, b) => a.or(b),
        })
    }

    /// Writes `blob` with the next sequence number into the slot not holding the newest record, and
    /// returns that sequence number. The newest record is never erased: a write cut short by power
    /// loss leaves it as what [`CalibrationStore::load`] returns.
    pub fn store(&mut self, blob: &Blob) -> Result<u32, StorageError<F::Error>> {
        blob.check().map_err(StorageError::Blob)?;
        let padded = Self::padded_len().ok_or(StorageError::Geometry)?;
        let (first, second) = (self.read_slot(0)?, self.read_slot(1)?);
        let (slot, newest) = match (first, second) {
            (Some(a), Some(b)) if is_newer(b.sequence, a.sequence) => (0, b.sequence),
            (Some(a), _) => (1, a.sequence),
            (None, Some(b)) => (0, b.sequence),
            (None, None) => (0, 0),
        };
        let sequence = newest.wrapping_add(1);
        let mut record = [0xFF; MAX_PADDED_LEN];
        write_record(&mut record, sequence, blob);
        let from = self.slot_offset(slot);
        self.flash.erase(from, from + self.slot_len).map_err(StorageError::Flash)?;
        let bytes = record.get(..padded).ok_or(StorageError::Geometry)?;
        self.flash.write(from, bytes).map_err(StorageError::Flash)?;
        Ok(sequence)
    }

    /// The record in `slot` (0 or 1), `None` when it is erased, torn or corrupted.
    fn read_slot(&mut self, slot: u32) -> Result<Option<StoredCalibration>, StorageError<F::Error>> {
        let padded = Self::padded_len().ok_or(StorageError::Geometry)?;
        let mut record = [0u8; MAX_PADDED_LEN];
        let bytes = record.get_mut(..padded).ok_or(StorageError::Geometry)?;
        self.flash.read(self.slot_offset(slot), bytes).map_err(StorageError::Flash)?;
        Ok(read_record(&record))
    }

    /// Gives the flash back.
    pub fn release(self) -> F {
        self.flash
    }
}

fn write_record(out: &mut [u8; MAX_PADDED_LEN], sequence: u32, blob: &Blob) {
    out[..4].copy_from_slice(&RECORD_MAGIC);
    out[4..8].copy_from_slice(&sequence.to_le_bytes());
    out[8..8 + BLOB_LEN].copy_from_slice(&blob.to_bytes());
    let crc = crc32(&out[..RECORD_LEN - 4]);
    out[RECORD_LEN - 4..RECORD_LEN].copy_from_slice(&crc.to_le_bytes());
}

fn read_record(record: &[u8; MAX_PADDED_LEN]) -> Option<StoredCalibration> {
    let word =
        |at: usize| record.get(at..at + 4).and_then(|w| <[u8; 4]>::try_from(w).ok()).map_or(0, u32::from_le_bytes);
    if record[..4] != RECORD_MAGIC || crc32(&record[..RECORD_LEN - 4]) != word(RECORD_LEN - 4) {
        return None;
    }
    let blob = Blob::from_bytes(&record[8..8 + BLOB_LEN]).ok()?;
    Some(StoredCalibration { blob, sequence: word(4) })
}

#[cfg(test)]
mod tests {
    use super::is_newer;

    #[test]
    fn sequence_comparison_wraps() {
        assert!(is_newer(2, 1));
        assert!(!is_newer(1, 2));
        assert!(!is_newer(5, 5));
        assert!(is_newer(0, u32::MAX));
        assert!(is_newer(3, u32::MAX - 2));
    }
}
