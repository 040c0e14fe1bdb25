//! Host side of accelcal: simulator, CLI support, paper reproduction, real-data calibration.

pub mod blind_eval;
pub mod blindgen;
pub mod calib;
pub mod convergence;
pub mod csvio;
pub mod diagnose;
pub mod io;
pub mod labelled;
pub mod paper;
pub mod poses;
pub mod report;
pub mod sim;
pub mod stats;
pub mod vec3;
