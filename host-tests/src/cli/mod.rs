//! The command line, one module per subcommand; `main.rs` only calls [`run`].
//!
//! Exit codes: 0 success, 1 a calibration ran but failed its verdict, 2 bad input. JSON output is
//! `#[derive(Serialize)]` structs; enum options are clap `ValueEnum`s (the pose plan and the
//! simulated output units carry numbers, `random:N`, `counts:LSB:OFFSET`, and keep their parsers).

/// `println!` to stdout that ends the program quietly when stdout is closed (output piped into
/// `head`) instead of panicking; any other write error is reported and exits with 2.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($arg)*) {
            accelcal_host::report::output::stdout_failed(e)
        }
    }};
}

/// `print!` likewise (see [`outln`]).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout(), $($arg)*) {
            accelcal_host::report::output::stdout_failed(e)
        }
    }};
}

mod calibrate;
mod demo;
mod diagnose;
mod input;
mod paper;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "accelcal", version, about = "Calibrate MEMS triaxial accelerometers (Zou et al. 2020 TAGA method)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate the paper's 24-position experiment and calibrate it with every method (no hardware).
    Demo(demo::DemoArgs),
    /// Write a simulated raw recording as CSV.
    Simulate(simulate::SimulateArgs),
    /// Calibrate a recording (raw samples or per-pose means) from a CSV file.
    Calibrate(calibrate::CalibrateArgs),
    /// Explain a calibration's residual gap: where it lies and which unmodelled effect causes it.
    Diagnose(diagnose::DiagnoseArgs),
    /// Reproduce the paper's experiments (Table 2 Monte Carlo vs the Cramer-Rao bound, Fig. 3, 6, 7).
    Paper(paper::PaperArgs),
}

/// A failure of a command: bad input (exit 2) or a failed verdict (exit 1).
enum Failure {
    Input(String),
    Verdict,
}

impl From<String> for Failure {
    fn from(s: String) -> Self {
        Self::Input(s)
    }
}

/// Parses the command line, runs the command, and maps its outcome to the exit code.
pub fn run() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    let result = match cli.command {
        Command::Demo(args) => demo::run(&args),
        Command::Simulate(args) => simulate::run(&args),
        Command::Calibrate(args) => calibrate::run(&args),
        Command::Diagnose(args) => diagnose::run(&args),
        Command::Paper(args) => paper::run(&args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Verdict) => ExitCode::from(1),
        Err(Failure::Input(msg)) => {
            eprintln!("accelcal: error: {msg}");
            ExitCode::from(2)
        }
    }
}

/// Writes `value` as one line of JSON on stdout (through [`serde_json::Value`]: keys sorted).
fn print_json(value: &impl serde::Serialize) -> Result<(), Failure> {
    let value = serde_json::to_value(value).map_err(|e| format!("JSON output: {e}"))?;
    outln!("{value}");
    Ok(())
}

/// Progress is drawn only when stderr is a terminal (and not in CI).
fn progress_drawn() -> bool {
    use std::io::IsTerminal as _;
    std::io::stderr().is_terminal() && std::env::var_os("CI").is_none()
}

/// A spinner on stderr for work without countable steps (see [`progress_drawn`]).
fn spinner(what: &str) -> indicatif::ProgressBar {
    if !progress_drawn() {
        return indicatif::ProgressBar::hidden();
    }
    let spinner = indicatif::ProgressBar::new_spinner().with_message(what.to_string());
    spinner.enable_steady_tick(std::time::Duration::from_millis(120));
    spinner
}

/// A progress bar on stderr for `len` steps (see [`progress_drawn`]).
fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    if !progress_drawn() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new(len);
    if let Ok(style) = indicatif::ProgressStyle::with_template("{msg} {wide_bar} {pos}/{len} ({eta})") {
        bar.set_style(style);
    }
    bar.set_message(what.to_string());
    bar
}
