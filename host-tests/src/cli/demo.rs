//! `accelcal demo`: the paper's 24-position experiment simulated and calibrated with every method.

use std::collections::BTreeMap;

use accelcal::calibrate::{Calibration, CalibrationConfig, Method};
use accelcal::model::{PARAM_COUNT, PARAM_NAMES, Params};
use accelcal_host::calib::{self, VerdictSummary};
use accelcal_host::csvio::{self, AccumulateOptions, ReadOptions, Units};
use accelcal_host::paper::format_sig;
use accelcal_host::sim::{self, SimConfig};
use serde::Serialize;

use super::{Failure, print_json};

#[derive(clap::Args)]
pub(super) struct DemoArgs {
    /// Machine-readable report on stdout.
    #[arg(long)]
    json: bool,
    /// Seed of the simulation and the GA.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// The `demo --json` document.
#[derive(Serialize)]
struct DemoDocument {
    seed: u64,
    plan: &'static str,
    noise_mg: f64,
    poses: usize,
    truth: Params,
    /// Per method name.
    results: BTreeMap<&'static str, MethodRow>,
}

/// One method's calibration of the simulated experiment.
#[derive(Serialize)]
struct MethodRow {
    params: Params,
    rel_err_pct: [f64; PARAM_COUNT],
    rmse_mg: BeforeAfter,
    noise_floor_mg: Option<f32>,
    generations: u32,
    evaluations: u32,
    iterations: u32,
    objective: f32,
    verdict: VerdictSummary,
}

/// Modulus RMSE before and after, mg.
#[derive(Serialize)]
struct BeforeAfter {
    before: f32,
    after: f32,
}

impl MethodRow {
    fn new(cal: &Calibration, rel_err_pct: [f64; PARAM_COUNT]) -> Self {
        let v = &cal.verdict;
        Self {
            params: cal.params,
            rel_err_pct,
            rmse_mg: BeforeAfter { before: v.rmse_before_mg, after: v.rmse_after_mg },
            noise_floor_mg: v.noise_floor_mg,
            generations: cal.generations,
            evaluations: cal.evaluations,
            iterations: cal.iterations,
            objective: cal.objective,
            verdict: VerdictSummary::from(v),
        }
    }
}

/// One method's result: the calibration and its relative errors (%).
type Row = (Method, Calibration, [f64; PARAM_COUNT]);

/// Runs `demo`.
pub(super) fn run(args: &DemoArgs) -> Result<(), Failure> {
    let cfg = SimConfig::paper(args.seed);
    let recording = sim::simulate(&cfg);
    let mut text = Vec::new();
    sim::write_csv(&recording, &mut text).map_err(|e| e.to_string())?;
    let opts = ReadOptions { units: Units::Mps2, ..ReadOptions::default() };
    let table = csvio::read_csv_bytes("simulated paper24", &text, &opts).map_err(|e| e.to_string())?;
    let acc = csvio::accumulate(&table, &AccumulateOptions::default()).map_err(|e| e.to_string())?;
    let mut rows: Vec<Row> = Vec::new();
    for method in [Method::Newton, Method::Taga, Method::Lm, Method::TagaLm] {
        let base = if method == Method::Taga { CalibrationConfig::TAGA_ALONE } else { CalibrationConfig::DEFAULT };
        let config = CalibrationConfig { method, before: Some(Params::IDENTITY), ..base };
        let cal = calib::run(&acc.poses, &config, args.seed).map_err(|e| format!("{}: {e}", method.name()))?;
        let (est, t) = (cal.params.to_array(), cfg.truth.to_array());
        let rel = std::array::from_fn(|i| 100.0 * (f64::from(est[i]) - f64::from(t[i])) / f64::from(t[i]));
        rows.push((method, cal, rel));
    }
    if args.json {
        let results = rows.iter().map(|(m, cal, rel)| (m.name(), MethodRow::new(cal, *rel))).collect();
        let truth = cfg.truth;
        let (seed, noise_mg, poses) = (args.seed, cfg.noise_mg, acc.poses.len());
        print_json(&DemoDocument { seed, plan: "paper24", noise_mg, poses, truth, results })?;
    } else {
        print_text(args.seed, &cfg, table.samples.len(), acc.poses.len(), &rows);
    }
    if rows.iter().all(|(_, cal, _)| cal.verdict.pass()) { Ok(()) } else { Err(Failure::Verdict) }
}

fn print_text(seed: u64, cfg: &SimConfig, samples: usize, poses: usize, rows: &[Row]) {
    outln!(
        "accelcal demo: the paper's 24-position experiment simulated (seed {seed}, {} mg noise, 200 Hz, 5 s per pose)",
        cfg.noise_mg
    );
    outln!("{samples} samples -> {poses} static poses found by the accumulator");
    let row = |label: &str, values: &[String]| {
        out!("{label:<10}");
        for v in values {
            out!("{v:>13}");
        }
        outln!();
    };
    row("", &PARAM_NAMES.map(String::from));
    row("truth", &cfg.truth.to_array().map(|v| format!("{v:.8}")));
    for (method, cal, rel) in rows {
        row(method.name(), &cal.params.to_array().map(|v| format!("{v:.8}")));
        row("  err %", &rel.map(format_sig));
    }
    for (method, cal, _) in rows {
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
