//! The report stage, presentation only: what a run shows and writes once its numbers are computed.
//!
//! - [`html`]: the one self-contained page of `calibrate`, `diagnose` and `paper --report DIR`;
//! - [`plots`]: the SVG figure files (`paper --out`, `diagnose --plots`);
//! - [`diagnosis`]: the diagnosis's text report and its figure files;
//! - [`output`]: stdout that survives a closed pipe.
//!
//! The JSON documents are `#[derive(Serialize)]` structs beside the results they describe
//! (`diagnose::report`, `calib`, `paper`); the page is drawn from those documents alone.

pub mod diagnosis;
pub mod html;
pub mod output;
pub mod plots;
