//! Step 3's second channel: how each pose moves *during* its hold. Each pose is cut into
//! [`SEGMENTS`] segments; a segment's modulus deviation from its pose's own mean is free of the
//! calibration (a constant per pose), so it tests time-varying effects (drift, temperature,
//! settling) even on logs with too few poses to withhold some at the pose level.
//!
//! The deviations are whitened by the white-equivalent noise of a mean (the per-sample variance
//! times the sensor low-pass filter's correlation factor, as at the pose level), so pure white noise
//! gives a ratio of 1 on a filtered sensor too (with the per-sample noise alone, a digitally
//! low-passed part's holds all looked as if they moved). A family's
//! parametrisation is fitted on the deviations of some poses and predicts the withheld poses'
//! (the folds of the pose level), with the same per-parameter penalty.

use std::ops::Range;

use super::PARAMETER_PENALTY;
use super::SEGMENTS;
use super::gap::{CORRELATION_BLOCK_S, Measured, PoseData, at_least_rounding, row_time};
use super::math::{PrefixSums, V3, cv_residuals, dot, mean_square, median, sum_sq};
use crate::csvio::Table;

/// Most cross-validation folds (leave-one-pose-out up to this many poses).
const MAX_FOLDS: usize = 20;

/// Fewest samples per segment for the channel.
const MIN_SEGMENT_SAMPLES: usize = 4;

/// The channel is significant when the mean squared whitened deviation exceeds 1 by this many of
/// its standard deviations under white noise (and the ratio is at least [`MIN_RATIO`]).
const SIGNIFICANT_Z: f64 = 4.0;

/// ... and at least this ratio.
const MIN_RATIO: f64 = 1.15;

/// Standard deviations (under white noise) by which the holds but the one that moves most still move
/// ([`Within::significant_beyond_one_hold`]). Without a hold of 72 s whose slow transient (2 mg, tau
/// 10 s) dominated the channel, the 24 short holds of an own-simulator log settling after every
/// set-down moved 3.5; the 15 other holds of a blind generator's bad pose (a board pushed during one
/// hold) 1.3, those of three own-simulator logs with one hold settling (4 mg, tau 3 s) -1.1 to 1.4.
const SPREAD_Z: f64 = 3.0;

/// The whitened deviations' mean square `ms` over `poses` poses lies `z` standard deviations (under
/// white noise) beyond 1, and its root at least [`MIN_RATIO`].
fn beyond_white(ms: f64, poses: usize, z: f64) -> bool {
    ms > 1.0 + z * (2.0 / (poses * (SEGMENTS - 1)) as f64).sqrt() && ms.sqrt() >= MIN_RATIO
}

/// The share of a random walk's movement within the holds a line per hold explains: about 0.7
/// for a Brownian path's six segment means pooled over 12 holds ([`Within::line_share`]).
const BROWNIAN_LINE_SHARE: f64 = 0.7;

/// One parametrisation on both channels: whitened within-pose columns (per row) and the pose-level
/// columns of the same parameters (per pose).
pub(crate) struct WithinVariant {
    /// Whitened rows on the modulus channel, one per segment.
    pub(crate) rows: Vec<Vec<f64>>,
    /// The same on the readings' three axes, three per segment ([`Axes`]; empty unless the channel
    /// is theirs, [`Within::on_axes`]).
    pub(crate) axis_rows: Vec<Vec<f64>>,
    pub(crate) pose_extra: Vec<Vec<f64>>,
    pub(crate) params: usize,
    pub(crate) detail: String,
}

/// The best parametrisation of a family on this channel.
pub(crate) struct WithinFit {
    pub(crate) heldout_ratio: f64,
    pub(crate) params: usize,
    pub(crate) detail: String,
    /// Coefficients fitted on every pose.
    pub(crate) coefficients: Vec<f64>,
    pub(crate) pose_extra: Vec<Vec<f64>>,
}

/// The within-pose deviations of a log.
pub(crate) struct Within {
    /// Whitened deviation per row (one row per pose and segment).
    pub(crate) d: Vec<f64>,
    /// Pose of each row.
    pub(crate) pose: Vec<usize>,
    /// Table rows of each row's segment.
    pub(crate) rows: Vec<Range<usize>>,
    /// Segment mid time of each row, s.
    pub(crate) t: Vec<f64>,
    /// Whitening factor of each row (1 / sigma, output unit).
    weight: Vec<f64>,
    fold: Vec<usize>,
    folds: usize,
    /// `sqrt(mean d^2)`: 1 for white noise.
    pub(crate) nominal_ratio: f64,
    pub(crate) significant: bool,
    /// The same segments on the three axes of the readings (a row per axis; filled on short logs
    /// only, [`Within::on_axes`]).
    axes: Axes,
    /// The families are fitted to and judged on the three axes ([`Axes`]) rather than the modulus,
    /// on logs of at most [`AXES_UP_TO_POSES`] poses.
    on_axes: bool,
    /// The channel's movement is significant ([`Within::significant`] on the modulus, the same test
    /// on the three axes' deviations when the channel is theirs).
    pub(crate) channel_significant: bool,
}

/// Most poses of a log whose within-pose channel is the readings' three axes. On a short log the
/// pose means leave a family of a few terms per axis untestable, and the holds are what tests it; on
/// the three axes they see a bias moving across gravity, which the modulus does not. On longer logs
/// the pose means test the families, and the three axes' stacked fits with them named aliased
/// vibrations and steps drift (stop 94, on every log: +60 -46 on eighteen blind groups, 9 fewer
/// out-of-catalogue logs honest); on logs of 16 poses or fewer (stop 95): +49 -28.
const AXES_UP_TO_POSES: usize = 16;

/// The segments' deviations on each axis of the readings (input unit, whitened per axis): an
/// effect moves the whole reading vector during a hold, whatever the pose's orientation, while the
/// modulus sees only its component along gravity. Three rows per segment, in the order of the
/// channel's segments.
#[derive(Default)]
pub(crate) struct Axes {
    d: Vec<f64>,
    /// Pose of each row.
    pose: Vec<usize>,
    weight: Vec<f64>,
    fold: Vec<usize>,
    /// `sqrt(mean d^2)`: 1 for white noise.
    nominal_ratio: f64,
}

/// The within-pose channel's rows ([`Within::channel`]): the modulus' or, on short logs, the three
/// axes' ([`Within::on_axes`]).
pub(crate) struct Channel<'a> {
    /// Whitened deviations.
    pub(crate) d: &'a [f64],
    /// The pose of each row.
    pub(crate) pose: &'a [usize],
    /// The fold of each row (its pose's).
    pub(crate) fold: &'a [usize],
    /// `sqrt(mean d^2)`: 1 for white noise.
    pub(crate) ratio: f64,
}

/// Variance of a segment mean's deviation from its hold's mean (of [`SEGMENTS`]) under white noise
/// of `per_reading` variance, with `seg_n` readings per segment.
fn segment_deviation_variance(per_reading: f64, seg_n: usize) -> f64 {
    per_reading / seg_n as f64 * (SEGMENTS - 1) as f64 / SEGMENTS as f64
}

/// The covariance of a Brownian path's means over segments `i` and `j` of a hold of unit duration
/// cut in [`SEGMENTS`]: segment `i`'s mean has variance `h (i + 1/3)`, two segments' means covary by
/// `h (min + 1/2)` (`h` a segment's duration).
fn brownian_cov(i: usize, j: usize) -> f64 {
    (i.min(j) as f64 + if i == j { 1.0 / 3.0 } else { 0.5 }) / SEGMENTS as f64
}

/// A random walk's variance over pose `p`'s hold and a floor's variance, both along the pose's
/// direction in the calibrated reading (`walk` variance per second and `floor` per axis, input unit).
fn noise_along_hold(m: &Measured, p: usize, walk: V3, floor: V3) -> (f64, f64) {
    let kt = m.model.kt_times(m.directions[p]);
    let along = |v: V3| (0..3).map(|a| kt[a] * kt[a] * v[a]).sum::<f64>();
    (along(walk) * m.poses[p].duration(), along(floor))
}

/// A Brownian path's segment means about their own mean over a hold of unit duration cut in
/// [`SEGMENTS`]: the mean variance of a segment's deviation.
fn brownian_deviation_share() -> f64 {
    let (s, cov) = (SEGMENTS, brownian_cov);
    let mean_var: f64 = (0..s).flat_map(|i| (0..s).map(move |j| cov(i, j))).sum::<f64>() / (s * s) as f64;
    (0..s).map(|j| cov(j, j) - 2.0 * (0..s).map(|i| cov(i, j)).sum::<f64>() / s as f64 + mean_var).sum::<f64>()
        / s as f64
}

/// White-equivalent variance per axis from differences of successive block means, `W(L) = L
/// var(mean[i+L] - mean[i]) / 2` over overlapping blocks of `L` samples (median over the poses: slow
/// movements within a pose barely reach a difference of neighbouring blocks): `W(1)` is the
/// classic `var(x[i+1] - x[i]) / 2`. A sensor's digital low-pass filter correlates successive
/// readings, so `W` rises with `L` until the correlation has died out and then stays level (white
/// noise); a noise slower than the filter (a flicker) makes it rise again. `L` doubles from 1, up
/// to [`CORRELATION_BLOCK_S`] (the gap's correlation blocks, beyond a MEMS low-pass filter's
/// correlation): the level where `W` first grows by less than [`WHITE_PLATEAU`] is
/// returned (`W(1)` for a sensor whose readings are not correlated), else the level where it grew
/// least (between the filter's correlation and the slower noise). A filter's correlation decays
/// slowly in `W`, as `1 - c / L`: the level is up to a few tenths below the white-equivalent one,
/// as the gap's own correlation blocks are.
pub(crate) fn white_from_differences(table: &Table, poses: &[PoseData], rate: f64) -> V3 {
    let longest = ((CORRELATION_BLOCK_S * rate).round() as usize).max(1);
    std::array::from_fn(|a| {
        let sums = pose_sums(table, poses, a);
        let level = |block: usize| median_block_difference(&sums, block);
        let (mut block, mut w) = (1, level(1));
        // The level where `W` grew least, and that growth.
        let mut knee = (w, f64::INFINITY);
        while 2 * block <= longest {
            let next = level(2 * block);
            let growth = next / w;
            if !(growth > WHITE_PLATEAU) {
                return w;
            }
            if growth < knee.1 {
                knee = (w, growth);
            }
            (block, w) = (2 * block, next);
        }
        knee.0
    })
}

/// White-equivalent variance per sample and axis from differences of successive block means of
/// [`CORRELATION_BLOCK_S`] (`L var(mean[i+L] - mean[i]) / 2`, median over the poses; 0 where no pose
/// holds four blocks). As the gap's level, a mean of `n` samples varies as it over `n` (a low-pass
/// filter's correlation counted); unlike it, a wander slower than the blocks (a Gauss-Markov noise,
/// a drift during the hold), which the holds' variance and the spread of their block means count
/// as white, is left for the segments to show.
pub(crate) fn block_difference_white(table: &Table, poses: &[PoseData], rate: f64) -> V3 {
    let block = ((CORRELATION_BLOCK_S * rate).round() as usize).max(2);
    std::array::from_fn(|a| {
        let sums = pose_sums(table, poses, a);
        median_block_difference(&sums, block).max(0.0)
    })
}

/// Each pose's readings on axis `a` as running sums.
fn pose_sums(table: &Table, poses: &[PoseData], a: usize) -> Vec<PrefixSums> {
    poses.iter().map(|p| PrefixSums::new(table.samples[p.rows.clone()].iter().map(|s| s[a]))).collect()
}

/// Growth of [`white_from_differences`]' level per doubling of the block below which it has
/// levelled off.
const WHITE_PLATEAU: f64 = 1.1;

/// `L var(mean[i+L] - mean[i]) / 2` over the overlapping blocks of `L = block` samples (the Allan
/// variance times `L`), median over the poses of at least four blocks.
fn median_block_difference(poses: &[PrefixSums], block: usize) -> f64 {
    let per_pose: Vec<f64> =
        poses.iter().filter(|p| p.len() >= 4 * block).map(|p| block as f64 * p.allan_variance(block)).collect();
    median(&per_pose)
}

/// The white level per reading and axis the holds' segments are whitened against:
/// [`block_difference_white`], at least the rounding's ([`at_least_rounding`], `m.rounding`); the gap's level where
/// no pose is long enough.
fn segment_white(table: &Table, m: &Measured) -> V3 {
    at_least_rounding(block_difference_white(table, &m.poses, m.rate), m.rounding, m.white)
}

impl Within {
    /// A channel with no deviations yet, over `folds` folds.
    fn empty(folds: usize) -> Self {
        Within {
            d: Vec::new(),
            pose: Vec::new(),
            rows: Vec::new(),
            t: Vec::new(),
            weight: Vec::new(),
            fold: Vec::new(),
            folds,
            nominal_ratio: 1.0,
            significant: false,
            axes: Axes::default(),
            on_axes: false,
            channel_significant: false,
        }
    }

    /// The deviations of every pose with enough samples per segment, whitened against
    /// [`segment_white`]; `None` when fewer than three poses qualify or the noise is not measurable.
    pub(crate) fn new(table: &Table, m: &Measured) -> Option<Self> {
        // Withheld poses are spread in time (pose i in fold i mod folds): a smooth effect is then
        // interpolated between the kept neighbours, not extrapolated over a gap.
        let folds = m.poses.len().min(MAX_FOLDS);
        let white = segment_white(table, m);
        let mut w = Within::empty(folds);
        w.on_axes = m.poses.len() <= AXES_UP_TO_POSES;
        let mut used = 0;
        for (p, pose) in m.poses.iter().enumerate() {
            if pose.seg_n < MIN_SEGMENT_SAMPLES {
                continue;
            }
            let kt = m.model.kt_times(m.directions[p]);
            let var = segment_deviation_variance((0..3).map(|a| kt[a] * kt[a] * white[a]).sum::<f64>(), pose.seg_n);
            if !(var > 0.0 && var.is_finite()) {
                continue;
            }
            used += 1;
            w.push_pose(table, m, p, pose, kt, 1.0 / var.sqrt(), p % w.folds);
            if w.on_axes {
                w.axes.push_pose(pose, white, p, p % w.folds);
            }
        }
        if used < 3 {
            return None;
        }
        let ms = mean_square(&w.d);
        w.nominal_ratio = ms.sqrt();
        w.significant = beyond_white(ms, used, SIGNIFICANT_Z);
        w.channel_significant = w.significant;
        if w.on_axes {
            let axes_ms = mean_square(&w.axes.d);
            w.axes.nominal_ratio = axes_ms.sqrt();
            w.channel_significant = beyond_white(axes_ms, 3 * used, SIGNIFICANT_Z);
        }
        Some(w)
    }

    /// The channel the families are fitted to and judged on: the three axes' on short logs
    /// ([`Within::on_axes`]), else the modulus'.
    pub(crate) fn channel(&self) -> Channel<'_> {
        if self.on_axes {
            let a = &self.axes;
            Channel { d: &a.d, pose: &a.pose, fold: &a.fold, ratio: a.nominal_ratio }
        } else {
            Channel { d: &self.d, pose: &self.pose, fold: &self.fold, ratio: self.nominal_ratio }
        }
    }

    /// The mean square of the whitened deviations a noise model predicts beyond white noise (0 for
    /// white noise): per segment, a bias-instability floor `floor` (variance per axis, input unit)
    /// moves its mean as an independent draw, a random walk `walk` (variance per second per axis) as
    /// a Brownian path over the hold does, both along the pose's direction.
    pub(crate) fn predicted_excess(&self, m: &Measured, walk: V3, floor: V3) -> f64 {
        if self.d.is_empty() {
            return 0.0;
        }
        let s = SEGMENTS as f64;
        let brownian = brownian_deviation_share();
        let total: f64 = (0..self.d.len())
            .map(|i| {
                let (walk, floor) = noise_along_hold(m, self.pose[i], walk, floor);
                (floor * (s - 1.0) / s + walk * brownian) * self.weight[i] * self.weight[i]
            })
            .sum();
        total / self.d.len() as f64
    }

    /// A random walk per axis (variance per second, input unit) that moves the holds' segment means
    /// as much as they move beyond white noise, axis by axis as the poses' directions see them (the
    /// method of moments: each deviation's square beyond 1 regressed on the walk each axis would
    /// give it; an axis whose level comes out negative is set to 0 and the others refitted). `None`
    /// when no axis moves.
    pub(crate) fn walk_per_axis(&self, m: &Measured) -> Option<V3> {
        let brownian = brownian_deviation_share();
        let unit = |a: usize| std::array::from_fn(|b| f64::from(u8::from(a == b)));
        let regressors: Vec<V3> = (0..self.d.len())
            .map(|i| {
                let w2 = self.weight[i] * self.weight[i];
                std::array::from_fn(|a| noise_along_hold(m, self.pose[i], unit(a), [0.0; 3]).0 * brownian * w2)
            })
            .collect();
        // `lstsq` minimises `(r + X x)^2`: `r` is the excess with its sign turned.
        let excess: Vec<f64> = self.d.iter().map(|v| 1.0 - v * v).collect();
        let mut axes: Vec<usize> = (0..3).collect();
        while !axes.is_empty() {
            let rows: Vec<Vec<f64>> = regressors.iter().map(|c| axes.iter().map(|&a| c[a]).collect()).collect();
            let all: Vec<usize> = (0..rows.len()).collect();
            let x = super::math::lstsq(&rows, &excess, &all)?;
            match (0..axes.len()).filter(|&j| x[j] < 0.0).min_by(|&j, &k| x[j].total_cmp(&x[k])) {
                Some(j) => _ = axes.remove(j),
                None => {
                    let mut walk = [0.0; 3];
                    axes.iter().zip(&x).for_each(|(&a, &v)| walk[a] = v);
                    return (walk.iter().any(|v| *v > 0.0) && walk.iter().all(|v| v.is_finite())).then_some(walk);
                }
            }
        }
        None
    }

    /// The holds' movement that a line per hold leaves (their roughness) against what a random walk
    /// `walk` and a floor `floor` (as in [`Within::predicted_excess`]) with the white noise would
    /// leave: `(shortfall, power)`, the observed roughness less the expected in standard deviations
    /// of the expectation (about 0 or above when the holds carry that noise, strongly negative when
    /// they move smoothly however much they move), and the noise's own share of the expectation in
    /// the same unit (how well the test can see it). Per hold the segment means have covariance
    /// `S = a C + (f + k/(k-1)) I` (whitened: `C` a Brownian path's, `a` the walk's variance over the
    /// hold, `f` the floor's); what a line leaves, `P x` (`P` the projection off a line in time),
    /// has mean `tr(P S)` and variance `2 tr((P S)^2)` (Gaussian). A random walk leaves 29 % of its
    /// movement to the roughness, a floor 80 %.
    pub(crate) fn roughness_shortfall(&self, m: &Measured, walk: V3, floor: V3) -> (f64, f64) {
        self.roughness_under(&|p, w| {
            let (walk, floor) = noise_along_hold(m, p, walk, floor);
            (walk * w * w, floor * w * w)
        })
    }

    /// [`Within::roughness_shortfall`] with each pose's whitened walk variance over its hold and
    /// floor variance given by `levels(pose, whitening weight)`.
    fn roughness_under(&self, levels: &dyn Fn(usize, f64) -> (f64, f64)) -> (f64, f64) {
        let (mut observed, mut mean, mut white_mean, mut var) = (0.0, 0.0, 0.0, 0.0);
        for range in self.pose_ranges() {
            let (walk, floor) = levels(self.pose[range.start], self.weight[range.start]);
            let hold = Roughness::of_hold(&self.d[range.clone()], &self.t[range], walk, floor);
            observed += hold.observed;
            mean += hold.mean;
            white_mean += hold.white_mean;
            var += hold.var;
        }
        if var > 0.0 { ((observed - mean) / var.sqrt(), (mean - white_mean) / var.sqrt()) } else { (0.0, 0.0) }
    }

    /// The movement stays beyond white noise without the hold that moves most (`holds`: each hold's
    /// poses, the pieces the pose finder cut it into), by [`SPREAD_Z`] standard deviations and
    /// [`MIN_RATIO`]: it is spread over the holds, not carried by one (a board pushed or knocked
    /// during one hold, a bad pose).
    pub(crate) fn significant_beyond_one_hold(&self, holds: &[Range<usize>]) -> bool {
        // Per hold: the sum of its squared deviations, its rows and its poses in the channel.
        let mut per_hold = vec![(0.0, 0, 0); holds.len()];
        for rows in self.pose_ranges() {
            let Some(h) = holds.iter().position(|hold| hold.contains(&self.pose[rows.start])) else { continue };
            per_hold[h].0 += self.d[rows.clone()].iter().map(|v| v * v).sum::<f64>();
            (per_hold[h].1, per_hold[h].2) = (per_hold[h].1 + rows.len(), per_hold[h].2 + 1);
        }
        let excess = |h: &(f64, usize, usize)| h.0 - h.1 as f64;
        let Some(largest) = (0..holds.len()).max_by(|&a, &b| excess(&per_hold[a]).total_cmp(&excess(&per_hold[b])))
        else {
            return false;
        };
        per_hold.swap_remove(largest);
        let (sum, rows, poses) = per_hold.iter().fold((0.0, 0, 0), |acc, h| (acc.0 + h.0, acc.1 + h.1, acc.2 + h.2));
        let ms = if rows > 0 { sum / rows as f64 } else { 0.0 };
        poses > 0 && beyond_white(ms, poses, SPREAD_Z)
    }

    /// The mean square of the whitened deviations beyond white noise, and its standard deviation
    /// under white noise (over the deviations' degrees of freedom).
    pub(crate) fn observed_excess(&self) -> (f64, f64) {
        let poses = self.pose.iter().collect::<std::collections::BTreeSet<_>>().len();
        let dof = self.d.len().saturating_sub(poses).max(1) as f64;
        (self.nominal_ratio * self.nominal_ratio - 1.0, (2.0 / dof).sqrt())
    }

    /// The share of the holds' movement beyond white noise that a line in time through each pose's
    /// deviations explains (the bias drifting at its own rate during each hold). About 1 for a
    /// smooth drift; a Brownian path's six segment means give about 0.7 pooled over 12 holds (99 %
    /// below 0.87).
    pub(crate) fn line_share(&self) -> f64 {
        self.line_share_with_error().0
    }

    /// The holds move more smoothly than a random walk: their line share exceeds a Brownian path's
    /// ([`BROWNIAN_LINE_SHARE`]) by two standard errors.
    pub(crate) fn smoother_than_a_walk(&self) -> bool {
        let (share, error) = self.line_share_with_error();
        share - 2.0 * error >= BROWNIAN_LINE_SHARE
    }

    /// [`Within::line_share`] and its standard error from the white noise in the deviations (the
    /// part the lines take, `k / (k - 1)` chi-square with one degree of freedom per pose, and the
    /// whole, with `k - 1`): a small movement beyond white noise leaves the share uncertain.
    fn line_share_with_error(&self) -> (f64, f64) {
        let (before, after, poses) = self.line_fit();
        // Whitened so that a deviation's mean square is 1 under white noise: `k` of them per pose
        // carry `k - 1` degrees of freedom before the lines and `k - 2` after.
        let (k, poses) = (SEGMENTS as f64, poses as f64);
        let (white_before, white_after) = (poses * k, poses * (k - 2.0) * k / (k - 1.0));
        let excess = before - white_before;
        if !(excess > 0.0) {
            return (0.0, f64::INFINITY);
        }
        let share = (excess - (after - white_after)) / excess;
        let var_lines = 2.0 * poses * (k / (k - 1.0)).powi(2);
        let var_whole = 2.0 * poses * k * k / (k - 1.0);
        (share, (var_lines + share * share * var_whole).sqrt() / excess)
    }

    /// Whether the holds' movement slows down within each hold: per pose a quadratic in time through
    /// its deviations, slope `b` and curvature `c` (in their standard errors under white noise); a
    /// decay has `b c < 0` in every hold, a drift or a random walk either sign. Returns the pooled
    /// `sum(b c) / sqrt(sum (b c)^2)`: about -sqrt(holds) for a decay, near 0 otherwise.
    pub(crate) fn slowing(&self) -> f64 {
        let (mut sum, mut sum_sq) = (0.0, 0.0);
        for (d, t) in self.by_pose() {
            let k = d.len() as f64;
            let tm = t.iter().sum::<f64>() / k;
            let x: Vec<f64> = t.iter().map(|v| v - tm).collect();
            let x2m = x.iter().map(|v| v * v).sum::<f64>() / k;
            let q: Vec<f64> = x.iter().map(|v| v * v - x2m).collect();
            let (sxx, sqq) = (x.iter().map(|v| v * v).sum::<f64>(), q.iter().map(|v| v * v).sum::<f64>());
            if !(sxx > 0.0 && sqq > 0.0) {
                continue;
            }
            // Centred `x` and `x^2 - mean` are orthogonal over symmetric segment times.
            let b = x.iter().zip(d).map(|(a, y)| a * y).sum::<f64>() / sxx.sqrt();
            let c = q.iter().zip(d).map(|(a, y)| a * y).sum::<f64>() / sqq.sqrt();
            sum += b * c;
            sum_sq += (b * c).powi(2);
        }
        if sum_sq > 0.0 { sum / sum_sq.sqrt() } else { 0.0 }
    }

    /// How evenly the holds move: the median hold's movement beyond white noise (the sum of its
    /// squared deviations less their number) over the mean hold's. About 0.4-0.9 when every hold
    /// moves alike (a noise); near 0 when a few holds carry the movement (a knock, a step, one
    /// disturbed pose).
    pub(crate) fn evenness(&self) -> f64 {
        let excess: Vec<f64> =
            self.by_pose().map(|(d, _)| d.iter().map(|v| v * v).sum::<f64>() - d.len() as f64).collect();
        let mean = excess.iter().sum::<f64>() / excess.len().max(1) as f64;
        if mean > 0.0 { super::math::median(&excess) / mean } else { 0.0 }
    }

    /// Each pose's deviations and segment times.
    fn by_pose(&self) -> impl Iterator<Item = (&[f64], &[f64])> {
        self.pose_ranges().map(|r| (&self.d[r.clone()], &self.t[r]))
    }

    /// Each pose's rows of the channel.
    fn pose_ranges(&self) -> impl Iterator<Item = Range<usize>> + '_ {
        let mut i = 0;
        std::iter::from_fn(move || {
            let j = (i..self.d.len()).find(|&j| self.pose[j] != self.pose[i]).unwrap_or(self.d.len());
            let out = (i < self.d.len()).then_some(i..j);
            i = j;
            out
        })
    }

    /// Per pose, a line in time through its deviations: the sums of squares before and after, and the
    /// poses.
    fn line_fit(&self) -> (f64, f64, usize) {
        let (mut before, mut after, mut poses) = (0.0, 0.0, 0);
        for (d, t) in self.by_pose() {
            before += d.iter().map(|y| y * y).sum::<f64>();
            after += off_line_sum_sq(&off_line_projection(t), d);
            poses += 1;
        }
        (before, after, poses)
    }

    #[allow(clippy::too_many_arguments)]
    fn push_pose(&mut self, table: &Table, m: &Measured, p: usize, pose: &PoseData, kt: V3, weight: f64, fold: usize) {
        let centre = super::math::mean_of(&pose.seg);
        for k in 0..SEGMENTS {
            let dev: V3 = std::array::from_fn(|a| pose.seg[k][a] - centre[a]);
            let start = pose.rows.start + k * pose.seg_n;
            let rows = start..start + pose.seg_n;
            let t = 0.5 * (row_time(table, rows.start, m.rate) + row_time(table, rows.end - 1, m.rate));
            self.d.push(dot(kt, dev) * weight);
            self.pose.push(p);
            self.rows.push(rows);
            self.t.push(t);
            self.weight.push(weight);
            self.fold.push(fold);
        }
    }

    /// A variant from the effect's contribution to the calibrated reading (output unit) of every
    /// parameter at each pose and segment: `effect(pose, t, rows)` (the segment's mid time and table
    /// rows) gives one vector per parameter, taken along each pose's direction for the modulus
    /// rows and the pose-level columns, and on short logs also back to the readings' three axes
    /// ([`Within::axis_rows`]).
    pub(crate) fn variant(&self, m: &Measured, params: usize, detail: String, effect: &Effect<'_>) -> WithinVariant {
        let n = m.poses.len();
        let mut pose_extra = vec![vec![0.0; params]; n];
        // Per pose, each segment's contribution of every parameter (output unit).
        let mut by_pose: Vec<Vec<(usize, Vec<V3>)>> = vec![Vec::new(); n];
        for (i, &p) in self.pose.iter().enumerate() {
            by_pose[p].push((i, effect(p, self.t[i], self.rows[i].clone())));
        }
        let mut rows = vec![vec![0.0; params]; self.d.len()];
        for (p, segs) in by_pose.iter().enumerate() {
            if segs.is_empty() {
                pose_extra[p] = effect_pose_mean(m, p, params, effect);
                continue;
            }
            let u = m.directions[p];
            let along: Vec<Vec<f64>> = segs.iter().map(|(_, c)| c.iter().map(|e| dot(u, *e)).collect()).collect();
            let mean: Vec<f64> =
                (0..params).map(|j| along.iter().map(|c| c[j]).sum::<f64>() / along.len() as f64).collect();
            for ((i, _), c) in segs.iter().zip(&along) {
                rows[*i] = (0..params).map(|j| (c[j] - mean[j]) * self.weight[*i]).collect();
            }
            pose_extra[p] = mean;
        }
        let axis_rows = if self.on_axes { self.axis_rows(m, params, &by_pose) } else { Vec::new() };
        WithinVariant { rows, axis_rows, pose_extra, params, detail }
    }

    /// The rows of a variant on the readings' three axes ([`Axes`]): each segment's contribution
    /// taken back through `Ka^-1` to the readings (input unit), less its pose's mean, whitened per
    /// axis.
    fn axis_rows(&self, m: &Measured, params: usize, by_pose: &[Vec<(usize, Vec<V3>)>]) -> Vec<Vec<f64>> {
        let mut rows = vec![vec![0.0; params]; self.axes.d.len()];
        for segs in by_pose.iter().filter(|segs| !segs.is_empty()) {
            let readings: Vec<Vec<V3>> =
                segs.iter().map(|(_, c)| c.iter().map(|e| m.model.ka_inverse_times(*e)).collect()).collect();
            let mean: Vec<V3> = (0..params)
                .map(|j| std::array::from_fn(|a| readings.iter().map(|c| c[j][a]).sum::<f64>() / readings.len() as f64))
                .collect();
            for ((i, _), c) in segs.iter().zip(&readings) {
                for a in 0..3 {
                    let row = 3 * i + a;
                    rows[row] = (0..params).map(|j| (c[j][a] - mean[j][a]) * self.axes.weight[row]).collect();
                }
            }
        }
        rows
    }

    /// Penalised held-out ratio of a variant on the withheld poses' deviations.
    fn heldout_ratio(&self, v: &WithinVariant) -> Option<f64> {
        let channel = self.channel();
        let dropped = vec![false; channel.d.len()];
        let cv = cv_residuals(v.rows_on(self), channel.d, channel.fold, self.folds, &dropped)?;
        let (ss, count) = sum_sq(&cv);
        (count > 0).then(|| ((ss + PARAMETER_PENALTY * v.params as f64) / count as f64).sqrt())
    }

    /// The variant with the smallest penalised held-out ratio, refitted on every pose, and its index
    /// in `variants`.
    pub(crate) fn best_of(&self, variants: Vec<WithinVariant>) -> Option<(usize, WithinFit)> {
        let mut best: Option<(f64, usize, WithinVariant)> = None;
        for (i, v) in variants.into_iter().enumerate() {
            if let Some(r) = self.heldout_ratio(&v)
                && best.as_ref().is_none_or(|(b, _, _)| r < *b)
            {
                best = Some((r, i, v));
            }
        }
        let (heldout_ratio, i, v) = best?;
        let d = self.channel().d;
        let train: Vec<usize> = (0..d.len()).collect();
        let coefficients = super::math::lstsq(v.rows_on(self), d, &train)?;
        let fit =
            WithinFit { heldout_ratio, params: v.params, detail: v.detail, coefficients, pose_extra: v.pose_extra };
        Some((i, fit))
    }
}

impl WithinVariant {
    /// The variant's rows on `w`'s channel.
    pub(crate) fn rows_on(&self, w: &Within) -> &[Vec<f64>] {
        if w.on_axes { &self.axis_rows } else { &self.rows }
    }
}

impl Axes {
    /// Pose `p`'s segments' deviations from their mean on each axis, whitened by the white noise
    /// of a segment mean on that axis (`white`: per reading, input unit).
    fn push_pose(&mut self, pose: &PoseData, white: V3, p: usize, fold: usize) {
        let weight: V3 = std::array::from_fn(|a| {
            let var = segment_deviation_variance(white[a], pose.seg_n);
            if var > 0.0 { 1.0 / var.sqrt() } else { 0.0 }
        });
        let centre = super::math::mean_of(&pose.seg);
        for k in 0..SEGMENTS {
            for a in 0..3 {
                self.d.push((pose.seg[k][a] - centre[a]) * weight[a]);
                self.pose.push(p);
                self.weight.push(weight[a]);
                self.fold.push(fold);
            }
        }
    }
}

/// One hold's roughness (what a line in time leaves of its whitened segment deviations) and its
/// expectation under a noise.
struct Roughness {
    observed: f64,
    mean: f64,
    white_mean: f64,
    var: f64,
}

impl Roughness {
    /// The hold's deviations `d` at segment times `t`, under a walk of whitened variance `a` over the
    /// hold and a floor of whitened variance `f`.
    fn of_hold(d: &[f64], t: &[f64], a: f64, f: f64) -> Self {
        let k = d.len();
        let white = k as f64 / (k as f64 - 1.0);
        let off_line = off_line_projection(t);
        let cov = |i: usize, j: usize| a * brownian_cov(i, j) + if i == j { f + white } else { 0.0 };
        // `P S`, its trace and the trace of its square.
        let ps: Vec<Vec<f64>> =
            (0..k).map(|i| (0..k).map(|j| (0..k).map(|l| off_line[i][l] * cov(l, j)).sum()).collect()).collect();
        let pairs = (0..k).flat_map(|i| (0..k).map(move |j| (i, j)));
        Roughness {
            observed: off_line_sum_sq(&off_line, d),
            mean: (0..k).map(|i| ps[i][i]).sum(),
            white_mean: white * (0..k).map(|i| off_line[i][i]).sum::<f64>(),
            var: 2.0 * pairs.map(|(i, j)| ps[i][j] * ps[j][i]).sum::<f64>(),
        }
    }
}

/// The projection that takes a line in time (`t`, the segments' times) out of a hold's segment
/// values: `I - 1/k - (t_i - tm)(t_j - tm) / stt`.
fn off_line_projection(t: &[f64]) -> Vec<Vec<f64>> {
    let k = t.len();
    let tm = t.iter().sum::<f64>() / k as f64;
    let stt: f64 = t.iter().map(|x| (x - tm).powi(2)).sum();
    let slope = |i: usize, j: usize| if stt > 0.0 { (t[i] - tm) * (t[j] - tm) / stt } else { 0.0 };
    (0..k).map(|i| (0..k).map(|j| f64::from(u8::from(i == j)) - 1.0 / k as f64 - slope(i, j)).collect()).collect()
}

/// The sum of squares of what the projection `off_line` leaves of `d`.
fn off_line_sum_sq(off_line: &[Vec<f64>], d: &[f64]) -> f64 {
    off_line.iter().map(|row| row.iter().zip(d).map(|(p, v)| p * v).sum::<f64>().powi(2)).sum()
}

/// The effect's contribution per parameter to the calibrated reading at a pose, a time and over
/// some table rows.
pub(crate) type Effect<'a> = dyn Fn(usize, f64, Range<usize>) -> Vec<V3> + 'a;

/// A pose's mean contribution of every parameter, for a pose outside the channel (its segments
/// evenly over its rows).
fn effect_pose_mean(m: &Measured, p: usize, params: usize, effect: &Effect<'_>) -> Vec<f64> {
    let (u, pose) = (m.directions[p], &m.poses[p]);
    let mut mean = vec![0.0; params];
    let seg = (pose.n / SEGMENTS).max(1);
    let mut parts = 0.0f64;
    for k in 0..SEGMENTS {
        let rows =
            (pose.rows.start + k * seg).min(pose.rows.end - 1)..(pose.rows.start + (k + 1) * seg).min(pose.rows.end);
        let t = pose.t_start + (k as f64 + 0.5) * seg as f64 / m.rate;
        if rows.is_empty() {
            continue;
        }
        parts += 1.0;
        for (j, e) in effect(p, t, rows).iter().enumerate().take(params) {
            mean[j] += dot(u, *e);
        }
    }
    mean.iter().map(|v| v / parts.max(1.0)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::{Rng, SeedableRng};
    use rand_distr::{Distribution, StandardNormal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    /// `holds` holds of 2000 readings at 500 Hz, reading `i` being `reading(i)` on x and y (z: 1
    /// more).
    fn holds_of(holds: usize, mut reading: impl FnMut(usize) -> f64) -> (Table, Vec<PoseData>) {
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..2000 * holds {
            let x = reading(i);
            text += &format!("{},{x},{x},{}\n", i as f64 / 500.0, 1.0 + x);
        }
        let table = crate::csvio::read_csv_str("holds", &text, &crate::csvio::ReadOptions::default()).unwrap();
        let poses = (0..holds).map(|k| super::super::gap::pose_data(&table, 2000 * k, 2000 * (k + 1), 500.0)).collect();
        (table, poses)
    }

    /// Eight holds of 2000 readings at 500 Hz, white noise of unit variance through a moving average
    /// of `width` readings, plus a random walk of `walk` per reading.
    fn filtered_holds(seed: u64, width: usize, walk: f64) -> (Table, Vec<PoseData>) {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let raw: Vec<f64> = (0..16_000 + width).map(|_| StandardNormal.sample(&mut rng)).collect();
        let mut level = 0.0;
        holds_of(8, |i| {
            let step: f64 = StandardNormal.sample(&mut rng);
            level += walk * step;
            raw[i..i + width].iter().sum::<f64>() / width as f64 + level
        })
    }

    #[test]
    fn block_differences_measure_a_low_passed_sensors_white_noise_once_its_correlation_dies_out() {
        // A moving average of 8 readings: per-reading variance 1/8, white-equivalent variance (of a
        // mean of many readings, times their count) 1; successive differences see 1/64. The level
        // where the differences stop growing by a tenth per doubling is 0.72-0.90 on these seeds.
        for seed in 1..=4 {
            let (table, poses) = filtered_holds(seed, 8, 0.0);
            let white = white_from_differences(&table, &poses, 500.0)[0];
            assert!((0.65..1.1).contains(&white), "seed {seed}: {white}");
        }
        // A walk that moves each hold by 20 times the noise of its mean (its level over a hold
        // against a mean of 2000 readings) barely reaches it.
        let (table, poses) = filtered_holds(5, 8, 0.01);
        let white = white_from_differences(&table, &poses, 500.0)[0];
        assert!((0.65..1.1).contains(&white), "walking: {white}");
    }

    /// 32 holds of 2000 readings at 500 Hz: white noise of unit variance plus a bias swinging by
    /// `amplitude` with an 8 s period (slower than the 0.2 s blocks, as fast as a hold).
    fn swinging_holds(seed: u64, amplitude: f64) -> (Table, Vec<PoseData>) {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        holds_of(32, |i| {
            let noise: f64 = StandardNormal.sample(&mut rng);
            let t = i as f64 / 500.0;
            noise + amplitude * (std::f64::consts::TAU * t / 8.0).sin()
        })
    }

    #[test]
    fn the_segments_white_level_is_blind_to_a_wander_slower_than_its_blocks() {
        // A swing of 0.3 moves a 4 s hold by up to 0.6 (the per-reading noise 1, a hold mean's
        // 0.02). The holds' variance barely sees it (within 2 %), but the gap's
        // correlation factor compares the spread of 0.2 s block means (the swing's included) with
        // it: 1.5-1.7 times white on these seeds. Successive blocks differ by the swing's change
        // over 0.2 s only: the block level is 0.99-1.11 on these seeds.
        for seed in 1..=4 {
            let (table, poses) = swinging_holds(seed, 0.3);
            let block = block_difference_white(&table, &poses, 500.0)[0];
            assert!((0.85..1.25).contains(&block), "seed {seed}: {block}");
            let holds = median(&mut poses.iter().map(|p| p.var[0]).collect::<Vec<_>>());
            let gap = holds * super::super::gap::correlation_factor(&table, &poses, 500.0)[0];
            assert!(gap > 1.35 * block, "seed {seed}: the gap's level {gap}, the blocks' {block}");
        }
        // Without the swing the two agree.
        let (table, poses) = swinging_holds(5, 0.0);
        let block = block_difference_white(&table, &poses, 500.0)[0];
        let holds = median(&mut poses.iter().map(|p| p.var[0]).collect::<Vec<_>>());
        let gap = holds * super::super::gap::correlation_factor(&table, &poses, 500.0)[0];
        assert!((0.9..1.1).contains(&block) && (0.9..1.1).contains(&gap), "white: {block} {gap}");
    }

    /// A channel of `poses` holds whose segment deviations are `path(pose, segment)` (whitened
    /// units) plus white noise whitened as the channel does it (mean square 1).
    fn channel(poses: usize, rng: &mut Xoshiro256PlusPlus, path: &mut dyn FnMut(usize, usize) -> f64) -> Within {
        let mut w = Within { significant: true, ..Within::empty(poses) };
        let white = (SEGMENTS as f64 / (SEGMENTS - 1) as f64).sqrt();
        for p in 0..poses {
            let raw: Vec<f64> = (0..SEGMENTS)
                .map(|k| path(p, k) + white * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, rng))
                .collect();
            let mean = raw.iter().sum::<f64>() / SEGMENTS as f64;
            for (k, v) in raw.iter().enumerate() {
                w.d.push(v - mean);
                w.pose.push(p);
                w.rows.push(0..0);
                w.t.push(40.0 * p as f64 + 4.0 * k as f64);
                w.weight.push(1.0);
                w.fold.push(p);
            }
        }
        w
    }

    fn median(v: &mut [f64]) -> f64 {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    }

    #[test]
    fn holds_moving_along_lines_are_too_smooth_for_a_walk_as_large_and_a_walk_is_not() {
        // 24 holds, whitened: a Brownian path with variance `level` over each hold, and lines whose
        // slopes move the holds as much (a line's six segment deviations carry 0.139 of the
        // squared slope over the hold as a Brownian path's do of its variance, for this share).
        let level = 40.0;
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(21);
        let mut draw = Xoshiro256PlusPlus::seed_from_u64(22);
        let mut normal = move || <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut draw);
        let (mut walk_short, mut line_short) = (Vec::new(), Vec::new());
        for _ in 0..20 {
            let steps: Vec<Vec<f64>> = (0..24).map(|_| (0..2 * SEGMENTS).map(|_| normal()).collect()).collect();
            let walk = channel(24, &mut rng, &mut |p, k| {
                // A Brownian path's mean over a segment of variance `h`: the path at its start, half
                // its step over the segment, and a bridge's mean (variance `h / 12`).
                let h = level / SEGMENTS as f64;
                let start = (0..k).map(|j| steps[p][j] * h.sqrt()).sum::<f64>();
                start + 0.5 * steps[p][k] * h.sqrt() + steps[p][SEGMENTS + k] * (h / 12.0).sqrt()
            });
            let slopes: Vec<f64> = (0..24).map(|_| normal()).collect();
            let lines = channel(24, &mut rng, &mut |p, k| {
                (level * brownian_deviation_share()).sqrt() * slopes[p] * (k as f64 - 2.5) / 1.708
            });
            let under_walk = |w: &Within| w.roughness_under(&|_, _| (level, 0.0));
            let (walk_z, power) = under_walk(&walk);
            assert!(power >= 3.0, "the test sees a walk this large: power {power}");
            walk_short.push(walk_z);
            line_short.push(under_walk(&lines).0);
        }
        let walks_refuted = walk_short.iter().filter(|z| **z < -3.0).count();
        let lines_refuted = line_short.iter().filter(|z| **z < -3.0).count();
        assert_eq!(walks_refuted, 0, "walks: {walk_short:?}");
        assert!(lines_refuted >= 18, "lines: {line_short:?}");
    }

    #[test]
    fn a_transient_slows_within_each_hold_a_drift_and_a_random_walk_do_not() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(11);
        let mut draw = Xoshiro256PlusPlus::seed_from_u64(12);
        let mut normal = move || <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut draw);
        let (mut settling, mut drift, mut walk) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..9 {
            // Each placement starts a transient of its own sign and size decaying over about a hold
            // (tau 2 segments): 6 white sigmas or more at the start (a visible settling's movement).
            let sizes: Vec<f64> = (0..15).map(|_| normal().signum() * (6.0 + normal().abs())).collect();
            settling.push(channel(15, &mut rng, &mut |p, k| sizes[p] * (-(k as f64) / 2.0).exp()).slowing());
            // A drift whose rate changes from hold to hold, and a random walk: neither slows.
            let rates: Vec<f64> = (0..15).map(|_| normal()).collect();
            drift.push(channel(15, &mut rng, &mut |p, k| rates[p] * k as f64).slowing());
            let mut level = 0.0;
            walk.push(
                channel(15, &mut rng, &mut |_, k| {
                    level = if k == 0 { 0.0 } else { level } + 2.0 * normal();
                    level
                })
                .slowing(),
            );
        }
        let (settling, drift, walk) = (median(&mut settling), median(&mut drift), median(&mut walk));
        assert!(settling <= -2.5, "transient: median slowing {settling}");
        assert!(drift.abs() < 1.0, "drift: median slowing {drift}");
        assert!(walk.abs() < 1.0, "random walk: median slowing {walk}");
    }

    #[test]
    fn a_walk_moves_every_hold_alike_a_knock_moves_few() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(21);
        let mut draw = Xoshiro256PlusPlus::seed_from_u64(22);
        let mut normal = move || <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut draw);
        let (mut walk, mut knock) = (Vec::new(), Vec::new());
        for _ in 0..9 {
            let mut level = 0.0;
            walk.push(
                channel(15, &mut rng, &mut |_, k| {
                    level = if k == 0 { 0.0 } else { level } + 1.5 * normal();
                    level
                })
                .evenness(),
            );
            // Two holds of fifteen knocked (an offset of 15 white sigmas over one segment).
            knock.push(channel(15, &mut rng, &mut |p, k| if p % 7 == 3 && k == 2 { 15.0 } else { 0.0 }).evenness());
        }
        let (walk, knock) = (median(&mut walk), median(&mut knock));
        assert!(walk >= 0.4, "random walk: median evenness {walk}");
        assert!(knock <= 0.1, "two knocked holds: median evenness {knock}");
    }

    #[test]
    fn a_line_per_hold_explains_a_smooth_drift_but_not_a_random_walk() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let (mut smooth, mut walk) = (Vec::new(), Vec::new());
        for _ in 0..20 {
            // A drift whose rate changes from hold to hold (slowly curving within it), 4 white sigmas
            // over a hold.
            let rates: Vec<f64> = (0..12).map(|p| (p as f64 * 1.3).sin()).collect();
            smooth.push(
                channel(12, &mut rng, &mut |p, k| rates[p] * (0.8 * k as f64 + 0.02 * (k * k) as f64)).line_share(),
            );
            // A random walk of the same size: its steps are independent.
            let mut steps = Xoshiro256PlusPlus::seed_from_u64(rng.next_u64());
            let mut level = 0.0;
            walk.push(
                channel(12, &mut rng, &mut |_, k| {
                    if k == 0 {
                        level = 0.0;
                    }
                    level += 2.0 * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut steps);
                    level
                })
                .line_share(),
            );
        }
        let (smooth, walk) = (median(&mut smooth), median(&mut walk));
        assert!(smooth >= 0.95, "smooth drift: line share {smooth}");
        assert!(walk < 0.85, "random walk: line share {walk}");
    }

    #[test]
    fn a_small_random_walk_is_not_taken_for_a_smooth_drift() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(8);
        let (mut walks, mut drifts) = (0, 0);
        for _ in 0..200 {
            // A random walk moving the holds about 1.3 times white noise, over 20 holds: a line
            // explains all of its movement now and then, rarely beyond two standard errors.
            let mut steps = Xoshiro256PlusPlus::seed_from_u64(rng.next_u64());
            let mut level = 0.0;
            let walk = channel(20, &mut rng, &mut |_, k| {
                if k == 0 {
                    level = 0.0;
                }
                level += 0.5 * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut steps);
                level
            });
            walks += usize::from(walk.smoother_than_a_walk());
            // A drift moving the holds about twice white noise, at a fresh rate in each hold.
            let rates: Vec<f64> =
                (0..20).map(|_| <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut rng)).collect();
            drifts += usize::from(channel(20, &mut rng, &mut |p, k| 1.2 * rates[p] * k as f64).smoother_than_a_walk());
        }
        assert!(walks <= 10, "{walks} of 200 random walks smoother than a walk");
        assert!(drifts >= 180, "{drifts} of 200 drifts smoother than a walk");
    }

    #[test]
    fn a_brownian_paths_segment_means_deviate_as_predicted() {
        // A unit-variance-per-unit-time random walk over a hold of unit length, 600 steps: the mean
        // variance of its six segment means about their mean, over 4000 paths.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(31);
        let (steps, paths) = (600, 4000);
        let mut total = 0.0;
        for _ in 0..paths {
            let mut level = 0.0;
            let means: Vec<f64> = (0..SEGMENTS)
                .map(|_| {
                    let per = steps / SEGMENTS;
                    (0..per)
                        .map(|_| {
                            level += (1.0 / steps as f64).sqrt()
                                * <StandardNormal as Distribution<f64>>::sample(&StandardNormal, &mut rng);
                            level
                        })
                        .sum::<f64>()
                        / per as f64
                })
                .collect();
            let centre = means.iter().sum::<f64>() / SEGMENTS as f64;
            total += means.iter().map(|m| (m - centre).powi(2)).sum::<f64>() / SEGMENTS as f64;
        }
        let simulated = total / paths as f64;
        let predicted = brownian_deviation_share();
        assert!((simulated / predicted - 1.0).abs() < 0.05, "simulated {simulated}, predicted {predicted}");
    }

    #[test]
    fn holds_of_a_coarsely_rounded_clean_log_do_not_move_beyond_their_rounding() {
        // Rounded to 6 or 12 times its noise, a clean log's readings sit on one level per hold and
        // axis but for rare flips, and the differences of successive block means see almost nothing.
        // Whitened by that level alone, the holds of these seeds moved 1.5-1.8 (6) and 6.9 to 2.1e11
        // (12) times white noise, significant on every one; with the rounding's own `q^2 / 12` per
        // reading as the least white level, 0.85-0.95 and 0.59-0.70.
        for seed in 1..=4 {
            for steps in [6.0, 12.0] {
                let table = crate::diagnose::testing::coarsely_rounded(seed, steps);
                let m = super::super::gap::measure(&table, &crate::diagnose::DiagnoseOptions::DEFAULT).unwrap();
                let w = Within::new(&table, &m).unwrap();
                let ratio = w.nominal_ratio;
                assert!(!w.significant && ratio < 1.2, "seed {seed}, step {steps}: holds {ratio:.3e} times white");
            }
        }
    }
}
