//! Host side of accelcal: simulator, CLI support, paper reproduction, real-data calibration.

pub mod blind_eval;
pub mod blindgen;
pub mod calib;
pub mod convergence;
pub mod csvio;
pub mod csvstream;
pub mod diagnose;
pub mod labelled;
pub mod output;
pub mod paper;
pub mod plots;
pub mod report_html;
pub mod sim;
pub mod stats;
