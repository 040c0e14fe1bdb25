//! Writes a directory of generated calibration logs for blind tests of the diagnosis: for each log
//! `NNNN.csv`, its twin without the effect `NNNN.twin.csv`, and one `manifest.json`.
//!
//! Manifest fields per log: `file`, `twin`, `family`, `shape`, `params` (the effect's parameters,
//! SI units, body or sensor frame as named), `magnitude` with `magnitude_unit` and `magnitude_what`
//! (the strength as drawn), `rms_effect_mg` (RMS of log minus twin over all samples) and
//! `max_hold_effect_mg` (largest change of a calibrated hold mean), `seed`, `held_out` (seed >=
//! 1 000 000), `units` (`m/s^2`, `g`, `counts`), `lsb_per_g`, `sample_rate_hz`, `noise_mg`, `truth`
//! (`B` in the output unit, `B_mps2`, `S`, `M`; the sensor at t = 0), `pose_count`, `rest_s`,
//! `duration_s`, `samples`, `temperature` (the thermometer profile, if the log has a column).
//!
//! ```text
//! cargo run -p accelcal-host --example blindgen -- --out target/blind --count 40
//! cargo run -p accelcal-host --example blindgen -- --out target/held --count 40 --held-out
//! ```

use std::path::PathBuf;

use accelcal_host::blindgen::{self, Family, HELD_OUT_SEED};
use clap::Parser;

/// Command-line options.
#[derive(Parser, Debug)]
struct Args {
    /// Output directory (created).
    #[arg(long, default_value = "target/blindgen")]
    out: PathBuf,
    /// Number of logs.
    #[arg(long, default_value_t = 40)]
    count: u64,
    /// Seed of the first log (log i gets seed first_seed + i).
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// Draw from the held-out seed range (seeds offset by 1 000 000).
    #[arg(long)]
    held_out: bool,
    /// Small logs (12 poses at 100 Hz) for quick runs.
    #[arg(long)]
    small: bool,
    /// Families, comma-separated (default: all), assigned round-robin.
    #[arg(long, value_delimiter = ',')]
    families: Vec<String>,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args = Args::parse();
    let families = parse_families(&args.families)?;
    std::fs::create_dir_all(&args.out)?;
    let offset = if args.held_out { HELD_OUT_SEED } else { 0 };
    let mut entries = Vec::new();
    for i in 0..args.count {
        let family = families[(i % families.len() as u64) as usize];
        let seed = offset + args.first_seed + i;
        let spec =
            if args.small { blindgen::random_small_spec(family, seed) } else { blindgen::random_spec(family, seed) };
        let (file, twin_file) = (format!("{i:04}.csv"), format!("{i:04}.twin.csv"));
        let log = blindgen::generate(&spec);
        let twin = blindgen::generate(&spec.twin());
        std::fs::write(args.out.join(&file), log.to_csv_string())?;
        std::fs::write(args.out.join(&twin_file), twin.to_csv_string())?;
        entries.push(blindgen::output::manifest_entry(&spec, &file, &twin_file, &log, &twin));
        eprintln!("{file}: {} / {} (seed {})", family.name(), spec.shape, spec.seed);
    }
    let manifest = serde_json::json!({ "generator": "accelcal_host::blindgen", "logs": entries });
    std::fs::write(args.out.join("manifest.json"), serde_json::to_string_pretty(&manifest)?)?;
    eprintln!("wrote {} logs to {}", args.count, args.out.display());
    Ok(())
}

/// The families named on the command line, or all of them.
fn parse_families(names: &[String]) -> Result<Vec<Family>, String> {
    if names.is_empty() {
        return Ok(Family::ALL.to_vec());
    }
    names.iter().map(|n| Family::from_name(n).ok_or_else(|| format!("unknown family {n:?}"))).collect()
}
