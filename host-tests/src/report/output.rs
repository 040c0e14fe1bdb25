//! Writing the CLI's output: a closed stdout (the output piped into `head`) ends the program quietly
//! instead of panicking as `println!` does.

use std::io::Write;

/// Ends the program after a failed write to stdout: quietly (exit 0) when the reader went away,
/// else with the error on stderr (exit 2).
pub fn stdout_failed(e: std::io::Error) -> ! {
    if e.kind() == std::io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    eprintln!("accelcal: error: writing the output: {e}");
    std::process::exit(2);
}

/// Writes `text` to stdout (see [`stdout_failed`]).
pub fn write_stdout(text: &str) {
    if let Err(e) = std::io::stdout().write_all(text.as_bytes()) {
        stdout_failed(e);
    }
}
