//! `accelcal calibrate FILE`: the calibration of a recording, as text, JSON or an HTML report.

use std::path::PathBuf;

use accelcal::calibrate::Method;
use accelcal::model::Params;
use accelcal_host::calib::{self, RowsDropped, VerdictSummary};
use accelcal_host::paper::format_sig;
use accelcal_host::report::html;
use serde::Serialize;

use super::input::{InputArgs, Loaded, MethodArg, StillLeftOut, load_and_calibrate};
use super::{Failure, print_json, progress_bar};

#[derive(clap::Args)]
pub(super) struct CalibrateArgs {
    #[command(flatten)]
    input: InputArgs,
    /// Optimiser.
    #[arg(long, value_enum, default_value_t = MethodArg::TagaLm)]
    method: MethodArg,
    /// Machine-readable report on stdout.
    #[arg(long)]
    json: bool,
    /// Seed of the GA.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Also time N runs of the whole pipeline (read, poses, calibration, leave-one-out).
    #[arg(long, value_name = "N")]
    bench: Option<usize>,
    /// Write a self-contained HTML report (DIR/index.html: inline SVG, no network).
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
}

/// The `calibrate --json` document (also embedded in the HTML report).
#[derive(Serialize)]
struct CalibrateDocument<'a> {
    file: String,
    method: &'static str,
    gravity: f32,
    units: String,
    rows_dropped: RowsDropped,
    still_intervals_left_out: Option<StillLeftOut>,
    units_header: Option<UnitsHeader<'a>>,
    poses: Vec<PoseRow>,
    params: Params,
    objective: f32,
    rmse_mg: Rmse,
    noise_floor_mg: Option<f32>,
    param_std: [f32; accelcal::model::PARAM_COUNT],
    generations: u32,
    iterations: u32,
    verdict: VerdictSummary,
    bench_ms: Option<Bench>,
}

/// The unit named in a column's header.
#[derive(Serialize)]
struct UnitsHeader<'a> {
    column: &'a str,
    unit: &'static str,
    factor: f64,
}

/// One pose: its time span, samples, mean and spread, temperature, calibrated direction, residuals.
#[derive(Serialize)]
struct PoseRow {
    t_start: Option<f64>,
    t_end: Option<f64>,
    n: u32,
    mean: [f32; 3],
    std: [f32; 3],
    temp_c: Option<f64>,
    direction: Option<[f32; 3]>,
    residual_before_mg: Option<f32>,
    residual_after_mg: Option<f32>,
}

/// Modulus RMSE, mg (non-finite values are `null`).
#[derive(Serialize)]
struct Rmse {
    before: f32,
    after: f32,
    loo: Option<f32>,
}

/// Wall time of the whole pipeline, ms.
#[derive(Clone, Copy, Serialize)]
struct Bench {
    runs: usize,
    min: f64,
    median: f64,
    max: f64,
}

/// Runs `calibrate`.
pub(super) fn run(args: &CalibrateArgs) -> Result<(), Failure> {
    let method = Method::from(args.method);
    let loaded = load_and_calibrate(&args.input, method, args.seed, true)?;
    let bench = match args.bench {
        Some(runs) => Some(bench(&args.input, method, args.seed, runs)?),
        None => None,
    };
    if args.json || args.report.is_some() {
        let document =
            serde_json::to_value(document(&args.input, &loaded, bench)).map_err(|e| format!("JSON output: {e}"))?;
        if let Some(dir) = &args.report {
            let page = html::write_calibrate_report(dir, &document)?;
            eprintln!("accelcal: report written to {}", page.display());
        }
        if args.json {
            print_json(&document)?;
        }
    }
    if !args.json {
        print_text(&args.input, &loaded, bench);
    }
    if loaded.host.calibration.verdict.pass() { Ok(()) } else { Err(Failure::Verdict) }
}

/// Wall time of `runs` repetitions of the whole pipeline (min, median, max).
fn bench(input: &InputArgs, method: Method, seed: u64, runs: usize) -> Result<Bench, Failure> {
    let mut ms = Vec::with_capacity(runs);
    let bar = progress_bar(runs.max(1) as u64, "bench");
    for _ in 0..runs.max(1) {
        let start = std::time::Instant::now();
        let loaded = load_and_calibrate(input, method, seed, false)?;
        ms.push(start.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(loaded.host.calibration.params);
        bar.inc(1);
    }
    bar.finish_and_clear();
    ms.sort_by(f64::total_cmp);
    Ok(Bench { runs, min: ms[0], median: accelcal_host::stats::median(&ms), max: ms[ms.len() - 1] })
}

fn document<'a>(input: &InputArgs, loaded: &'a Loaded, bench: Option<Bench>) -> CalibrateDocument<'a> {
    let Loaded { table, host, config, stale_repeats, left_out, .. } = loaded;
    let cal = host.calibration;
    let v = &cal.verdict;
    CalibrateDocument {
        file: input.file.display().to_string(),
        method: config.method.name(),
        gravity: config.gravity,
        units: table.units.to_string(),
        rows_dropped: RowsDropped::new(&table.dropped, *stale_repeats),
        still_intervals_left_out: *left_out,
        units_header: table.units_header.as_ref().map(|h| UnitsHeader {
            column: &h.column,
            unit: h.label,
            factor: h.factor,
        }),
        poses: pose_rows(loaded),
        params: cal.params,
        objective: cal.objective,
        rmse_mg: Rmse { before: v.rmse_before_mg, after: v.rmse_after_mg, loo: host.rmse_loo_mg },
        noise_floor_mg: v.noise_floor_mg,
        param_std: v.param_std,
        generations: cal.generations,
        iterations: cal.iterations,
        verdict: VerdictSummary::from(v),
        bench_ms: bench,
    }
}

fn pose_rows(loaded: &Loaded) -> Vec<PoseRow> {
    let Loaded { table, poses, spans, host, config, .. } = loaded;
    let params = &host.calibration.params;
    let residuals = html::pose_residuals_mg(poses, config, params);
    let temps = html::pose_temperatures_c(table, spans.as_deref(), poses.len());
    let rows = poses.iter().enumerate().map(|(i, p)| {
        let span = spans.as_ref().and_then(|s| s.get(i));
        PoseRow {
            t_start: span.and_then(|s| s.start_s),
            t_end: span.and_then(|s| s.end_s),
            n: p.n,
            mean: p.mean,
            std: p.variance.map(f32::sqrt),
            temp_c: temps.get(i).copied().flatten(),
            direction: html::calibrated_direction(params, p.mean),
            residual_before_mg: residuals.get(i).map(|r| r.before_mg),
            residual_after_mg: residuals.get(i).map(|r| r.after_mg),
        }
    });
    rows.collect()
}

fn print_text(input: &InputArgs, loaded: &Loaded, bench: Option<Bench>) {
    let Loaded { table, poses, host, config, stale_repeats, left_out, rows, .. } = loaded;
    let cal = host.calibration;
    let v = &cal.verdict;
    if let Some(Bench { runs, min, median, max }) = bench {
        outln!(
            "bench: read + find poses + calibrate + leave-one-out, {runs} runs: min {min:.1} ms, median {median:.1} ms, max {max:.1} ms"
        );
    }
    let (file, units, method) = (input.file.display(), table.units_summary(), config.method.name());
    outln!("{file}: {rows} rows in {units}, {} poses, method {method}", poses.len());
    let p = &cal.params;
    outln!("{:<6}{:>16}{:>16}{:>16}", "", "x", "y", "z");
    outln!("{:<6}{:>16.8}{:>16.8}{:>16.8}", "B", p.bias[0], p.bias[1], p.bias[2]);
    outln!("{:<6}{:>16.8e}{:>16.8e}{:>16.8e}", "S", p.scale[0], p.scale[1], p.scale[2]);
    outln!("{:<6}{:>16.8e}{:>16.8e}{:>16.8e}", "M", p.nonorth[0], p.nonorth[1], p.nonorth[2]);
    let optional = |x: Option<f32>| x.map_or("?".into(), |x| format_sig(f64::from(x)));
    outln!(
        "modulus RMSE before {} mg, after {} mg, leave-one-pose-out {} mg, noise floor {} mg",
        format_sig(f64::from(v.rmse_before_mg)),
        format_sig(f64::from(v.rmse_after_mg)),
        optional(host.rmse_loo_mg),
        optional(v.noise_floor_mg)
    );
    outln!("verdict: {}", if v.pass() { "PASS".to_string() } else { format!("FAIL {}", calib::verdict_json(v)) });
    let warnings = calib::warnings_line(v);
    if !warnings.is_empty() {
        outln!("warning: {warnings}");
    }
    if let Some(line) = calib::rows_dropped_line(&table.dropped, *stale_repeats) {
        outln!("{line}");
    }
    if let Some(line) = left_out.as_ref().and_then(StillLeftOut::line) {
        outln!("{line}");
    }
}
