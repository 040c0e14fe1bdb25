//! Pose detection, not I/O: the rows of a [`Table`] fed through the library's static detector
//! ([`Accumulator`]) with settings taken from the data (block length from the sample rate, the
//! quantisation floor, stale repeats skipped when they look like stale reads, time gaps
//! interrupting the stream), and where each pose lies in the file.
//!
//! ```
//! use accelcal_host::io::{ReadOptions, read_csv_str};
//! use accelcal_host::poses::{AccumulateOptions, accumulate};
//! let mut text = String::from("t,ax,ay,az\n");
//! for i in 0..300 {
//!     text.push_str(&format!("{:.2},0.0,0.0,{}\n", f64::from(i) * 0.01, 1.0 + 0.001 * f64::from(i % 3)));
//! }
//! let table = read_csv_str("still.csv", &text, &ReadOptions::default()).unwrap();
//! let found = accumulate(&table, &AccumulateOptions::default()).unwrap();
//! assert_eq!(found.poses.len(), 1);
//! ```

use accelcal::accumulator::{Accumulator, AccumulatorConfig, AccumulatorError, Pose, Rejections};

use crate::io::Table;

/// Pose capacity of the accumulator used by [`accumulate`].
pub const MAX_POSES: usize = crate::calib::MAX_POSES;

/// Block lengths (samples) [`accumulate`] can use; the block length is a const generic of the
/// library's accumulator, so only these are compiled in.
pub const BLOCK_SIZES: [usize; 5] = [8, 16, 32, 64, 128];

/// Block duration [`accumulate`] aims at when the sample rate is known, seconds.
pub const TARGET_BLOCK_S: f64 = 0.16;

/// Block length used when the sample rate is unknown (no time column), samples.
pub const DEFAULT_BLOCK_SAMPLES: usize = 16;

/// Shortest still interval taken as a pose, seconds (the library counts shorter ones as rejected,
/// too short). A hold cut up by a knock or a hand leaves fragments the detector finds still (its
/// default keeps 100 samples: 0.125 s at 800 Hz) whose means carry the motion's edges: on three
/// clean high-rate logs of an independent generator, fragments of 0.16-0.32 s had residuals of 5-11
/// mg and made a gap 35-59 times white noise (1.3 or less without them).
pub const MIN_POSE_S: f64 = 0.5;

/// Static-detection settings for [`accumulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccumulateOptions {
    /// The library's detector settings. Its `min_noise_variance` is raised to the quantisation floor
    /// measured in the data (`sum over axes of q^2 / 12`, `q` the smallest step between readings).
    pub config: AccumulatorConfig,
    /// Sample rate, Hz; `None` takes it from the time column (if any).
    pub sample_rate_hz: Option<f64>,
    /// Block length, samples (one of [`BLOCK_SIZES`]); `None` chooses about [`TARGET_BLOCK_S`] of
    /// samples from the sample rate, or [`DEFAULT_BLOCK_SAMPLES`] without one.
    pub block_samples: Option<usize>,
    /// A time step longer than this multiple of the mean step interrupts the stream (a pose never
    /// spans a gap in the recording). Defaults to 10.
    pub gap_factor: f64,
    /// Skip rows that repeat the previous row exactly (all three axes): stale reads of a sensor polled
    /// faster than its output data rate. `None` (default) decides from the data with
    /// [`repeats_look_stale`]: a coarsely quantised sensor repeats readings too, and those are kept.
    /// Stale readings are not independent samples, and the library's detector assumes independent
    /// noise.
    pub skip_repeats: Option<bool>,
    /// Shortest pose, seconds: with a known sample rate the library's `min_pose_samples` is raised
    /// to this many seconds of samples. Defaults to [`MIN_POSE_S`]; 0 keeps the library's setting.
    pub min_pose_s: f64,
    /// Widen the library's test of a block's mean change (`drift_enter_factor`, `drift_exit_factor`)
    /// by the readings' measured correlation ([`block_mean_correlation`]) when it is at least
    /// [`CORRELATED_AT_LEAST`]: the test assumes independent readings, and a heavily low-passed
    /// sensor's block means move several times more than its per-sample scatter predicts. Defaults to
    /// `false`; [`accumulate_holds`] sets it when the other settings find too few poses (widened on
    /// every log, the test also let the tails of moves into the poses of logs found well without it).
    pub correlated_readings: bool,
    /// With [`correlated_readings`](Self::correlated_readings), and the readings measured correlated: the
    /// block this many times longer (at most the longest of [`BLOCK_SIZES`]), the widening measured at
    /// that length. A block of a heavily low-passed sensor holds few independent readings, so its
    /// variance scatters far about the noise level and the variance test closes poses at random (an
    /// MPU-6050 at 50 Hz behind a 2.5 Hz filter: 1-2 of 23-30 holds found in 8-sample blocks, 20-27 in
    /// 16-sample blocks; a flicker noise on top of it: 6 in 16-sample blocks, 30 in 32). Defaults to 1;
    /// [`accumulate_holds`] tries 2, then 4 last.
    pub correlated_block_multiple: usize,
    /// The shortest pose, in blocks, instead of the library's `min_pose_samples` (100), when it is
    /// shorter. A log of holds of 100 readings each (logging paused while the sensor is turned; or
    /// 2 s holds at 50 Hz) keeps at most 80-90 of each after the still test's first block. `None`
    /// (default) keeps the library's; [`accumulate_holds`] tries 4 last. With a sample rate the
    /// pose is still at least [`Self::min_pose_s`] long.
    pub short_min_pose_blocks: Option<u32>,
}

/// Per-axis RMS scatter of a pose's readings, in units of the log's median |a| (gravity), above which
/// a pose found in longer blocks ([`AccumulateOptions::correlated_block_multiple`]) is a move, not a
/// hold. A MEMS accelerometer at rest scatters by about 0.01 g at most (the noisiest parts' white noise,
/// a coarse step, a hand's tremor of 0.01-0.04 g); in blocks as long as half a slow periodic move, a log
/// in continuous motion has block means that barely change, uniform block variances, and 0.5 g of
/// scatter. The longer blocks, with the widened test, have no other guard against it.
pub const STILL_SCATTER_MAX_G: f64 = 0.1;

/// Least fraction of rows repeating their predecessor (all three axes) for [`repeats_look_stale`].
pub const STALE_REPEAT_FRACTION: f64 = 0.2;

/// Least ratio of all-axes repeats to the count independent axes would give (per window of
/// [`STALE_WINDOW_ROWS`]) for [`repeats_look_stale`]. Quantisation measures about 1.05, stale reads
/// of a sensor polled 4x its data rate 1.6, 2x: 3.
pub const STALE_DEPENDENCE_RATIO: f64 = 1.3;

/// Rows per window in which [`repeats_look_stale`] compares the repeats of the axes.
pub const STALE_WINDOW_ROWS: usize = 64;

impl Default for AccumulateOptions {
    fn default() -> Self {
        Self {
            config: AccumulatorConfig::DEFAULT,
            sample_rate_hz: None,
            block_samples: None,
            gap_factor: 10.0,
            skip_repeats: None,
            min_pose_s: MIN_POSE_S,
            correlated_readings: false,
            correlated_block_multiple: 1,
            short_min_pose_blocks: None,
        }
    }
}

/// Row `i` repeats the previous row exactly (all three axes): a stale read when
/// [`AccumulateOptions::skip_repeats`] applies.
fn repeats_previous(samples: &[[f64; 3]], i: usize) -> bool {
    i > 0 && samples[i - 1] == samples[i]
}

/// Fraction of rows that repeat the previous row exactly (all three axes).
pub fn repeat_fraction(samples: &[[f64; 3]]) -> f64 {
    if samples.len() < 2 {
        return 0.0;
    }
    samples.windows(2).filter(|w| w[0] == w[1]).count() as f64 / (samples.len() - 1) as f64
}

/// `true` when rows repeating their predecessor exactly look like stale reads, not quantisation: more
/// than [`STALE_REPEAT_FRACTION`] of the rows repeat on all three axes, and all three repeat together
/// more than [`STALE_DEPENDENCE_RATIO`] times as often as the per-axis repeats would by chance. A stale
/// read repeats the whole sample; a quantised sensor whose noise is below one step repeats each axis
/// on its own (counted per window, so that still and moving stretches are not mixed).
pub fn repeats_look_stale(samples: &[[f64; 3]]) -> bool {
    if repeat_fraction(samples) <= STALE_REPEAT_FRACTION {
        return false;
    }
    let (mut observed, mut expected) = (0.0, 0.0);
    for window in samples.windows(2).collect::<Vec<_>>().chunks(STALE_WINDOW_ROWS) {
        let per_axis = [0, 1, 2].map(|a| window.iter().filter(|w| w[0][a] == w[1][a]).count() as f64);
        let n = window.len() as f64;
        observed += window.iter().filter(|w| w[0] == w[1]).count() as f64;
        expected += per_axis[0] * per_axis[1] * per_axis[2] / (n * n);
    }
    observed > STALE_DEPENDENCE_RATIO * expected
}

/// Where a pose came from in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseSpan {
    /// First row averaged (index into the table).
    pub first_row: usize,
    /// Last row averaged.
    pub last_row: usize,
    /// File line of the first row.
    pub first_line: usize,
    /// File line of the last row.
    pub last_line: usize,
    /// Time of the first row, seconds (with a time column).
    pub start_s: Option<f64>,
    /// Time of the last row, seconds.
    pub end_s: Option<f64>,
}

/// The result of [`accumulate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Accumulation {
    /// The poses found, in order.
    pub poses: Vec<Pose>,
    /// Where each pose came from.
    pub spans: Vec<PoseSpan>,
    /// Static intervals rejected, by reason.
    pub rejections: Rejections,
    /// Poses dropped because [`MAX_POSES`] were already stored.
    pub dropped_full: u32,
    /// Gaps in the time stamps that interrupted the stream.
    pub interruptions: u32,
    /// Block length used, samples.
    pub block_samples: usize,
    /// Sample rate used to choose it (of the rows fed, after skipping stale repeats), Hz.
    pub sample_rate_hz: Option<f64>,
    /// Rows skipped as stale repeats of the previous row.
    pub skipped_repeats: usize,
    /// The noise floor imposed (quantisation), input unit squared, summed over axes.
    pub min_noise_variance: f32,
    /// The detector's final noise variance estimate, input unit squared, summed over axes.
    pub noise_variance: f32,
    /// Shortest pose kept, samples (shorter still intervals are in `rejections.too_short`).
    pub min_pose_samples: u32,
    /// The factor the test of a block's mean change was widened by for correlated readings
    /// ([`AccumulateOptions::correlated_readings`]); `None` when it was not.
    pub mean_change_widened: Option<f64>,
}

/// The block length [`accumulate`] picks for a sample rate: the one of [`BLOCK_SIZES`] nearest (in
/// ratio) to [`TARGET_BLOCK_S`] of samples; [`DEFAULT_BLOCK_SAMPLES`] without a rate.
pub fn choose_block_samples(sample_rate_hz: Option<f64>) -> usize {
    let Some(rate) = sample_rate_hz.filter(|r| r.is_finite() && *r > 0.0) else {
        return DEFAULT_BLOCK_SAMPLES;
    };
    let target = (rate * TARGET_BLOCK_S).max(1.0).log2();
    BLOCK_SIZES
        .iter()
        .copied()
        .min_by(|a, b| ((*a as f64).log2() - target).abs().total_cmp(&((*b as f64).log2() - target).abs()))
        .unwrap_or(DEFAULT_BLOCK_SAMPLES)
}

/// Shortest pose, in blocks, of the last attempts (holds shorter than the library's shortest pose)
/// ([`AccumulateOptions::short_min_pose_blocks`]).
pub const SHORT_MIN_POSE_BLOCKS: u32 = 4;

/// `block` times `multiple`, at most the longest of [`BLOCK_SIZES`] (a block length the detector has).
fn longer_block(block: usize, multiple: usize) -> usize {
    let longest = BLOCK_SIZES[BLOCK_SIZES.len() - 1];
    BLOCK_SIZES.iter().copied().find(|&b| b >= block.saturating_mul(multiple)).unwrap_or(longest)
}

/// The quantisation floor of the readings: `sum over axes of q^2 / 12` with `q` the smallest non-zero
/// step between consecutive readings of that axis (input unit squared).
pub fn quantisation_variance(samples: &[[f64; 3]]) -> f32 {
    let mut total = 0.0;
    for a in 0..3 {
        let step = samples
            .windows(2)
            .map(|w| (w[1][a] as f32 - w[0][a] as f32).abs())
            .filter(|d| *d > 0.0)
            .fold(f32::INFINITY, f32::min);
        if step.is_finite() {
            total += step * step / 12.0;
        }
    }
    total
}

/// Where a quarter of the normalised changes between the means of still blocks fall under white
/// noise: the 25th percentile of chi-square with 3 degrees of freedom, over 3.
const WHITE_CHANGE_Q25: f64 = 0.404;

/// Least [`block_mean_correlation`] for which [`AccumulateOptions::correlated_readings`] widens the
/// test (white noise measures about 1.0-1.3).
pub const CORRELATED_AT_LEAST: f64 = 2.0;

/// Fewest pairs of consecutive blocks from which [`block_mean_correlation`] is measured.
pub const MIN_BLOCK_PAIRS: usize = 20;

/// How many times more the means of consecutive blocks of `block` samples differ than the
/// samples' own scatter predicts (`2 v / block`, `v` the blocks' variance, at least `floor`, summed
/// over axes), in the log's stillest blocks: its 25th percentile over that of white noise (at least
/// one; one with fewer than [`MIN_BLOCK_PAIRS`] pairs). A sensor's digital low-pass filter
/// correlates successive readings (an MPU-6050 at 50 Hz behind its 5 Hz filter: about 25 times),
/// and the library's test of a block's mean change, which assumes independent readings, then finds
/// no still block; a moving block changes by far more.
pub fn block_mean_correlation(samples: impl Iterator<Item = [f64; 3]>, block: usize, floor: f64) -> f64 {
    let samples: Vec<[f64; 3]> = samples.collect();
    let blocks: Vec<([f64; 3], f64)> = samples
        .chunks_exact(block.max(2))
        .map(|c| {
            let n = c.len() as f64;
            let mean: [f64; 3] = std::array::from_fn(|a| c.iter().map(|s| s[a]).sum::<f64>() / n);
            let var: f64 = (0..3).map(|a| c.iter().map(|s| (s[a] - mean[a]).powi(2)).sum::<f64>() / (n - 1.0)).sum();
            (mean, var.max(floor))
        })
        .collect();
    let mut changes: Vec<f64> = blocks
        .windows(2)
        .map(|w| {
            let d: f64 = (0..3).map(|a| (w[1].0[a] - w[0].0[a]).powi(2)).sum();
            d * block as f64 / (w[0].1 + w[1].1)
        })
        .filter(|r| r.is_finite())
        .collect();
    if changes.len() < MIN_BLOCK_PAIRS {
        return 1.0;
    }
    changes.sort_by(f64::total_cmp);
    (changes[changes.len() / 4] / WHITE_CHANGE_Q25).max(1.0)
}

/// The detector's settings for a table, as [`accumulate`] derives them (the streaming reader from
/// its first rows).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Detector {
    /// The library's settings: the noise floor raised to the readings' quantisation, the shortest
    /// pose to `min_pose_s` of samples.
    pub(crate) config: AccumulatorConfig,
    /// Block length, samples.
    pub(crate) block: usize,
    /// Sample rate of the rows fed (after skipping stale repeats), Hz.
    pub(crate) sample_rate_hz: Option<f64>,
    /// Rows repeating the previous one are skipped.
    pub(crate) skip_repeats: bool,
    /// A time step longer than this interrupts the stream, s.
    pub(crate) gap_s: Option<f64>,
    /// The factor the test of a block's mean change is widened by, if it is.
    pub(crate) mean_change_widened: Option<f64>,
    /// The block was lengthened for correlated readings: poses scattering by more than
    /// [`STILL_SCATTER_MAX_G`] are moves ([`Detector::drop_scattered`]).
    pub(crate) block_lengthened: bool,
}

/// The readings' correlation as [`Detector::derive`] widens the test of a block's mean change by it.
struct Correlated {
    /// The block length, lengthened by the multiple when the readings are correlated.
    block: usize,
    /// It was lengthened.
    lengthened: bool,
    /// [`block_mean_correlation`] at that length, when at least [`CORRELATED_AT_LEAST`].
    factor: Option<f64>,
}

impl Correlated {
    /// [`block_mean_correlation`] of the rows fed (stale repeats skipped) in blocks of `block`; when
    /// correlated and `multiple` > 1, again in blocks `multiple` times as long
    /// ([`AccumulateOptions::correlated_block_multiple`]).
    fn measure(table: &Table, skip_repeats: bool, block: usize, floor: f64, multiple: usize) -> Self {
        let fed = || {
            (0..table.samples.len())
                .filter(move |&i| !(skip_repeats && repeats_previous(&table.samples, i)))
                .map(|i| table.samples[i])
        };
        let mut out = Self { block, lengthened: false, factor: None };
        let mut correlation = block_mean_correlation(fed(), block, floor);
        if correlation >= CORRELATED_AT_LEAST && multiple > 1 {
            (out.block, out.lengthened) = (longer_block(block, multiple), true);
            correlation = block_mean_correlation(fed(), out.block, floor);
        }
        out.factor = (correlation >= CORRELATED_AT_LEAST).then_some(correlation);
        out
    }
}

/// The shortest pose, samples: `library` (the library's setting), lowered to
/// `opts.short_min_pose_blocks` blocks, then raised to `opts.min_pose_s` of samples with a sample rate.
fn shortest_pose(opts: &AccumulateOptions, sample_rate_hz: Option<f64>, block: usize, library: u32) -> u32 {
    let block = u32::try_from(block).unwrap_or(u32::MAX);
    let library = opts.short_min_pose_blocks.map_or(library, |blocks| library.min(blocks.saturating_mul(block).max(1)));
    let Some(rate) = sample_rate_hz else { return library };
    let samples = (opts.min_pose_s * rate).ceil();
    if samples.is_finite() && samples > f64::from(library) { samples.min(f64::from(u32::MAX)) as u32 } else { library }
}

impl Detector {
    pub(crate) fn derive(table: &Table, opts: &AccumulateOptions) -> Self {
        let repeats = repeat_fraction(&table.samples);
        let skip_repeats = opts.skip_repeats.unwrap_or_else(|| repeats_look_stale(&table.samples));
        let fed_fraction = if skip_repeats { 1.0 - repeats } else { 1.0 };
        let sample_rate_hz = opts.sample_rate_hz.or_else(|| table.sample_rate_hz()).map(|r| r * fed_fraction);
        let mut block = opts.block_samples.unwrap_or_else(|| choose_block_samples(sample_rate_hz));
        let mut config = opts.config;
        config.min_noise_variance = config.min_noise_variance.max(quantisation_variance(&table.samples));
        let (mut mean_change_widened, mut block_lengthened) = (None, false);
        if opts.correlated_readings {
            let floor = f64::from(config.min_noise_variance);
            let correlated = Correlated::measure(table, skip_repeats, block, floor, opts.correlated_block_multiple);
            (block, block_lengthened) = (correlated.block, correlated.lengthened);
            if let Some(correlation) = correlated.factor {
                config.drift_enter_factor *= correlation as f32;
                config.drift_exit_factor *= correlation as f32;
                mean_change_widened = Some(correlation);
            }
        }
        config.min_pose_samples = shortest_pose(opts, sample_rate_hz, block, config.min_pose_samples);
        let gap_s = table.times_s.as_ref().and_then(|t| {
            let span = t.last()? - t.first()?;
            (t.len() >= 2 && span > 0.0).then(|| opts.gap_factor * span / (t.len() - 1) as f64)
        });
        Self { config, block, sample_rate_hz, skip_repeats, gap_s, mean_change_widened, block_lengthened }
    }

    /// With the block lengthened, the poses (and their spans) whose readings scatter by more than
    /// [`STILL_SCATTER_MAX_G`] of `gravity` (input unit) on an axis are removed and counted as moving.
    pub(crate) fn drop_scattered(&self, acc: &mut Accumulation, gravity: f64) {
        if !self.block_lengthened {
            return;
        }
        let limit = (STILL_SCATTER_MAX_G * gravity).powi(2);
        let moving: Vec<bool> = acc.poses.iter().map(|p| !p.variance.iter().all(|v| f64::from(*v) <= limit)).collect();
        remove_marked(&mut acc.poses, &moving);
        remove_marked(&mut acc.spans, &moving);
        let moved = moving.iter().filter(|m| **m).count();
        acc.rejections.moving = acc.rejections.moving.saturating_add(u32::try_from(moved).unwrap_or(u32::MAX));
    }
}

/// The options to find the poses with, in order, while too few are found: `opts`; the library's
/// shortest pose alone (a log of short holds only is still calibrated from them); then both with the
/// test of a block's mean change widened for correlated readings
/// ([`AccumulateOptions::correlated_readings`]: a heavily low-passed sensor's holds); then both with
/// blocks twice, then four times as long as well ([`AccumulateOptions::correlated_block_multiple`]);
/// last, poses of [`SHORT_MIN_POSE_BLOCKS`] blocks (holds of 100 readings or fewer), then with the
/// widened test as well. A log found with the first two is found as before the widened test
/// existed, one found with the first four as before the longer blocks. Repeats left out.
pub(crate) fn attempts(opts: &AccumulateOptions) -> Vec<AccumulateOptions> {
    let library = AccumulateOptions { min_pose_s: 0.0, ..*opts };
    let widened = |o: AccumulateOptions| AccumulateOptions { correlated_readings: true, ..o };
    let longer =
        |o: AccumulateOptions, multiple| AccumulateOptions { correlated_block_multiple: multiple, ..widened(o) };
    let mut out: Vec<AccumulateOptions> = Vec::new();
    let first = [*opts, library, widened(*opts), widened(library)];
    let longer_blocks = [2, 4].into_iter().flat_map(|m| [longer(*opts, m), longer(library, m)]);
    let short = AccumulateOptions { short_min_pose_blocks: Some(SHORT_MIN_POSE_BLOCKS), ..library };
    for o in first.into_iter().chain(longer_blocks).chain([short, widened(short)]) {
        if !out.contains(&o) {
            out.push(o);
        }
    }
    out
}

/// [`accumulate`] with `opts`, then while the poses number fewer than `min_poses`: with the library's
/// shortest pose alone (a log of short holds only), then both with the test of a block's mean change
/// widened for correlated readings ([`AccumulateOptions::correlated_readings`]), then with longer
/// blocks as well ([`AccumulateOptions::correlated_block_multiple`]); the first of the most poses
/// found when none finds that many.
///
/// # Errors
/// As [`accumulate`].
pub fn accumulate_holds(
    table: &Table,
    opts: &AccumulateOptions,
    min_poses: usize,
) -> Result<Accumulation, AccumulatorError> {
    accumulate_until(table, opts, |poses| poses.len() >= min_poses)
}

/// [`accumulate_holds`] until the poses found are `enough` (e.g. what a calibration's initial
/// estimate fits, [`crate::calib::enough_poses`]): a log whose first settings find seven poses in a
/// few directions may be found whole with the later ones.
///
/// # Errors
/// As [`accumulate`].
pub fn accumulate_until(
    table: &Table,
    opts: &AccumulateOptions,
    enough: impl Fn(&[Pose]) -> bool,
) -> Result<Accumulation, AccumulatorError> {
    until_enough(
        opts,
        |a: &Accumulation| enough(&a.poses),
        |a| !fragmented(a),
        |a| a.poses.len(),
        |o| accumulate(table, o),
    )
}

/// The settings cut the holds into fragments (a low-passed sensor's block means and variances
/// scatter past the still test), and later settings may find them whole: more still intervals were
/// left out as too short than poses were found, or the holds were found cut in pieces
/// ([`split_holds`]).
pub(crate) fn fragmented(acc: &Accumulation) -> bool {
    acc.rejections.too_short as usize > acc.poses.len() || split_holds(acc)
}

/// Largest angle between the mean readings of two consecutive poses that are one hold cut in two,
/// degrees. Two fragments of a hold agree to the noise of their means (hundredths of a degree); the
/// poses of a calibration differ by tens of degrees, and a hand or a jig turning the board back to a
/// pose takes more than [`SAME_HOLD_BREAK_S`].
pub const SAME_HOLD_DEG: f64 = 1.0;

/// Longest break between two consecutive poses of one hold cut in two, seconds.
pub const SAME_HOLD_BREAK_S: f64 = 1.0;

/// Share of consecutive poses that are one hold cut in two from which the holds were found cut in
/// pieces ([`split_holds`]). On the third generator's development sets (384 logs) a sensor behind a
/// digital low-pass at a tenth of its output rate or below had its holds cut in two or more in 42 of
/// 101 logs (found 1.5 to 5 times as many poses as it held; the widened test found them whole); a
/// knock in a hold cuts it too, but does not correlate the readings and no later setting joins it.
pub const SPLIT_SHARE: f64 = 0.15;

/// At least [`SPLIT_SHARE`] of the consecutive poses are one hold cut in two: their mean readings
/// within [`SAME_HOLD_DEG`], less than [`SAME_HOLD_BREAK_S`] apart (with a sample rate).
pub(crate) fn split_holds(acc: &Accumulation) -> bool {
    let Some(rate) = acc.sample_rate_hz.filter(|r| *r > 0.0) else { return false };
    let cos_max = SAME_HOLD_DEG.to_radians().cos();
    let pairs = acc.poses.windows(2).zip(acc.spans.windows(2));
    let cut = pairs
        .filter(|(p, s)| {
            let (a, b) = (p[0].mean.map(f64::from), p[1].mean.map(f64::from));
            let norms = crate::vec3::norm(a) * crate::vec3::norm(b);
            let break_s = s[1].first_row.saturating_sub(s[0].last_row) as f64 / rate;
            norms > 0.0 && crate::vec3::dot(a, b) >= cos_max * norms && break_s < SAME_HOLD_BREAK_S
        })
        .count();
    !acc.poses.is_empty() && cut as f64 >= SPLIT_SHARE * acc.poses.len() as f64
}

/// `find` with each of [`attempts`] in order until what it finds is `enough` and `whole` (not
/// [`fragmented`]); when none is, the first that is `enough`; when none is, the first of those that
/// found the most poses (`count`).
pub(crate) fn until_enough<T, E>(
    opts: &AccumulateOptions,
    enough: impl Fn(&T) -> bool,
    whole: impl Fn(&T) -> bool,
    count: impl Fn(&T) -> usize,
    mut find: impl FnMut(&AccumulateOptions) -> Result<T, E>,
) -> Result<T, E> {
    // Enough before not enough; among those not enough, the most poses; the first on a tie.
    let rank = |t: &T| if enough(t) { (true, 0) } else { (false, count(t)) };
    let chosen = |t: &T| enough(t) && whole(t);
    let mut best = find(opts)?;
    if chosen(&best) {
        return Ok(best);
    }
    for next in attempts(opts).iter().skip(1) {
        let found = find(next)?;
        if chosen(&found) {
            return Ok(found);
        }
        if rank(&found) > rank(&best) {
            best = found;
        }
    }
    Ok(best)
}

/// Feeds every row of `table` (as `f32`, in the table's units) through the library's
/// `Accumulator::<f32, MAX_POSES, BLOCK>` and returns the poses it found, where they are in the file
/// and what was rejected. Time gaps (see [`AccumulateOptions::gap_factor`]) interrupt the stream.
///
/// # Errors
/// [`AccumulatorError::InvalidConfig`] for an invalid `opts.config` or a block length not in
/// [`BLOCK_SIZES`]. A full pose buffer is not an error: the poses beyond [`MAX_POSES`] are counted in
/// [`Accumulation::dropped_full`].
pub fn accumulate(table: &Table, opts: &AccumulateOptions) -> Result<Accumulation, AccumulatorError> {
    let detector = Detector::derive(table, opts);
    let run = Run { table, detector };
    let mut out = match detector.block {
        8 => run.go::<8>()?,
        16 => run.go::<16>()?,
        32 => run.go::<32>()?,
        64 => run.go::<64>()?,
        128 => run.go::<128>()?,
        _ => return Err(AccumulatorError::InvalidConfig),
    };
    out.sample_rate_hz = detector.sample_rate_hz;
    detector.drop_scattered(&mut out, table.median_magnitude);
    Ok(out)
}

struct Run<'a> {
    table: &'a Table,
    detector: Detector,
}

impl Run<'_> {
    fn go<const BLOCK: usize>(&self) -> Result<Accumulation, AccumulatorError> {
        let table = self.table;
        let Detector { config, skip_repeats, gap_s, .. } = self.detector;
        let mut acc = Accumulator::<f32, MAX_POSES, BLOCK>::new(config)?;
        let mut dropped_full = 0u32;
        let mut interruptions = 0u32;
        let mut handle = |r: Result<_, AccumulatorError>| match r {
            Ok(_) | Err(AccumulatorError::NonFiniteSample) => Ok(()),
            Err(AccumulatorError::Full) => {
                dropped_full += 1;
                Ok(())
            }
            Err(e) => Err(e),
        };
        // Table row of each sample pushed (pose indices count pushed samples).
        let mut row_of_pushed: Vec<usize> = Vec::with_capacity(table.samples.len());
        for (i, s) in table.samples.iter().enumerate() {
            if let (Some(t), Some(gap)) = (&table.times_s, gap_s)
                && i > 0
                && t[i] - t[i - 1] > gap
            {
                interruptions += 1;
                handle(acc.interrupt())?;
            }
            if skip_repeats && repeats_previous(&table.samples, i) {
                continue;
            }
            row_of_pushed.push(i);
            handle(acc.push(s.map(|v| v as f32)))?;
        }
        handle(acc.finish())?;
        let poses = acc.poses().to_vec();
        let last_pushed = row_of_pushed.len().saturating_sub(1);
        let spans = poses
            .iter()
            .map(|p| {
                let first = (p.start_index as usize).min(last_pushed);
                let last = (p.end_index as usize).saturating_sub(1).clamp(first, last_pushed);
                let (first_row, last_row) = (row_of_pushed[first], row_of_pushed[last]);
                PoseSpan {
                    first_row,
                    last_row,
                    first_line: table.line_of_row[first_row],
                    last_line: table.line_of_row[last_row],
                    start_s: table.times_s.as_ref().map(|t| t[first_row]),
                    end_s: table.times_s.as_ref().map(|t| t[last_row]),
                }
            })
            .collect();
        Ok(Accumulation {
            poses,
            spans,
            rejections: acc.rejections(),
            dropped_full,
            interruptions,
            block_samples: BLOCK,
            sample_rate_hz: None,
            skipped_repeats: table.samples.len() - row_of_pushed.len(),
            min_noise_variance: config.min_noise_variance,
            noise_variance: acc.noise_variance(),
            min_pose_samples: config.min_pose_samples,
            mean_change_widened: self.detector.mean_change_widened,
        })
    }
}

/// Removes the items of `items` marked in `marked` (one mark per item, in order; items beyond the
/// marks stay): the poses and their parallel lists (spans, the library's poses) lose the same ones.
pub(crate) fn remove_marked<T>(items: &mut Vec<T>, marked: &[bool]) {
    let mut marks = marked.iter();
    items.retain(|_| !marks.next().copied().unwrap_or(false));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::knocked::knocked_log;

    fn library_minimum() -> AccumulateOptions {
        AccumulateOptions { min_pose_s: 0.0, ..AccumulateOptions::default() }
    }

    #[test]
    fn marked_items_are_removed_and_unmarked_ones_kept_in_order() {
        let mut items = vec![10, 11, 12, 13, 14];
        remove_marked(&mut items, &[true, false, true, false]);
        assert_eq!(items, [11, 13, 14], "an item beyond the marks stays");
    }

    #[test]
    fn still_fragments_shorter_than_the_shortest_pose_are_rejected_and_counted() {
        // One knock in every fourth hold, mid-hold: a 0.45 s fragment pressed, then the hold resumes.
        let table = knocked_log(4, 0.5, 0.45, 1);
        let library = accumulate(&table, &library_minimum()).unwrap();
        let holds = accumulate(&table, &AccumulateOptions::default()).unwrap();
        let rate = holds.sample_rate_hz.unwrap();
        assert_eq!(holds.min_pose_samples, (MIN_POSE_S * rate).ceil() as u32);
        assert_eq!(library.min_pose_samples, AccumulatorConfig::DEFAULT.min_pose_samples);
        let left_out = library.poses.len() - holds.poses.len();
        assert!(left_out >= 3, "{left_out} of {} still intervals", library.poses.len());
        assert_eq!(holds.rejections.too_short, library.rejections.too_short + left_out as u32);
        assert!(holds.spans.iter().all(|s| (s.last_row + 1 - s.first_row) as f64 >= MIN_POSE_S * rate));
    }

    /// A clean simulated log through a first-order low-pass of time constant `tau_samples` (a
    /// sensor's digital filter; 0: unfiltered).
    fn low_passed(tau_samples: f64, seed: u64) -> Table {
        low_passed_stages(tau_samples, 1, seed)
    }

    /// A clean simulated log through `stages` first-order low-passes of `tau_samples` each.
    fn low_passed_stages(tau_samples: f64, stages: usize, seed: u64) -> Table {
        use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};
        let mut table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
        let alpha = 1.0 / (1.0 + tau_samples);
        for _ in 0..stages {
            let mut state = table.samples[0];
            for s in &mut table.samples {
                state = std::array::from_fn(|a| state[a] + alpha * (s[a] - state[a]));
                *s = state;
            }
        }
        table
    }

    #[test]
    fn holds_cut_into_more_fragments_than_poses_are_found_whole_by_the_widened_test() {
        // Two low-pass stages of 2 samples: the default settings find enough poses to calibrate,
        // among far more fragments of holds left out as too short; the widened test finds them whole.
        for seed in [1, 3] {
            let unfiltered = accumulate(&low_passed(0.0, seed), &AccumulateOptions::default()).unwrap();
            let filtered = low_passed_stages(2.0, 2, seed);
            let first = accumulate(&filtered, &AccumulateOptions::default()).unwrap();
            assert!(first.poses.len() >= crate::calib::MIN_POSES && fragmented(&first), "seed {seed}: {first:?}");
            let found = accumulate_holds(&filtered, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
            assert!(!fragmented(&found) && found.mean_change_widened.is_some(), "seed {seed}: {:?}", found.rejections);
            assert!(
                4 * found.poses.len() >= 3 * unfiltered.poses.len(),
                "seed {seed}: {} poses, {} unfiltered",
                found.poses.len(),
                unfiltered.poses.len()
            );
        }
    }

    #[test]
    fn holds_cut_in_two_by_a_low_pass_filter_are_found_whole_by_the_widened_test() {
        // Two low-pass stages of 1.5 samples (a second-order filter near a tenth of the rate): the
        // default settings find two to four times the holds, most of them consecutive fragments at one
        // orientation, with fewer still intervals left out as too short than poses found; the
        // widened test finds the holds whole.
        for seed in [2, 5] {
            let unfiltered = accumulate(&low_passed(0.0, seed), &AccumulateOptions::default()).unwrap();
            assert!(!split_holds(&unfiltered), "seed {seed}: the unfiltered holds are whole");
            let filtered = low_passed_stages(1.5, 2, seed);
            let first = accumulate(&filtered, &AccumulateOptions::default()).unwrap();
            assert!(first.poses.len() > 2 * unfiltered.poses.len(), "seed {seed}: {} poses", first.poses.len());
            assert!((first.rejections.too_short as usize) < first.poses.len() && split_holds(&first), "seed {seed}");
            let found = accumulate_holds(&filtered, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
            assert!(!fragmented(&found) && found.mean_change_widened.is_some(), "seed {seed}: {:?}", found.rejections);
            assert_eq!(found.poses.len(), unfiltered.poses.len(), "seed {seed}");
        }
    }

    #[test]
    fn a_log_whose_blocks_hold_few_independent_readings_is_found_in_longer_blocks() {
        // Two low-pass stages of 3.2 samples (a second-order filter at a twentieth of the rate, as an
        // MPU-6050 at 50 Hz behind its 2.5 Hz filter) read in blocks of 8: the block variances scatter
        // so far that even the widened test finds too few poses; blocks of 16 find most, or blocks of
        // 32 where 16 cut holds in two (before the short poses, tried last).
        let eight = AccumulateOptions { block_samples: Some(8), ..AccumulateOptions::default() };
        for seed in [1, 2, 3] {
            let unfiltered = accumulate(&low_passed(0.0, seed), &eight).unwrap().poses.len();
            let filtered = low_passed_stages(3.2, 2, seed);
            let widened: Vec<usize> = attempts(&eight)
                .iter()
                .filter(|o| o.correlated_block_multiple == 1 && o.short_min_pose_blocks.is_none())
                .map(|o| accumulate(&filtered, o).unwrap().poses.len())
                .collect();
            let found = accumulate_holds(&filtered, &eight, crate::calib::MIN_POSES).unwrap();
            assert!(
                widened.iter().all(|&n| n < crate::calib::MIN_POSES) && 4 * found.poses.len() >= 3 * unfiltered,
                "seed {seed}: {widened:?} in blocks of 8, {} in blocks of {}, {unfiltered} unfiltered",
                found.poses.len(),
                found.block_samples
            );
            // Blocks of 16 cut eight of seed 2's 32 holds in two (40 poses, `split_holds`); blocks of
            // 32 find the 32 whole.
            assert!(!fragmented(&found), "seed {seed}: {:?}", found.rejections);
            assert_eq!(found.block_samples, if seed == 2 { 32 } else { 16 }, "seed {seed}");
            assert!(found.mean_change_widened.is_some(), "seed {seed}: the widening is reported");
        }
    }

    #[test]
    fn a_heavily_low_passed_log_is_found_with_the_mean_change_test_widened() {
        for seed in [1, 3, 4] {
            // Unfiltered: white noise measures no correlation, and the first settings find the poses.
            let white = low_passed(0.0, seed);
            let c = block_mean_correlation(white.samples.iter().copied(), 16, 0.0);
            assert!(c < CORRELATED_AT_LEAST, "seed {seed}: {c}");
            let unfiltered = accumulate(&white, &AccumulateOptions::default()).unwrap();
            let holds = accumulate_holds(&white, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
            assert_eq!(holds, unfiltered);
            assert_eq!(holds.mean_change_widened, None);
            // A 12-sample time constant (1.3 Hz at 100 Hz): block means move about 20 times more than
            // the per-sample scatter says; the library's test, which assumes independent readings,
            // finds 2 poses. Widened, at least three quarters of the unfiltered log's.
            let filtered = low_passed(12.0, seed);
            let c = block_mean_correlation(filtered.samples.iter().copied(), 16, 0.0);
            assert!(c >= CORRELATED_AT_LEAST, "seed {seed}: {c}");
            let refused = accumulate(&filtered, &AccumulateOptions::default()).unwrap().poses.len();
            let found = accumulate_holds(&filtered, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
            assert!(
                refused < crate::calib::MIN_POSES && 4 * found.poses.len() >= 3 * unfiltered.poses.len(),
                "seed {seed}: {refused} poses by default, {} widened ({c:.1}x), {} unfiltered",
                found.poses.len(),
                unfiltered.poses.len()
            );
            assert_eq!(found.mean_change_widened, Some(c), "seed {seed}: the widening is reported");
        }
    }

    #[test]
    fn a_log_in_continuous_motion_has_no_pose_in_longer_blocks() {
        // Slow periodic motion (0.8 Hz at 100 Hz, +-1 g): in blocks of half its period the block means
        // barely change and the widened test alone would keep a pose.
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..3000 {
            let w = f64::from(i) * 0.05;
            text.push_str(&format!(
                "{:.2},{:.4},{:.4},{:.4}\n",
                f64::from(i) * 0.01,
                w.sin(),
                w.cos(),
                (2.0 * w).sin()
            ));
        }
        let moving = crate::io::read_csv_str("moving.csv", &text, &crate::io::ReadOptions::default()).unwrap();
        for o in attempts(&AccumulateOptions::default()) {
            let found = accumulate(&moving, &o).unwrap();
            assert!(found.poses.is_empty(), "{} poses with {o:?}", found.poses.len());
        }
        let longest =
            attempts(&AccumulateOptions::default()).into_iter().rfind(|o| o.correlated_block_multiple == 4).unwrap();
        let found = accumulate(&moving, &longest).unwrap();
        assert!(found.rejections.moving >= 1 && found.spans.is_empty(), "{:?}", found.rejections);
        // A low-passed still log keeps every pose its longer blocks find.
        let filtered = low_passed_stages(3.2, 2, 1);
        let kept = accumulate(&filtered, &longest).unwrap();
        let scatter_limit = 0.02 * filtered.median_magnitude;
        assert!(kept.poses.len() >= crate::calib::MIN_POSES && kept.rejections.moving == 0, "{:?}", kept.rejections);
        assert!(kept.poses.iter().all(|p| p.variance.iter().all(|v| f64::from(*v).sqrt() < scatter_limit)));
    }

    /// 12 holds of 100 readings, each a jump from the last (as a public example log of 160 such
    /// holds), with a time column at `rate_hz` between the holds' readings (a 1 s turn between
    /// holds) or none.
    fn holds_of_100_readings(rate_hz: Option<f64>) -> crate::csvio::Table {
        let mut text = String::from(if rate_hz.is_some() { "t,ax,ay,az\n" } else { "ax,ay,az\n" });
        for hold in 0..12u32 {
            let a = f64::from(hold) * 0.9;
            let d = [a.cos() * (0.3 * a).cos(), a.sin() * (0.3 * a).cos(), (0.3 * a).sin()];
            for i in 0..100u32 {
                if let Some(rate) = rate_hz {
                    text.push_str(&format!("{:.4},", f64::from(hold) * (100.0 / rate + 1.0) + f64::from(i) / rate));
                }
                let e = f64::from((i * 7919 + hold * 31) % 17) * 1e-4 - 8e-4;
                text.push_str(&format!("{:.5},{:.5},{:.5}\n", d[0] + e, d[1] - e, d[2] + 0.5 * e));
            }
        }
        crate::io::read_csv_str("blocks.csv", &text, &crate::io::ReadOptions::default()).unwrap()
    }

    #[test]
    fn an_untimed_log_of_holds_of_100_readings_is_found_with_shorter_poses() {
        // No time column; logging paused while the sensor was turned.
        let table = holds_of_100_readings(None);
        assert_eq!(accumulate(&table, &AccumulateOptions::default()).unwrap().poses.len(), 0);
        let found = accumulate_holds(&table, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
        let shortest = SHORT_MIN_POSE_BLOCKS * DEFAULT_BLOCK_SAMPLES as u32;
        assert_eq!(found.min_pose_samples, shortest);
        assert!(found.poses.len() >= 10, "{} poses", found.poses.len());
        assert!(found.poses.iter().all(|p| p.n >= shortest && p.n <= 100));
    }

    #[test]
    fn a_timed_log_of_two_second_holds_at_50_hz_is_found_with_shorter_poses() {
        // 2 s holds at 50 Hz: the library's shortest pose (100 readings) is the whole hold.
        let table = holds_of_100_readings(Some(50.0));
        let opts = AccumulateOptions::default();
        assert_eq!(accumulate(&table, &opts).unwrap().poses.len(), 0);
        let found = accumulate_holds(&table, &opts, crate::calib::MIN_POSES).unwrap();
        let shortest = SHORT_MIN_POSE_BLOCKS * choose_block_samples(Some(50.0)) as u32;
        assert_eq!(found.min_pose_samples, shortest);
        assert!(shortest as f64 >= MIN_POSE_S * 50.0, "no shorter than the timed minimum");
        assert!(found.poses.len() >= 10, "{} poses", found.poses.len());
        assert!(found.poses.iter().all(|p| p.n >= shortest && p.n <= 100));
    }

    #[test]
    fn the_attempts_stop_at_the_first_enough_and_whole_and_otherwise_keep_the_first_enough_or_the_most_poses() {
        let opts = AccumulateOptions::default();
        let tried = attempts(&opts).len();
        assert_eq!(tried, 10, "defaults, library minimum, widened, blocks 2x and 4x, each with both; short poses");
        // Poses found by each attempt in turn, and whether they are whole (not fragmented); "enough"
        // is at least 9.
        let run = |found: &[(usize, bool)]| {
            let mut next = found.iter().copied();
            let mut calls = 0;
            let got = until_enough(
                &opts,
                |f: &(usize, bool)| f.0 >= 9,
                |f: &(usize, bool)| f.1,
                |f: &(usize, bool)| f.0,
                |_| -> Result<(usize, bool), ()> {
                    calls += 1;
                    Ok(next.next().unwrap_or((0, true)))
                },
            )
            .unwrap();
            (got.0, calls)
        };
        let whole = |n: &[usize]| n.iter().map(|&n| (n, true)).collect::<Vec<_>>();
        assert_eq!(run(&whole(&[12, 30])), (12, 1), "the first enough is kept: later settings are not tried");
        assert_eq!(run(&whole(&[7, 3, 10, 40])), (10, 3), "seven poses that do not fit: the later settings are tried");
        assert_eq!(run(&whole(&[7, 3, 8, 8, 2, 0, 1, 0])), (8, tried), "none enough: the first of the most poses");
        let fragments = [(13, false), (13, false), (30, true), (28, true)];
        assert_eq!(run(&fragments), (30, 3), "13 poses among fragments: the first whole settings that are enough");
        let split = [(7, true), (149, false), (140, false), (8, true)];
        assert_eq!(run(&split), (149, tried), "none whole: the first enough");
    }

    #[test]
    fn a_log_of_short_holds_only_falls_back_to_the_library_minimum() {
        // Every hold knocked from its start: still intervals of 0.4 s only.
        let table = knocked_log(1, 0.0, 0.4, 1000);
        let holds = accumulate(&table, &AccumulateOptions::default()).unwrap();
        assert!(holds.poses.len() < crate::calib::MIN_POSES, "{} poses", holds.poses.len());
        let library = accumulate(&table, &library_minimum()).unwrap();
        let found = accumulate_holds(&table, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
        assert_eq!(found, library);
        // A log with enough long holds keeps the shortest pose.
        let knocked = knocked_log(4, 0.5, 0.45, 1);
        let found = accumulate_holds(&knocked, &AccumulateOptions::default(), crate::calib::MIN_POSES).unwrap();
        assert_eq!(found, accumulate(&knocked, &AccumulateOptions::default()).unwrap());
    }
}
