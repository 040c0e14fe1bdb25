//! The paper's experiments reproduced with the library, with the physical limit beside them:
//! Table 2 as a Monte Carlo against the Cramer-Rao bound, Fig. 3 (operators on Rastrigin), Fig. 6/7
//! (one TAGA run), and the bound of the paper's 24 positions against a 26-direction cube.

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::ops::ControlFlow;

use accelcal::accumulator::Pose;
use accelcal::calibrate::{Calibration, CalibrationConfig, Init, Intervals, Method, NormalizedPoses};
use accelcal::coarse::SearchWidths;
use accelcal::ellipsoid::OutlierRule;
use accelcal::ga::{Aga, Ga, GaConfig, Laga, Operators, SearchBox, Taga, rastrigin};
use accelcal::model::{PARAM_COUNT, PARAM_NAMES, Params};
use accelcal::solve::levenberg_marquardt;
use accelcal::verdict::{deviation_covariance, param_std};
use rand_core::SeedableRng;
use rand_xoshiro::Xoshiro128PlusPlus;

use crate::calib::{self, MAX_POSES, POPULATION};
use crate::sim::{Plan, SimConfig, simulate_pose_means};

/// The paper's Table 2: relative errors (%) of classical Newton and of the paper's method.
pub const PAPER_TABLE2: [(f64, f64); PARAM_COUNT] = [
    (-0.52876, -0.62649),
    (-0.59382, -0.50195),
    (-1.13195, -1.03374),
    (0.04330, 0.02604),
    (-0.00766, -0.00532),
    (-0.02904, -0.01750),
    (-61.43882, -59.16780),
    (1.77396, -0.62760),
    (31.77682, 30.99998),
];

/// Methods of the Monte Carlo, in report order.
pub const METHODS: [&str; 5] = ["newton", "taga", "lm", "taga+lm", "lm-neutral"];

/// Monte Carlo settings.
#[derive(Debug, Clone)]
pub struct PaperOptions {
    /// Simulated experiments.
    pub runs: usize,
    /// White noise per sample and axis, mg.
    pub noise_mg: f64,
    /// Pose plan (the paper's is `paper24`).
    pub plan: Plan,
    /// First seed; run `i` uses `seed + i`.
    pub seed: u64,
    /// Seeds for the Rastrigin operator comparison.
    pub operator_seeds: u64,
}

/// RMS relative error (%) per parameter and the effort of one method.
#[derive(Debug, Clone, Default)]
pub struct MethodResult {
    /// RMS over runs of `100 (estimate - truth) / truth`.
    pub rel_err_pct: [f64; PARAM_COUNT],
    /// Mean GA generations (0 for gradient methods).
    pub mean_generations: f64,
    /// Mean cost evaluations by the GA.
    pub mean_evaluations: f64,
    /// Mean Newton/LM iterations.
    pub mean_iterations: f64,
    /// Runs whose solve failed.
    pub failures: usize,
}

/// Operator comparison on Rastrigin.
#[derive(Debug, Clone)]
pub struct OperatorResult {
    /// Name (`aga`, `laga`, `taga`).
    pub name: &'static str,
    /// Seeds whose best cost went below 1e-3 within 100 generations.
    pub successes: u64,
    /// Seeds run.
    pub seeds: u64,
    /// Mean best cost per generation (index 0 = initial population).
    pub mean_best: Vec<f64>,
}

/// Everything `accelcal paper` reports.
#[derive(Debug, Clone)]
pub struct PaperReport {
    /// The settings.
    pub options: PaperOptions,
    /// Per method (see [`METHODS`]).
    pub methods: Vec<(&'static str, MethodResult)>,
    /// Cramer-Rao bound (%, relative to the truth) per parameter, RMS over the runs' geometries.
    pub crlb_rel_pct: [f64; PARAM_COUNT],
    /// The bound for `paper24` and for `cube26` at the same noise (%).
    pub crlb_paper24: [f64; PARAM_COUNT],
    /// See `crlb_paper24`.
    pub crlb_cube26: [f64; PARAM_COUNT],
    /// Per parameter: the noise (mg) at which our Newton RMS error equals the paper's Table 2
    /// magnitude (errors scale linearly with the noise).
    pub noise_to_match_paper_mg: [f64; PARAM_COUNT],
    /// Fig. 3.
    pub operators: Vec<OperatorResult>,
    /// Fig. 6/7: per generation of one TAGA run: (best cost, mean cost, best params).
    pub trace: Vec<(f64, f64, Params)>,
    /// Generations for TAGA to come within 1 % of the LM optimum, per initialisation.
    pub convergence: Vec<crate::convergence::Convergence>,
}

fn rel_err_pct(estimate: &Params, truth: &Params) -> [f64; PARAM_COUNT] {
    let (e, t) = (estimate.to_array(), truth.to_array());
    std::array::from_fn(|i| 100.0 * (f64::from(e[i]) - f64::from(t[i])) / f64::from(t[i]))
}

fn sim_config(plan: Plan, seed: u64, noise_mg: f64) -> SimConfig {
    SimConfig { noise_mg, ..SimConfig::for_plan(plan, seed) }
}

/// Variance (relative %, squared) of each parameter's Cramer-Rao bound for one geometry.
fn crlb_variance(plan: Plan, seed: u64, noise_mg: f64) -> Option<[f64; PARAM_COUNT]> {
    let cfg = sim_config(plan, seed, 0.0);
    let sigma = noise_mg * 1e-3 * cfg.gravity;
    let poses: Vec<Pose> =
        simulate_pose_means(&cfg).into_iter().map(|p| Pose { variance: [(sigma * sigma) as f32; 3], ..p }).collect();
    let norm = NormalizedPoses::<MAX_POSES>::new(&poses, cfg.gravity as f32).ok()?;
    let frame = norm.frame();
    let x = frame.to_deviation(&cfg.truth);
    let cov = deviation_covariance(&x, frame, &norm.pose_set(&poses), accelcal::linalg::Held::NONE)?;
    let std = param_std(frame, &cov);
    let t = cfg.truth.to_array();
    Some(std::array::from_fn(|i| (100.0 * f64::from(std[i]) / f64::from(t[i])).powi(2)))
}

/// RMS Cramer-Rao bound (%) over `runs` geometries of `plan`.
pub fn crlb_rel_pct(plan: Plan, seed: u64, runs: usize, noise_mg: f64) -> [f64; PARAM_COUNT] {
    let mut sum = [0.0; PARAM_COUNT];
    let mut n = 0;
    for run in 0..runs.max(1) {
        if let Some(v) = crlb_variance(plan, seed + run as u64, noise_mg) {
            for i in 0..PARAM_COUNT {
                sum[i] += v[i];
            }
            n += 1;
        }
    }
    sum.map(|s| (s / n.max(1) as f64).sqrt())
}

/// The paper's set-up of the calibration pipeline ([`calib::run`], as `accelcal calibrate` runs
/// it): the six-position start, the fixed search widths, every pose kept, TAGA with the paper's
/// operators run to convergence (200 generations at most), `method` after it.
pub fn paper_config(method: Method, gravity: f32) -> CalibrationConfig {
    CalibrationConfig {
        gravity,
        method,
        init: Init::SixPosition,
        intervals: Intervals::Fixed(SearchWidths::DEFAULT),
        outliers: OutlierRule::KEEP_ALL,
        ga: CalibrationConfig::TAGA_ALONE.ga,
        ..CalibrationConfig::DEFAULT
    }
}

/// What one Monte Carlo experiment gave.
struct RunOutcome {
    /// Relative errors (%) per method of [`METHODS`]; `None` where the solve failed.
    errors: [Option<[f64; PARAM_COUNT]>; 5],
    /// GA generations and cost evaluations.
    generations: u32,
    evaluations: u32,
    /// Iterations per method of [`METHODS`] (0 for TAGA alone).
    iterations: [u32; 5],
}

/// LM from the neutral model (`Params::IDENTITY`) instead of an initial estimate: not a pipeline
/// `calibrate` offers, the experiment that shows LM needs no initial estimate on this problem.
/// The parameters and the LM iterations.
fn lm_from_neutral(poses: &[Pose], gravity: f32) -> Option<(Params, u32)> {
    let norm = NormalizedPoses::<MAX_POSES>::new(poses, gravity).ok()?;
    let frame = norm.frame();
    let start = frame.to_deviation(&Params::IDENTITY);
    let report = levenberg_marquardt(start, norm.poses(), &CalibrationConfig::DEFAULT.lm).ok()?;
    Some((frame.to_params(&report.x), report.iterations))
}

/// One Monte Carlo experiment: every method of [`METHODS`] through the calibration pipeline (the
/// paper's set-up), TAGA and TAGA+LM from the same GA seed (the same GA run).
fn one_run(cfg: &SimConfig, ga_seed: u64) -> RunOutcome {
    let poses = simulate_pose_means(cfg);
    let gravity = cfg.gravity as f32;
    let run = |method| calib::run(&poses, &paper_config(method, gravity), ga_seed).ok();
    let [newton, taga, lm, taga_lm] = [Method::Newton, Method::Taga, Method::Lm, Method::TagaLm].map(run);
    let neutral = lm_from_neutral(&poses, gravity);
    let err = |p: &Params| rel_err_pct(p, &cfg.truth);
    let pipeline = |c: &Option<Calibration>| c.as_ref().map(|c| (err(&c.params), c.iterations));
    let outcomes =
        [pipeline(&newton), pipeline(&taga), pipeline(&lm), pipeline(&taga_lm), neutral.map(|(p, i)| (err(&p), i))];
    RunOutcome {
        errors: outcomes.map(|o| o.map(|(e, _)| e)),
        generations: taga.as_ref().map_or(0, |c| c.generations),
        evaluations: taga.as_ref().map_or(0, |c| c.evaluations),
        iterations: outcomes.map(|o| o.map_or(0, |(_, i)| i)),
    }
}

/// The Monte Carlo's sums over the runs, per method of [`METHODS`].
#[derive(Default)]
struct Tally {
    runs: usize,
    /// Sums of squared relative errors.
    squares: [[f64; PARAM_COUNT]; 5],
    /// Runs whose solve succeeded.
    counts: [usize; 5],
    iterations: [u64; 5],
    /// GA generations and cost evaluations of the TAGA runs that succeeded.
    generations: u64,
    evaluations: u64,
}

impl Tally {
    fn add(&mut self, outcome: &RunOutcome) {
        self.runs += 1;
        for (m, errors) in outcome.errors.iter().enumerate() {
            let Some(errors) = errors else { continue };
            for i in 0..PARAM_COUNT {
                self.squares[m][i] += errors[i] * errors[i];
            }
            self.counts[m] += 1;
            self.iterations[m] += u64::from(outcome.iterations[m]);
        }
        self.generations += u64::from(outcome.generations);
        self.evaluations += u64::from(outcome.evaluations);
    }

    /// RMS errors and mean effort per method (the GA's effort for TAGA and TAGA+LM).
    fn methods(&self) -> Vec<(&'static str, MethodResult)> {
        let taga_runs = self.counts[1].max(1) as f64;
        let per_taga_run = |v: u64| v as f64 / taga_runs;
        let results = METHODS.iter().enumerate().map(|(m, name)| {
            let n = self.counts[m].max(1) as f64;
            let is_ga = *name == "taga" || *name == "taga+lm";
            let result = MethodResult {
                rel_err_pct: self.squares[m].map(|s| (s / n).sqrt()),
                mean_generations: if is_ga { per_taga_run(self.generations) } else { 0.0 },
                mean_evaluations: if is_ga { per_taga_run(self.evaluations) } else { 0.0 },
                mean_iterations: self.iterations[m] as f64 / n,
                failures: self.runs - self.counts[m],
            };
            (*name, result)
        });
        results.collect()
    }
}

/// Steps of [`run`] reported to its `progress`: each Monte Carlo run, and each run of each of the
/// three convergence set-ups.
pub fn progress_steps(options: &PaperOptions) -> u64 {
    4 * options.runs as u64
}

/// Runs the whole reproduction. `progress` is called after each of its [`progress_steps`].
pub fn run(options: &PaperOptions, mut progress: impl FnMut()) -> PaperReport {
    let mut tally = Tally::default();
    for run in 0..options.runs {
        let seed = options.seed + run as u64;
        tally.add(&one_run(&sim_config(options.plan, seed, options.noise_mg), seed));
        progress();
    }
    let methods = tally.methods();
    let crlb_runs = options.runs.clamp(1, 200);
    let crlb = crlb_rel_pct(options.plan, options.seed, crlb_runs, options.noise_mg);
    let crlb_paper24 = crlb_rel_pct(Plan::Paper24, options.seed, crlb_runs, options.noise_mg);
    let crlb_cube26 = crlb_rel_pct(Plan::Cube26, options.seed, crlb_runs, options.noise_mg);
    let newton_rms = methods[0].1.rel_err_pct;
    let noise_to_match_paper_mg =
        std::array::from_fn(|i| options.noise_mg * PAPER_TABLE2[i].0.abs() / newton_rms[i].max(f64::MIN_POSITIVE));
    PaperReport {
        options: options.clone(),
        methods,
        crlb_rel_pct: crlb,
        crlb_paper24,
        crlb_cube26,
        noise_to_match_paper_mg,
        operators: operator_comparison(options.operator_seeds),
        trace: taga_trace(options.plan, options.seed, options.noise_mg),
        convergence: crate::convergence::compare(options.plan, options.seed, options.runs, options.noise_mg, progress),
    }
}

/// Fig. 3: AGA, LAGA and TAGA (the paper's constants) on 2-D Rastrigin, population 40, 100
/// generations, the same seeds for each.
pub fn operator_comparison(seeds: u64) -> Vec<OperatorResult> {
    vec![
        operator_result("aga", Aga::PAPER, seeds),
        operator_result("laga", Laga::PAPER, seeds),
        operator_result("taga", Taga::PAPER, seeds),
    ]
}

/// One policy of [`operator_comparison`].
fn operator_result<O: Operators>(name: &'static str, operators: O, seeds: u64) -> OperatorResult {
    const GENERATIONS: usize = 100;
    let mut mean_best = vec![0.0; GENERATIONS + 1];
    let mut successes = 0;
    if let Ok(bounds) = SearchBox::new([-5.12; 2], [5.12; 2]) {
        for seed in 0..seeds {
            let config = GaConfig { operators, max_generations: GENERATIONS as u32, ..GaConfig::DEFAULT };
            let rng = Xoshiro128PlusPlus::seed_from_u64(seed);
            let Ok(mut ga) = Ga::<_, POPULATION, 2, O>::new(config, bounds, rng, &rastrigin) else { continue };
            mean_best[0] += f64::from(ga.best_cost());
            for g in 1..=GENERATIONS {
                ga.step(&rastrigin);
                mean_best[g] += f64::from(ga.best_cost());
            }
            successes += u64::from(ga.best_cost() < 1e-3);
        }
    }
    mean_best.iter_mut().for_each(|v| *v /= seeds.max(1) as f64);
    OperatorResult { name, successes, seeds, mean_best }
}

/// Fig. 6/7: best and mean cost (`fE`, (m/s^2)^4) and the best parameters per generation of one TAGA
/// run (the calibration pipeline, the paper's set-up, all 200 generations) on one simulated experiment.
pub fn taga_trace(plan: Plan, seed: u64, noise_mg: f64) -> Vec<(f64, f64, Params)> {
    let cfg = sim_config(plan, seed, noise_mg);
    let poses = simulate_pose_means(&cfg);
    let gravity = cfg.gravity as f32;
    let base = paper_config(Method::Taga, gravity);
    let config = CalibrationConfig { ga: GaConfig { stall_generations: 0, ..base.ga }, ..base };
    let g4 = cfg.gravity.powi(4);
    let mut out = Vec::new();
    let traced = calib::run_observed(&poses, &config, seed, |ga, frame| {
        out.push((f64::from(ga.best_cost()) * g4, f64::from(ga.mean_cost()) * g4, frame.to_params(ga.best())));
        ControlFlow::Continue(())
    });
    if traced.is_err() {
        out.clear();
    }
    out
}

/// The `paper --json` document (keys as documented in the README).
#[derive(Debug, Clone, serde::Serialize)]
pub struct PaperDocument {
    /// Monte Carlo runs.
    pub runs: usize,
    /// White noise per sample and axis, mg.
    pub noise_mg: f64,
    /// Pose plan.
    pub plan: String,
    /// First seed.
    pub seed: u64,
    /// Parameter names, in the order of every array.
    pub params: [&'static str; PARAM_COUNT],
    /// Per method: RMS relative error (%) per parameter.
    pub rel_err_pct: BTreeMap<&'static str, [f64; PARAM_COUNT]>,
    /// The Cramer-Rao bound (%) per parameter.
    pub crlb_rel_pct: [f64; PARAM_COUNT],
    /// Per method: the RMS error over the bound.
    pub ratio_to_crlb: BTreeMap<&'static str, [f64; PARAM_COUNT]>,
    /// Per method: its mean effort.
    pub effort: BTreeMap<&'static str, Effort>,
    /// The paper's Table 2 (%): `newton` and `taga`.
    pub paper_table2_pct: BTreeMap<&'static str, [f64; PARAM_COUNT]>,
    /// See [`PaperReport::noise_to_match_paper_mg`].
    pub noise_to_match_paper_mg: [f64; PARAM_COUNT],
    /// The bound (%) of `paper24`, `cube26` and their `ratio`.
    pub crlb_plans_pct: BTreeMap<&'static str, [f64; PARAM_COUNT]>,
    /// Fig. 3, per operator.
    pub operators: BTreeMap<&'static str, OperatorCurve>,
    /// Generations to within 1 % of the LM optimum, per set-up.
    pub generations_to_1pct: Vec<GenerationsTo1Pct>,
    /// Fig. 6/7, per generation.
    pub trace: Vec<TracePoint>,
}

/// Mean effort of one method over the runs.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Effort {
    /// GA generations.
    pub generations: f64,
    /// Cost evaluations by the GA.
    pub evaluations: f64,
    /// Newton/LM iterations.
    pub iterations: f64,
    /// Runs whose solve failed.
    pub failures: usize,
}

/// One operator of Fig. 3.
#[derive(Debug, Clone, serde::Serialize)]
pub struct OperatorCurve {
    /// Seeds whose best cost went below 1e-3.
    pub successes: u64,
    /// Seeds run.
    pub seeds: u64,
    /// Mean best cost per generation.
    pub mean_best: Vec<f64>,
}

/// Generations to within 1 % of the LM optimum from one set-up.
#[derive(Debug, Clone, serde::Serialize)]
pub struct GenerationsTo1Pct {
    /// The set-up.
    pub init: &'static str,
    /// Median generations.
    pub median: u32,
    /// 95th percentile.
    pub p95: u32,
    /// Share of runs within 1 % by generation 40.
    pub share_by_40: f64,
    /// Runs.
    pub runs: usize,
}

/// One generation of Fig. 6/7: best and mean `fE` ((m/s^2)^4), the best parameters.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TracePoint {
    /// Best cost.
    pub best: f64,
    /// Mean cost.
    pub mean: f64,
    /// Best parameters ([`PARAM_NAMES`] order).
    pub params: [f32; PARAM_COUNT],
}

/// Element-wise `a / b`.
fn ratio(a: &[f64; PARAM_COUNT], b: &[f64; PARAM_COUNT]) -> [f64; PARAM_COUNT] {
    std::array::from_fn(|i| a[i] / b[i])
}

/// The report as the `paper --json` document.
pub fn to_document(r: &PaperReport) -> PaperDocument {
    let per_method =
        |f: &dyn Fn(&MethodResult) -> [f64; PARAM_COUNT]| r.methods.iter().map(|(n, m)| (*n, f(m))).collect();
    let effort = |m: &MethodResult| Effort {
        generations: m.mean_generations,
        evaluations: m.mean_evaluations,
        iterations: m.mean_iterations,
        failures: m.failures,
    };
    let operator = |o: &OperatorResult| {
        (o.name, OperatorCurve { successes: o.successes, seeds: o.seeds, mean_best: o.mean_best.clone() })
    };
    let convergence = |c: &crate::convergence::Convergence| GenerationsTo1Pct {
        init: c.init,
        median: c.median,
        p95: c.p95,
        share_by_40: c.by_40,
        runs: c.runs,
    };
    let (p24, c26) = (r.crlb_paper24, r.crlb_cube26);
    PaperDocument {
        runs: r.options.runs,
        noise_mg: r.options.noise_mg,
        plan: r.options.plan.to_string(),
        seed: r.options.seed,
        params: PARAM_NAMES,
        rel_err_pct: per_method(&|m| m.rel_err_pct),
        crlb_rel_pct: r.crlb_rel_pct,
        ratio_to_crlb: per_method(&|m| ratio(&m.rel_err_pct, &r.crlb_rel_pct)),
        effort: r.methods.iter().map(|(n, m)| (*n, effort(m))).collect(),
        paper_table2_pct: [("newton", PAPER_TABLE2.map(|p| p.0)), ("taga", PAPER_TABLE2.map(|p| p.1))].into(),
        noise_to_match_paper_mg: r.noise_to_match_paper_mg,
        crlb_plans_pct: [("paper24", p24), ("cube26", c26), ("ratio", ratio(&p24, &c26))].into(),
        operators: r.operators.iter().map(operator).collect(),
        generations_to_1pct: r.convergence.iter().map(convergence).collect(),
        trace: r
            .trace
            .iter()
            .map(|(best, mean, p)| TracePoint { best: *best, mean: *mean, params: p.to_array() })
            .collect(),
    }
}

/// The report as JSON ([`PaperDocument`], keys sorted).
pub fn to_json(r: &PaperReport) -> serde_json::Value {
    serde_json::to_value(to_document(r)).unwrap_or_default()
}

/// The report as text tables.
pub fn to_text(r: &PaperReport) -> String {
    let mut s = String::new();
    table2_text(&mut s, r);
    effort_text(&mut s, r);
    crlb_plans_text(&mut s, r);
    figures_text(&mut s, r);
    s
}

/// One row of a text table: a label and nine numbers.
fn text_row(s: &mut String, label: &str, v: &[f64]) {
    let _ = write!(s, "{label:<12}");
    for x in v {
        let _ = write!(s, "{:>10}", format_sig(*x));
    }
    let _ = writeln!(s);
}

/// Table 2: our RMS errors and their ratio to the bound, the paper's values, the noise to match them.
fn table2_text(s: &mut String, r: &PaperReport) {
    let o = &r.options;
    let _ = writeln!(
        s,
        "Table 2 as a Monte Carlo: {} runs, plan {}, {} mg white noise per sample, seeds {}..{}",
        o.runs,
        o.plan,
        o.noise_mg,
        o.seed,
        o.seed + o.runs as u64
    );
    let _ = writeln!(s, "RMS relative error (%) per parameter, and its ratio to the Cramer-Rao bound:");
    let _ = write!(s, "{:<12}", "");
    for n in PARAM_NAMES {
        let _ = write!(s, "{n:>10}");
    }
    let _ = writeln!(s);
    text_row(s, "CRLB", &r.crlb_rel_pct);
    for (name, m) in &r.methods {
        text_row(s, name, &m.rel_err_pct);
        text_row(s, "  /CRLB", &ratio(&m.rel_err_pct, &r.crlb_rel_pct));
    }
    text_row(s, "paper newton", &PAPER_TABLE2.map(|p| p.0));
    text_row(s, "paper TAGA", &PAPER_TABLE2.map(|p| p.1));
    text_row(s, "noise->paper", &r.noise_to_match_paper_mg);
    let _ = writeln!(
        s,
        "(noise->paper: the per-sample noise in mg at which our Newton RMS error equals the paper's Table 2"
    );
    let _ =
        writeln!(s, " magnitude; the paper's single run is one draw, so only the order of magnitude means anything)");
}

/// The mean effort of each method.
fn effort_text(s: &mut String, r: &PaperReport) {
    for (name, m) in &r.methods {
        if m.mean_generations > 0.0 {
            let _ = writeln!(
                s,
                "{name}: {:.1} generations, {:.0} cost evaluations, {:.1} LM iterations on average; {} failed runs",
                m.mean_generations, m.mean_evaluations, m.mean_iterations, m.failures
            );
        } else {
            let _ = writeln!(s, "{name}: {:.1} iterations on average; {} failed runs", m.mean_iterations, m.failures);
        }
    }
}

/// The bound of the paper's plan against a 26-direction cube.
fn crlb_plans_text(s: &mut String, r: &PaperReport) {
    let _ = writeln!(s, "\nCramer-Rao bound (%) of the paper's 24 positions vs a 26-direction cube, same noise:");
    text_row(s, "paper24", &r.crlb_paper24);
    text_row(s, "cube26", &r.crlb_cube26);
    text_row(s, "ratio", &ratio(&r.crlb_paper24, &r.crlb_cube26));
}

/// Fig. 3, Fig. 6 and the generations to within 1 % of the optimum.
fn figures_text(s: &mut String, r: &PaperReport) {
    let _ = writeln!(s, "\nFig. 3: operators on 2-D Rastrigin (population 40, 100 generations, same seeds):");
    for op in &r.operators {
        let at = |g: usize| format_sig(op.mean_best.get(g).copied().unwrap_or(f64::NAN));
        let _ = writeln!(
            s,
            "{:<5} success (best < 1e-3) {:>3}/{}; mean best cost at generation 10: {}, 25: {}, 50: {}, 100: {}",
            op.name,
            op.successes,
            op.seeds,
            at(10),
            at(25),
            at(50),
            at(100)
        );
    }
    if let (Some(first), Some(last)) = (r.trace.first(), r.trace.last()) {
        let converged = r.trace.iter().position(|t| t.0 <= last.0 * 1.01).unwrap_or(0);
        let _ = writeln!(
            s,
            "\nFig. 6: one TAGA run: best fE {} -> {} ((m/s^2)^4); within 1 % of its final value at generation {converged}",
            format_sig(first.0),
            format_sig(last.0)
        );
    }
    let runs = r.options.runs;
    let _ = writeln!(s, "\nTAGA (population {POPULATION}) generations to within 1 % of the LM optimum, {runs} runs:");
    for c in &r.convergence {
        let _ = writeln!(
            s,
            "{:<32} median {}, p95 {}, within 1 % by generation 40 in {:.1} % of runs",
            c.init,
            c.median,
            c.p95,
            100.0 * c.by_40
        );
    }
}

/// Four significant digits, scientific when small or large.
pub fn format_sig(v: f64) -> String {
    if v == 0.0 {
        "0".into()
    } else if (1e-3..1e5).contains(&v.abs()) {
        let decimals = (3 - v.abs().log10().floor() as i32).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.3e}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_runs_every_generation_of_the_paper_setup_and_never_worsens() {
        let trace = taga_trace(Plan::Paper24, 2, 1.0);
        let generations = paper_config(Method::Taga, 9.8).ga.max_generations as usize;
        assert_eq!(trace.len(), generations + 1, "the first population and each generation");
        assert!(trace.windows(2).all(|w| w[1].0 <= w[0].0), "the best objective never rises");
        assert!(trace.iter().all(|t| t.1 >= t.0), "the mean is never below the best");
    }

    #[test]
    fn document_keeps_the_documented_keys_and_the_papers_table() {
        let options = PaperOptions { runs: 2, noise_mg: 1.0, plan: Plan::Paper24, seed: 1, operator_seeds: 2 };
        let mut steps = 0;
        let report = run(&options, || steps += 1);
        assert_eq!(steps, progress_steps(&options));
        let json = to_json(&report);
        let keys: Vec<&str> = json.as_object().unwrap().keys().map(String::as_str).collect();
        let documented = [
            "crlb_plans_pct",
            "crlb_rel_pct",
            "effort",
            "generations_to_1pct",
            "noise_mg",
            "noise_to_match_paper_mg",
            "operators",
            "paper_table2_pct",
            "params",
            "plan",
            "ratio_to_crlb",
            "rel_err_pct",
            "runs",
            "seed",
            "trace",
        ];
        assert_eq!(keys, documented);
        assert_eq!(json["paper_table2_pct"]["newton"][6], -61.43882);
        assert_eq!(json["rel_err_pct"].as_object().unwrap().len(), METHODS.len());
        assert_eq!(json["effort"]["taga"]["failures"], 0);
        assert_eq!(json["operators"]["taga"]["mean_best"].as_array().unwrap().len(), 101);
    }
}
