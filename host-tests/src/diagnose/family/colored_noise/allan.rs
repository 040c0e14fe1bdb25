//! The noise levels beyond white measured in time segments (the longest rest, every hold) from
//! their overlapping Allan variances: a random walk and a bias-instability floor, or a
//! Gauss-Markov noise.

use std::ops::Range;

use crate::csvio::Table;
use crate::diagnose::WALK_EXCESS;
use crate::diagnose::gap::row_time;
use crate::diagnose::math::{PrefixSums, V3, lstsq, mean, median, predict};

/// One averaging time of a record's Allan variance: the time, the excess over white noise, its
/// weight, and the cluster's and the record's lengths in samples (a model's curve is measured as
/// the record was: [`ClearedMarkov`]).
#[derive(Clone, Copy)]
struct AllanPoint {
    tau_s: f64,
    excess: f64,
    weight: f64,
    cluster: usize,
    record: usize,
}

/// The noise beyond white per axis (input unit), measured on the longest rest (a time segment, not
/// the pose means it is judged on): the rest is detrended (quadratic in time, linear in temperature
/// when there is a temperature column, so warm-up and temperature are not taken for noise), then
/// the excess of its overlapping Allan variance over white noise for `tau` from 1/50 to 1/5 of the
/// rest is fitted as a random walk `K^2 tau / 3` plus a flat bias-instability floor (weighted
/// least squares; when one term comes out negative, the better of the two alone). Returns
/// `(K^2 per s, floor variance)`; both zero when the excess is not at
/// least [`WALK_EXCESS`] times the white noise at the longest `tau`.
pub(super) fn colored_noise_estimate(table: &Table, first: usize, end: usize, rate: f64, white: V3) -> (V3, V3) {
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

/// [`colored_noise_estimate`] pooled over every hold (`holds`: table rows; a log may have no long
/// rest): each hold is cleared of its mean and slope, and the Allan excesses of all holds are
/// fitted together; the excess test is on their mean at each hold's longest `tau`.
pub(super) fn pooled_estimate(table: &Table, holds: &[Range<usize>], rate: f64, white: V3) -> (V3, V3) {
    let mut walk = [0.0; 3];
    let mut floor = [0.0; 3];
    for a in 0..3 {
        let (points, lasts) = hold_excesses(table, holds, rate, white[a], a);
        if lasts.len() >= 3 && mean(&lasts) > WALK_EXCESS {
            (walk[a], floor[a]) = fit_walk_and_floor(&points);
        }
    }
    (walk, floor)
}

/// The Allan excesses (`tau`, excess, weight) of every hold of at least 100 rows on axis `a`, each
/// cleared of its mean and slope, and each hold's excess at its longest `tau` (in units of the
/// white Allan variance there).
fn hold_excesses(
    table: &Table,
    holds: &[Range<usize>],
    rate: f64,
    white: f64,
    a: usize,
) -> (Vec<AllanPoint>, Vec<f64>) {
    let (mut points, mut lasts) = (Vec::new(), Vec::new());
    for rows in holds.iter().filter(|r| r.len() >= 100) {
        let y: Vec<f64> = table.samples[rows.clone()].iter().map(|s| s[a]).collect();
        let (hold_points, last) = allan_excess(&detrend_linear(&y), rate, white);
        points.extend(hold_points);
        lasts.push(last);
    }
    (points, lasts)
}

/// A Gauss-Markov noise ([`fit_markov`]) measured on the whole holds (`holds`: a hold the pose
/// finder cut at a bias jump is whole here), on the axes where most holds move beyond white noise
/// (the median hold's excess at its longest `tau` above [`WALK_EXCESS`]), or where a telegraph
/// noise would ([`telegraph_moves`]): a noise moves many holds, one disturbed hold (a bias step
/// within it) is none. Returns the fits `(variances, correlation time)` the holds tell apart from
/// the best by less than [`MARKOV_MISFIT_SPAN`] (widened by the best fit's misfit: [`fit_markov`]),
/// the best first.
pub(super) fn pooled_markov(table: &Table, holds: &[Range<usize>], rate: f64, white: V3) -> Vec<(V3, f64)> {
    let excesses: [Vec<AllanPoint>; 3] = std::array::from_fn(|a| {
        let (points, lasts) = hold_excesses(table, holds, rate, white[a], a);
        let moves = lasts.len() >= 3 && (median(&lasts) > WALK_EXCESS || telegraph_moves(&lasts));
        if moves { white_weighted(&points, white[a]) } else { Vec::new() }
    });
    fit_markov(&excesses, rate)
}

/// Excess of a hold at its longest `tau` (in units of the white Allan variance there) that white
/// noise passes in about one hold of 200 (0.4-0.5 % of 20 000 simulated holds each of 300, 1 000
/// and 4 000 samples cleared of their lines; [`WALK_EXCESS`] in one of 20): three such holds on one
/// axis of 30 holds happen by chance about once in 2 000 axes. On the development sets (13 440 logs)
/// asking 3 holds beyond 4 (chance about once in 10 000 holds) named one more telegraph noise
/// colored noise; beyond 2, four more noises, and two hand-held motions went from `unexplained` to
/// colored noise (wrong either way); no other answer where visible changed.
const FAR_EXCESS: f64 = 2.0;

/// Fewest holds, as a share of all, that a telegraph noise moves beyond white noise.
const TELEGRAPH_SHARE: f64 = 0.25;

/// Fewest holds a telegraph noise moves beyond white noise: one or two are a bias step, a bad pose.
const TELEGRAPH_HOLDS: usize = 3;

/// A telegraph (popcorn) noise moves the holds it jumps in, and only those: with a dwell time of
/// several holds most holds stand still (the median hold's excess is white), but at least
/// [`TELEGRAPH_HOLDS`] and [`TELEGRAPH_SHARE`] of the holds move beyond white noise (excess at their
/// longest `tau` above [`WALK_EXCESS`]), or at least [`TELEGRAPH_HOLDS`] move far beyond it
/// ([`FAR_EXCESS`]): a telegraph whose short visits to one level come every few holds moves fewer
/// than a quarter of them, each by its whole jump.
fn telegraph_moves(lasts: &[f64]) -> bool {
    let beyond = |excess: f64| lasts.iter().filter(|&&l| l > excess).count();
    let moving = beyond(WALK_EXCESS);
    moving >= TELEGRAPH_HOLDS && moving as f64 >= TELEGRAPH_SHARE * lasts.len() as f64
        || beyond(FAR_EXCESS) >= TELEGRAPH_HOLDS
}

/// The Allan points re-weighted by the clusters over the white noise's
/// Allan variance squared instead of the observed one's: a telegraph noise moves some holds far
/// more than others, and weights from the observed variance would fit the quiet holds only.
fn white_weighted(points: &[AllanPoint], white: f64) -> Vec<AllanPoint> {
    points
        .iter()
        .map(|&p| {
            let white_avar = white / p.cluster as f64;
            AllanPoint { weight: p.weight * ((p.excess + white_avar) / white_avar).powi(2), ..p }
        })
        .collect()
}

/// Correlation times of the Gauss-Markov noise tried, s.
const MARKOV_TAUS_S: [f64; 8] = [0.25, 0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 32.0];

/// The Allan variance of a unit Gauss-Markov noise of correlation time `tau_c` at `tau`:
/// `(tau_c / tau)^2 (2 x - 3 + 4 e^-x - e^-2x)`, `x = tau / tau_c` (a walk for `tau` far below
/// `tau_c`, white noise far above).
fn markov_allan(tau: f64, tau_c: f64) -> f64 {
    let x = tau / tau_c;
    (2.0 * x - 3.0 + 4.0 * (-x).exp() - (-2.0 * x).exp()) / (x * x)
}

/// Rise in the weighted misfit (about a chi-square under white noise, [`white_weighted`]: the
/// weights are the clusters over the white Allan variance squared, and one hold's taus overlap)
/// within which a Gauss-Markov fit at another correlation time is as good as the best: the 95th
/// percentile of a chi-square of one degree of freedom. Holds shorter than the correlation time see
/// only the noise's rise (variance over correlation time), not where it levels off. Where the best
/// fit leaves more misfit than its degrees of freedom (a telegraph's jumps move a few holds far and
/// the others not at all: no Gauss-Markov curve follows that scatter), the span grows by that
/// ratio, as a weighted fit's uncertainties grow with its residual scatter: a blindgen6 telegraph
/// (a visit of 4 s to one level every 25 s, holds of 3.7 s) left 2 609 on about 160 points at
/// 0.5 s and 2 638 at 32 s, and only 0.5 s was tried: the withheld pose means' held-out ratio was
/// 3.8 under it, 0.99 under the fit at 8 s (truth: 3.7 s).
const MARKOV_MISFIT_SPAN: f64 = 3.84;

/// A Gauss-Markov noise's Allan variance (unit variance) as a record cleared of its least-squares
/// line measures it: the line takes part of the noise's slow wander, most at the longest clusters.
/// At a fifth of the record a walk-like noise keeps about two thirds of [`markov_allan`] (the raw
/// curve then reads a correlation time longer than a hold as a short one). With `t` the record's
/// centred sample times (their squares summing to `S`), `C` the noise's correlation matrix and `d`
/// the mean over the clusters' starts of the difference of two successive clusters' means, the
/// line takes `m d'Ct / S` and gives back `m^2 t'Ct / (2 S^2)`.
struct ClearedMarkov {
    tau_c: f64,
    rate: f64,
    times_sq: f64,
    line_share: f64,
    correlated_times: PrefixSums,
}

impl ClearedMarkov {
    /// A record of `record` samples at `rate`, a noise of correlation time `tau_c`.
    fn new(record: usize, rate: f64, tau_c: f64) -> Self {
        let rho = (-1.0 / (rate * tau_c)).exp();
        let centre = (record as f64 - 1.0) / 2.0;
        let t = |i: usize| i as f64 - centre;
        // `Ct`: the sum over `j` of `rho^|i - j| t_j`, one pass each way.
        let mut up_to = vec![0.0; record];
        let mut acc = 0.0;
        for (i, u) in up_to.iter_mut().enumerate() {
            acc = t(i) + rho * acc;
            *u = acc;
        }
        let mut from = 0.0;
        let mut ct = vec![0.0; record];
        for i in (0..record).rev() {
            from = t(i) + rho * from;
            ct[i] = up_to[i] + from - t(i);
        }
        let times_sq = (0..record).map(|i| t(i).powi(2)).sum();
        let line_share = (0..record).map(|i| t(i) * ct[i]).sum();
        Self { tau_c, rate, times_sq, line_share, correlated_times: PrefixSums::new(ct) }
    }

    /// The Allan variance at clusters of `cluster` samples.
    fn allan(&self, cluster: usize) -> f64 {
        let (m, s) = (cluster as f64, self.times_sq);
        let along = self.correlated_times.mean_second_difference(cluster) / m;
        markov_allan(m / self.rate, self.tau_c) - m * along / s + m * m * self.line_share / (2.0 * s * s)
    }
}

/// [`ClearedMarkov::allan`] of every point's record and cluster at correlation time `tau_c`, each
/// record length measured once.
fn cleared_curves(excesses: &[Vec<AllanPoint>; 3], rate: f64, tau_c: f64) -> [Vec<f64>; 3] {
    let mut records: Vec<(usize, ClearedMarkov)> = Vec::new();
    std::array::from_fn(|a| {
        excesses[a]
            .iter()
            .map(|p| {
                let i = records.iter().position(|(n, _)| *n == p.record).unwrap_or_else(|| {
                    records.push((p.record, ClearedMarkov::new(p.record, rate, tau_c)));
                    records.len() - 1
                });
                records[i].1.allan(p.cluster)
            })
            .collect()
    })
}

/// The excesses per axis (empty: none) fitted as a Gauss-Markov noise at each correlation time of
/// [`MARKOV_TAUS_S`] (its curve as the holds, cleared of their lines, measure it:
/// [`ClearedMarkov`]), each axis's variance by weighted least squares (at least 0); the fits whose
/// misfit over the axes is within [`MARKOV_MISFIT_SPAN`] of the least (times the least's misfit per
/// degree of freedom, when above one: [`misfit_dof`]), the best first, as `(variances, correlation
/// time)`.
fn fit_markov(excesses: &[Vec<AllanPoint>; 3], rate: f64) -> Vec<(V3, f64)> {
    let fit = |points: &[AllanPoint], curve: &[f64]| {
        let pairs = || points.iter().zip(curve);
        let num: f64 = pairs().map(|(p, c)| p.weight * p.excess * c).sum();
        let den: f64 = pairs().map(|(p, c)| p.weight * c * c).sum();
        let var = if den > 0.0 { (num / den).max(0.0) } else { 0.0 };
        let misfit: f64 = pairs().map(|(p, c)| p.weight * (p.excess - var * c).powi(2)).sum();
        (var, misfit)
    };
    let mut fits: Vec<(V3, f64, f64)> = MARKOV_TAUS_S
        .iter()
        .map(|&tau_c| {
            let curves = cleared_curves(excesses, rate, tau_c);
            let per_axis: [(f64, f64); 3] = std::array::from_fn(|a| fit(&excesses[a], &curves[a]));
            (per_axis.map(|(v, _)| v), tau_c, per_axis.iter().map(|(_, m)| m).sum())
        })
        .collect();
    fits.sort_by(|a, b| a.2.total_cmp(&b.2));
    let least = fits.first().map_or(0.0, |f| f.2);
    let span = MARKOV_MISFIT_SPAN * (least / misfit_dof(excesses)).max(1.0);
    fits.into_iter().filter(|f| f.2 <= least + span).map(|(v, tau, _)| (v, tau)).collect()
}

/// Degrees of freedom of [`fit_markov`]'s misfit: the points less one variance per axis fitted (at
/// least one).
fn misfit_dof(excesses: &[Vec<AllanPoint>; 3]) -> f64 {
    let points: usize = excesses.iter().map(Vec::len).sum();
    let fitted = excesses.iter().filter(|e| !e.is_empty()).count();
    points.saturating_sub(fitted).max(1) as f64
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
/// 1/5 of the record: an [`AllanPoint`] per `tau`, and the excess at the longest `tau` in units of
/// the white Allan variance there.
fn allan_excess(detrended: &[f64], rate: f64, white: f64) -> (Vec<AllanPoint>, f64) {
    let n = detrended.len();
    let sums = PrefixSums::new(detrended.iter().copied());
    let mut points = Vec::new();
    let mut last_excess = 0.0;
    let mut m = ((n as f64 / 50.0) as usize).max(1);
    while 5 * m <= n {
        let avar = sums.allan_variance(m);
        let white_avar = white / m as f64;
        let excess = avar - white_avar;
        // Weighted by the number of independent clusters over the relative variance.
        let w = (n as f64 / m as f64) / (avar * avar).max(1e-300);
        points.push(AllanPoint { tau_s: m as f64 / rate, excess, weight: w, cluster: m, record: n });
        last_excess = excess / white_avar;
        m *= 2;
    }
    (points, last_excess)
}

/// The excess fitted as a random walk `K^2 tau / 3` plus a flat floor (weighted least squares):
/// both when both come out positive, else the better single term. Returns `(K^2, floor)`.
fn fit_walk_and_floor(points: &[AllanPoint]) -> (f64, f64) {
    let sum = |f: &dyn Fn(f64, f64) -> f64| points.iter().map(|p| p.weight * f(p.tau_s, p.excess)).sum::<f64>();
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

    use crate::sim::random::standard_normal;

    #[test]
    fn the_allan_variance_of_a_simulated_gauss_markov_noise_follows_its_formula() {
        // First-order Gauss-Markov noises (unit variance, correlation time 100 s) at 10 Hz for
        // 2000 s, averaged over 16 runs: their overlapping Allan variance at tau 40-320 s (0.4-3.2
        // correlation times: the walk-like rise, the peak, the white-like fall) against the closed
        // form.
        let (rate, tau_c, runs): (f64, f64, usize) = (10.0, 100.0, 16);
        let phi = (-1.0 / (rate * tau_c)).exp();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let mut sums: Vec<(f64, f64)> = Vec::new();
        for _ in 0..runs {
            let mut x = standard_normal(&mut rng);
            let series: Vec<f64> = (0..20_000)
                .map(|_| {
                    x = phi * x + (1.0 - phi * phi).sqrt() * standard_normal(&mut rng);
                    x
                })
                .collect();
            let (points, _) = super::allan_excess(&series, rate, 0.0);
            sums.resize(points.len(), (0.0, 0.0));
            points.iter().zip(&mut sums).for_each(|(p, s)| *s = (p.tau_s, s.1 + p.excess / runs as f64));
        }
        assert!(sums.len() >= 3);
        for (tau, avar) in sums {
            let expected = super::markov_allan(tau, tau_c);
            assert!((avar / expected - 1.0).abs() < 0.25, "tau {tau}: {avar} vs {expected}");
        }
    }

    /// A Gauss-Markov noise of unit variance and correlation time `tau_c` at `rate`, `n` samples.
    fn markov_series(rng: &mut Xoshiro256PlusPlus, rate: f64, tau_c: f64, n: usize) -> Vec<f64> {
        let phi = (-1.0 / (rate * tau_c)).exp();
        let mut x = standard_normal(rng);
        (0..n)
            .map(|_| {
                x = phi * x + (1.0 - phi * phi).sqrt() * standard_normal(rng);
                x
            })
            .collect()
    }

    #[test]
    fn a_hold_cleared_of_its_line_measures_a_slow_gauss_markov_noise_as_the_cleared_curve_says() {
        // 2 000 holds of 20 s at 10 Hz, each cleared of its line as the holds are, of a
        // Gauss-Markov noise of unit variance and correlation time 40 s (longer than a hold): their
        // mean Allan variance at 2-4 s (a tenth and a fifth of a hold) against the cleared curve,
        // and the raw curve, which the line's share makes about 1.4 times too high at a fifth.
        let (rate, tau_c, record, runs): (f64, f64, usize, usize) = (10.0, 40.0, 200, 2000);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        let mut sums: Vec<(usize, f64)> = Vec::new();
        for _ in 0..runs {
            let series = super::detrend_linear(&markov_series(&mut rng, rate, tau_c, record));
            let (points, _) = super::allan_excess(&series, rate, 0.0);
            sums.resize(points.len(), (0, 0.0));
            points.iter().zip(&mut sums).for_each(|(p, s)| *s = (p.cluster, s.1 + p.excess / runs as f64));
        }
        let cleared = super::ClearedMarkov::new(record, rate, tau_c);
        let (longest, at_longest) = sums[sums.len() - 1];
        assert_eq!(longest, 32);
        for (cluster, avar) in sums.into_iter().filter(|(m, _)| *m >= 16) {
            let expected = cleared.allan(cluster);
            assert!((avar / expected - 1.0).abs() < 0.1, "cluster {cluster}: {avar} vs {expected}");
        }
        let raw = super::markov_allan(longest as f64 / rate, tau_c);
        assert!(raw > 1.3 * at_longest, "raw {raw} vs measured {at_longest}");
    }

    #[test]
    fn a_telegraph_moving_few_holds_far_beyond_white_noise_is_measured_and_two_such_holds_are_not() {
        // Each hold's excess at its longest tau, in white Allan variances: 33 holds of which 5
        // carry the jumps of a telegraph that visits its upper level for 4 s every 25 s (a
        // blindgen6 log's x axis: 8.1, 6.6, 11.1, 8.8 and 8.6, a sixth of the holds), the others
        // at white noise's chance levels; then only two holds so moved (a bias step, a pressed pose).
        let chance = [0.0, 0.45, -0.03, 0.23, -0.32, 0.46, 0.19, 0.47, 0.08, -0.13, 1.56];
        let mut lasts: Vec<f64> = chance.iter().cycle().take(28).copied().collect();
        lasts.extend([8.1, 6.6, 11.1, 8.8, 8.6]);
        assert!(super::telegraph_moves(&lasts));
        lasts.truncate(30);
        assert!(!super::telegraph_moves(&lasts));
    }

    #[test]
    fn a_noise_moving_a_few_holds_far_and_the_others_not_leaves_every_correlation_time_its_holds_cannot_tell_open() {
        // 33 holds of 3.7 s at 100 Hz, white variance 1 per sample: 5 carry a Gauss-Markov noise's
        // excess (correlation time 8 s, longer than a hold) six times over, 28 none, as a telegraph
        // moves the holds it jumps in. No curve follows that scatter; the misfit per degree of
        // freedom grows the span, and the times from 2 s up stay open.
        let (rate, record) = (100.0, 370);
        let cleared = super::ClearedMarkov::new(record, rate, 8.0);
        let hold = |scale: f64, h: usize| -> Vec<super::AllanPoint> {
            [7, 14, 28, 56]
                .iter()
                .map(|&cluster| {
                    let white_avar = 1.0 / cluster as f64;
                    // Each hold's excesses scatter about the curve by half of it (a jump's place).
                    let scatter = 1.0 + 0.5 * ((7 * h + cluster) as f64).sin();
                    let excess = scale * scatter * 0.2 * cleared.allan(cluster);
                    super::AllanPoint {
                        tau_s: cluster as f64 / rate,
                        excess,
                        weight: (record / cluster) as f64 / (white_avar * white_avar)
                            * ((excess + white_avar) / white_avar).powi(2),
                        cluster,
                        record,
                    }
                })
                .collect()
        };
        let points: Vec<super::AllanPoint> = (0..33).flat_map(|h| hold(if h < 5 { 6.0 } else { 0.0 }, h)).collect();
        let taus: Vec<f64> =
            super::fit_markov(&[points, Vec::new(), Vec::new()], rate).iter().map(|(_, t)| *t).collect();
        assert!([2.0, 4.0, 8.0, 16.0, 32.0].iter().all(|t| taus.contains(t)), "{taus:?}");
    }

    #[test]
    fn holds_that_see_only_the_rise_leave_the_correlation_time_open_and_the_level_off_them_closes_it() {
        // Twelve holds of 10 s at 100 Hz, white variance 1 per sample, the excess of a Gauss-Markov
        // noise (variance 0.2) exactly at its expectation, as holds cleared of their lines measure
        // it, at tau 0.2-2 s. With a correlation time of 16 s the holds see the rise only: 8 s and
        // 32 s fit as well; with 0.5 s they see it level off and fall, and no time but 0.5 s fits.
        let (rate, record) = (100.0, 1000);
        let points = |tau_c: f64| -> Vec<super::AllanPoint> {
            let (holds, white) = (12.0, 1.0);
            let cleared = super::ClearedMarkov::new(record, rate, tau_c);
            [20, 40, 80, 160, 200]
                .iter()
                .map(|&cluster| {
                    let white_avar = white / cluster as f64;
                    super::AllanPoint {
                        tau_s: cluster as f64 / rate,
                        excess: 0.2 * cleared.allan(cluster),
                        weight: holds * (record / cluster) as f64 / (white_avar * white_avar),
                        cluster,
                        record,
                    }
                })
                .collect()
        };
        let taus = |tau_c: f64| -> Vec<f64> {
            let p = points(tau_c);
            super::fit_markov(&[p.clone(), p.clone(), p], rate).iter().map(|(_, t)| *t).collect()
        };
        let slow = taus(16.0);
        assert_eq!(slow[0], 16.0, "{slow:?}");
        assert!(slow.len() >= 3 && slow.iter().all(|t| *t >= 2.0), "{slow:?}");
        assert_eq!(taus(0.5), vec![0.5]);
    }
}
