//! `accelcal simulate`: a simulated raw recording written as CSV.

use std::path::PathBuf;

use accelcal::model::Params;
use accelcal_host::sim::{self, OutputUnits, Plan, SimConfig};
use serde::Serialize;

use super::{Failure, print_json, spinner};

#[derive(clap::Args)]
pub(super) struct SimulateArgs {
    /// Pose plan: paper24, cube26, random:N or freehand:N.
    #[arg(long, default_value = "paper24")]
    plan: Plan,
    /// Seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// White noise per sample and axis, mg.
    #[arg(long, default_value_t = 1.0)]
    noise_mg: f64,
    /// Sample rate, Hz.
    #[arg(long, default_value_t = 200.0)]
    rate: f64,
    /// Static seconds per pose.
    #[arg(long, default_value_t = 5.0)]
    seconds: f64,
    /// Output units: counts (16384 LSB/g), counts:LSB_PER_G or counts:LSB_PER_G:OFFSET, g or mps2.
    #[arg(long, default_value = "mps2")]
    units: OutputUnits,
    /// Random sensor errors instead of the paper's Table 1 truth.
    #[arg(long)]
    random_truth: bool,
    /// Output file.
    #[arg(short, long)]
    output: PathBuf,
    /// Print a JSON summary on stdout.
    #[arg(long)]
    json: bool,
}

/// The `simulate --json` summary.
#[derive(Serialize)]
struct SimulateSummary {
    file: String,
    plan: String,
    seed: u64,
    samples: usize,
    poses: usize,
    units: String,
    truth: Params,
}

/// Runs `simulate`.
pub(super) fn run(args: &SimulateArgs) -> Result<(), Failure> {
    let SimulateArgs { plan, seed, units, .. } = *args;
    let truth = if args.random_truth { sim::random_truth(seed) } else { SimConfig::paper(seed).truth };
    let cfg = SimConfig {
        noise_mg: args.noise_mg,
        rate_hz: args.rate,
        seconds_per_pose: args.seconds,
        units,
        truth,
        ..SimConfig::for_plan(plan, seed)
    };
    cfg.validate().map_err(|e| format!("simulate: {e}"))?;
    let spinner = spinner("simulating and writing the recording");
    let recording = sim::simulate(&cfg);
    let output = &args.output;
    let file = std::fs::File::create(output).map_err(|e| format!("{}: {e}", output.display()))?;
    let mut w = std::io::BufWriter::new(file);
    sim::write_csv(&recording, &mut w).map_err(|e| format!("{}: {e}", output.display()))?;
    spinner.finish_and_clear();
    let (samples, poses) = (recording.samples.len(), recording.poses.len());
    if args.json {
        let file = output.display().to_string();
        let (plan, units) = (plan.to_string(), units.to_string());
        print_json(&SimulateSummary { file, plan, seed, samples, poses, units, truth })?;
    } else {
        outln!(
            "wrote {} ({samples} samples, {poses} poses, plan {plan}, seed {seed}, units {units})",
            output.display()
        );
    }
    Ok(())
}
