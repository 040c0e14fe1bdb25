//! `accelcal paper`: the paper's experiments reproduced (Table 2 against the Cramer-Rao bound,
//! Fig. 3, 6, 7), as text, JSON, SVG figures or an HTML report.

use std::path::{Path, PathBuf};

use accelcal::model::{PARAM_NAMES, Params};
use accelcal_host::paper::{self, PaperOptions};
use accelcal_host::report::html;
use accelcal_host::report::plots::{Scale, Series, line_chart};
use accelcal_host::sim::Plan;

use super::{Failure, print_json, progress_bar};

#[derive(clap::Args)]
pub(super) struct PaperArgs {
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
    /// HTML report (Table 2, Fig. 3, 6) in DIR/index.html.
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Machine-readable report on stdout.
    #[arg(long)]
    json: bool,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

/// Runs `paper`.
pub(super) fn run(args: &PaperArgs) -> Result<(), Failure> {
    let options = PaperOptions {
        runs: args.runs,
        noise_mg: args.noise_mg,
        plan: args.plan,
        seed: args.seed,
        operator_seeds: args.operator_seeds,
    };
    if options.runs == 0 {
        return Err("--runs must be at least 1".to_string().into());
    }
    if !(options.noise_mg.is_finite() && options.noise_mg > 0.0) {
        return Err(format!("--noise-mg {} must be positive", options.noise_mg).into());
    }
    let bar = progress_bar(paper::progress_steps(&options), "paper: Monte Carlo and convergence runs");
    let report = paper::run(&options, || bar.inc(1));
    bar.finish_and_clear();
    if let Some(dir) = &args.out {
        write_figures(&report, dir)?;
        if !args.json {
            outln!("figures written to {}", dir.display());
        }
    }
    if let Some(dir) = &args.report {
        let page = html::write_paper_report(dir, &paper::to_json(&report))?;
        eprintln!("accelcal: report written to {}", page.display());
    }
    if args.json {
        print_json(&paper::to_document(&report))?;
    } else {
        out!("{}", paper::to_text(&report));
    }
    Ok(())
}

/// Fig. 3, 6 and 7 as SVG files in `dir`.
fn write_figures(r: &paper::PaperReport, dir: &Path) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let ops: Vec<Series> = r
        .operators
        .iter()
        .map(|o| Series { name: o.name, points: o.mean_best.iter().enumerate().map(|(g, v)| (g as f64, *v)).collect() })
        .collect();
    line_chart(
        &dir.join("fig3_operators.svg"),
        "Fig. 3: mean best Rastrigin cost",
        "generation",
        "cost",
        &ops,
        Scale::LogY,
    )?;
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
        Scale::LogY,
    )?;
    for (group, range, file) in
        [("bias", 0..3, "fig7_bias.svg"), ("scale", 3..6, "fig7_scale.svg"), ("nonorth", 6..9, "fig7_nonorth.svg")]
    {
        let series: Vec<Series> =
            range.map(|i| Series { name: PARAM_NAMES[i], points: gens(&|t| f64::from(t.2.to_array()[i])) }).collect();
        line_chart(
            &dir.join(file),
            &format!("Fig. 7: {group} per generation"),
            "generation",
            group,
            &series,
            Scale::Linear,
        )?;
    }
    Ok(())
}
