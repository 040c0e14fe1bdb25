//! # accelcal
//!
//! Calibrates a MEMS triaxial accelerometer on its own microcontroller: `no_std`, no allocation,
//! no panics on input. It implements Zou, Xu, Xu & Zhao, *An Improved Adaptive Genetic Algorithm for
//! MEMS Triaxial Accelerometer Calibration Method* (Chinese Journal of Sensors and Actuators 33(10),
//! 2020): the 9-parameter model `f_b = Ka f_s - B` fitted by the modulus principle `|f_b| = g`.
//!
//! ## The front door: a guided session
//!
//! A [`Session`] takes raw samples, finds the still poses, tells the person holding the board which
//! orientation helps most next (any start, any order, no face required), and when ready calibrates:
//! an initial estimate (a closed-form ellipsoid fit, or the paper's six faces), the paper's TAGA, an LM
//! polish, and a verdict. A failed verdict keeps every pose: capture more and finish again. A passing
//! one gives the [`blob`] to store. [`ImuSession`] is the device configuration; [`Mode::SixFace`] is the
//! ArduPilot/PX4-style six-face quick mode.
//!
//! ```
//! use accelcal::{seeded_rng, ImuSession, RunLimits, SessionConfig, sensor::AccelSensor};
//! use core::ops::ControlFlow;
//!
//! /// A raw i16 sensor in (any [`AccelSensor`]: the MPU-6050 driver here, any `accelerometer` crate
//! /// driver with the `accelerometer` feature), the flash blob out.
//! fn calibrate_imu<S: AccelSensor>(imu: &mut S) -> Result<[u8; accelcal::blob::BLOB_LEN], accelcal::RunError<S::Error>> {
//!     let mut session = ImuSession::new(SessionConfig::at_rate(200.0, 3.0, 0.5))?;
//!     let result = session.run_with_sensor(imu, seeded_rng(1), &RunLimits::DEFAULT, |progress| {
//!         // Show progress.guidance.next (e.g. "vertex +x-y+z") to the person; stop when ready.
//!         if progress.ready { ControlFlow::Break(()) } else { ControlFlow::Continue(()) }
//!     })?;
//!     Ok(result.blob) // a failed verdict was an Err above, with every pose kept in the session
//! }
//! ```
//!
//! ## The layers underneath (for your own pipeline)
//!
//! - [`accumulator`]: feed samples, get static poses (averaged, with their variance).
//! - [`ellipsoid`], [`coarse`], [`init`]: the initial estimate (any orientations, or the six faces).
//! - [`ga`]: fixed-size adaptive GA (AGA, LAGA, TAGA), usable for any cost function.
//! - [`solve`]: the classical Newton baseline and Levenberg-Marquardt.
//! - [`verdict`]: RMSE before/after, noise floor, parameter standard deviations, held parameters,
//!   poses left out, pass/fail.
//! - [`calibrate()`]: all of it in one call, or [`Calibrator`] in bounded steps; [`blob`]: the result
//!   for flash; [`sensor`]: the sample source.
//!
//! Features: `mpu6050` (driver), `micromath` (vector types), `default-rng` (`DefaultRng`,
//! `seeded_rng`) are on by default; `storage` (two-slot power-loss-safe flash storage of the blob on
//! an `embedded-storage` NorFlash), `accelerometer` (any `accelerometer` crate driver as the sensor),
//! `async` (the session in an async task: `session_async`), `serde` (`Serialize` on the parameters,
//! poses and verdict) and `defmt` are opt-in.
//!
//! ```
//! use accelcal::accumulator::{Accumulator, AccumulatorConfig};
//! use accelcal::calibrate::{calibrate, CalibrationConfig};
//! use accelcal::model::Params;
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
//! let cal = calibrate::<_, 40, 16>(acc.poses(), &CalibrationConfig::DEFAULT, accelcal::seeded_rng(1)).unwrap();
//! assert!((cal.params.scale[0] - 0.97).abs() < 1e-4);
//! assert!(cal.verdict.rmse_after_mg < 0.1);
//! let blob = accelcal::blob::encode(&cal.params, g); // store in flash
//! ```
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

#[cfg(feature = "accelerometer")]
pub mod accelerometer;
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
#[cfg(feature = "mpu6050")]
pub mod mpu6050;
#[cfg(feature = "default-rng")]
pub mod rng;
pub mod sensor;
pub mod session;
#[cfg(feature = "async")]
pub mod session_async;
pub mod solve;
#[cfg(feature = "storage")]
pub mod storage;
pub mod verdict;

#[cfg(feature = "default-rng")]
pub use calibrate::DefaultRng;
pub use calibrate::{Calibration, CalibrationConfig, CalibrationError, Calibrator, Step, calibrate};
pub use model::Params;
pub use session::{Mode, Progress, RunError, RunLimits, Session, SessionConfig, SessionError, SessionResult, State};

/// The device configuration of the guided session: raw `i16` counts, room for 24 poses, stillness
/// judged on blocks of 32 samples, a GA population of 24 (measured on the firmware bench: the same
/// final objective as the paper's 40, bit for bit, at less RAM and time; the host and the paper
/// reproduction keep 40).
pub type ImuSession = Session<i16, 24, 32, 24>;
/// The random-number traits the GA is generic over, so that firmware needs no own dependency on them.
pub use rand_core;
#[cfg(feature = "default-rng")]
pub use rng::seeded_rng;

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
