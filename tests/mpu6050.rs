//! MPU-6050 driver against a mocked I2C bus.
//!
//! Every address and value below is re-declared from the *MPU-6000 and MPU-6050 Register Map and
//! Descriptions*, revision 4.2 (RM-MPU-6000A-00), not taken from the driver, so a typo in the driver's
//! constants fails here.

use accelcal::mpu6050::{AccelRange, Address, Error, Mpu6050};
use accelcal::sensor::AccelSensor;
use embedded_hal::i2c::ErrorKind;
use embedded_hal_mock::eh1::i2c::{Mock, Transaction};

/// Datasheet section 9.2: AD0 low -> b1101000, AD0 high -> b1101001.
const ADDR_AD0_LOW: u8 = 0b110_1000;
const ADDR_AD0_HIGH: u8 = 0b110_1001;

/// Register 28 (0x1C), ACCEL_CONFIG.
const ACCEL_CONFIG: u8 = 28;
/// Register 59 (0x3B), ACCEL_XOUT[15:8]; 60..64 follow with XOUT_L, YOUT_H, YOUT_L, ZOUT_H, ZOUT_L.
const ACCEL_XOUT_H: u8 = 59;
/// Register 107 (0x6B), PWR_MGMT_1.
const PWR_MGMT_1: u8 = 107;
/// Register 117 (0x75), WHO_AM_I; bits 6:1 are 110100, bits 0 and 7 read 0: 0x68.
const WHO_AM_I: u8 = 117;
const WHO_AM_I_MPU6050: u8 = 0b0110_1000;

/// PWR_MGMT_1 = SLEEP (bit 6) clear, CLKSEL (bits 2:0) = 1, "PLL with X axis gyroscope reference".
const PWR_MGMT_1_AWAKE_PLL_X: u8 = 0b0000_0001;

/// ACCEL_CONFIG AFS_SEL in bits 4:3: 0 = +-2 g, 1 = +-4 g, 2 = +-8 g, 3 = +-16 g; self-test bits 7:5 clear.
const AFS_2G: u8 = 0b0000_0000;
const AFS_4G: u8 = 0b0000_1000;
const AFS_8G: u8 = 0b0001_0000;
const AFS_16G: u8 = 0b0001_1000;

fn init_transactions(address: u8) -> Vec<Transaction> {
    vec![
        Transaction::write_read(address, vec![WHO_AM_I], vec![WHO_AM_I_MPU6050]),
        Transaction::write(address, vec![PWR_MGMT_1, PWR_MGMT_1_AWAKE_PLL_X]),
        Transaction::write(address, vec![ACCEL_CONFIG, AFS_2G]),
    ]
}

#[test]
fn init_checks_who_am_i_wakes_and_sets_the_default_range() {
    let mut i2c = Mock::new(&init_transactions(ADDR_AD0_LOW));
    let mut imu = Mpu6050::new(i2c.clone(), Address::Ad0Low);
    imu.init().unwrap();
    assert_eq!(imu.full_scale(), AccelRange::G2);
    assert_eq!(imu.lsb_per_g(), 16384.0);
    i2c.done();
}

#[test]
fn ad0_high_uses_the_other_address() {
    let mut i2c = Mock::new(&init_transactions(ADDR_AD0_HIGH));
    let mut imu = Mpu6050::new(i2c.clone(), Address::Ad0High);
    imu.init().unwrap();
    assert_eq!(u8::from(Address::Ad0High), ADDR_AD0_HIGH);
    assert_eq!(u8::from(Address::default()), ADDR_AD0_LOW);
    i2c.done();
}

#[test]
fn wrong_who_am_i_is_a_typed_error_and_nothing_is_written() {
    // An MPU-6500 answers 0x70 at the same address.
    let mut i2c = Mock::new(&[Transaction::write_read(ADDR_AD0_LOW, vec![WHO_AM_I], vec![0x70])]);
    let mut imu = Mpu6050::new(i2c.clone(), Address::Ad0Low);
    assert_eq!(imu.init(), Err(Error::WrongDevice(0x70)));
    let message = format!("{}", Error::<ErrorKind>::WrongDevice(0x70));
    assert!(message.contains("0x70") && message.contains("0x68"), "{message}");
    i2c.done();
}

#[test]
fn full_scale_selection_writes_afs_sel_and_sets_the_sensitivity() {
    let cases = [
        (AccelRange::G4, AFS_4G, 8192.0),
        (AccelRange::G8, AFS_8G, 4096.0),
        (AccelRange::G16, AFS_16G, 2048.0),
        (AccelRange::G2, AFS_2G, 16384.0),
    ];
    let expectations: Vec<_> =
        cases.iter().map(|&(_, bits, _)| Transaction::write(ADDR_AD0_LOW, vec![ACCEL_CONFIG, bits])).collect();
    let mut i2c = Mock::new(&expectations);
    let mut imu = Mpu6050::new(i2c.clone(), Address::Ad0Low);
    for (range, _, lsb_per_g) in cases {
        imu.set_full_scale(range).unwrap();
        assert_eq!(imu.full_scale(), range);
        assert_eq!(imu.lsb_per_g(), lsb_per_g);
        assert_eq!(range.full_scale_g() * lsb_per_g, 32768.0);
    }
    i2c.done();
}

#[test]
fn burst_read_is_big_endian_and_signed() {
    // x = -2 (0xFFFE), y = +16384 (0x4000, 1 g at +-2 g), z = -32768 (0x8000).
    let bytes = vec![0xFF, 0xFE, 0x40, 0x00, 0x80, 0x00];
    let mut i2c = Mock::new(&[
        Transaction::write_read(ADDR_AD0_LOW, vec![ACCEL_XOUT_H], bytes.clone()),
        Transaction::write_read(ADDR_AD0_LOW, vec![ACCEL_XOUT_H], vec![0x12, 0x34, 0xED, 0xCC, 0x7F, 0xFF]),
    ]);
    let mut imu = Mpu6050::new(i2c.clone(), Address::Ad0Low);
    assert_eq!(imu.read_accel_raw(), Ok([-2, 16384, -32768]));
    // The same burst through the sensor trait the calibration uses.
    assert_eq!(AccelSensor::read_raw(&mut imu), Ok([0x1234, -0x1234, i16::MAX]));
    i2c.done();
}

#[test]
fn i2c_errors_propagate() {
    let mut i2c = Mock::new(&[
        Transaction::write_read(ADDR_AD0_LOW, vec![WHO_AM_I], vec![0]).with_error(ErrorKind::Other),
        Transaction::write(ADDR_AD0_LOW, vec![ACCEL_CONFIG, AFS_8G]).with_error(ErrorKind::Other),
        Transaction::write_read(ADDR_AD0_LOW, vec![ACCEL_XOUT_H], vec![0; 6]).with_error(ErrorKind::Other),
    ]);
    let mut imu = Mpu6050::new(i2c.clone(), Address::Ad0Low);
    assert_eq!(imu.init(), Err(Error::I2c(ErrorKind::Other)));
    assert_eq!(imu.set_full_scale(AccelRange::G8), Err(Error::I2c(ErrorKind::Other)));
    // A failed write leaves the driver's range (and so the sensitivity) unchanged.
    assert_eq!(imu.full_scale(), AccelRange::G2);
    assert_eq!(imu.read_raw(), Err(Error::I2c(ErrorKind::Other)));
    assert!(format!("{}", Error::I2c(ErrorKind::Other)).contains("I2C"));
    i2c.done();
}

#[test]
fn release_gives_the_bus_back() {
    let i2c = Mock::new(&[Transaction::write_read(ADDR_AD0_LOW, vec![WHO_AM_I], vec![WHO_AM_I_MPU6050])]);
    let mut imu = Mpu6050::new(i2c, Address::Ad0Low);
    assert_eq!(imu.who_am_i(), Ok(WHO_AM_I_MPU6050));
    let mut i2c = imu.release();
    i2c.done();
}
