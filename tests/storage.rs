//! Two-slot calibration storage on an in-memory NOR flash, including power lost mid-write/mid-erase.

use accelcal::blob::Blob;
use accelcal::model::Params;
use accelcal::storage::{CalibrationStore, RECORD_LEN, StorageError};
use embedded_storage::nor_flash::{
    ErrorType, NorFlash, NorFlashErrorKind, ReadNorFlash, check_erase, check_read, check_write,
};

const SECTOR: usize = 256;
const CAPACITY: usize = 4 * SECTOR;

/// NOR semantics: erase sets bytes to 0xFF, a write can only clear bits and only on erased words.
/// `budget` counts the bytes still written or erased before the power is lost (`None`: never).
struct MockFlash {
    data: Vec<u8>,
    budget: Option<usize>,
}

impl MockFlash {
    fn new() -> Self {
        Self { data: vec![0xFF; CAPACITY], budget: None }
    }

    /// Takes one byte of the power budget: `false` when the power is gone.
    fn spend(&mut self) -> bool {
        match &mut self.budget {
            Some(0) => false,
            Some(n) => {
                *n -= 1;
                true
            }
            None => true,
        }
    }
}

impl ErrorType for MockFlash {
    type Error = NorFlashErrorKind;
}

impl ReadNorFlash for MockFlash {
    const READ_SIZE: usize = 4;

    fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        check_read(self, offset, bytes.len())?;
        bytes.copy_from_slice(&self.data[offset as usize..offset as usize + bytes.len()]);
        Ok(())
    }

    fn capacity(&self) -> usize {
        CAPACITY
    }
}

impl NorFlash for MockFlash {
    const WRITE_SIZE: usize = 8;
    const ERASE_SIZE: usize = SECTOR;

    fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        check_erase(self, from, to)?;
        for i in from as usize..to as usize {
            if !self.spend() {
                return Err(NorFlashErrorKind::Other);
            }
            self.data[i] = 0xFF;
        }
        Ok(())
    }

    fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        check_write(self, offset, bytes.len())?;
        let at = offset as usize;
        if self.data[at..at + bytes.len()].iter().any(|&b| b != 0xFF) {
            return Err(NorFlashErrorKind::Other); // writing over unerased flash
        }
        for (i, &b) in bytes.iter().enumerate() {
            if !self.spend() {
                return Err(NorFlashErrorKind::Other);
            }
            self.data[at + i] &= b;
        }
        Ok(())
    }
}

fn blob(bias_x: f32) -> Blob {
    let params = Params { bias: [bias_x, -0.2, 0.3], scale: [0.97, 1.01, 0.99], nonorth: [-0.01, 0.02, 0.005] };
    Blob { temperature_c: Some(21.0), ..Blob::new(params, 9.806_65) }
}

fn store_on(flash: MockFlash) -> CalibrationStore<MockFlash> {
    CalibrationStore::new(flash, SECTOR as u32, SECTOR as u32).unwrap()
}

#[test]
fn empty_flash_loads_nothing_then_stores_alternate() {
    let mut store = store_on(MockFlash::new());
    assert_eq!(store.load(), Ok(None));
    for (i, bias) in [0.1, 0.2, 0.3, 0.4].into_iter().enumerate() {
        assert_eq!(store.store(&blob(bias)), Ok(i as u32 + 1));
        let loaded = store.load().unwrap().unwrap();
        assert_eq!((loaded.blob, loaded.sequence), (blob(bias), i as u32 + 1));
    }
    let flash = store.release();
    // The records alternate: slot 0 (offset 256) holds sequences 1 and 3, slot 1 (512) holds 2 and 4.
    assert_eq!(&flash.data[SECTOR..SECTOR + 4], b"ACSR");
    assert_eq!(flash.data[SECTOR + 4], 3);
    assert_eq!(flash.data[2 * SECTOR + 4], 4);
    // The padding up to the write size is erased flash; nothing is written outside the slots.
    assert!(flash.data[SECTOR + RECORD_LEN..2 * SECTOR].iter().all(|&b| b == 0xFF));
    assert!(flash.data[..SECTOR].iter().chain(&flash.data[3 * SECTOR..]).all(|&b| b == 0xFF));
}

#[test]
fn power_lost_at_any_byte_of_a_store_keeps_the_previous_calibration() {
    let mut store = store_on(MockFlash::new());
    store.store(&blob(0.1)).unwrap();
    store.store(&blob(0.2)).unwrap();
    let before = store.release();
    // A store erases one sector and writes one padded record: try losing power after every byte.
    let padded = RECORD_LEN.div_ceil(8) * 8;
    for budget in 0..SECTOR + padded {
        let mut flash = MockFlash { data: before.data.clone(), budget: Some(budget) };
        let mut store = CalibrationStore::new(&mut flash, SECTOR as u32, SECTOR as u32).unwrap();
        assert_eq!(store.store(&blob(0.3)), Err(StorageError::Flash(NorFlashErrorKind::Other)), "budget {budget}");
        flash.budget = None;
        let mut store = store_on(flash);
        // Only the 0xFF padding was left to write once the whole record is in: then the new one reads.
        let complete = budget >= SECTOR + RECORD_LEN;
        let expected = if complete { (blob(0.3), 3) } else { (blob(0.2), 2) };
        let loaded = store.load().unwrap().unwrap();
        assert_eq!((loaded.blob, loaded.sequence), expected, "power lost after {budget} bytes");
        // The next store after the power returns succeeds and wins.
        assert_eq!(store.store(&blob(0.4)), Ok(expected.1 + 1));
        assert_eq!(store.load().unwrap().unwrap().blob, blob(0.4));
    }
    // With enough power the same store completes.
    let mut flash = MockFlash { data: before.data, budget: Some(SECTOR + padded) };
    assert_eq!(store_on_ref(&mut flash).store(&blob(0.3)), Ok(3));
}

fn store_on_ref(flash: &mut MockFlash) -> CalibrationStore<&mut MockFlash> {
    CalibrationStore::new(flash, SECTOR as u32, SECTOR as u32).unwrap()
}

#[test]
fn a_corrupted_slot_is_skipped() {
    let mut store = store_on(MockFlash::new());
    store.store(&blob(0.1)).unwrap();
    store.store(&blob(0.2)).unwrap();
    let mut flash = store.release();
    flash.data[2 * SECTOR + 40] ^= 0x04; // a bit of the newest record (slot 1) flips
    let mut store = store_on(flash);
    assert_eq!(store.load().unwrap().unwrap().blob, blob(0.1));
    // The next store replaces the corrupted slot, not the good one.
    assert_eq!(store.store(&blob(0.3)), Ok(2));
    let flash = store.release();
    assert_eq!(flash.data[SECTOR + 4], 1);
    assert_eq!(flash.data[2 * SECTOR + 4], 2);
}

#[test]
fn implausible_blob_is_not_stored() {
    let mut store = store_on(MockFlash::new());
    let mut bad = blob(0.1);
    bad.params.scale[1] = 0.0;
    assert!(matches!(store.store(&bad), Err(StorageError::Blob(_))));
    assert_eq!(store.load(), Ok(None));
}

#[test]
fn geometry_is_checked() {
    let bad = [(1, SECTOR), (0, SECTOR / 2), (0, 3 * SECTOR), (2 * SECTOR, 2 * SECTOR)];
    for (base, slot_len) in bad {
        let result = CalibrationStore::new(MockFlash::new(), base as u32, slot_len as u32);
        assert!(matches!(result, Err(StorageError::Geometry)), "base {base} slot {slot_len}");
    }
    assert!(CalibrationStore::new(MockFlash::new(), 2 * SECTOR as u32, SECTOR as u32).is_ok());
}
