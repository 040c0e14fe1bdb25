//! A minimal InvenSense MPU-6050 accelerometer driver over an [`embedded_hal::i2c::I2c`] bus.
//!
//! Enough to calibrate the accelerometer: check the device and wake it ([`Mpu6050::init`]), pick the
//! full scale ([`Mpu6050::set_full_scale`]), read one raw sample in a single 6-byte burst (so the three
//! axes belong to the same sample) and give the bus back ([`Mpu6050::release`]). It implements
//! [`AccelSensor`], so it plugs straight into the [`accumulator`](crate::accumulator).
//! Register addresses and bit fields follow the *MPU-6000 and MPU-6050 Register Map and Descriptions*,
//! revision 4.2.
//!
//! ```
//! use accelcal::mpu6050::{AccelRange, Address, Mpu6050};
//! use accelcal::sensor::AccelSensor;
//! # use embedded_hal::i2c::{ErrorKind, ErrorType, I2c, Operation};
//! # /// A stand-in MPU-6050 lying flat: WHO_AM_I 0x68, z = +1 g at +-4 g.
//! # struct Bus;
//! # impl ErrorType for Bus { type Error = ErrorKind; }
//! # impl I2c for Bus {
//! #     fn transaction(&mut self, _: u8, ops: &mut [Operation<'_>]) -> Result<(), ErrorKind> {
//! #         let mut register = 0;
//! #         for op in ops {
//! #             match op {
//! #                 Operation::Write(w) => register = w.first().copied().unwrap_or(0),
//! #                 Operation::Read(r) if register == 0x75 => r[0] = 0x68,
//! #                 Operation::Read(r) => r.copy_from_slice(&[0, 0, 0, 0, 0x20, 0]),
//! #             }
//! #         }
//! #         Ok(())
//! #     }
//! # }
//! # let i2c = Bus;
//! let mut imu = Mpu6050::new(i2c, Address::Ad0Low);
//! imu.init()?;
//! imu.set_full_scale(AccelRange::G4)?;
//! assert_eq!(imu.lsb_per_g(), 8192.0);
//! assert_eq!(imu.raw_format().lsb_per_g(), imu.lsb_per_g());
//! let [x, y, z] = imu.read_raw()?;
//! assert_eq!((x, y, z), (0, 0, 8192));
//! let _i2c = imu.release();
//! # Ok::<(), accelcal::mpu6050::Error<ErrorKind>>(())
//! ```

use embedded_hal::i2c::I2c;

use crate::sensor::{AccelSensor, RawFormat};

/// Register addresses (register map rev. 4.2).
mod register {
    /// ACCEL_CONFIG: self-test bits 7:5, AFS_SEL bits 4:3.
    pub const ACCEL_CONFIG: u8 = 0x1C;
    /// ACCEL_XOUT_H, the first of six output bytes (X, Y, Z; high byte first).
    pub const ACCEL_XOUT_H: u8 = 0x3B;
    /// PWR_MGMT_1: DEVICE_RESET bit 7, SLEEP bit 6, CLKSEL bits 2:0. Resets to 0x40 (asleep).
    pub const PWR_MGMT_1: u8 = 0x6B;
    /// WHO_AM_I: reads 0x68 whatever the AD0 pin.
    pub const WHO_AM_I: u8 = 0x75;
}

/// The value of WHO_AM_I on an MPU-6050.
pub const WHO_AM_I_VALUE: u8 = 0x68;

/// PWR_MGMT_1 after [`Mpu6050::init`]: SLEEP cleared, clock from the X gyro PLL (CLKSEL = 1), which
/// the register map recommends over the internal 8 MHz oscillator.
const PWR_MGMT_1_AWAKE_PLL_X: u8 = 0x01;

/// The I2C address, chosen by the AD0 pin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Address {
    /// AD0 tied low: 0x68.
    #[default]
    Ad0Low,
    /// AD0 tied high: 0x69.
    Ad0High,
}

impl Address {
    /// The 7-bit address.
    pub const fn addr(self) -> u8 {
        match self {
            Self::Ad0Low => 0x68,
            Self::Ad0High => 0x69,
        }
    }
}

impl From<Address> for u8 {
    fn from(a: Address) -> Self {
        a.addr()
    }
}

/// Accelerometer full scale (ACCEL_CONFIG.AFS_SEL).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AccelRange {
    /// +-2 g, 16384 LSB/g (the power-on value).
    #[default]
    G2,
    /// +-4 g, 8192 LSB/g.
    G4,
    /// +-8 g, 4096 LSB/g.
    G8,
    /// +-16 g, 2048 LSB/g.
    G16,
}

impl AccelRange {
    /// The AFS_SEL field value (0 to 3).
    pub const fn afs_sel(self) -> u8 {
        match self {
            Self::G2 => 0,
            Self::G4 => 1,
            Self::G8 => 2,
            Self::G16 => 3,
        }
    }

    /// Sensitivity, LSB per g.
    pub const fn lsb_per_g(self) -> f32 {
        match self {
            Self::G2 => 16384.0,
            Self::G4 => 8192.0,
            Self::G8 => 4096.0,
            Self::G16 => 2048.0,
        }
    }

    /// Full scale, g.
    pub const fn full_scale_g(self) -> f32 {
        match self {
            Self::G2 => 2.0,
            Self::G4 => 4.0,
            Self::G8 => 8.0,
            Self::G16 => 16.0,
        }
    }
}

/// Driver errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error<E> {
    /// The bus failed.
    I2c(E),
    /// WHO_AM_I did not read [`WHO_AM_I_VALUE`]: another device (or none) answers at this address.
    WrongDevice(u8),
}

impl<E: core::fmt::Debug> core::fmt::Display for Error<E> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::I2c(e) => write!(f, "I2C error: {e:?}"),
            Self::WrongDevice(id) => {
                write!(f, "WHO_AM_I reads {id:#04x}, expected {WHO_AM_I_VALUE:#04x} (not an MPU-6050)")
            }
        }
    }
}

impl<E: core::fmt::Debug> core::error::Error for Error<E> {}

/// An MPU-6050 on an I2C bus.
#[derive(Debug)]
pub struct Mpu6050<I2C> {
    i2c: I2C,
    address: u8,
    range: AccelRange,
}

#[cfg(feature = "defmt")]
impl<I2C> defmt::Format for Mpu6050<I2C> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "Mpu6050 {{ address: {=u8:#04x}, range: {} }}", self.address, self.range)
    }
}

impl<I2C: I2c> Mpu6050<I2C> {
    /// Takes the bus; talks to nothing until [`Mpu6050::init`]. The range is assumed to be the
    /// power-on [`AccelRange::G2`] until `init` writes it.
    pub const fn new(i2c: I2C, address: Address) -> Self {
        Self { i2c, address: address.addr(), range: AccelRange::G2 }
    }

    /// Checks WHO_AM_I, wakes the device (PWR_MGMT_1: SLEEP cleared, X gyro PLL clock) and writes the
    /// driver's full scale to ACCEL_CONFIG, so driver and device agree even after an MCU-only reset.
    /// Nothing is written to a device that is not an MPU-6050.
    pub fn init(&mut self) -> Result<(), Error<I2C::Error>> {
        let id = self.who_am_i()?;
        if id != WHO_AM_I_VALUE {
            return Err(Error::WrongDevice(id));
        }
        self.write_register(register::PWR_MGMT_1, PWR_MGMT_1_AWAKE_PLL_X)?;
        self.set_full_scale(self.range)
    }

    /// Reads WHO_AM_I.
    pub fn who_am_i(&mut self) -> Result<u8, Error<I2C::Error>> {
        let mut id = [0u8];
        self.i2c.write_read(self.address, &[register::WHO_AM_I], &mut id).map_err(Error::I2c)?;
        Ok(id[0])
    }

    /// Selects the full scale (ACCEL_CONFIG bits 4:3; the self-test bits are cleared). The driver's
    /// range changes only when the write succeeded.
    pub fn set_full_scale(&mut self, range: AccelRange) -> Result<(), Error<I2C::Error>> {
        self.write_register(register::ACCEL_CONFIG, range.afs_sel() << 3)?;
        self.range = range;
        Ok(())
    }

    /// The full scale last written.
    pub const fn full_scale(&self) -> AccelRange {
        self.range
    }

    /// Sensitivity at the current full scale, LSB per g.
    pub const fn lsb_per_g(&self) -> f32 {
        self.range.lsb_per_g()
    }

    /// The register format at the current full scale (16-bit, right-justified): its
    /// [`RawFormat::accumulator_full_scale`] makes the accumulator flag saturation.
    pub const fn raw_format(&self) -> RawFormat {
        RawFormat { full_scale_g: self.range.full_scale_g(), resolution_bits: 16, left_justified: false }
    }

    /// Reads X, Y, Z in counts: one 6-byte burst from ACCEL_XOUT_H, big-endian.
    pub fn read_accel_raw(&mut self) -> Result<[i16; 3], Error<I2C::Error>> {
        let mut b = [0u8; 6];
        self.i2c.write_read(self.address, &[register::ACCEL_XOUT_H], &mut b).map_err(Error::I2c)?;
        Ok([i16::from_be_bytes([b[0], b[1]]), i16::from_be_bytes([b[2], b[3]]), i16::from_be_bytes([b[4], b[5]])])
    }

    /// Gives the bus back.
    pub fn release(self) -> I2C {
        self.i2c
    }

    fn write_register(&mut self, register: u8, value: u8) -> Result<(), Error<I2C::Error>> {
        self.i2c.write(self.address, &[register, value]).map_err(Error::I2c)
    }
}

impl<I2C: I2c> AccelSensor for Mpu6050<I2C> {
    type Error = Error<I2C::Error>;

    fn read_raw(&mut self) -> Result<[i16; 3], Self::Error> {
        self.read_accel_raw()
    }
}
