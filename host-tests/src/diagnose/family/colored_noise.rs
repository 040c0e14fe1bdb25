//! Colored noise: a bias random walk and/or a bias-instability floor, measured on the longest
//! rest and pooled over every hold (time segments, not the pose means it is judged on) and given to
//! the simulator; judged by how well the noise model predicts the nominal model's held-out scatter.

use super::{Candidate, Context, Evaluation, Family, Variant};
use crate::csvio::Table;
use crate::diagnose::gap::PoseData;
use crate::diagnose::gap::{Noise, expected_cv_ms, quantisation_step, residual_noise_draws, row_time, simulate_gap};
use crate::diagnose::math::cv_residuals;
use crate::diagnose::math::{V3, lstsq, mean, predict};
use crate::diagnose::verdict::NOISE_LEAVES_AT_MOST;
use crate::diagnose::within::white_from_differences;
use crate::diagnose::{CV_NOISE_DRAWS, PARAMETER_PENALTY, WALK_EXCESS};

/// Least evenness ([`crate::diagnose::within::Within::evenness`]) of holds that all wander.
const EVEN_HOLDS: f64 = 0.25;

/// The holds wander: their movement is significant, every hold moves about alike (a noise, not a
/// few disturbed holds) and, asked after settling and drift, it neither slows nor follows a line
/// per hold. A walk or flicker wanders through every hold; the withheld pose means show it only as
/// spread, and no more than a random walk at the holds' level spreads them
/// ([`walk_accounts_for_poses`]). The description, or `None`.
pub(crate) fn wandering_holds(ctx: &Context<'_>) -> Option<String> {
    let within = ctx.within.as_ref().filter(|_| wander_alike(ctx))?;
    let evenness = within.evenness();
    walk_accounts_for_poses(ctx).then(|| {
        format!(
            "the holds wander alike ({:.1}x white, evenness {evenness:.2}), rougher than a line per hold ({:.0} % explained)",
            within.nominal_ratio,
            100.0 * within.line_share().clamp(0.0, 1.0)
        )
    })
}

/// The holds' movement is significant and every hold moves about alike (a noise, not a few
/// disturbed holds).
fn wander_alike(ctx: &Context<'_>) -> bool {
    ctx.within.as_ref().is_some_and(|w| w.significant && w.evenness() >= EVEN_HOLDS)
}

pub(crate) struct ColoredNoise;

/// A random walk (the same variance per second on every axis) at the level that moves the holds'
/// segment means as much as they move beyond white noise (the method of moments on the within-pose
/// channel); `None` when the holds do not move beyond white noise.
fn walk_from_holds(ctx: &Context<'_>) -> Option<V3> {
    let within = ctx.within.as_ref()?;
    let (observed, _) = within.observed_excess();
    let level = observed / within.predicted_excess(ctx.m, [1.0; 3], [0.0; 3]);
    (level > 0.0 && level.is_finite()).then_some([level; 3])
}

/// The random walk at the holds' level ([`walk_from_holds`]) with the held-out ratio of the withheld
/// pose means under it (`None` when the data put far more of their scatter in one pose than any
/// draw of the walk does); measured once per log.
fn holds_walk(ctx: &Context<'_>) -> Option<(V3, Option<f64>)> {
    *ctx.holds_walk
        .get_or_init(|| walk_from_holds(ctx).map(|walk| (walk, ColoredNoise.heldout_ratio(ctx, walk, [0.0; 3]))))
}

/// The holds' wander can account for the withheld pose means' scatter: a random walk at the holds'
/// level ([`walk_from_holds`]) leaves it at most [`NOISE_LEAVES_AT_MOST`] times its prediction.
/// Of the noises that wander through the holds (flicker, Gauss-Markov, a walk), a walk spreads
/// the pose means the most for the same movement within the holds, so a scatter beyond it is not
/// the holds' noise (a hysteresis 73 times the noise, on holds moving 1.2 times white). Logs too
/// short to withhold poses are not judged, nor a scatter concentrated in one pose beyond any draw
/// of the walk (an end pose of a walk's path, extrapolated by its fold's fit, can be).
fn walk_accounts_for_poses(ctx: &Context<'_>) -> bool {
    !ctx.pose_level || holds_walk(ctx).is_some_and(|(_, ratio)| ratio.is_none_or(|ratio| ratio <= NOISE_LEAVES_AT_MOST))
}

/// Held-out ratio up to which a random walk at the holds' level accounts closely for the withheld
/// poses' scatter. On the development sets' walks (holds wandering alike) it left 0.45-1.1; a
/// smooth wander, whose pose means move more than its holds imply, 1.36-3.3 but for one at 0.88.
const WALK_ACCOUNTS: f64 = 1.2;

/// The holds wander as a noise ([`wander_alike`]) and a random walk at their level spreads the
/// withheld pose means as much as they are spread, within [`WALK_ACCOUNTS`] (so within
/// [`walk_accounts_for_poses`]' limit too): a time-varying fit of the pose means then follows the
/// walk's path.
pub(crate) fn walk_accounts_closely(ctx: &Context<'_>) -> bool {
    wander_alike(ctx) && holds_walk(ctx).and_then(|(_, ratio)| ratio).is_some_and(|ratio| ratio <= WALK_ACCOUNTS)
}

/// Share of the squared held-out residual in the largest pose (0 without residuals).
fn largest_share(cv: &[Option<f64>]) -> f64 {
    let squares: Vec<f64> = cv.iter().flatten().map(|r| r * r).collect();
    let total: f64 = squares.iter().sum();
    if total > 0.0 { squares.iter().copied().fold(0.0, f64::max) / total } else { 0.0 }
}

/// A noise estimate: random walk and floor (variances per axis), and whether it is pooled over the
/// holds (else from the longest rest).
type Estimate = (V3, V3, bool);

/// Standard deviations (under white noise) by which the holds' movement may fall short of what a
/// noise model predicts for them.
const HOLDS_SHORT_Z: f64 = 3.0;

/// The holds move far less than the noise model predicts they would (its floor and walk move every
/// hold's segment means; the holds are where it was measured): the model's level is an artefact of
/// the white level it was measured against (successive differences understate a digitally
/// low-passed sensor's white noise, and its excess then reads as a floor), not a noise the holds
/// carry.
fn holds_refute(ctx: &Context<'_>, walk: V3, floor: V3) -> bool {
    let Some(within) = ctx.within.as_ref() else { return false };
    let predicted = within.predicted_excess(ctx.m, walk, floor);
    let (observed, sigma) = within.observed_excess();
    observed < predicted - HOLDS_SHORT_Z * sigma * (1.0 + predicted)
}

/// Fewest noise draws out of [`CV_NOISE_DRAWS`] that must put as large a share of the scatter in one
/// pose as the data do, for the noise model to stay credible.
const MIN_DRAWS_AS_CONCENTRATED: usize = 1;

impl ColoredNoise {
    /// Penalised held-out ratio of the pose means under white noise plus this walk and floor; `None`
    /// when the data put far more of their scatter in one pose than the model ever does (one bad
    /// pose, not noise: no draw of the model concentrates it so).
    fn heldout_ratio(&self, ctx: &Context<'_>, walk: V3, floor: V3) -> Option<f64> {
        let m = ctx.m;
        let noise = Noise { white: m.white, walk, floor: std::array::from_fn(|a| floor[a] + m.quantisation[a]) };
        let draws = residual_noise_draws(&m.model, &m.directions, &m.poses, &noise, CV_NOISE_DRAWS, ctx.opts.seed);
        let observed = largest_share(&ctx.nominal_cv);
        let as_concentrated = draws
            .iter()
            .filter_map(|d| cv_residuals(&ctx.base_rows, d, &ctx.fold, ctx.folds, &ctx.none_dropped))
            .filter(|cv| largest_share(cv) >= observed)
            .count();
        if as_concentrated < MIN_DRAWS_AS_CONCENTRATED {
            return None;
        }
        let e_col = expected_cv_ms(&ctx.base_rows, &draws, &ctx.fold, ctx.folds, &ctx.none_dropped);
        let ms =
            (crate::diagnose::math::sum_sq(&ctx.nominal_cv).0 + PARAMETER_PENALTY * ctx.e_white) / m.poses.len() as f64;
        Some((ms / e_col).sqrt())
    }

    /// The noise model the withheld poses' scatter agrees with best, among each estimate's random
    /// walk and floor together and each alone (their levels come from the holds, not from the pose
    /// means): `(ratio, walk, floor)`.
    ///
    /// An estimate pooled over the holds is checked against the holds' own movement
    /// ([`holds_refute`]); the longest rest's reaches time scales longer than a hold, where a slow
    /// Gauss-Markov noise has not yet reached its floor.
    fn best_noise(&self, ctx: &Context<'_>, estimates: &[Estimate]) -> Option<(f64, V3, V3)> {
        let zero = [0.0; 3];
        let mut best: Option<(f64, V3, V3)> = None;
        for &(walk, floor, pooled) in estimates {
            for (w, f) in [(walk, floor), (walk, zero), (zero, floor)] {
                if !(ctx.pose_level && w.iter().chain(&f).any(|v| *v > 0.0)) || (pooled && holds_refute(ctx, w, f)) {
                    continue;
                }
                let Some(ratio) = self.heldout_ratio(ctx, w, f) else { continue };
                if best.is_none_or(|(b, _, _)| ctx.noise_gain(ratio) > ctx.noise_gain(b)) {
                    best = Some((ratio, w, f));
                }
            }
        }
        best
    }
}

/// The colored noise measured in the holds: on the longest rest, and pooled over every hold
/// (evidence from all of them, not the longest one only), each against two white levels: the
/// noise of successive differences (blind to slow wander, at least the rounding's `q^2 / 12`),
/// and the holds' median variance (which counts a wander faster than a hold as white: the lower
/// estimate when the wander does not grow as a random walk over the log, as a Gauss-Markov noise).
fn hold_estimates(ctx: &Context<'_>) -> Vec<Estimate> {
    let m = ctx.m;
    let q = quantisation_step(ctx.table);
    let diff = white_from_differences(ctx.table, ctx.poses);
    let white: V3 = std::array::from_fn(|a| if diff[a] > 0.0 { diff[a].max(q[a] * q[a] / 12.0) } else { m.white[a] });
    let longest = (0..ctx.poses.len()).max_by_key(|&i| ctx.poses[i].n).unwrap_or(0);
    let rows = ctx.poses[longest].rows.clone();
    [white, m.white]
        .iter()
        .flat_map(|&w| {
            let (walk, floor) = colored_noise_estimate(ctx.table, rows.start, rows.end, m.rate, w);
            let (pooled_walk, pooled_floor) = pooled_estimate(ctx.table, ctx.poses, m.rate, w);
            [(walk, floor, false), (pooled_walk, pooled_floor, true)]
        })
        .collect()
}

impl Family for ColoredNoise {
    fn name(&self) -> &'static str {
        "colored-noise"
    }

    fn predicts_values(&self) -> bool {
        false
    }

    fn variants(&self, _ctx: &Context<'_>) -> Vec<Variant> {
        Vec::new()
    }

    fn evaluate(&self, ctx: &Context<'_>) -> Evaluation {
        // Motion in the tremor band is no sensor noise: the motion family measures it.
        if ctx.tremor().is_some() {
            let mut e = ctx.not_testable(self.name());
            e.candidate.detail = "the holds move at 2-20 Hz: motion, not sensor noise".into();
            return e;
        }
        // A noise of the bias that spreads the pose means moves it within the holds too: holds that
        // move no more than white noise (not even by chance) refute it. On the development sets
        // no colored noise named right had such holds; 4 logs named colored noise wrongly did (two
        // hysteresis, a clean log, a temperature scale).
        if ctx.within.as_ref().is_some_and(|w| w.observed_excess().0 <= 0.0) {
            let mut e = ctx.not_testable(self.name());
            e.candidate.detail = "the holds move no more than white noise: no bias noise spreads the pose means".into();
            return e;
        }
        self.noise_model(ctx)
    }
}

impl ColoredNoise {
    /// The noise model measured in the holds, judged on the withheld poses' scatter.
    pub(crate) fn noise_model(&self, ctx: &Context<'_>) -> Evaluation {
        let m = ctx.m;
        let mut estimates = hold_estimates(ctx);
        // The walk whose level the holds' wander measures, when it accounts for the pose means.
        if walk_accounts_closely(ctx) {
            estimates.extend(holds_walk(ctx).map(|(walk, _)| (walk, [0.0; 3], true)));
        }
        let best = self.best_noise(ctx, &estimates);
        let (walk, floor, _) = estimates[0];
        let applicable = best.is_some();
        let (heldout_ratio, walk, floor) = best.unwrap_or((ctx.heldout_ratio_nominal, walk, floor));
        let noise = Noise { white: m.white, walk, floor: std::array::from_fn(|a| floor[a] + m.quantisation[a]) };
        let sim_after = if applicable {
            let sims =
                simulate_gap(&m.model, &m.directions, &m.poses, &noise, m.gravity, ctx.opts.repeats, ctx.opts.seed);
            mean(&sims)
        } else {
            m.gap.sim_rmse_mg
        };
        let scale: V3 = std::array::from_fn(|a| m.model.ka[a][a]);
        let mg = |v: V3, a: usize| m.to_mg(v[a].sqrt() * scale[a]);
        let candidate = Candidate {
            effect: "colored-noise",
            applicable,
            heldout_ratio,
            heldout_gain: if applicable { ctx.noise_gain(heldout_ratio) } else { 0.0 },
            ratio_after: m.gap.real_rmse_mg / sim_after,
            extra_params: 1,
            detail: format!(
                "random walk {:.3}/{:.3}/{:.3} mg/sqrt(s), bias instability {:.3}/{:.3}/{:.3} mg",
                mg(walk, 0),
                mg(walk, 1),
                mg(walk, 2),
                mg(floor, 0),
                mg(floor, 1),
                mg(floor, 2)
            ),
            within_gain: f64::NAN,
            within_detail: String::new(),
            within_disagreement: f64::NAN,
            variants: Vec::new(),
        };
        Evaluation {
            candidate,
            after: m.r.iter().map(|v| Some(*v)).collect(),
            predicts_values: false,
            gain_without_worst: f64::NAN,
            wander: false,
        }
    }
}

/// The noise beyond white per axis (input unit), measured on the longest rest (a time segment, not
/// the pose means it is judged on): the rest is detrended (quadratic in time, linear in temperature
/// when there is a temperature column, so warm-up and temperature are not taken for noise), then
/// the excess of its overlapping Allan variance over white noise for `tau` from 1/50 to 1/5 of the
/// rest is fitted as a random walk `K^2 tau / 3` plus a flat bias-instability floor (weighted
/// least squares; when one term comes out negative, the better of the two alone). Returns
/// `(K^2 per s, floor variance)`; both zero when the excess is not at
/// least [`WALK_EXCESS`] times the white noise at the longest `tau`.
pub(crate) fn colored_noise_estimate(table: &Table, first: usize, end: usize, rate: f64, white: V3) -> (V3, V3) {
    let n = end - first;
    let mut walk = [0.0; 3];
    let mut floor = [0.0; 3];
    if n < 200 {
        return (walk, floor);
    }
    let rows = trend_design(table, first, end, rate);
    let idx: Vec<usize> = (0..n).collect();
    for a in 0..3 {
        let y: Vec<f64> = table.samples[first..end].iter().map(|s| -s[a]).collect();
        let Some(x) = lstsq(&rows, &y, &idx) else { continue };
        let detrended: Vec<f64> = (0..n).map(|i| -predict(&rows, &y, &x, i)).collect();
        let (points, last_excess) = allan_excess(&detrended, rate, white[a]);
        if points.is_empty() || !(last_excess > WALK_EXCESS) {
            continue;
        }
        (walk[a], floor[a]) = fit_walk_and_floor(&points);
    }
    (walk, floor)
}

/// [`colored_noise_estimate`] pooled over every hold (a log may have no long rest): each
/// hold is cleared of its mean and slope, and the Allan excesses of all holds are fitted together;
/// the excess test is on their weighted mean at each hold's longest `tau`.
pub(crate) fn pooled_estimate(table: &Table, poses: &[PoseData], rate: f64, white: V3) -> (V3, V3) {
    let mut walk = [0.0; 3];
    let mut floor = [0.0; 3];
    for a in 0..3 {
        let (mut points, mut excess, mut holds) = (Vec::new(), 0.0, 0usize);
        for p in poses.iter().filter(|p| p.n >= 100) {
            let y: Vec<f64> = table.samples[p.rows.clone()].iter().map(|s| s[a]).collect();
            let (pose_points, last) = allan_excess(&detrend_linear(&y), rate, white[a]);
            points.extend(pose_points);
            excess += last;
            holds += 1;
        }
        if holds >= 3 && excess / holds as f64 > WALK_EXCESS {
            (walk[a], floor[a]) = fit_walk_and_floor(&points);
        }
    }
    (walk, floor)
}

/// `y` less its least-squares line over the sample index.
fn detrend_linear(y: &[f64]) -> Vec<f64> {
    let n = y.len() as f64;
    let x_mean = (n - 1.0) / 2.0;
    let y_mean = y.iter().sum::<f64>() / n;
    let sxx: f64 = (0..y.len()).map(|i| (i as f64 - x_mean).powi(2)).sum();
    let sxy: f64 = y.iter().enumerate().map(|(i, v)| (i as f64 - x_mean) * (v - y_mean)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    y.iter().enumerate().map(|(i, v)| v - y_mean - slope * (i as f64 - x_mean)).collect()
}

/// The trend a rest is cleared of: quadratic in time, linear in temperature when it varies.
fn trend_design(table: &Table, first: usize, end: usize, rate: f64) -> Vec<Vec<f64>> {
    let t0 = row_time(table, first, rate);
    let span = (row_time(table, end - 1, rate) - t0).max(1e-9);
    let temps = table.temps_c.as_ref().map(|t| &t[first..end]);
    let t_mean = temps.map_or(0.0, mean);
    let has_temp = temps.is_some_and(|t| t.iter().any(|v| (v - t_mean).abs() > 1e-9));
    (first..end)
        .map(|i| {
            let x = 2.0 * (row_time(table, i, rate) - t0) / span - 1.0;
            let mut row = vec![1.0, x, x * x];
            if let (true, Some(t)) = (has_temp, temps) {
                row.push(t[i - first] - t_mean);
            }
            row
        })
        .collect()
}

/// Overlapping Allan variance in excess of white noise (`white` per sample) for `tau` from 1/50 to
/// 1/5 of the record: `(tau s, excess, weight)` per `tau`, and the excess at the longest `tau` in
/// units of the white Allan variance there.
fn allan_excess(detrended: &[f64], rate: f64, white: f64) -> (Vec<(f64, f64, f64)>, f64) {
    let n = detrended.len();
    let mut prefix = vec![0.0; n + 1];
    for i in 0..n {
        prefix[i + 1] = prefix[i] + detrended[i];
    }
    let mut points = Vec::new();
    let mut last_excess = 0.0;
    let mut m = ((n as f64 / 50.0) as usize).max(1);
    while 5 * m <= n {
        let count = n - 2 * m + 1;
        let sum: f64 = (0..count).map(|k| (prefix[k + 2 * m] - 2.0 * prefix[k + m] + prefix[k]).powi(2)).sum();
        let avar = sum / (2.0 * count as f64 * (m * m) as f64);
        let white_avar = white / m as f64;
        let excess = avar - white_avar;
        // Weighted by the number of independent clusters over the relative variance.
        let w = (n as f64 / m as f64) / (avar * avar).max(1e-300);
        points.push((m as f64 / rate, excess, w));
        last_excess = excess / white_avar;
        m *= 2;
    }
    (points, last_excess)
}

/// The excess fitted as a random walk `K^2 tau / 3` plus a flat floor (weighted least squares):
/// both when both come out positive, else the better single term. Returns `(K^2, floor)`.
fn fit_walk_and_floor(points: &[(f64, f64, f64)]) -> (f64, f64) {
    let sum = |f: &dyn Fn(f64, f64) -> f64| points.iter().map(|&(t, e, w)| w * f(t, e)).sum::<f64>();
    let k2 = (sum(&|t, e| e * t / 3.0) / sum(&|t, _| (t / 3.0).powi(2))).max(0.0);
    let level = (sum(&|_, e| e) / sum(&|_, _| 1.0)).max(0.0);
    let (saa, sab, sbb) = (sum(&|t, _| (t / 3.0).powi(2)), sum(&|t, _| t / 3.0), sum(&|_, _| 1.0));
    let (sea, seb) = (sum(&|t, e| e * t / 3.0), sum(&|_, e| e));
    let det = saa * sbb - sab * sab;
    let joint = (det > 0.0).then(|| ((sea * sbb - seb * sab) / det, (saa * seb - sab * sea) / det));
    match joint {
        Some((k, c)) if k >= 0.0 && c >= 0.0 => (k, c),
        _ => {
            let misfit_walk = sum(&|t, e| (e - k2 * t / 3.0).powi(2));
            let misfit_floor = sum(&|_, e| (e - level).powi(2));
            if misfit_walk <= misfit_floor { (k2, 0.0) } else { (0.0, level) }
        }
    }
}

#[cfg(test)]
mod tests {
    use rand_core::SeedableRng;
    use rand_xoshiro::Xoshiro256PlusPlus;

    use super::{ColoredNoise, Context, Family, walk_accounts_for_poses};
    use crate::csvio::{self, AccumulateOptions, Table};
    use crate::diagnose::{DiagnoseOptions, gap};
    use crate::sim::random::{random_sign, standard_normal};
    use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};

    /// A clean simulated log with a bias random walk of `walk_mg` mg per sqrt(s) on every axis, and
    /// an offset of its own from each hold on (`offset_mg` along each axis, random signs): the
    /// holds wander with the walk, the pose means spread with the offsets.
    fn walk_log(seed: u64, walk_mg: f64, offset_mg: f64) -> Table {
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "walk").unwrap();
        let acc = csvio::accumulate(&table, &AccumulateOptions::default()).unwrap();
        let (mg, dt) = (table.median_magnitude / 1000.0, 1.0 / acc.sample_rate_hz.unwrap());
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let mut walk = [0.0; 3];
        for sample in &mut table.samples {
            walk = walk.map(|w| w + walk_mg * mg * dt.sqrt() * standard_normal(&mut rng));
            (0..3).for_each(|a| sample[a] += walk[a]);
        }
        for (k, span) in acc.spans.iter().enumerate() {
            let offset: [f64; 3] = std::array::from_fn(|_| random_sign(&mut rng) * offset_mg * mg);
            let end = acc.spans.get(k + 1).map_or(table.samples.len(), |next| next.first_row);
            for sample in &mut table.samples[span.first_row..end] {
                (0..3).for_each(|a| sample[a] += offset[a]);
            }
        }
        table
    }

    #[test]
    fn a_walk_at_the_holds_level_accounts_for_the_pose_means_only_if_they_spread_no_more() {
        let opts = DiagnoseOptions::DEFAULT;
        for seed in [3, 5] {
            let accounts = |offset_mg| {
                let table = walk_log(seed, 0.05, offset_mg);
                let m = gap::measure(&table, &opts).unwrap();
                let ctx = Context::new(&table, &m, &opts).unwrap();
                walk_accounts_for_poses(&ctx)
            };
            assert!(accounts(0.0), "seed {seed}: the walk alone");
            assert!(!accounts(10.0), "seed {seed}: offsets of 10 mg per hold");
        }
    }

    #[test]
    fn holds_that_move_no_more_than_white_noise_refute_a_bias_noise() {
        let opts = DiagnoseOptions::DEFAULT;
        let mut refuted = 0;
        for seed in 1..=6 {
            // Offsets of 1 mg per hold (a hysteresis, a bad pose): the pose means spread, the holds
            // are white. The holds' excess is zero up to chance: where chance leaves it at or below
            // zero, colored noise is not a candidate.
            let table = walk_log(seed, 0.0, 1.0);
            let m = gap::measure(&table, &opts).unwrap();
            let ctx = Context::new(&table, &m, &opts).unwrap();
            let excess = ctx.within.as_ref().unwrap().observed_excess().0;
            let e = ColoredNoise.evaluate(&ctx);
            if excess <= 0.0 {
                refuted += 1;
                assert!(!e.candidate.applicable && e.candidate.detail.contains("no more than white"), "seed {seed}");
            }
        }
        assert!(refuted >= 1, "no seed whose holds' excess is at most zero");
        // Holds that walk are not refuted.
        let table = walk_log(3, 0.05, 0.0);
        let m = gap::measure(&table, &opts).unwrap();
        let ctx = Context::new(&table, &m, &opts).unwrap();
        assert!(ctx.within.as_ref().unwrap().observed_excess().0 > 0.0);
        assert!(!ColoredNoise.evaluate(&ctx).candidate.detail.contains("no more than white"));
    }
}
