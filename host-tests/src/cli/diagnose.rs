//! `accelcal diagnose FILE`: where a calibration's residual gap lies and which effect causes it.

use std::path::PathBuf;

use accelcal_host::calib::{self, RowsDropped};
use accelcal_host::csvio;
use accelcal_host::diagnose;
use accelcal_host::report_html;

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
    let stale_repeats = accumulate_all(&table, &input.file)?.skipped_repeats;
    let options =
        diagnose::DiagnoseOptions { gravity: input.gravity, seed: args.seed, ..diagnose::DiagnoseOptions::DEFAULT };
    let report = diagnose::diagnose(&table, &options).map_err(|e| e.to_string())?;
    if let Some(dir) = &args.plots {
        report.write_plots(dir)?;
    }
    let mut json = report.to_json();
    if let Some(object) = json.as_object_mut() {
        let rows_dropped = RowsDropped::new(&table.dropped, stale_repeats);
        object.insert("rows_dropped".into(), serde_json::to_value(rows_dropped).unwrap_or_default());
    }
    if let Some(dir) = &args.report {
        let page = report_html::write_diagnose_report(dir, &json)?;
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
