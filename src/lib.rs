//! # accelcal
//!
//! Calibrates a MEMS triaxial accelerometer on its own microcontroller: `no_std`, no allocation,
//! no panics on input. It implements Zou, Xu, Xu & Zhao, *An Improved Adaptive Genetic Algorithm for
//! MEMS Triaxial Accelerometer Calibration Method* (Chinese Journal of Sensors and Actuators 33(10),
//! 2020): the 9-parameter model `f_b = Ka f_s - B` fitted by the modulus principle `|f_b| = g`.
//!
//! - [`accumulator`]: feed samples, get static poses (averaged, with their variance).
//! - [`coarse`]: six-position coarse calibration and GA search intervals.
//! - [`ga`]: fixed-size adaptive GA (AGA, LAGA, TAGA), usable for any cost function.
//! - [`solve`]: the classical Newton baseline and Levenberg-Marquardt.
//! - [`verdict`]: RMSE before/after, noise floor, parameter standard deviations, pass/fail.
//! - [`calibrate`]: all of it in one call; [`blob`]: the result for flash; [`sensor`]: the sample source.
//!
//! ```
//! use accelcal::accumulator::{Accumulator, AccumulatorConfig};
//! use accelcal::calibrate::{calibrate, CalibrationConfig};
//! use accelcal::model::Params;
//! use rand_core::SeedableRng;
//!
//! // A sensor with known errors, held still in 14 orientations (faces and some diagonals).
//! let truth = Params { bias: [0.12; 3], scale: [0.97, 0.98, 0.99], nonorth: [-0.015, 0.01, 0.02] };
//! let g = 9.80665;
//! let s = 0.57735;
//! let dirs = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0],
//!     [0.0, 0.0, -1.0], [s, s, s], [-s, s, s], [s, -s, s], [s, s, -s], [-s, -s, s], [-s, s, -s],
//!     [s, -s, -s], [-s, -s, -s]];
//! let mut acc: Accumulator<f32, 16, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
//! let mut noise = 0u32;
//! for d in dirs {
//!     let reading = truth.invert([d[0] * g, d[1] * g, d[2] * g]).unwrap();
//!     for _ in 0..400 {
//!         noise = noise.wrapping_mul(1664525).wrapping_add(1013904223);
//!         let n = (noise >> 16) as f32 / 65536.0 - 0.5; // +-0.5 mm/s^2
//!         acc.push([reading[0] + 1e-3 * n, reading[1] - 1e-3 * n, reading[2] + 1e-3 * n]).unwrap();
//!     }
//!     for i in 0..50 { // the person turns the board: large motion
//!         acc.push([reading[0] + i as f32 * 0.3, reading[1], reading[2] - i as f32 * 0.2]).unwrap();
//!     }
//! }
//! acc.finish().unwrap();
//! assert_eq!(acc.poses().len(), 14);
//!
//! let rng = rand_xoshiro::Xoshiro128PlusPlus::seed_from_u64(1);
//! let cal = calibrate::<_, 40, 16>(acc.poses(), &CalibrationConfig::DEFAULT, rng).unwrap();
//! assert!((cal.params.scale[0] - 0.97).abs() < 1e-4);
//! assert!(cal.verdict.rmse_after_mg < 0.1);
//! let blob = accelcal::blob::encode(&cal.params, g); // store in flash
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod accumulator;
pub mod blob;
pub mod calibrate;
pub mod coarse;
pub mod ellipsoid;
pub mod frame;
pub mod ga;
pub mod init;
pub mod linalg;
pub mod model;
pub mod mpu6050;
pub mod sensor;
pub mod session;
#[cfg(feature = "async")]
pub mod session_async;
pub mod solve;
pub mod verdict;

/// The README's usage example, compiled as a doctest.
#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;

/// `"x"`, `"y"` or `"z"` for an axis index.
pub(crate) const fn axis_name(axis: u8) -> &'static str {
    match axis {
        0 => "x",
        1 => "y",
        _ => "z",
    }
}
