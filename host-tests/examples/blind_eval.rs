//! The blind test of the diagnosis on the independent generator's logs: per family, how often the
//! verdict is right, from which visibility it is right 80 % of the time, false alarms on clean logs,
//! refusals, the shrink, and the time per log.
//!
//! ```text
//! cargo run --release -p accelcal-host --example blind_eval -- --per-family 20
//! cargo run --release -p accelcal-host --example blind_eval -- --per-family 20 --held-out   # at the end only
//! ```

use accelcal_host::blind_eval::{self, Outcome};
use accelcal_host::blindgen::{self, Family, HELD_OUT_SEED};
use clap::Parser;

/// Command-line options.
#[derive(Parser, Debug)]
struct Args {
    /// Logs per family.
    #[arg(long, default_value_t = 10)]
    per_family: u64,
    /// First seed (log i of a family gets seed first_seed + 1000 * family index + i).
    #[arg(long, default_value_t = 1)]
    first_seed: u64,
    /// Draw from the held-out seed range (seeds offset by 1 000 000): look at these only at the end.
    #[arg(long)]
    held_out: bool,
    /// Families, comma-separated (default: all).
    #[arg(long, value_delimiter = ',')]
    families: Vec<String>,
    /// Short logs (12 poses at 100 Hz: the CI size).
    #[arg(long)]
    small: bool,
    /// Print every log.
    #[arg(long)]
    verbose: bool,
    /// Also write the logs scored wrong where visible into this directory (CSV, named
    /// family-shape-seed), for `accelcal diagnose`.
    #[arg(long)]
    write_wrong: Option<std::path::PathBuf>,
}

fn main() -> Result<(), String> {
    let args = Args::parse();
    let families: Vec<Family> = if args.families.is_empty() {
        Family::ALL.to_vec()
    } else {
        args.families
            .iter()
            .map(|n| Family::from_name(n).ok_or(format!("unknown family {n:?}")))
            .collect::<Result<_, _>>()?
    };
    let offset = if args.held_out { HELD_OUT_SEED } else { 0 };
    let mut outcomes: Vec<Outcome> = Vec::new();
    // A progress bar on a terminal (indicatif draws nothing when stderr is not one).
    let bar = indicatif::ProgressBar::new(families.len() as u64 * args.per_family);
    for family in families {
        let k = Family::ALL.iter().position(|f| *f == family).unwrap_or(0) as u64;
        for i in 0..args.per_family {
            let seed = offset + args.first_seed + 1000 * k + i;
            let spec = if args.small {
                blindgen::random_small_spec(family, seed)
            } else {
                blindgen::random_spec(family, seed)
            };
            let o = blind_eval::evaluate(&spec);
            if args.verbose || (!o.right && o.visible()) {
                eprintln!(
                    "{:<16} {:<28} seed {:>8} magnitude {:>10.3} visibility {:>7.2} -> {}{}",
                    family.name(),
                    o.shape,
                    o.seed,
                    o.magnitude,
                    o.visibility,
                    o.verdict,
                    if o.right { "" } else { "   (wrong)" }
                );
            }
            if let (Some(dir), false, true) = (&args.write_wrong, o.right, o.visible()) {
                let name = format!("{}-{}-{}.csv", family.name(), o.shape, o.seed);
                std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
                std::fs::write(dir.join(name), blindgen::generate(&spec).to_csv_string()).map_err(|e| e.to_string())?;
            }
            outcomes.push(o);
            bar.inc(1);
        }
    }
    bar.finish_and_clear();
    print!("{}", blind_eval::table(&blind_eval::summarize(&outcomes)));
    print!("\n{}", blind_eval::overall(&outcomes).to_text());
    print!("{}", blind_eval::by_poses_text(&outcomes));
    let slowest = outcomes.iter().map(|o| (o.seconds, o.samples)).fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
    println!(
        "\nslowest diagnosis: {:.2} s for {} samples (release build: these figures need --release)",
        slowest.0, slowest.1
    );
    Ok(())
}
