//! Step 3, the effect families. Each family is one file behind [`Family`]: it proposes its
//! parametrisations as extra design columns (fitted on some poses, predicting the withheld ones by
//! cross-validation) or, for noise, a noise model; the best parametrisation by the penalised
//! held-out ratio represents the family. Adding a family is adding a file and a line in [`all`].

pub(crate) mod colored_noise;
mod context;
mod corrected;
mod drift;
mod joint;
pub(crate) mod motion;
mod nonlinearity;
pub(crate) mod periodic;
mod ringing;
mod settling;
mod smooth;
pub(crate) mod steady_line;
mod temperature;
pub(super) mod tremor;

pub(crate) use context::{Context, IN_SAMPLE_MIN_DOF, ONE_COLUMN_MIN_DOF, gain_over};

use context::CHANNELS_DISAGREE;

use super::math::{V3, axis};
use super::report::{Candidate, InSampleFit};
use super::within::{Within, WithinVariant};

/// One parametrisation of a family: extra design columns per pose (the modulus residual's
/// derivative in the effect's parameters), the parameters it costs and what it is.
pub(crate) struct Variant {
    pub(crate) extra: Vec<Vec<f64>>,
    pub(crate) params: usize,
    pub(crate) detail: String,
}

/// A design-type family's best parametrisation.
pub(crate) struct Fitted {
    pub(crate) rows: Vec<Vec<f64>>,
    pub(crate) dropped: Vec<bool>,
    pub(crate) score_ratio: f64,
    pub(crate) params: usize,
    pub(crate) detail: String,
    /// Every parametrisation tried with its penalised held-out ratio.
    pub(crate) tried: Vec<(String, f64)>,
    /// The parametrisation that fits every pose best ([`Context::in_sample`]).
    pub(crate) in_sample: Option<InSampleFit>,
}

/// A family's result: its candidate line and the pose residuals with it added (`None`: dropped).
pub(crate) struct Evaluation {
    pub(crate) candidate: Candidate,
    pub(crate) after: Vec<Option<f64>>,
    /// The family predicts the withheld values ([`Family::predicts_values`]; set by the caller of
    /// [`Family::evaluate`]).
    pub(crate) predicts_values: bool,
    /// The pose-level gain with the pose the nominal model predicts worst left out of both scores
    /// (NaN when not measured: a fit of both channels, a noise model).
    pub(crate) gain_without_worst: f64,
    /// The pose-level fit is a penalised wander (`smooth.rs`: its prior a random walk's steps).
    pub(crate) wander: bool,
    /// Poses beyond the columns of the pose-level fit that leaves `candidate.ratio_after` (`None`:
    /// not a fit of the pose means alone: a noise model, a stacked fit, not testable).
    pub(crate) residual_dof: Option<usize>,
    /// A temperature fit whose coefficients a MEMS part can have: the thermometer is a credible
    /// cause, named before time on a near tie ([`super::verdict`]).
    pub(crate) credible_cause: bool,
}

/// An effect family.
pub(crate) trait Family {
    /// The report name.
    fn name(&self) -> &'static str;

    /// The parametrisations the data can test (none: not testable).
    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant>;

    /// The parametrisations on the within-pose channel (none: the family does not move during a
    /// hold).
    fn within_variants(&self, _ctx: &Context<'_>, _within: &Within) -> Vec<WithinVariant> {
        Vec::new()
    }

    /// The best parametrisation on withheld poses.
    fn fit(&self, ctx: &Context<'_>) -> Option<Fitted> {
        ctx.best_of(self.variants(ctx))
    }

    /// The candidate line: held-out evidence on both channels and the gap with the family added.
    fn evaluate(&self, ctx: &Context<'_>) -> Evaluation {
        standard_evaluation(self, ctx)
    }

    /// The stacked fit of the pose means and the holds ([`joint`]) is tried only when the holds move
    /// significantly: a shape of time fitted to holds that barely move fits their noise, and a
    /// drift's many shapes then predict some withheld pose means by chance.
    fn joint_needs_moving_holds(&self) -> bool {
        true
    }

    /// The family predicts the withheld poses' values (a drift, a non-linearity...): stronger evidence
    /// than a model of their spread only (a noise model), which the verdict names only when no
    /// value-predicting family explains.
    fn predicts_values(&self) -> bool {
        true
    }
}

/// [`Family::evaluate`]'s default: the best pose-level parametrisation, then the within-pose
/// channel's.
pub(crate) fn standard_evaluation<F: Family + ?Sized>(family: &F, ctx: &Context<'_>) -> Evaluation {
    evaluation_of(family, ctx, family.fit(ctx)).0
}

/// [`standard_evaluation`] of the pose-level fit `fit`, with the parametrisation the candidate line
/// names in the end: the pose-level fit's, or the stacked fit's when that predicts the withheld
/// poses better (`None`: neither fitted).
pub(crate) fn evaluation_of<F: Family + ?Sized>(
    family: &F,
    ctx: &Context<'_>,
    fit: Option<Fitted>,
) -> (Evaluation, Option<String>) {
    let mut named = fit.as_ref().map(|f| f.detail.clone());
    let mut e = match fit {
        Some(f) => ctx.evaluate_fitted(family.name(), f),
        None => ctx.not_testable(family.name()),
    };
    let Some(w) = ctx.within.as_ref().filter(|w| w.channel_significant || !family.joint_needs_moving_holds()) else {
        return (e, named);
    };
    let variants = family.within_variants(ctx, w);
    let stacked = joint::best(ctx, w, &variants);
    if w.channel_significant {
        add_within_credit(ctx, &mut e, w, variants);
    }
    if let Some(fit) = stacked
        && let Some(detail) = joint::add(ctx, &mut e, fit)
    {
        named = Some(detail);
    }
    (e, named)
}

/// Credits `e` with the best of `variants` on the holds alone (the within-pose channel), among those
/// whose coefficients from the holds and from the pose means do not disagree beyond
/// [`CHANNELS_DISAGREE`].
fn add_within_credit(ctx: &Context<'_>, e: &mut Evaluation, w: &Within, variants: Vec<WithinVariant>) {
    let (variants, disagreements): (Vec<WithinVariant>, Vec<f64>) = variants
        .into_iter()
        .map(|v| {
            let disagreement = ctx.channel_disagreement(w, &v).unwrap_or(f64::NAN);
            (v, disagreement)
        })
        .filter(|(_, x)| !(*x > CHANNELS_DISAGREE))
        .unzip();
    if let Some((i, fit)) = w.best_of(variants) {
        ctx.add_within(e, w, fit, disagreements[i]);
    }
}

/// The calibrated-reading change per parameter of a bias per axis and/or a relative scale per axis
/// (in that order) changing as `x`, for each power of `x` up to `power`, at the calibrated reading
/// `f` (temperature's coefficients, and drift's scale in time).
pub(crate) fn bias_scale_effect(f: V3, x: f64, power: usize, bias: bool, scale: bool) -> Vec<V3> {
    let mut out = Vec::new();
    for k in 1..=power {
        let xk = x.powi(k as i32);
        if bias {
            out.extend((0..3).map(|a| axis(a, xk)));
        }
        if scale {
            out.extend((0..3).map(|a| axis(a, f[a] * xk)));
        }
    }
    out
}

/// The calibrated-reading change per parameter of one relative scale common to every axis changing
/// as `x`, for each power of `x` up to `power`, at the calibrated reading `f` (a ratiometric supply
/// or a shared reference; drift's).
pub(crate) fn common_scale_effect(f: V3, x: f64, power: usize) -> Vec<V3> {
    (1..=power).map(|k| f.map(|c| c * x.powi(k as i32))).collect()
}

/// A verdict from the holds' movement alone, for when no family explains the withheld poses:
/// colored noise when the bias switches between levels inside the holds (a telegraph noise, whether
/// it splits them or not, [`colored_noise::switching_holds`]), else settling when the movement slows within
/// each hold, else drift when a line per hold explains it, else colored noise when every hold
/// wanders alike; motion when they move in the tremor band,
/// whether every hold moves alike (a hand) or a few (a passing truck); with what supports it. Not
/// the last two when the holds carry a steady line ([`Context::steady_line`]): a pickup or an
/// aliased vibration moves them, not the sensor nor its noise. Nor the telegraph when they carry a
/// steady line or one sinusoid in phase over the whole log ([`Context::periodic_line`]): in holds
/// of a few seconds a slow sinusoid's swings read as one step inside each (on the development sets,
/// 4 320 logs, one aliased motor vibration named colored noise, now unexplained; no other answer
/// changed).
pub(crate) fn from_holds(ctx: &Context<'_>) -> Option<(&'static str, String)> {
    let steady = ctx.steady_line().is_some();
    let periodic = steady || ctx.periodic_line().is_some();
    colored_noise::switching_holds(ctx, colored_noise::Jumps::AlsoInsidePieces)
        .filter(|_| !periodic)
        .map(|d| ("colored-noise", d))
        .or_else(|| settling::settling_holds(ctx, settling::Decay::Significant).map(|d| ("settling", d)))
        .or_else(|| drift::drifting_holds(ctx).map(|d| ("drift", d)))
        .or_else(|| {
            if steady {
                return None;
            }
            let Some(wander) = colored_noise::wandering_holds(ctx) else {
                return ctx.tremor().map(|t| ("motion", format!("the holds move at 2-20 Hz ({})", t.describe())));
            };
            Some(match ctx.tremor() {
                Some(t) => ("motion", format!("{wander}; they move at 2-20 Hz ({})", t.describe())),
                None => ("colored-noise", wander),
            })
        })
}

/// Every family, in report order.
pub(crate) fn all() -> Vec<Box<dyn Family>> {
    vec![
        Box::new(drift::Drift),
        Box::new(temperature::Temperature),
        Box::new(nonlinearity::ScaleNonlinearity),
        Box::new(settling::Settling),
        Box::new(motion::Motion),
        Box::new(colored_noise::ColoredNoise),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::csvio::Table;
    use crate::diagnose::testing::log_with;
    use crate::diagnose::{DiagnoseOptions, MIN_GAIN, gap};
    use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};

    #[test]
    fn a_steady_line_in_every_hold_is_not_motion_a_tremor_band_is() {
        // A mains pickup aliased to 9.7 Hz along one board direction, 3 mg, in every hold of a clean
        // simulated log: the tremor test sees power near 10 Hz, the holds' answer named motion.
        // The same power spread over 8-12 Hz with a fresh phase in each hold is a hand's tremor.
        use std::f64::consts::TAU;
        for seed in 1..=3 {
            let line = |_: usize, _: f64, t: f64| {
                let s = 3.0 * (TAU * 9.7 * t).sin();
                [0.6 * s, 0.3 * s, 0.74 * s]
            };
            let tremor = |p: usize, _: f64, t: f64| {
                let s: f64 = (0..9).map(|j| (TAU * (8.0 + 0.5 * j as f64) * t + (7 * p + 3 * j) as f64).sin()).sum();
                [0.6 * s, 0.3 * s, 0.74 * s]
            };
            for (bias, steady) in [(&line as &dyn Fn(usize, f64, f64) -> [f64; 3], true), (&tremor, false)] {
                let table = log_with(seed, bias);
                let m = gap::measure(&table, &DiagnoseOptions::DEFAULT).unwrap();
                let ctx = Context::new(&table, &m, &DiagnoseOptions::DEFAULT).unwrap();
                assert!(ctx.tremor().is_some(), "seed {seed}, steady {steady}");
                let named = from_holds(&ctx).map(|(effect, _)| effect);
                let found = ctx.steady_line();
                assert_eq!(found.is_some_and(|l| (l.hz - 9.7).abs() < 0.3), steady, "seed {seed}: {found:?}");
                assert_eq!(named == Some("motion"), !steady, "seed {seed}, steady {steady}: {named:?}");
            }
        }
    }

    #[test]
    fn a_sinusoid_in_phase_over_the_log_that_steps_inside_short_holds_is_not_a_telegraph_noise() {
        // A motor beside the bench at a multiple of the output rate plus a fraction of a hertz: its
        // vibration aliases to a slow sinusoid (0.25-0.38 Hz, 5 mg along one board direction) through
        // the whole session. In holds of 2-3 s its swings read as one step inside each hold: the
        // telegraph test counted them, and the holds' answer was colored noise (a fourth generator's
        // motor-aliasing log, 40 poses). The holds carry the sinusoid in phase over the whole log.
        use std::f64::consts::TAU;
        let opts = DiagnoseOptions::DEFAULT;
        let mut read_as_switching = 0;
        for (seed, hold_s, hz) in [(2, 2.0, 0.38), (5, 2.0, 0.38), (2, 3.0, 0.25), (3, 3.0, 0.25)] {
            let mut scenario = random_scenario(EffectClass::None, seed);
            scenario.sim.seconds_per_pose = hold_s;
            let mut table = to_table(&generate(&scenario), "sim").unwrap();
            let mg = table.median_magnitude * 1e-3;
            for (i, row) in table.samples.iter_mut().enumerate() {
                let s = 5.0 * mg * (TAU * hz * i as f64 / scenario.sim.rate_hz + 0.7).sin();
                (0..3).for_each(|a| row[a] += [0.5, -0.7, 0.5][a] * s);
            }
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            let case = format!("seed {seed}, holds {hold_s} s, {hz} Hz");
            assert!(ctx.periodic_line().is_some(), "{case}");
            read_as_switching +=
                colored_noise::switching_holds(&ctx, colored_noise::Jumps::AlsoInsidePieces).is_some() as usize;
            assert_ne!(from_holds(&ctx).map(|(effect, _)| effect), Some("colored-noise"), "{case}");
        }
        // The telegraph test reads some of them as switching (two of the four with jumps inside a
        // piece counted from 6 standard deviations, all four from 10): there the sinusoid's guard is
        // what answers.
        assert!(read_as_switching >= 2, "{read_as_switching} of 4 read as switching");
    }

    #[test]
    fn vibration_bursts_in_a_few_holds_are_the_holds_answer_motion() {
        // Three passing trucks shake the bench: 8-10 Hz along a fresh direction, 8 mg at the peak
        // of a Gaussian envelope of 4 s, at a fifth, a half and four fifths of the log. Only the
        // holds they pass move, so the holds do not wander alike (no colored-noise evidence), but
        // they move in the 2-20 Hz band. Before, the holds gave no answer (seeds 3-5).
        let dirs = [[0.6, 0.0, 0.8], [0.0, -0.8, 0.6], [0.48, 0.6, -0.64]];
        let opts = DiagnoseOptions::DEFAULT;
        for seed in [3, 4, 5] {
            let clean = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
            let end_s = clean.times_s.as_ref().and_then(|t| t.last()).copied().unwrap();
            let table = log_with(seed, &|_, _, t| {
                let mut b = [0.0; 3];
                for (k, d) in dirs.iter().enumerate() {
                    let centre = end_s * (0.2 + 0.3 * k as f64);
                    let envelope = 8.0 * (-0.5 * ((t - centre) / 4.0).powi(2)).exp();
                    let wave = envelope * (std::f64::consts::TAU * (8.0 + k as f64) * t).sin();
                    (0..3).for_each(|a| b[a] += wave * d[a]);
                }
                b
            });
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            assert_eq!(from_holds(&ctx).map(|(effect, _)| effect), Some("motion"), "seed {seed}");
        }
    }

    /// Chi-square per coefficient between the holds' and the pose means' fits of a family's
    /// within-pose variant.
    fn disagreement(table: &Table, family: &dyn Family, detail: &str) -> f64 {
        let opts = DiagnoseOptions::DEFAULT;
        let m = gap::measure(table, &opts).unwrap();
        let ctx = Context::new(table, &m, &opts).unwrap();
        let w = ctx.within.as_ref().unwrap();
        let variants = family.within_variants(&ctx, w);
        let variant = variants.iter().find(|v| v.detail == detail).unwrap();
        ctx.channel_disagreement(w, variant).unwrap()
    }

    fn linear_drift_disagreement(table: &Table) -> f64 {
        disagreement(table, &drift::Drift, "bias polynomial in time, degree 1")
    }

    #[test]
    fn a_transient_repeated_in_every_hold_is_no_drift_of_the_pose_means() {
        // 3 mg along one sensor direction.
        let v = [0.6, -0.48, 0.64];
        for seed in [3, 4] {
            // Package stress relaxing after each set-down, tau 5 s: nearly a line in each hold.
            let settling = log_with(seed, &|_, t, _| v.map(|c| 3.0 * c * (-t / 5.0).exp()));
            let chi = linear_drift_disagreement(&settling);
            assert!(chi > CHANNELS_DISAGREE, "seed {seed}: transient: {chi}");
            let transient = "bias transient along one sensor direction from each hold's start, tau 4 s";
            let chi = disagreement(&settling, &settling::Settling, transient);
            assert!(chi < CHANNELS_DISAGREE, "seed {seed}: transient as settling: {chi}");
            // The same bias drifting over the log at a tenth of the rate it has at a hold's start.
            let drift = log_with(seed, &|_, _, t| v.map(|c| -0.06 * c * t));
            let chi = linear_drift_disagreement(&drift);
            assert!(chi < CHANNELS_DISAGREE, "seed {seed}: drift: {chi}");
        }
    }

    #[test]
    fn a_slow_transient_in_every_hold_is_settling_and_a_drift_of_the_same_holds_is_drift() {
        // A hand's warmth leaving the board after each set-down: 2 mg along one sensor direction,
        // tau 10 s (longer than a hold: nearly a line in each).
        let v = [0.6, -0.48, 0.64];
        let opts = DiagnoseOptions::DEFAULT;
        for seed in [3, 4] {
            let touched = log_with(seed, &|_, t, _| v.map(|c| 2.0 * c * (-t / 10.0).exp()));
            let d = crate::diagnose::diagnose(&touched, &opts).unwrap();
            assert_eq!(d.verdict, "settling", "seed {seed}: {}", d.to_text());
            let drift = d.candidates.iter().find(|c| c.effect == "drift").unwrap();
            assert!(!(drift.within_disagreement <= 5.0), "seed {seed}: {drift:?}");
            // The same holds' slope, but a drift of the whole log (no thermometer: a steady warm-up
            // would explain it as well).
            let mut drifting = log_with(seed, &|_, _, t| v.map(|c| -0.2 / 10.0 * c * t));
            drifting.temps_c = None;
            let d = crate::diagnose::diagnose(&drifting, &opts).unwrap();
            assert_eq!(d.verdict, "drift", "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_scale_sagging_over_the_log_is_drift_unless_a_thermometer_moves() {
        // A ratiometric front end on a discharging supply: every axis' scale falls by 0.2 % over the
        // log (2 mg at 1 g), readings between the poses included.
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, 5)), "sim").unwrap();
        let end = gap::row_time(&table, table.samples.len() - 1, 100.0);
        let fraction: Vec<f64> = (0..table.samples.len()).map(|row| gap::row_time(&table, row, 100.0) / end).collect();
        for (sample, f) in table.samples.iter_mut().zip(&fraction) {
            *sample = sample.map(|v| v * (1.0 - 0.002 * f));
        }
        let thermometer = |span_k: f64| {
            let mut t = table.clone();
            t.temps_c = Some(fraction.iter().map(|f| 25.0 + span_k * f).collect());
            t
        };
        let opts = DiagnoseOptions::DEFAULT;
        // No thermometer, or a warmed-up part's (0.4 K over the log): the scale drifts with time.
        let mut without = table.clone();
        without.temps_c = None;
        for log in [without, thermometer(0.4)] {
            let m = gap::measure(&log, &opts).unwrap();
            let ctx = Context::new(&log, &m, &opts).unwrap();
            let e = drift::Drift.evaluate(&ctx);
            assert!(e.candidate.heldout_gain >= MIN_GAIN, "{:?}", e.candidate);
            assert!(e.candidate.detail.contains("scale"), "{}", e.candidate.detail);
        }
        // A thermometer warming by 3 K: a scale changing over the log is the temperature family's.
        let warming = thermometer(3.0);
        let m = gap::measure(&warming, &opts).unwrap();
        let ctx = Context::new(&warming, &m, &opts).unwrap();
        assert!(drift::Drift.variants(&ctx).iter().all(|v| !v.detail.contains("scale")));
    }

    /// A cube's 4 side faces, its 4 edges in the x-y plane and its 4 upper corners (12 poses), the
    /// bias drifting along z by `mg_per_s`: across gravity in 8 of the 12 holds.
    fn sideways_drift_log(seed: u64, mg_per_s: f64) -> Table {
        let cfg = crate::sim::SimConfig { plan: crate::sim::Plan::Cube26, ..crate::sim::SimConfig::paper(seed) };
        let g = cfg.gravity;
        let recording = crate::sim::simulate_with(
            &cfg,
            &mut [&mut |t: f64, _p: Option<usize>, r: &mut [f64; 3]| r[2] += g * mg_per_s * 1e-3 * t],
        );
        let keep = |u: &[f64; 3]| u[2].abs() < 0.3 || (u[2] > 0.5 && u[2] < 0.6);
        crate::diagnose::testing::table_of_poses(recording, keep, "sideways")
    }

    #[test]
    fn a_short_logs_holds_show_a_bias_drifting_across_gravity_on_the_three_axes() {
        // 0.1 mg/s along z, 12 poses: the modulus sees the drift in the 4 corners' holds only (at
        // 0.58 of it), and their movement stays within white noise; on the three axes every hold
        // moves, and a drift in time fitted to the holds predicts the withheld ones. Judged on the
        // modulus the holds' movement was not significant and gave the drift no credit. Without
        // the drift the holds give it nothing either way.
        let opts = DiagnoseOptions::DEFAULT;
        let within_gain = |table: &Table| {
            let d = crate::diagnose::diagnose(table, &opts).unwrap();
            d.candidates.iter().find(|c| c.effect == "drift").unwrap().within_gain
        };
        for seed in [2, 3] {
            let gain = within_gain(&sideways_drift_log(seed, 0.1));
            assert!(gain >= MIN_GAIN, "seed {seed}: drift's within-pose gain {gain}");
            let gain = within_gain(&sideways_drift_log(seed, 0.0));
            assert!(!(gain >= MIN_GAIN), "seed {seed}: no drift: within-pose gain {gain}");
        }
    }
}
