//! `accelcal diagnose FILE`: where a calibration's residual gap lies and which effect causes it.

use std::path::PathBuf;

use accelcal_host::calib::{self, RowsDropped};
use accelcal_host::csvio;
use accelcal_host::diagnose;
use accelcal_host::report::html;

use super::Failure;
use super::input::{InputArgs, accumulate_all};

#[derive(clap::Args)]
pub(super) struct DiagnoseArgs {
    #[command(flatten)]
    input: InputArgs,
    /// Machine-readable report on stdout.
    #[arg(long)]
    json: bool,
    /// Directory for the SVG plots.
    #[arg(long)]
    plots: Option<PathBuf>,
    /// Write a self-contained HTML report (DIR/index.html: inline SVG, no network).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Seed of the GA and of the simulations.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// The `diagnose --json` document: the diagnosis's and the rows the reading dropped.
#[derive(serde::Serialize)]
struct DiagnoseOutput<'a> {
    #[serde(flatten)]
    diagnosis: diagnose::DiagnosisDocument<'a>,
    rows_dropped: RowsDropped,
}

/// Runs `diagnose`.
pub(super) fn run(args: &DiagnoseArgs) -> Result<(), Failure> {
    let input = &args.input;
    if input.means {
        let msg = "diagnose needs raw samples (within-pose noise, time, settling), not per-pose means";
        return Err(msg.to_string().into());
    }
    let table = csvio::read_csv(&input.file, &input.read_options(false)).map_err(|e| e.to_string())?;
    for w in &table.warnings {
        eprintln!("accelcal: warning: {w}");
    }
    calib::check_gravity(input.gravity, table.units, table.median_magnitude)
        .map_err(|e| format!("{}: {e}", input.file.display()))?;
    // The diagnosis calibrates the same poses: refuse a log with more than one calibration takes.
    let stale_repeats = accumulate_all(&table, input)?.skipped_repeats;
    let options =
        diagnose::DiagnoseOptions { gravity: input.gravity, seed: args.seed, ..diagnose::DiagnoseOptions::DEFAULT };
    let report = diagnose::diagnose(&table, &options).map_err(|e| e.to_string())?;
    if let Some(dir) = &args.plots {
        report.write_plots(dir)?;
    }
    let document =
        DiagnoseOutput { diagnosis: report.document(), rows_dropped: RowsDropped::new(&table.dropped, stale_repeats) };
    let json = serde_json::to_value(document).map_err(|e| format!("JSON output: {e}"))?;
    if let Some(dir) = &args.report {
        let page = html::write_diagnose_report(dir, &json)?;
        eprintln!("accelcal: report written to {}", page.display());
    }
    if args.json {
        outln!("{json}");
    } else {
        out!("{}", report.to_text());
        if let Some(line) = calib::rows_dropped_line(&table.dropped, stale_repeats) {
            outln!("{line}");
        }
    }
    Ok(())
}
