//! Host side of accelcal: simulator, CLI support, paper reproduction, real-data calibration.

pub mod blind_eval;
pub mod blindgen;
pub mod calib;
pub mod convergence;
pub mod csvio;
pub mod diagnose;
pub mod io;
pub mod labelled;
pub mod output;
pub mod paper;
pub mod plots;
pub mod poses;
pub mod report_html;
pub mod sim;
pub mod stats;
