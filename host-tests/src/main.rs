//! `accelcal`: the command-line tool of the accelcal calibration library.
//!
//! Exit codes: 0 success, 1 a calibration ran but failed its verdict, 2 bad input.

use std::path::PathBuf;
use std::process::ExitCode;

/// `println!` to stdout that ends the program quietly when stdout is closed (output piped into
/// `head`) instead of panicking; any other write error is reported and exits with 2.
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = writeln!(std::io::stdout(), $($arg)*) {
            accelcal_host::output::stdout_failed(e)
        }
    }};
}

/// `print!` likewise (see [`outln`]).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        if let Err(e) = write!(std::io::stdout(), $($arg)*) {
            accelcal_host::output::stdout_failed(e)
        }
    }};
}

use accelcal::calibrate::{CalibrationConfig, Method};
use accelcal::model::{PARAM_COUNT, PARAM_NAMES, Params};
use accelcal_host::calib::{self, num, params_json, verdict_json};
use accelcal_host::csvio::{self, AccumulateOptions, ColumnSpec, ReadOptions, Units};
use accelcal_host::diagnose;
use accelcal_host::io::stream as csvstream;
use accelcal_host::paper::{self, PaperOptions, format_sig};
use accelcal_host::plots::{Series, line_chart};
use accelcal_host::report_html;
use accelcal_host::sim::{self, OutputUnits, Plan, SimConfig};
use clap::{Parser, Subcommand};
use serde_json::json;

#[derive(Parser)]
#[command(name = "accelcal", version, about = "Calibrate MEMS triaxial accelerometers (Zou et al. 2020 TAGA method)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate the paper's 24-position experiment and calibrate it with every method (no hardware).
    Demo {
        /// Machine-readable report on stdout.
        #[arg(long)]
        json: bool,
        /// Seed of the simulation and the GA.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
    /// Write a simulated raw recording as CSV.
    Simulate {
        /// Pose plan: paper24, cube26 or random:N.
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
        /// Output units: counts (16384 LSB/g), g or mps2.
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
    },
    /// Calibrate a recording (raw samples or per-pose means) from a CSV file.
    Calibrate {
        #[command(flatten)]
        input: InputArgs,
        /// Optimiser: taga+lm, taga, lm or newton.
        #[arg(long, default_value = "taga+lm")]
        method: String,
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
    },
    /// Explain a calibration's residual gap: where it lies and which unmodelled effect causes it.
    Diagnose {
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
    },
    /// Size and cycle report of the firmware on an emulated Cortex-M4, against the budgets.
    Report {
        /// Machine-readable report on stdout.
        #[arg(long)]
        json: bool,
        /// Exit with 1 when a budget marked enforced is exceeded.
        #[arg(long)]
        check: bool,
    },
    /// Reproduce the paper's experiments (Table 2 Monte Carlo vs the Cramer-Rao bound, Fig. 3, 6, 7).
    Paper {
        /// Monte Carlo runs.
        #[arg(long, default_value_t = 500)]
        runs: usize,
        /// White noise per sample and axis, mg.
        #[arg(long, default_value_t = 1.0)]
        noise_mg: f64,
        /// Pose plan.
        #[arg(long, default_value = "paper24")]
        plan: Plan,
        /// Seeds of the Rastrigin operator comparison.
        #[arg(long, default_value_t = 200)]
        operator_seeds: u64,
        /// Directory for the SVG figures.
        #[arg(long)]
        out: Option<PathBuf>,
        /// Machine-readable report on stdout.
        #[arg(long)]
        json: bool,
        /// First seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
    },
}

/// How to read a CSV file (shared by the commands that read one).
#[derive(clap::Args)]
struct InputArgs {
    /// The CSV file (header row required).
    file: PathBuf,
    /// Columns to use: t,ax,ay,az[,temp] as header names or 0-based indices.
    #[arg(long)]
    columns: Option<ColumnSpec>,
    /// Units of the acceleration columns: auto, counts, g or mps2.
    #[arg(long, default_value = "auto")]
    units: Units,
    /// Rows are per-pose means (optional `n` column), not raw samples.
    #[arg(long)]
    means: bool,
    /// Local gravity, m/s^2.
    #[arg(long, default_value_t = 9.80665)]
    gravity: f64,
    /// Initial estimate: auto (ellipsoid fit of the pose means, any orientations; the six faces when no
    /// ellipsoid fits), ellipsoid, or six-position (the paper's: each axis pointed up and down).
    #[arg(long, value_enum, default_value_t = InitArg::Auto)]
    init: InitArg,
    /// Read a raw log as a stream (constant memory; automatic from 64 MB): units, rate and noise floor
    /// from its first 4 MB.
    #[arg(long)]
    stream: bool,
    /// Segment the raw log by this label column (one pose per contiguous run of a label) instead of
    /// detecting still intervals.
    #[arg(long, value_name = "NAME", conflicts_with = "means")]
    pose_column: Option<String>,
}

/// `--init`: the library's [`accelcal::calibrate::Init`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum InitArg {
    Auto,
    Ellipsoid,
    SixPosition,
}

impl From<InitArg> for accelcal::calibrate::Init {
    fn from(a: InitArg) -> Self {
        match a {
            InitArg::Auto => Self::Auto,
            InitArg::Ellipsoid => Self::Ellipsoid,
            InitArg::SixPosition => Self::SixPosition,
        }
    }
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

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() { 2 } else { 0 };
            let _ = e.print();
            return ExitCode::from(code);
        }
    };
    let result = match cli.command {
        Command::Demo { json, seed } => demo(seed, json),
        Command::Simulate { plan, seed, noise_mg, rate, seconds, units, random_truth, output, json } => {
            simulate(plan, seed, noise_mg, rate, seconds, units, random_truth, &output, json)
        }
        Command::Calibrate { input, method, json, seed, bench, report } => {
            calibrate_file(&input, &method, seed, CalibrateOutput { json, bench, report })
        }
        Command::Diagnose { input, json, plots, report, seed } => {
            diagnose_file(&input, json, plots.as_deref(), report.as_deref(), seed)
        }
        Command::Report { json, check } => match accelcal_host::report::run(json, check) {
            Ok(true) => Ok(()),
            Ok(false) => Err(Failure::Verdict),
            Err(e) => Err(Failure::Input(e)),
        },
        Command::Paper { runs, noise_mg, plan, operator_seeds, out, json, seed } => {
            paper_cmd(PaperOptions { runs, noise_mg, plan, seed, operator_seeds }, out, json)
        }
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

fn demo(seed: u64, as_json: bool) -> Result<(), Failure> {
    let cfg = SimConfig::paper(seed);
    let recording = sim::simulate(&cfg);
    let mut text = Vec::new();
    sim::write_csv(&recording, &mut text).map_err(|e| e.to_string())?;
    let opts = ReadOptions { units: Units::Mps2, ..ReadOptions::default() };
    let table = csvio::read_csv_bytes("simulated paper24", &text, &opts).map_err(|e| e.to_string())?;
    let acc = csvio::accumulate(&table, &AccumulateOptions::default()).map_err(|e| e.to_string())?;
    let truth = cfg.truth;
    let mut results = serde_json::Map::new();
    let mut lines = Vec::new();
    let mut all_pass = true;
    for method in [Method::Newton, Method::Taga, Method::Lm, Method::TagaLm] {
        let base = if method == Method::Taga { CalibrationConfig::TAGA_ALONE } else { CalibrationConfig::DEFAULT };
        let config = CalibrationConfig { method, before: Some(Params::IDENTITY), ..base };
        let cal = calib::run(&acc.poses, &config, seed).map_err(|e| format!("{}: {e}", method.name()))?;
        let (est, t) = (cal.params.to_array(), truth.to_array());
        let rel: [f64; PARAM_COUNT] =
            std::array::from_fn(|i| 100.0 * (f64::from(est[i]) - f64::from(t[i])) / f64::from(t[i]));
        all_pass &= cal.verdict.pass();
        results.insert(
            method.name().into(),
            json!({
                "params": params_json(&cal.params),
                "rel_err_pct": rel,
                "rmse_mg": {"before": num(cal.verdict.rmse_before_mg), "after": num(cal.verdict.rmse_after_mg)},
                "noise_floor_mg": cal.verdict.noise_floor_mg,
                "generations": cal.generations,
                "evaluations": cal.evaluations,
                "iterations": cal.iterations,
                "objective": cal.objective,
                "verdict": verdict_json(&cal.verdict),
            }),
        );
        lines.push((method, cal, rel));
    }
    if as_json {
        let out = json!({
            "seed": seed,
            "plan": "paper24",
            "noise_mg": cfg.noise_mg,
            "poses": acc.poses.len(),
            "truth": params_json(&truth),
            "results": results,
        });
        outln!("{out}");
    } else {
        outln!(
            "accelcal demo: the paper's 24-position experiment simulated (seed {seed}, {} mg noise, 200 Hz, 5 s per pose)",
            cfg.noise_mg
        );
        outln!("{} samples -> {} static poses found by the accumulator", table.samples.len(), acc.poses.len());
        out!("{:<10}", "");
        for n in PARAM_NAMES {
            out!("{n:>13}");
        }
        outln!();
        out!("{:<10}", "truth");
        for v in truth.to_array() {
            out!("{v:>13.8}");
        }
        outln!();
        for (method, cal, rel) in &lines {
            out!("{:<10}", method.name());
            for v in cal.params.to_array() {
                out!("{v:>13.8}");
            }
            outln!();
            out!("{:<10}", "  err %");
            for v in rel {
                out!("{:>13}", format_sig(*v));
            }
            outln!();
        }
        for (method, cal, _) in &lines {
            let v = &cal.verdict;
            outln!(
                "{:<8} modulus RMSE {} -> {} mg (noise floor {} mg); {} generations, {} iterations; verdict {}",
                method.name(),
                format_sig(f64::from(v.rmse_before_mg)),
                format_sig(f64::from(v.rmse_after_mg)),
                v.noise_floor_mg.map_or("?".into(), |f| format_sig(f64::from(f))),
                cal.generations,
                cal.iterations,
                if v.pass() { "PASS" } else { "FAIL" }
            );
        }
    }
    if all_pass { Ok(()) } else { Err(Failure::Verdict) }
}

#[allow(clippy::too_many_arguments)]
fn simulate(
    plan: Plan,
    seed: u64,
    noise_mg: f64,
    rate_hz: f64,
    seconds: f64,
    units: OutputUnits,
    random_truth: bool,
    output: &std::path::Path,
    as_json: bool,
) -> Result<(), Failure> {
    let truth = if random_truth { sim::random_truth(seed) } else { SimConfig::paper(seed).truth };
    let cfg =
        SimConfig { noise_mg, rate_hz, seconds_per_pose: seconds, units, truth, ..SimConfig::for_plan(plan, seed) };
    cfg.validate().map_err(|e| format!("simulate: {e}"))?;
    let recording = sim::simulate(&cfg);
    let file = std::fs::File::create(output).map_err(|e| format!("{}: {e}", output.display()))?;
    let mut w = std::io::BufWriter::new(file);
    sim::write_csv(&recording, &mut w).map_err(|e| format!("{}: {e}", output.display()))?;
    if as_json {
        outln!(
            "{}",
            json!({"file": output.display().to_string(), "plan": plan.to_string(), "seed": seed,
                   "samples": recording.samples.len(), "poses": recording.poses.len(),
                   "units": units.to_string(), "truth": params_json(&truth)})
        );
    } else {
        outln!(
            "wrote {} ({} samples, {} poses, plan {plan}, seed {seed}, units {units})",
            output.display(),
            recording.samples.len(),
            recording.poses.len()
        );
    }
    Ok(())
}

/// A file read, its poses found and calibrated.
struct Loaded {
    table: csvio::Table,
    poses: Vec<accelcal::accumulator::Pose>,
    spans: Option<Vec<csvio::PoseSpan>>,
    host: calib::HostCalibration,
    /// The configuration calibrated with.
    config: CalibrationConfig,
    /// Rows the pose detection skipped as stale repeats.
    stale_repeats: usize,
    /// Data rows read (a large file's `table` holds only its first rows).
    rows: usize,
}

/// A file read: the table (a large raw log's first rows only), its data rows, and for a large raw log
/// the poses found while streaming it (constant memory).
fn read_input(input: &InputArgs) -> Result<(csvio::Table, usize, Option<csvio::Accumulation>), Failure> {
    let opts = ReadOptions { columns: input.columns.clone(), units: input.units, means: input.means, delimiter: None };
    let large = input.stream || csvstream::is_large(&input.file);
    if input.means || input.pose_column.is_some() || !large {
        let table = csvio::read_csv(&input.file, &opts).map_err(|e| e.to_string())?;
        let rows = table.samples.len();
        return Ok((table, rows, None));
    }
    let streamed = csvstream::stream_poses(&input.file, &opts, &AccumulateOptions::default(), csvstream::PREFIX_BYTES)
        .map_err(|e| e.to_string())?;
    Ok((streamed.table, streamed.rows, Some(streamed.accumulation)))
}

/// The whole `calibrate` pipeline: read, find poses (or take the means), calibrate, leave-one-out.
fn load_and_calibrate(input: &InputArgs, method: Method, seed: u64, warn: bool) -> Result<Loaded, Failure> {
    calib::check_gravity_positive(input.gravity)?;
    let (table, rows, streamed) = read_input(input)?;
    calib::check_gravity(input.gravity, table.units, table.median_magnitude)
        .map_err(|e| format!("{}: {e}", input.file.display()))?;
    if warn {
        for w in &table.warnings {
            eprintln!("accelcal: warning: {w}");
        }
    }
    let mut stale_repeats = 0;
    let (poses, spans) = if input.means {
        (csvio::to_poses_from_means(&table), None)
    } else if let Some(column) = &input.pose_column {
        (accelcal_host::labelled::poses_by_label(&table, &input.file, column)?, None)
    } else {
        let acc = match streamed {
            Some(acc) => check_accumulation(acc, &input.file)?,
            None => accumulate_all(&table, &input.file)?,
        };
        stale_repeats = acc.skipped_repeats;
        (acc.poses, Some(acc.spans))
    };
    check_pose_count(&input.file, poses.len(), None)?;
    let file = input.file.display();
    // Six faces fit biases and scales (the non-orthogonality held); nine directions or more fit all nine.
    if poses.len() < 6 {
        return Err(format!(
            "{file}: {} static poses found, at least 6 are needed ({PARAM_COUNT} or more in different directions fit \
             all {PARAM_COUNT} parameters; hold the sensor still in more orientations)",
            poses.len()
        )
        .into());
    }
    let gravity = input.gravity as f32;
    // "Before": the readings taken at face value in their unit (counts: the coarse six-position model).
    let before = match table.units {
        Units::G => Some(Params { scale: [gravity; 3], ..Params::IDENTITY }),
        Units::Mps2 => Some(Params::IDENTITY),
        _ => None,
    };
    let config = CalibrationConfig { gravity, method, before, init: input.init.into(), ..CalibrationConfig::DEFAULT };
    let host = calib::run_with_loo(&poses, &config, seed).map_err(|e| format!("{file}: {e}"))?;
    Ok(Loaded { table, poses, spans, host, config, stale_repeats, rows })
}

/// Refuses more poses than one calibration takes ([`calib::MAX_POSES`], the library's buffer),
/// naming the count and, when known, the line where the last pose that fits ends.
fn check_pose_count(file: &std::path::Path, found: usize, last_fitting_line: Option<usize>) -> Result<(), Failure> {
    let limit = calib::MAX_POSES;
    if found <= limit {
        return Ok(());
    }
    let cut = last_fitting_line.map_or(String::new(), |l| format!("; pose {limit} ends at line {l}"));
    Err(format!(
        "{}: {found} poses found, one calibration takes at most {limit}: split the log (or the means file) into \
         parts of at most {limit} poses{cut}",
        file.display()
    )
    .into())
}

/// The poses of a raw log; more than one calibration takes is an error (never a silent drop).
fn accumulate_all(table: &csvio::Table, file: &std::path::Path) -> Result<csvio::Accumulation, Failure> {
    let acc =
        csvio::accumulate(table, &AccumulateOptions::default()).map_err(|e| format!("{}: {e}", file.display()))?;
    check_accumulation(acc, file)
}

/// The accumulation, unless it found more poses than one calibration takes.
fn check_accumulation(acc: csvio::Accumulation, file: &std::path::Path) -> Result<csvio::Accumulation, Failure> {
    let found = acc.poses.len() + acc.dropped_full as usize;
    check_pose_count(file, found, acc.spans.get(calib::MAX_POSES - 1).map(|s| s.last_line))?;
    Ok(acc)
}

/// Wall time of `runs` repetitions of the whole pipeline: (min, median, max) in ms.
fn bench(input: &InputArgs, method: Method, seed: u64, runs: usize) -> Result<(f64, f64, f64), Failure> {
    let mut ms = Vec::with_capacity(runs);
    for _ in 0..runs.max(1) {
        let start = std::time::Instant::now();
        let loaded = load_and_calibrate(input, method, seed, false)?;
        ms.push(start.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(loaded.host.calibration.params);
    }
    ms.sort_by(f64::total_cmp);
    Ok((ms[0], ms[ms.len() / 2], ms[ms.len() - 1]))
}

/// What `calibrate` writes besides its exit code.
struct CalibrateOutput {
    /// JSON on stdout instead of text.
    json: bool,
    /// Also time N runs.
    bench: Option<usize>,
    /// Directory for the HTML report.
    report: Option<PathBuf>,
}

/// The `calibrate --json` document (also embedded in the HTML report).
fn calibrate_json(
    input: &InputArgs,
    loaded: &Loaded,
    timing: Option<(f64, f64, f64)>,
    runs: Option<usize>,
) -> serde_json::Value {
    let Loaded { table, poses, spans, host, config, stale_repeats, .. } = loaded;
    let cal = host.calibration;
    let v = &cal.verdict;
    let residuals = report_html::pose_residuals_mg(poses, config, &cal.params);
    let temps = report_html::pose_temperatures_c(table, spans.as_deref(), poses.len());
    let pose_json: Vec<serde_json::Value> = poses
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let span = spans.as_ref().and_then(|s| s.get(i));
            json!({
                "t_start": span.and_then(|s| s.start_s),
                "t_end": span.and_then(|s| s.end_s),
                "n": p.n,
                "mean": p.mean,
                "std": p.variance.map(f32::sqrt),
                "temp_c": temps.get(i).copied().flatten(),
                "direction": report_html::calibrated_direction(&cal.params, p.mean),
                "residual_before_mg": residuals.get(i).map(|r| num(r.before_mg)),
                "residual_after_mg": residuals.get(i).map(|r| num(r.after_mg)),
            })
        })
        .collect();
    json!({
        "file": input.file.display().to_string(),
        "method": config.method.name(),
        "gravity": config.gravity,
        "units": table.units.to_string(),
        "rows_dropped": calib::rows_dropped_json(&table.dropped, *stale_repeats),
        "units_header": table.units_header.as_ref().map(|h| json!({"column": h.column, "unit": h.label, "factor": h.factor})),
        "poses": pose_json,
        "params": params_json(&cal.params),
        "objective": cal.objective,
        "rmse_mg": {"before": num(v.rmse_before_mg), "after": num(v.rmse_after_mg), "loo": host.rmse_loo_mg},
        "noise_floor_mg": v.noise_floor_mg,
        "param_std": v.param_std.map(num),
        "generations": cal.generations,
        "iterations": cal.iterations,
        "verdict": verdict_json(v),
        "bench_ms": timing.map(|(min, median, max)| json!({"runs": runs, "min": min, "median": median, "max": max})),
    })
}

fn calibrate_file(input: &InputArgs, method: &str, seed: u64, output: CalibrateOutput) -> Result<(), Failure> {
    let method = calib::parse_method(method)?;
    let loaded = load_and_calibrate(input, method, seed, true)?;
    let bench_runs = output.bench;
    let timing = match bench_runs {
        Some(runs) => Some(bench(input, method, seed, runs)?),
        None => None,
    };
    let document = (output.json || output.report.is_some()).then(|| calibrate_json(input, &loaded, timing, bench_runs));
    if let (Some(dir), Some(document)) = (&output.report, &document) {
        let page = report_html::write_calibrate_report(dir, document)?;
        eprintln!("accelcal: report written to {}", page.display());
    }
    let Loaded { table, poses, host, stale_repeats, rows, .. } = loaded;
    let file = input.file.display();
    let cal = host.calibration;
    let v = &cal.verdict;
    if let (true, Some(out)) = (output.json, document) {
        outln!("{out}");
    } else {
        if let (Some((min, median, max)), Some(runs)) = (timing, bench_runs) {
            outln!(
                "bench: read + find poses + calibrate + leave-one-out, {runs} runs: min {min:.1} ms, median {median:.1} ms, max {max:.1} ms"
            );
        }
        outln!("{file}: {} rows in {}, {} poses, method {}", rows, table.units_summary(), poses.len(), method.name());
        outln!("{:<6}{:>16}{:>16}{:>16}", "", "x", "y", "z");
        outln!("{:<6}{:>16.8}{:>16.8}{:>16.8}", "B", cal.params.bias[0], cal.params.bias[1], cal.params.bias[2]);
        outln!("{:<6}{:>16.8e}{:>16.8e}{:>16.8e}", "S", cal.params.scale[0], cal.params.scale[1], cal.params.scale[2]);
        outln!(
            "{:<6}{:>16.8e}{:>16.8e}{:>16.8e}",
            "M",
            cal.params.nonorth[0],
            cal.params.nonorth[1],
            cal.params.nonorth[2]
        );
        outln!(
            "modulus RMSE before {} mg, after {} mg, leave-one-pose-out {} mg, noise floor {} mg",
            format_sig(f64::from(v.rmse_before_mg)),
            format_sig(f64::from(v.rmse_after_mg)),
            host.rmse_loo_mg.map_or("?".into(), |x| format_sig(f64::from(x))),
            v.noise_floor_mg.map_or("?".into(), |x| format_sig(f64::from(x)))
        );
        outln!("verdict: {}", if v.pass() { "PASS".to_string() } else { format!("FAIL {}", verdict_json(v)) });
        let warnings = calib::warnings_line(v);
        if !warnings.is_empty() {
            outln!("warning: {warnings}");
        }
        if let Some(line) = calib::rows_dropped_line(&table.dropped, stale_repeats) {
            outln!("{line}");
        }
    }
    if v.pass() { Ok(()) } else { Err(Failure::Verdict) }
}

fn diagnose_file(
    input: &InputArgs,
    as_json: bool,
    plots: Option<&std::path::Path>,
    report_dir: Option<&std::path::Path>,
    seed: u64,
) -> Result<(), Failure> {
    if input.means {
        let msg = "diagnose needs raw samples (within-pose noise, time, settling), not per-pose means";
        return Err(msg.to_string().into());
    }
    let opts = ReadOptions { columns: input.columns.clone(), units: input.units, means: false, delimiter: None };
    let table = csvio::read_csv(&input.file, &opts).map_err(|e| e.to_string())?;
    for w in &table.warnings {
        eprintln!("accelcal: warning: {w}");
    }
    calib::check_gravity(input.gravity, table.units, table.median_magnitude)
        .map_err(|e| format!("{}: {e}", input.file.display()))?;
    // The diagnosis calibrates the same poses: refuse a log with more than one calibration takes.
    let stale_repeats = accumulate_all(&table, &input.file)?.skipped_repeats;
    let options = diagnose::DiagnoseOptions { gravity: input.gravity, seed, ..diagnose::DiagnoseOptions::DEFAULT };
    let report = diagnose::diagnose(&table, &options).map_err(|e| e.to_string())?;
    if let Some(dir) = plots {
        report.write_plots(dir)?;
    }
    let mut json = report.to_json();
    if let Some(object) = json.as_object_mut() {
        object.insert("rows_dropped".into(), calib::rows_dropped_json(&table.dropped, stale_repeats));
    }
    if let Some(dir) = report_dir {
        let page = report_html::write_diagnose_report(dir, &json)?;
        eprintln!("accelcal: report written to {}", page.display());
    }
    if as_json {
        outln!("{json}");
    } else {
        out!("{}", report.to_text());
        if let Some(line) = calib::rows_dropped_line(&table.dropped, stale_repeats) {
            outln!("{line}");
        }
    }
    Ok(())
}

fn paper_cmd(options: PaperOptions, out: Option<PathBuf>, as_json: bool) -> Result<(), Failure> {
    if options.runs == 0 {
        return Err("--runs must be at least 1".to_string().into());
    }
    if !(options.noise_mg.is_finite() && options.noise_mg > 0.0) {
        return Err(format!("--noise-mg {} must be positive", options.noise_mg).into());
    }
    let bar = indicatif::ProgressBar::new(options.runs as u64);
    if as_json || std::env::var_os("CI").is_some() {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let report = paper::run(&options, || bar.inc(1));
    bar.finish_and_clear();
    if let Some(dir) = out {
        write_figures(&report, &dir)?;
        if !as_json {
            outln!("figures written to {}", dir.display());
        }
    }
    if as_json {
        outln!("{}", paper::to_json(&report));
    } else {
        out!("{}", paper::to_text(&report));
    }
    Ok(())
}

fn write_figures(r: &paper::PaperReport, dir: &std::path::Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let ops: Vec<Series> = r
        .operators
        .iter()
        .map(|o| Series { name: o.name, points: o.mean_best.iter().enumerate().map(|(g, v)| (g as f64, *v)).collect() })
        .collect();
    line_chart(&dir.join("fig3_operators.svg"), "Fig. 3: mean best Rastrigin cost", "generation", "cost", &ops, true)?;
    let gens = |f: &dyn Fn(&(f64, f64, Params)) -> f64| -> Vec<(f64, f64)> {
        r.trace.iter().enumerate().map(|(g, t)| (g as f64, f(t))).collect()
    };
    let fitness =
        [Series { name: "best fE", points: gens(&|t| t.0) }, Series { name: "mean fE", points: gens(&|t| t.1) }];
    line_chart(
        &dir.join("fig6_fitness.svg"),
        "Fig. 6: TAGA objective per generation",
        "generation",
        "fE (m/s^2)^4",
        &fitness,
        true,
    )?;
    for (group, range, file) in
        [("bias", 0..3, "fig7_bias.svg"), ("scale", 3..6, "fig7_scale.svg"), ("nonorth", 6..9, "fig7_nonorth.svg")]
    {
        let series: Vec<Series> =
            range.map(|i| Series { name: PARAM_NAMES[i], points: gens(&|t| f64::from(t.2.to_array()[i])) }).collect();
        line_chart(&dir.join(file), &format!("Fig. 7: {group} per generation"), "generation", group, &series, false)?;
    }
    Ok(())
}
