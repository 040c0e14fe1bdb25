//! A simulated InvenSense MPU-6050 on an [`embedded_hal::i2c::I2c`] bus, answering from a sample
//! stream (e.g. a [`sim::Recording`](crate::sim::Recording)), so that firmware code (the
//! [`accelcal::mpu6050`] driver, [`accelcal::session`]) runs on the host exactly as on the board.
//!
//! The device model, re-declared from the *MPU-6000 and MPU-6050 Register Map and Descriptions*
//! revision 4.2 (not taken from the driver):
//!
//! - 7-bit address 0x68 (AD0 low); any other address is not acknowledged;
//! - a register pointer set by the first byte of a write, auto-incremented by further written and by
//!   read bytes;
//! - WHO_AM_I (0x75) reads 0x68 and is read-only; PWR_MGMT_1 (0x6B) powers up as 0x40 (SLEEP), its
//!   DEVICE_RESET bit (7) restores every register to its power-on value; ACCEL_CONFIG (0x1C) bits 4:3
//!   (AFS_SEL) select +-2/4/8/16 g = 16384/8192/4096/2048 LSB/g;
//! - ACCEL_XOUT_H..ACCEL_ZOUT_L (0x3B..0x40): X, Y, Z, big-endian two's complement. A read that
//!   touches them takes the *next* sample of the stream (one sample per burst read), quantised at the
//!   selected full scale: `round(value_g * lsb_per_g)` clamped to `i16`. While SLEEP is set the data
//!   registers keep their last value (zero after power-up) and the stream does not advance.
//!
//! Failures: a burst read of sample `i` fails with [`ErrorKind::Bus`] when `i` was injected with
//! [`SimMpu6050::fail_at`] (the sample is lost: the next read gets `i + 1`, as time goes on during a
//! bus glitch), and with [`ErrorKind::NoAcknowledge`] once the stream is exhausted (the device is gone).
//!
//! ```
//! use accelcal::mpu6050::{Address, Mpu6050};
//! use accelcal::sensor::AccelSensor;
//! use accelcal_host::sim::i2c::SimMpu6050;
//! let mut bus = SimMpu6050::from_counts(&[[0, 0, 16384], [1, -2, 16383]], 16384.0);
//! bus.fail_at(1);
//! let mut imu = Mpu6050::new(bus, Address::Ad0Low);
//! imu.init().unwrap();
//! assert_eq!(imu.read_raw().unwrap(), [0, 0, 16384]);
//! assert!(imu.read_raw().is_err()); // injected
//! assert!(imu.read_raw().is_err()); // end of the stream
//! assert_eq!(imu.release().samples_read(), 2);
//! ```

use std::collections::BTreeSet;

use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, NoAcknowledgeSource, Operation};

use crate::sim::{OutputUnits, Recording};

/// The 7-bit address with AD0 low (register map section 9.2).
pub const ADDRESS: u8 = 0b110_1000;

/// Register 28, ACCEL_CONFIG.
const ACCEL_CONFIG: u8 = 0x1C;
/// Register 59, ACCEL_XOUT_H; 60..64 follow.
const ACCEL_XOUT_H: u8 = 0x3B;
/// Register 64, ACCEL_ZOUT_L.
const ACCEL_ZOUT_L: u8 = 0x40;
/// Register 107, PWR_MGMT_1.
const PWR_MGMT_1: u8 = 0x6B;
/// Register 117, WHO_AM_I.
const WHO_AM_I: u8 = 0x75;
/// WHO_AM_I of an MPU-6050.
const WHO_AM_I_VALUE: u8 = 0x68;
/// PWR_MGMT_1 at power-up: SLEEP set.
const PWR_MGMT_1_POWER_ON: u8 = 0x40;
/// PWR_MGMT_1 bit 7.
const DEVICE_RESET: u8 = 0x80;
/// PWR_MGMT_1 bit 6.
const SLEEP: u8 = 0x40;

/// Number of register addresses (7-bit).
const REGISTERS: usize = 128;

/// The simulated device and its bus.
#[derive(Debug, Clone)]
pub struct SimMpu6050 {
    registers: [u8; REGISTERS],
    pointer: u8,
    samples_g: Vec<[f64; 3]>,
    next: usize,
    fail_at: BTreeSet<usize>,
    errors: usize,
    transactions: usize,
}

impl SimMpu6050 {
    /// A device answering with `samples_g` (units of g, sensor axes), powered up.
    pub fn new(samples_g: Vec<[f64; 3]>) -> Self {
        let mut device = Self {
            registers: [0; REGISTERS],
            pointer: 0,
            samples_g,
            next: 0,
            fail_at: BTreeSet::new(),
            errors: 0,
            transactions: 0,
        };
        device.power_on_reset();
        device
    }

    /// A device replaying a recording made in signed counts (`OutputUnits::Counts` with offset 0,
    /// e.g. [`OutputUnits::MPU6050_2G`]); `None` for other units.
    pub fn from_recording(recording: &Recording) -> Option<Self> {
        match recording.units {
            OutputUnits::Counts { lsb_per_g, offset } if offset == 0.0 && lsb_per_g > 0.0 => {
                Some(Self::new(recording.samples.iter().map(|s| s.map(|v| v / lsb_per_g)).collect()))
            }
            _ => None,
        }
    }

    /// A device replaying raw counts taken at `lsb_per_g`.
    pub fn from_counts(counts: &[[i16; 3]], lsb_per_g: f64) -> Self {
        Self::new(counts.iter().map(|s| s.map(|v| f64::from(v) / lsb_per_g)).collect())
    }

    /// Makes the burst read of sample `index` fail (the sample is lost).
    pub fn fail_at(&mut self, index: usize) {
        self.fail_at.insert(index);
    }

    /// Samples consumed by burst reads so far (including failed ones): the index of the next.
    pub fn samples_read(&self) -> usize {
        self.next
    }

    /// Samples in the stream.
    pub fn len(&self) -> usize {
        self.samples_g.len()
    }

    /// `true` for an empty stream.
    pub fn is_empty(&self) -> bool {
        self.samples_g.is_empty()
    }

    /// Failed transactions so far.
    pub fn errors(&self) -> usize {
        self.errors
    }

    /// Transactions addressed to the device so far.
    pub fn transactions(&self) -> usize {
        self.transactions
    }

    /// A register's current value.
    pub fn register(&self, address: u8) -> u8 {
        self.registers[usize::from(address) % REGISTERS]
    }

    /// Sensitivity selected by ACCEL_CONFIG.AFS_SEL, LSB per g.
    pub fn lsb_per_g(&self) -> f64 {
        16384.0 / f64::from(1u8 << ((self.register(ACCEL_CONFIG) >> 3) & 0b11))
    }

    fn power_on_reset(&mut self) {
        self.registers = [0; REGISTERS];
        self.registers[usize::from(PWR_MGMT_1)] = PWR_MGMT_1_POWER_ON;
        self.registers[usize::from(WHO_AM_I)] = WHO_AM_I_VALUE;
    }

    fn write_register(&mut self, register: u8, value: u8) {
        match register {
            WHO_AM_I | ACCEL_XOUT_H..=ACCEL_ZOUT_L => {} // read-only
            PWR_MGMT_1 if value & DEVICE_RESET != 0 => self.power_on_reset(),
            _ => self.registers[usize::from(register) % REGISTERS] = value,
        }
    }

    /// Latches the next sample into the data registers (a burst read of them has started).
    fn latch_sample(&mut self) -> Result<(), ErrorKind> {
        if self.register(PWR_MGMT_1) & SLEEP != 0 {
            return Ok(());
        }
        let index = self.next;
        let Some(sample) = self.samples_g.get(index).copied() else {
            return Err(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address));
        };
        self.next += 1;
        if self.fail_at.contains(&index) {
            return Err(ErrorKind::Bus);
        }
        let lsb = self.lsb_per_g();
        for (axis, value) in sample.iter().enumerate() {
            let counts = (value * lsb).round().clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16;
            let [high, low] = counts.to_be_bytes();
            let at = usize::from(ACCEL_XOUT_H) + 2 * axis;
            self.registers[at] = high;
            self.registers[at + 1] = low;
        }
        Ok(())
    }

    fn read_into(&mut self, buffer: &mut [u8]) -> Result<(), ErrorKind> {
        let start = usize::from(self.pointer);
        let touches_data = start <= usize::from(ACCEL_ZOUT_L) && start + buffer.len() > usize::from(ACCEL_XOUT_H);
        if touches_data && !buffer.is_empty() {
            self.latch_sample()?;
        }
        for byte in buffer.iter_mut() {
            *byte = self.register(self.pointer);
            self.pointer = (self.pointer + 1) % REGISTERS as u8;
        }
        Ok(())
    }

    fn operate(&mut self, operations: &mut [Operation<'_>]) -> Result<(), ErrorKind> {
        for operation in operations {
            match operation {
                Operation::Write(bytes) => {
                    if let Some((&register, values)) = bytes.split_first() {
                        self.pointer = register % REGISTERS as u8;
                        for &value in values {
                            self.write_register(self.pointer, value);
                            self.pointer = (self.pointer + 1) % REGISTERS as u8;
                        }
                    }
                }
                Operation::Read(buffer) => self.read_into(buffer)?,
            }
        }
        Ok(())
    }
}

impl ErrorType for SimMpu6050 {
    type Error = ErrorKind;
}

impl I2c for SimMpu6050 {
    fn transaction(&mut self, address: u8, operations: &mut [Operation<'_>]) -> Result<(), Self::Error> {
        if address != ADDRESS {
            self.errors += 1;
            return Err(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address));
        }
        self.transactions += 1;
        let result = self.operate(operations);
        if result.is_err() {
            self.errors += 1;
        }
        result
    }
}

#[cfg(test)]
mod tests {
    use accelcal::mpu6050::{AccelRange, Address, Error, Mpu6050};
    use accelcal::sensor::AccelSensor;

    use super::*;
    use crate::sim::{SimConfig, simulate};

    #[test]
    fn the_driver_initialises_and_reads_the_stream_in_order() {
        let counts = [[100, -200, 16384], [-32768, 32767, 0], [1, 2, 3]];
        let mut imu = Mpu6050::new(SimMpu6050::from_counts(&counts, 16384.0), Address::Ad0Low);
        imu.init().unwrap();
        for c in counts {
            assert_eq!(imu.read_raw().unwrap(), c);
        }
        assert_eq!(imu.read_raw(), Err(Error::I2c(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address))));
        let bus = imu.release();
        assert_eq!(bus.register(PWR_MGMT_1), 0x01);
        assert_eq!((bus.samples_read(), bus.errors()), (3, 1));
    }

    #[test]
    fn full_scale_requantises_and_sleep_freezes_the_stream() {
        let mut imu =
            Mpu6050::new(SimMpu6050::from_counts(&[[0, 8192, 16384], [16384, 0, 0]], 16384.0), Address::Ad0Low);
        // Asleep (power-on): zeros, nothing consumed.
        assert_eq!(imu.read_raw().unwrap(), [0, 0, 0]);
        imu.init().unwrap();
        imu.set_full_scale(AccelRange::G8).unwrap();
        assert_eq!(imu.release().lsb_per_g(), 4096.0);
        let mut imu =
            Mpu6050::new(SimMpu6050::from_counts(&[[0, 8192, 16384], [16384, 0, 0]], 16384.0), Address::Ad0Low);
        imu.init().unwrap();
        imu.set_full_scale(AccelRange::G8).unwrap();
        assert_eq!(imu.read_raw().unwrap(), [0, 2048, 4096]);
        // DEVICE_RESET: asleep again at +-2 g.
        let mut bus = imu.release();
        bus.write(ADDRESS, &[PWR_MGMT_1, DEVICE_RESET]).unwrap();
        assert_eq!((bus.register(PWR_MGMT_1), bus.register(ACCEL_CONFIG)), (PWR_MGMT_1_POWER_ON, 0));
    }

    #[test]
    fn injected_errors_lose_one_sample_and_other_addresses_are_not_acknowledged() {
        let mut bus = SimMpu6050::from_counts(&[[1, 1, 1], [2, 2, 2], [3, 3, 3]], 16384.0);
        bus.fail_at(1);
        assert_eq!(bus.write(0x69, &[PWR_MGMT_1, 0]), Err(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)));
        let mut imu = Mpu6050::new(bus, Address::Ad0Low);
        assert_eq!(imu.init(), Ok(()));
        assert_eq!(imu.read_raw().unwrap(), [1, 1, 1]);
        assert_eq!(imu.read_raw(), Err(Error::I2c(ErrorKind::Bus)));
        assert_eq!(imu.read_raw().unwrap(), [3, 3, 3]);
        assert_eq!(
            Mpu6050::new(SimMpu6050::new(Vec::new()), Address::Ad0High).init(),
            Err(Error::I2c(ErrorKind::NoAcknowledge(NoAcknowledgeSource::Address)))
        );
    }

    #[test]
    fn a_recording_in_counts_replays_exactly() {
        let cfg = SimConfig { units: OutputUnits::MPU6050_2G, seconds_per_pose: 0.5, ..SimConfig::paper(3) };
        let rec = simulate(&cfg);
        let mut imu = Mpu6050::new(SimMpu6050::from_recording(&rec).unwrap(), Address::Ad0Low);
        imu.init().unwrap();
        for s in &rec.samples {
            assert_eq!(imu.read_raw().unwrap().map(f64::from), *s);
        }
        assert!(SimMpu6050::from_recording(&simulate(&SimConfig::paper(3))).is_none());
    }
}
