//! `accelcal`: the command-line tool of the accelcal calibration library (see [`cli`]).
//!
//! Exit codes: 0 success, 1 a calibration ran but failed its verdict, 2 bad input.

mod cli;

fn main() -> std::process::ExitCode {
    cli::run()
}
