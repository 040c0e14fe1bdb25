//! Host side of accelcal: simulator, CLI support, paper reproduction, real-data calibration.

pub mod calib;
pub mod csvio;
pub mod paper;
pub mod plots;
pub mod sim;
