//! `cargo xtask`: project tasks that build firmware and run tools, kept out of the library and the host CLI.
//!
//! - `cargo xtask report [--json] [--check] [--target TRIPLE]...`: the firmware size and cycle report (see
//!   [`report`]), Cortex-M4F against its budgets, Cortex-M0+ and RISC-V beside it, and the feature costs.
//! - `cargo xtask feature-costs [--json]`: the flash cost of each opt-in feature alone (see [`features`]).

mod elf;
mod features;
mod firmware;
mod report;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "xtask", about = "accelcal project tasks (cargo xtask ...)")]
struct Cli {
    #[command(subcommand)]
    command: Task,
}

#[derive(Subcommand)]
enum Task {
    /// Flash, RAM and emulated cycles of the bench firmware per target; Cortex-M4F against the budgets.
    Report {
        /// Machine-readable report on stdout.
        #[arg(long)]
        json: bool,
        /// Exit with 1 when a Cortex-M4F budget marked enforced, or a regression ceiling, is exceeded.
        #[arg(long)]
        check: bool,
        /// Measure only these targets (repeatable; default all three). The budgets need thumbv7em-none-eabihf.
        #[arg(long = "target", value_name = "TRIPLE")]
        targets: Vec<String>,
    },
    /// The flash cost of each opt-in feature on the Cortex-M4F (also part of `report`), without the bench.
    FeatureCosts {
        /// Machine-readable output on stdout.
        #[arg(long)]
        json: bool,
    },
}

fn main() -> ExitCode {
    match Cli::parse().command {
        Task::Report { json, check, targets } => match report::run(json, check, &targets) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::from(1),
            Err(e) => {
                eprintln!("xtask report: {e}");
                ExitCode::from(2)
            }
        },
        Task::FeatureCosts { json } => match features::run(json) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("xtask feature-costs: {e}");
                ExitCode::from(2)
            }
        },
    }
}
