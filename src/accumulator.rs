//! Position averaging: feed samples one at a time ([`Accumulator::push`]) or a sensor FIFO read at once
//! ([`Accumulator::push_slice`]); static intervals are found and averaged into [`Pose`]s.
//!
//! Samples are grouped in blocks of `BLOCK`. Each block's per-axis variance and its mean's change from
//! the previous block are compared with the *measured* noise (a leaky minimum of the block variances:
//! a low percentile of them, never below the quantisation floor), with hysteresis: a pose opens after two quiet blocks and closes at the
//! first block that moves. The block in which motion starts and the one before it are never averaged
//! in (a one-block delay line). A closed pose is kept if it is long enough, never touched the rails and
//! its own variance is noise-like; otherwise it is counted as rejected with the reason.
//!
//! Sums are exact: `i16` counts are summed raw in `i64` (so that a block adds to a pose with six
//! additions), `f32` samples in `f64` relative to a reference sample; the hot path has no division and
//! no float for `i16`.
//!
//! ```
//! use accelcal::accumulator::{Accumulator, AccumulatorConfig};
//! let mut acc: Accumulator<i16, 8, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
//! for i in 0..2000u32 {
//!     let wobble = (i % 3) as i16 - 1; // +-1 LSB noise
//!     acc.push([100 + wobble, -50, 16384 - wobble]).unwrap();
//! }
//! acc.finish().unwrap();
//! assert_eq!(acc.poses().len(), 1);
//! assert!((acc.poses()[0].mean[2] - 16384.0).abs() < 0.01);
//! ```

use core::ops::{Add, AddAssign, Mul, Sub};

/// Most samples one pose (or block) averages: its count saturates here, and later quiet blocks are not
/// added to it. Below `2^31` the `i64` sums of `i16` readings cannot overflow (each squared deviation
/// from the reference sample is below `2^32`).
pub const MAX_POSE_SAMPLES: u32 = i32::MAX as u32;

/// Exact sums of one block of samples, relative to its reference ([`Reading::block_reference`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BlockSums<S> {
    /// Per-axis sum of `sample - reference`.
    pub sum: [S; 3],
    /// Per-axis sum of `(sample - reference)^2`.
    pub sum_sq: [S; 3],
    /// A sample of the block is saturated.
    pub saturated: bool,
}

/// A per-axis sample type the accumulator can sum exactly.
pub trait Reading: Copy + Default {
    /// Exact running-sum type.
    type Sum: Copy + Default + AddAssign + Add<Output = Self::Sum> + Sub<Output = Self::Sum> + Mul<Output = Self::Sum>;
    /// Variance (sum over axes) below which no noise can be resolved: the quantisation floor.
    const QUANTUM_VARIANCE: f32;
    /// An upper bound of the squared magnitude `|mean|^2` of a block's mean (input unit squared): where
    /// `1e-12` of it stays below [`Reading::QUANTUM_VARIANCE`], the noise floor's relative term can never
    /// win and is not computed. Defaults to infinity (always computed).
    const MAX_MAGNITUDE_SQ: f32 = f32::INFINITY;
    /// Sums are kept relative to a reference sample (the first of a block or pose), for precision;
    /// `false`: summed raw (the reference is zero), exact in the sum type, merged by addition.
    const RELATIVE: bool;
    /// The reference of a block whose first sample is `first`: `first`, or zero for raw sums.
    fn block_reference(first: Self) -> Self;
    /// `self - reference` in the sum type (exact).
    fn delta(self, reference: Self) -> Self::Sum;
    /// `n` in the sum type.
    fn count(n: u32) -> Self::Sum;
    /// The exact sums of `samples` relative to [`Reading::block_reference`] of the first one (zero for
    /// none), and whether one of them is saturated at `limit` (blocks of any length; the accumulator
    /// sums its full buffer with [`Reading::full_block`]).
    fn block_sums(axes: [&[Self]; 3], limit: Self::Limit) -> BlockSums<Self::Sum> {
        let mut out = BlockSums::default();
        for (a, values) in axes.iter().enumerate() {
            let (sum, sum_sq, saturated) = Self::axis_sums(values, limit);
            (out.sum[a], out.sum_sq[a]) = (sum, sum_sq);
            out.saturated |= saturated;
        }
        out
    }
    /// [`Reading::block_sums`] of a full block of samples (the accumulator's buffer, or `N` samples of
    /// the caller's slice), written in place into `sum` and `sum_sq`, with the block's statistics:
    /// `(mean, variance, saturated)`, the per-axis mean offset from the reference and the population
    /// variance summed over the axes, in `f32` (no exact rounding needed), and whether a sample is
    /// saturated.
    fn full_block<const N: usize>(
        samples: &[[Self; 3]; N],
        limit: Self::Limit,
        sum: &mut [Self::Sum; 3],
        sum_sq: &mut [Self::Sum; 3],
    ) -> ([f32; 3], f32, bool);
    /// One axis of [`Reading::block_sums`]: `(sum, sum of squares, saturated)`.
    fn axis_sums(values: &[Self], limit: Self::Limit) -> (Self::Sum, Self::Sum, bool);
    /// Mean and (population) variance of `n` samples, from their sums relative to `reference`
    /// (pose close; no software `f64` for `i16` on a Cortex-M4F).
    fn mean_and_variance(reference: Self, sum: Self::Sum, sum_sq: Self::Sum, n: u32) -> (f32, f32);
    /// The value as `f32` (exact for `i16`; no software `f64` on a Cortex-M4F).
    fn to_f32(self) -> f32;
    /// `false` for NaN or infinity.
    fn is_finite(self) -> bool;
    /// A full-scale limit in the form the per-sample check compares against.
    type Limit: Copy;
    /// The limit for `full_scale` (input unit), computed once.
    fn saturation_limit(full_scale: f32) -> Self::Limit;
    /// At a rail of the type or at or beyond the limit.
    fn saturated(self, limit: Self::Limit) -> bool;
}

/// `v` as `f32` from its two 32-bit halves: two hardware conversions instead of the library's
/// `__aeabi_ul2f` (rounded twice: within 1 ulp, enough for statistics; exact below `2^24`).
#[inline]
fn u64_to_f32_halves(v: u64) -> f32 {
    const TWO_POW_32: f32 = 4_294_967_296.0;
    ((v >> 32) as u32) as f32 * TWO_POW_32 + (v as u32) as f32
}

/// `m / d` and `m % d` for the magnitude `m` of a sum of `d` `i16` readings (`m <= d 2^15`, a quotient
/// of at most `2^15`; a larger `m` is clamped to that bound), without the compiler's 64-bit division
/// (`__udivmoddi4`, ~1 KB of flash on a Cortex-M): one hardware division when `m` fits 32 bits (a pose
/// of fewer than `2^17` samples), else 16 shift-and-subtract steps. Three calls per pose.
fn div_rem_sum(m: u64, d: u32) -> (u32, u32) {
    let d = d.max(1);
    if let Ok(x) = u32::try_from(m) {
        return (x / d, x % d);
    }
    // Quotient bits 15 down to 0: the remainder shifted up instead of the divisor down. Before each
    // comparison the shifted remainder is below 2 divisor (it starts at most divisor), at most 2^48.
    let divisor = u64::from(d) << 15;
    let (mut r, mut q) = (m.min(divisor), 0u32);
    for _ in 0..16 {
        q <<= 1;
        if r >= divisor {
            (q, r) = (q | 1, r - divisor);
        }
        r <<= 1;
    }
    // Shifted 16 times: r = remainder 2^16 (below d 2^16).
    (q, (r >> 16) as u32)
}

/// `q + r / d` (`r < d`, `q < 2^25`) rounded once to the nearest `f32` (ties to even): the quotient
/// extended bit by bit (long division of the remainder) until it has 26 significant bits, two below
/// the `f32`'s 24, the last or-ed with a sticky bit for a remainder left (so a tie is one only when
/// exact), converted by the hardware (a 32-bit integer: rounded once, to nearest even), then scaled by
/// an exact power of two: the exact mean of integer samples without `f64` nor 64-bit library calls.
fn fraction_to_f32(q: u32, r: u32, d: u32) -> f32 {
    if q == 0 && r == 0 {
        return 0.0;
    }
    let (mut q, mut r, mut shift) = (q, r, 0u32);
    // r < d throughout; the quotient gets a bit per step until it has 26 (at most 57 steps: a fraction
    // of at least 1 / (2^32 - 1) has a 1 within its first 32 bits).
    while q < 1 << 25 {
        // 2 r >= d, without overflow (r < d): r >= d - r; then 2 r - d = r - (d - r) < d.
        let rest = d - r;
        let bit = r >= rest;
        r = if bit { r - rest } else { r + r };
        (q, shift) = ((q << 1) | u32::from(bit), shift + 1);
    }
    // q < 2^26: exact in u32; 2^-shift (shift <= 57) is a normal f32 and the product is exact.
    (q | u32::from(r != 0)) as f32 * f32::from_bits((127 - shift) << 23)
}

/// The exact mean `total / n` of `n` `i16` readings summing to `total` (`|total| <= n 2^15`), rounded
/// once to the nearest `f32`, and the floor division `total = q n + rem` with `0 <= rem < n`.
fn mean_and_floor_div(total: i64, n: u32) -> (f32, i64, u32) {
    let n = n.max(1);
    let (q, r) = div_rem_sum(total.unsigned_abs(), n);
    let magnitude = fraction_to_f32(q, r, n);
    let q = i64::from(q);
    match (total < 0, r) {
        (false, _) => (magnitude, q, r),
        (true, 0) => (-magnitude, -q, 0),
        (true, r) => (-magnitude, -q - 1, n - r),
    }
}

/// Raw sums `(sum x, sum x^2)` of one axis (`axis` of each value) of a block of `i16` samples (at most `2^16`: the `i32` sum
/// is exact, `2^16 * 2^15 = 2^31`, and so is every partial sum), eight samples per step (their loads
/// pipeline on a Cortex-M4); each square (at most `2^30`) is one multiply-accumulate into the `i64`
/// (`smlal`). Raw sums of a pose stay exact in `i64`: at most `2^31` samples, `2^31 * 2^30 = 2^61`.
#[inline(always)]
fn raw_i16_axis_sums(samples: &[[i16; 3]], axis: usize) -> (i32, i64) {
    let (mut sum, mut sum_sq) = (0i32, 0i64);
    let axis = axis % 3;
    let (eights, rest) = samples.as_chunks::<8>();
    for s in eights {
        let (a, b, c, d) = (i64::from(s[0][axis]), i64::from(s[1][axis]), i64::from(s[2][axis]), i64::from(s[3][axis]));
        let (e, f, g, h) = (i64::from(s[4][axis]), i64::from(s[5][axis]), i64::from(s[6][axis]), i64::from(s[7][axis]));
        sum += (((a + b) + (c + d)) + ((e + f) + (g + h))) as i32;
        sum_sq += a * a + b * b + c * c + d * d;
        sum_sq += e * e + f * f + g * g + h * h;
    }
    for v in rest {
        let x = i64::from(v[axis]);
        sum += x as i32;
        sum_sq += x * x;
    }
    (sum, sum_sq)
}

/// One axis of a block of at most `2^16` samples: raw `(sum, sum of squares, saturated)`, the saturation
/// by the block's bound ([`i16_may_saturate`], from the exact `n^2` variance `n sum_sq - sum^2`) and only
/// then sample by sample, as for a full block.
#[inline(always)]
fn i16_axis_chunk(values: &[i16], limit: i32) -> (i32, i64, bool) {
    let (mut sum, mut sum_sq) = (0i32, 0i64);
    for &v in values {
        (sum, sum_sq) = (sum + i32::from(v), sum_sq + i64::from(v) * i64::from(v));
    }
    let n = values.len();
    let spread = (n as i64 * sum_sq - i64::from(sum) * i64::from(sum)) as u64;
    let saturated = i16_may_saturate(sum.unsigned_abs(), spread, n, limit) && i16_any_saturated(values, limit);
    (sum, sum_sq, saturated)
}

/// The raw sums of a full block of samples, axis after axis: `sum` and `sum_sq` written, the total `n^2`
/// variance `sum_a (n sum_sq_a - sum_a^2)` returned (exact: each term at most `2^62`, three fit a `u64`).
/// Inlined into the block close (one call fewer per axis than an out-of-line axis function); each axis
/// loop keeps its eight values and running sums in registers (the samples are read with a stride).
#[inline(always)]
fn i16_block_sums(samples: &[[i16; 3]], sum: &mut [i64; 3], sum_sq: &mut [i64; 3]) -> u64 {
    for a in 0..3 {
        let (s, q) = raw_i16_axis_sums(samples, a);
        (sum[a], sum_sq[a]) = (i64::from(s), q);
    }
    // sum_a (n sum_sq_a - sum_a^2) = n sum_a sum_sq_a - sum_a sum_a^2: each block sum fits an i32, each
    // square and the result (at most 3 2^62) a u64, which holds the intermediate terms modulo 2^64.
    let square = |s: i64| (i64::from(s as i32) * i64::from(s as i32)) as u64;
    let squares = square(sum[0]) + square(sum[1]) + square(sum[2]);
    let total_sq = (sum_sq[0] + sum_sq[1] + sum_sq[2]) as u64;
    (samples.len() as u64).wrapping_mul(total_sq).wrapping_sub(squares)
}

/// `false` when no sample of a block of `n` samples (one axis or three) can be saturated, from the
/// largest `|sum|` of its axes and its total `n^2` variance `spread` (exact integers): on every axis
/// `sum_i (n x_i - sum)^2 = n spread_axis <= n spread`, so every `|n x_i| <= |sum| + sqrt(n spread)`, and
/// none reaches `min(limit, i16::MAX)` (nor a rail) when `margin = n min(limit, i16::MAX) - max |sum| > 0`
/// and `margin^2 > n spread`. Only otherwise are the samples checked.
#[inline(always)]
fn i16_may_saturate(largest: u32, spread: u64, n: usize, limit: i32) -> bool {
    // n min(limit, i16::MAX) < 2^16 2^15 = 2^31.
    let reach = n as u32 * limit.clamp(0, i32::from(i16::MAX)) as u32;
    let margin = u64::from(reach.saturating_sub(largest));
    margin == 0 || spread.checked_mul(n as u64).is_none_or(|t| t >= margin * margin)
}

/// The largest `|sum|` of a block's three raw sums (each fits an `i32`: at most `2^16` samples of at most
/// `2^15`).
#[inline(always)]
fn largest_magnitude(sum: &[i64; 3]) -> u32 {
    let magnitude = |s: i64| (s as i32).unsigned_abs();
    magnitude(sum[0]).max(magnitude(sum[1])).max(magnitude(sum[2]))
}

/// Whether one of `values` is saturated at `limit` ([`Reading::saturated`]): at or beyond
/// `min(limit, i16::MAX)` or at or below `-min(limit, 2^15)` (the rails included), one unsigned
/// comparison per value.
#[inline(always)]
fn i16_any_saturated(values: &[i16], limit: i32) -> bool {
    let (high, low) = (limit.clamp(0, i32::from(i16::MAX)), -limit.clamp(0, 1 << 15));
    // Not saturated: low < v < high, i.e. 0 <= v - low - 1 < high - low - 1.
    let inside = (high - low - 1).max(0) as u32;
    values.iter().any(|&v| (i32::from(v) - low - 1) as u32 >= inside)
}

impl Reading for i16 {
    type Sum = i64;
    const QUANTUM_VARIANCE: f32 = 3.0 / 12.0;
    // Every axis mean lies within [-2^15, 2^15] (3 2^30), with room for the f32 rounding of the means.
    const MAX_MAGNITUDE_SQ: f32 = 4.0 * 32_768.0 * 32_768.0;
    const RELATIVE: bool = false;
    fn block_reference(_first: i16) -> i16 {
        0
    }
    #[inline]
    fn delta(self, reference: Self) -> i64 {
        i64::from(self) - i64::from(reference)
    }
    fn count(n: u32) -> i64 {
        i64::from(n)
    }
    /// Any number of samples (exact below `2^33`, where the sum of squares could reach `2^63`), in
    /// chunks of `2^16` samples: [`i16_axis_chunk`]'s `i32` sum and saturation pre-test are exact there.
    fn axis_sums(values: &[i16], limit: i32) -> (i64, i64, bool) {
        let (mut sum, mut sum_sq, mut saturated) = (0i64, 0i64, false);
        for chunk in values.chunks(1 << 16) {
            let (s, q, chunk_saturated) = i16_axis_chunk(chunk, limit);
            (sum, sum_sq) = (sum + i64::from(s), sum_sq + q);
            saturated |= chunk_saturated;
        }
        (sum, sum_sq, saturated)
    }
    #[inline(always)]
    fn full_block<const N: usize>(
        samples: &[[i16; 3]; N],
        limit: i32,
        sum: &mut [i64; 3],
        sum_sq: &mut [i64; 3],
    ) -> ([f32; 3], f32, bool) {
        let n_inverse = 1.0 / N as f32;
        // The three axes' n^2 variances (each at most 2^62) fit a u64.
        let n_squared_variance = i16_block_sums(samples, sum, sum_sq);
        // A block's raw sum fits an i32 (at most 2^16 samples of at most 2^15).
        let mean_of = |s: i64| s as i32 as f32 * n_inverse;
        let mean = [mean_of(sum[0]), mean_of(sum[1]), mean_of(sum[2])];
        let variance = u64_to_f32_halves(n_squared_variance) * n_inverse * n_inverse;
        let saturated = i16_may_saturate(largest_magnitude(sum), n_squared_variance, N, limit)
            && i16_any_saturated(samples.as_flattened(), limit);
        (mean, variance, saturated)
    }
    fn mean_and_variance(reference: i16, sum: i64, sum_sq: i64, n: u32) -> (f32, f32) {
        let count = n.max(1);
        let reference = i64::from(reference);
        // total = q_total n + rem with 0 <= rem < n; the samples' sum relative to the reference is
        // sum = total - n reference = q n + rem with q = q_total - reference (the same remainder).
        let (mean, q_total, rem) = mean_and_floor_div(i64::from(count) * reference + sum, count);
        let q = q_total - reference;
        // Squares about reference + q, exactly: sum (d - q)^2 = sum_sq - 2 q sum + n q^2
        // = sum_sq - q (2 sum - n q) = sum_sq - q (sum + rem), as n q = sum - rem. It is below 2^63 and
        // computed modulo 2^64, so a wrapped intermediate term cancels exactly.
        let about_q = sum_sq.wrapping_sub(q.wrapping_mul(sum.wrapping_add(i64::from(rem))));
        let fraction = rem as f32 / count as f32;
        // about_q is a sum of squares: not negative.
        let variance = u64_to_f32_halves(about_q as u64) / count as f32 - fraction * fraction;
        (mean, if variance > 0.0 { variance } else { 0.0 })
    }
    #[inline]
    fn to_f32(self) -> f32 {
        f32::from(self)
    }
    #[inline]
    fn is_finite(self) -> bool {
        true
    }
    type Limit = i32;
    fn saturation_limit(full_scale: f32) -> i32 {
        // |x| >= full_scale  <=>  |x| >= ceil(full_scale) for integer x; beyond the type: never.
        if full_scale > 32_768.0 { 32_769 } else { libm::ceilf(if full_scale > 0.0 { full_scale } else { 0.0 }) as i32 }
    }
    #[inline]
    fn saturated(self, limit: i32) -> bool {
        self == i16::MIN || self == i16::MAX || i32::from(self).abs() >= limit
    }
}

impl Reading for f32 {
    type Sum = f64;
    const QUANTUM_VARIANCE: f32 = 0.0;
    const RELATIVE: bool = true;
    fn block_reference(first: f32) -> f32 {
        first
    }
    #[inline]
    fn delta(self, reference: Self) -> f64 {
        f64::from(self) - f64::from(reference)
    }
    fn count(n: u32) -> f64 {
        f64::from(n)
    }
    fn axis_sums(values: &[f32], limit: f32) -> (f64, f64, bool) {
        f32_axis_sums(values.iter().copied(), limit)
    }
    fn mean_and_variance(reference: f32, sum: f64, sum_sq: f64, n: u32) -> (f32, f32) {
        let n = f64::from(n.max(1));
        let m = sum / n;
        let variance = sum_sq / n - m * m;
        ((f64::from(reference) + m) as f32, if variance > 0.0 { variance as f32 } else { 0.0 })
    }
    fn full_block<const N: usize>(
        samples: &[[f32; 3]; N],
        limit: f32,
        sum: &mut [f64; 3],
        sum_sq: &mut [f64; 3],
    ) -> ([f32; 3], f32, bool) {
        let n_inverse = 1.0 / N as f32;
        let (mut mean, mut variance, mut saturated) = ([0.0; 3], 0.0, false);
        for a in 0..3 {
            let axis = f32_axis_sums(samples.iter().map(|s| s[a]), limit);
            (sum[a], sum_sq[a]) = (axis.0, axis.1);
            saturated |= axis.2;
            mean[a] = sum[a] as f32 * n_inverse;
            let v = sum_sq[a] as f32 * n_inverse - mean[a] * mean[a];
            variance += if v > 0.0 { v } else { 0.0 };
        }
        (mean, variance, saturated)
    }
    fn to_f32(self) -> f32 {
        self
    }
    #[inline]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
    type Limit = f32;
    fn saturation_limit(full_scale: f32) -> f32 {
        full_scale
    }
    #[inline]
    fn saturated(self, limit: f32) -> bool {
        self.abs() >= limit
    }
}

/// One axis of `f32` samples: `(sum, sum of squares, saturated)` relative to the first sample, in `f64`.
fn f32_axis_sums(mut values: impl Iterator<Item = f32> + Clone, limit: f32) -> (f64, f64, bool) {
    let (mut sum, mut sum_sq, mut saturated) = (0.0, 0.0, false);
    let Some(first) = values.clone().next() else { return (sum, sum_sq, saturated) };
    for v in &mut values {
        let d = v.delta(first);
        sum += d;
        sum_sq += d * d;
        saturated |= v.saturated(limit);
    }
    (sum, sum_sq, saturated)
}

/// `f32::max` as a comparison: the other value when one is NaN.
#[inline]
fn max_f32(a: f32, b: f32) -> f32 {
    if b > a || a.is_nan() { b } else { a }
}

/// One static position: the average of its samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Pose {
    /// Per-axis mean, input unit.
    pub mean: [f32; 3],
    /// Per-axis sample variance (population, divided by `n`), input unit squared.
    pub variance: [f32; 3],
    /// Number of samples averaged.
    pub n: u32,
    /// Index (from 0, counting every sample pushed) of the first sample averaged.
    pub start_index: u32,
    /// Index one past the last sample averaged.
    pub end_index: u32,
}

impl Pose {
    /// A pose from a mean alone (e.g. published per-pose means), with unknown variance and `n`.
    pub const fn from_mean(mean: [f32; 3], n: u32) -> Self {
        Self { mean, variance: [0.0; 3], n, start_index: 0, end_index: 0 }
    }

    /// Start time in seconds at a fixed `sample_rate_hz`.
    pub fn start_time_s(&self, sample_rate_hz: f32) -> f32 {
        self.start_index as f32 / sample_rate_hz
    }

    /// End time in seconds at a fixed `sample_rate_hz`.
    pub fn end_time_s(&self, sample_rate_hz: f32) -> f32 {
        self.end_index as f32 / sample_rate_hz
    }
}

/// Why a static interval was not kept as a pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Rejection {
    /// Fewer samples than `min_pose_samples`.
    TooShort,
    /// A sample reached full scale: the mean is clipped.
    Saturated,
    /// The interval's own variance is well above the noise: it moved.
    Moving,
}

/// What a pushed sample completed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Event {
    /// A static interval began (a pose is being averaged).
    StillnessDetected,
    /// A pose was captured and stored at this index of [`Accumulator::poses`] (`u16`: the whole
    /// `Result<Option<Event>, AccumulatorError>` of a push fits in one register).
    PoseCaptured(u16),
    /// A static interval ended and was not kept.
    PoseRejected(Rejection),
}

/// Rejected intervals so far, by reason.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rejections {
    /// Too short.
    pub too_short: u32,
    /// Saturated.
    pub saturated: u32,
    /// Moving.
    pub moving: u32,
}

/// Accumulator errors. The accumulator's state and its poses are unchanged by an `Err`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum AccumulatorError {
    /// A sample was NaN or infinite; it was skipped.
    NonFiniteSample,
    /// A pose was completed but all `POSES` places are taken; it was dropped, the stored ones are kept.
    Full,
    /// A configuration value is out of range (see [`AccumulatorConfig::validate`]).
    InvalidConfig,
}

impl core::fmt::Display for AccumulatorError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::NonFiniteSample => f.write_str("non-finite sample skipped"),
            Self::Full => f.write_str("pose capacity is full; the new pose was dropped"),
            Self::InvalidConfig => f.write_str("accumulator configuration out of range"),
        }
    }
}

impl core::error::Error for AccumulatorError {}

/// Static-detection settings. Variances are sums over the three axes, in input unit squared.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AccumulatorConfig {
    /// Shortest pose kept, samples. Defaults to 100.
    pub min_pose_samples: u32,
    /// A block is quiet enough to open a pose when its variance is below this multiple of the noise.
    /// Defaults to 4.
    pub enter_factor: f32,
    /// An open pose closes when a block's variance exceeds this multiple of the noise. Defaults to 9.
    pub exit_factor: f32,
    /// Block-to-block mean change (squared, in units of its expected noise `2 noise / BLOCK`) that still
    /// opens a pose. Defaults to 9.
    pub drift_enter_factor: f32,
    /// Block-to-block mean change that closes an open pose. Defaults to 25.
    pub drift_exit_factor: f32,
    /// Absolute reading (input unit) at which a sample counts as saturated. Defaults to infinity
    /// (`i16` readings at the type's rails always count).
    pub full_scale: f32,
    /// Smallest noise variance assumed, input unit squared. Defaults to 0 (the quantisation floor of the
    /// reading type and the quiet blocks decide).
    pub min_noise_variance: f32,
    /// The noise level follows a quieter block down at once and otherwise rises by this fraction per
    /// block, so it tracks a low percentile of the block variances rather than an ever-falling minimum
    /// (which would shut out holds that are a little noisier than the quietest one, e.g. hand-held).
    /// Defaults to 0.02.
    pub noise_rise_per_block: f32,
}

impl AccumulatorConfig {
    /// The documented defaults.
    pub const DEFAULT: Self = Self {
        min_pose_samples: 100,
        enter_factor: 4.0,
        exit_factor: 9.0,
        drift_enter_factor: 9.0,
        drift_exit_factor: 25.0,
        full_scale: f32::INFINITY,
        min_noise_variance: 0.0,
        noise_rise_per_block: 0.02,
    };

    /// Checks that every factor is finite and positive, exits are not below entries, and the noise
    /// floor and rise are finite and not negative.
    pub fn validate(&self) -> Result<(), AccumulatorError> {
        // Plain comparisons (every one is false for NaN): smaller than `is_finite` on a Cortex-M4F.
        let below_infinity = |v: f32| v < f32::INFINITY;
        let ok = self.enter_factor > 0.0
            && self.drift_enter_factor > 0.0
            && self.exit_factor >= self.enter_factor
            && below_infinity(self.exit_factor)
            && self.drift_exit_factor >= self.drift_enter_factor
            && below_infinity(self.drift_exit_factor)
            && self.full_scale > 0.0
            && self.min_noise_variance >= 0.0
            && below_infinity(self.min_noise_variance)
            && self.noise_rise_per_block >= 0.0
            && below_infinity(self.noise_rise_per_block);
        if ok { Ok(()) } else { Err(AccumulatorError::InvalidConfig) }
    }
}

impl Default for AccumulatorConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Sums of one block or one pose, relative to a reference sample.
#[derive(Clone, Copy)]
struct Sums<R: Reading> {
    reference: [R; 3],
    sum: [R::Sum; 3],
    sum_sq: [R::Sum; 3],
    n: u32,
    start_index: u32,
    /// Index one past the last sample summed (skipped non-finite samples lie between start and end).
    end_index: u32,
    saturated: bool,
}

impl<R: Reading> Sums<R> {
    fn new(reference: [R; 3], start_index: u32) -> Self {
        Self {
            reference,
            sum: [R::Sum::default(); 3],
            sum_sq: [R::Sum::default(); 3],
            n: 0,
            start_index,
            end_index: start_index,
            saturated: false,
        }
    }

    /// Adds `other` (relative to its own reference; raw sums when not [`Reading::RELATIVE`]) to these
    /// sums, exactly. A merge that would take the
    /// count above [`MAX_POSE_SAMPLES`] is not made: the count saturates and the sums stay exact.
    #[inline(always)]
    fn merge(&mut self, other: &Self) {
        if other.n > MAX_POSE_SAMPLES - self.n.min(MAX_POSE_SAMPLES) {
            return;
        }
        self.end_index = other.end_index;
        self.n += other.n;
        self.saturated |= other.saturated;
        if !R::RELATIVE {
            // Raw sums: both references are zero. Six additions, unrolled (no loop).
            let (sum, sum_sq) = (&mut self.sum, &mut self.sum_sq);
            (sum[0], sum[1], sum[2]) = (sum[0] + other.sum[0], sum[1] + other.sum[1], sum[2] + other.sum[2]);
            (sum_sq[0], sum_sq[1]) = (sum_sq[0] + other.sum_sq[0], sum_sq[1] + other.sum_sq[1]);
            sum_sq[2] += other.sum_sq[2];
            return;
        }
        let n = R::count(other.n);
        for a in 0..3 {
            let shift = other.reference[a].delta(self.reference[a]);
            self.sum_sq[a] += other.sum_sq[a] + (other.sum[a] * shift + other.sum[a] * shift) + n * shift * shift;
            self.sum[a] += other.sum[a] + n * shift;
        }
    }

    fn pose(&self) -> Pose {
        let (n, start_index, end_index) = (self.n, self.start_index, self.end_index);
        let mut pose = Pose { mean: [0.0; 3], variance: [0.0; 3], n, start_index, end_index };
        for a in 0..3 {
            // Raw sums have a zero reference (folded away at compile time).
            let reference = if R::RELATIVE { self.reference[a] } else { R::default() };
            (pose.mean[a], pose.variance[a]) = R::mean_and_variance(reference, self.sum[a], self.sum_sq[a], n);
        }
        pose
    }
}

/// A block's summary: mean and total variance.
#[derive(Clone, Copy)]
struct BlockStats<R: Reading> {
    sums: Sums<R>,
    mean: [f32; 3],
    variance: f32,
}

/// The accumulator: up to `POSES` poses, static detection on blocks of `BLOCK` samples.
pub struct Accumulator<R: Reading, const POSES: usize, const BLOCK: usize> {
    config: AccumulatorConfig,
    poses: heapless::Vec<Pose, POSES>,
    rejections: Rejections,
    /// The open block's samples, summed when it is full (a push only stores its sample).
    buffer: [[R; 3]; BLOCK],
    /// Samples in `buffer`.
    buffered: usize,
    /// Index of the open block's first sample.
    block_start: u32,
    saturation_limit: R::Limit,
    /// The last two blocks, written in turn (no copies): `blocks[previous_slot]` is the delay line (while a
    /// pose is open it is merged in only once the next block is still too), valid if `has_previous`.
    blocks: [BlockStats<R>; 2],
    previous_slot: usize,
    has_previous: bool,
    pose: Option<Sums<R>>,
    noise_variance: f32,
    /// The noise variance's fixed floor: `max(min_noise_variance, R::QUANTUM_VARIANCE)`.
    noise_floor: f32,
    /// `1 + noise_rise_per_block`.
    noise_rise_factor: f32,
    /// Samples seen (saturating), except those in `buffer`.
    counted: u32,
}

impl<R: Reading, const POSES: usize, const BLOCK: usize> Accumulator<R, POSES, BLOCK> {
    const VALID: () = {
        assert!(BLOCK >= 4, "a block needs at least 4 samples to estimate a variance");
        assert!(BLOCK <= 1 << 16, "a block is summed in 32 bits: at most 65536 samples");
        assert!(POSES <= 1 << 16, "a pose index is a u16: at most 65536 poses");
    };

    /// An empty accumulator.
    pub fn new(config: AccumulatorConfig) -> Result<Self, AccumulatorError> {
        let () = Self::VALID;
        config.validate()?;
        Ok(Self {
            config,
            poses: heapless::Vec::new(),
            rejections: Rejections::default(),
            buffer: [[R::default(); 3]; BLOCK],
            buffered: 0,
            block_start: 0,
            saturation_limit: R::saturation_limit(config.full_scale),
            blocks: [BlockStats { sums: Sums::new([R::default(); 3], 0), mean: [0.0; 3], variance: 0.0 }; 2],
            previous_slot: 0,
            has_previous: false,
            pose: None,
            noise_variance: f32::INFINITY,
            noise_floor: max_f32(config.min_noise_variance, R::QUANTUM_VARIANCE),
            noise_rise_factor: 1.0 + config.noise_rise_per_block,
            counted: 0,
        })
    }

    /// Feeds one sample (x, y, z in the input unit).
    #[inline]
    pub fn push(&mut self, sample: [R; 3]) -> Result<Option<Event>, AccumulatorError> {
        if !(sample[0].is_finite() && sample[1].is_finite() && sample[2].is_finite()) {
            return Err(self.skip_sample());
        }
        // Always below BLOCK (a full buffer is summed at once); a power-of-two BLOCK is masked instead of
        // checked (no branch on the hot path).
        let i = if BLOCK.is_power_of_two() { self.buffered & (BLOCK - 1) } else { self.buffered };
        if i >= BLOCK {
            self.drop_block();
            return Ok(None);
        }
        self.buffered = i + 1;
        self.buffer[i] = sample;
        if i + 1 == BLOCK {
            return self.close_block(None);
        }
        Ok(None)
    }

    /// [`Accumulator::push`] for micromath's vector types (`I16x3`, `F32x3`), which the embedded
    /// sensor-driver ecosystem returns.
    #[cfg(feature = "micromath")]
    #[inline]
    pub fn push_vector(&mut self, v: micromath::vector::Vector3d<R>) -> Result<Option<Event>, AccumulatorError>
    where
        R: micromath::vector::Component,
    {
        self.push([v.x, v.y, v.z])
    }

    /// Marks a gap in the stream (e.g. a sensor read error): the open block is dropped and an open pose
    /// is closed as if motion had started. Poses already stored are kept.
    pub fn interrupt(&mut self) -> Result<Option<Event>, AccumulatorError> {
        self.drop_block();
        self.has_previous = false;
        self.close_pose()
    }

    /// Ends the stream: a pose still open is closed with every quiet block it has (no motion followed).
    pub fn finish(&mut self) -> Result<Option<Event>, AccumulatorError> {
        self.drop_block();
        if let (Some(pose), true) = (self.pose.as_mut(), self.has_previous) {
            pose.merge(&self.blocks[self.previous_slot % 2].sums);
        }
        self.has_previous = false;
        self.close_pose()
    }

    /// Counts a skipped non-finite sample (out of line: not the hot path).
    #[inline(never)]
    fn skip_sample(&mut self) -> AccumulatorError {
        self.counted = self.counted.saturating_add(1);
        if self.buffered == 0 {
            self.block_start = self.counted;
        }
        AccumulatorError::NonFiniteSample
    }

    /// Drops the open block's samples; the next block starts at the next sample.
    fn drop_block(&mut self) {
        self.counted = self.samples_seen();
        self.buffered = 0;
        self.block_start = self.counted;
    }

    /// Feeds the samples of `samples` in order, as [`Accumulator::push`] of each would, up to and
    /// including the first that completes an event or is refused: returns how many samples were taken
    /// and that push's result (`Ok(None)` when all were taken without an event). Call it again with the
    /// rest. Whole blocks of the slice are summed where they lie (no copy, no per-sample bookkeeping):
    /// the fast path for a sensor FIFO read. The events, poses and statistics are bit for bit those of
    /// pushing one sample at a time.
    pub fn push_slice(&mut self, samples: &[[R; 3]]) -> (usize, Result<Option<Event>, AccumulatorError>) {
        let mut taken = 0;
        while let Some(rest) = samples.get(taken..) {
            if let (0, Some(block)) = (self.buffered, rest.first_chunk::<BLOCK>())
                && block.iter().flatten().all(|v| v.is_finite())
            {
                taken += BLOCK;
                let event = self.close_block(Some(block));
                if !matches!(event, Ok(None)) {
                    return (taken, event);
                }
                continue;
            }
            let Some(&sample) = rest.first() else { break };
            taken += 1;
            let event = self.push(sample);
            if !matches!(event, Ok(None)) {
                return (taken, event);
            }
        }
        (taken, Ok(None))
    }

    /// Sums the full `block` into `stats` with its statistics (mean, total variance, which it returns,
    /// and whether a sample is saturated); the index span is set after.
    #[inline(always)]
    fn sum_block(stats: &mut BlockStats<R>, block: &[[R; 3]; BLOCK], limit: R::Limit) -> ([f32; 3], f32, bool) {
        let sums = &mut stats.sums;
        let (mut mean, variance, saturated) = R::full_block(block, limit, &mut sums.sum, &mut sums.sum_sq);
        // Raw sums keep the zero reference set by `new` (no store, no `+ 0.0` at run time).
        if R::RELATIVE {
            for (a, (m, reference)) in mean.iter_mut().zip(&mut sums.reference).enumerate() {
                *reference = R::block_reference(block[0][a]);
                *m += reference.to_f32();
            }
        }
        (stats.mean, stats.variance) = (mean, variance);
        (mean, variance, saturated)
    }

    /// Closes the full block: the buffer's (`None`), or a whole block of the caller's samples while the
    /// buffer is empty. Once per BLOCK samples: kept out of line so that `push`, inlined into the
    /// caller's sample loop, stays small (inlined, its register pressure made every push save and
    /// restore all FPU registers). The samples are summed first, the bookkeeping done after (nothing of
    /// it is kept across the summing loops).
    #[inline(never)]
    fn close_block(&mut self, whole: Option<&[[R; 3]; BLOCK]>) -> Result<Option<Event>, AccumulatorError> {
        let slot = (self.previous_slot + 1) % 2;
        let block = whole.unwrap_or(&self.buffer);
        let (mean, variance, saturated) = Self::sum_block(&mut self.blocks[slot], block, self.saturation_limit);
        // The block's samples are BLOCK from `block_start` (all in the buffer, or none when whole).
        let start_index = self.block_start;
        self.buffered = BLOCK;
        self.drop_block();
        let sums = &mut self.blocks[slot].sums;
        (sums.n, sums.start_index, sums.end_index, sums.saturated) =
            (BLOCK as u32, start_index, self.counted, saturated);
        self.judge_block(slot, mean, variance)
    }

    /// The pose logic after a block of this mean and variance was summed into `blocks[slot]`.
    fn judge_block(&mut self, slot: usize, mean: [f32; 3], variance: f32) -> Result<Option<Event>, AccumulatorError> {
        let noise = self.update_noise(mean, variance);
        let previous = &self.blocks[self.previous_slot % 2];
        let drift = self.has_previous.then(|| {
            let d = [mean[0] - previous.mean[0], mean[1] - previous.mean[1], mean[2] - previous.mean[2]];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) * (BLOCK as f32 * 0.5) / noise
        });
        let event = if self.pose.is_some() {
            let still = variance <= self.config.exit_factor * noise
                && drift.is_some_and(|d| d <= self.config.drift_exit_factor);
            self.continue_pose(still)
        } else {
            let quiet = variance <= self.config.enter_factor * noise
                && drift.is_some_and(|d| d <= self.config.drift_enter_factor);
            Ok(self.open_pose(quiet, noise))
        };
        (self.previous_slot, self.has_previous) = (slot, true);
        event
    }

    /// The noise variance after a block of this mean and variance (a leaky minimum, above the floor).
    fn update_noise(&mut self, mean: [f32; 3], variance: f32) -> f32 {
        const RELATIVE_FLOOR: f32 = 1e-12;
        // Infinite before the first block: it stays so (the factor is finite and at least 1).
        let risen = self.noise_variance * self.noise_rise_factor;
        let floor = if RELATIVE_FLOOR * R::MAX_MAGNITUDE_SQ < R::QUANTUM_VARIANCE {
            // The relative term is below the quantum, itself at most the floor: it cannot win.
            self.noise_floor
        } else {
            let magnitude_sq = mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2];
            max_f32(self.noise_floor, RELATIVE_FLOOR * magnitude_sq)
        };
        // As max_f32(min_f32(risen, variance), floor), without the NaN tests: `risen` is never NaN (the
        // noise starts infinite, is never NaN after an update, and its factor is finite and at least 1),
        // so a NaN variance leaves `risen` in both forms, and the floor compares with a number.
        let lower = if variance < risen { variance } else { risen };
        self.noise_variance = if floor > lower { floor } else { lower };
        self.noise_variance
    }

    /// An open pose: the last block is merged in if this one is still too; else the pose closes.
    fn continue_pose(&mut self, still: bool) -> Result<Option<Event>, AccumulatorError> {
        if !still {
            return self.close_pose();
        }
        if let (Some(pose), true) = (self.pose.as_mut(), self.has_previous) {
            pose.merge(&self.blocks[self.previous_slot % 2].sums);
        }
        Ok(None)
    }

    /// Two quiet blocks in a row with little change between them open a pose (with the first of them).
    fn open_pose(&mut self, quiet: bool, noise: f32) -> Option<Event> {
        let last = &self.blocks[self.previous_slot % 2];
        if !(self.has_previous && quiet && last.variance <= self.config.enter_factor * noise) {
            return None;
        }
        // A block (BLOCK <= 2^16 samples) merged into an empty pose of its reference: the block's sums,
        // copied field by field in place (each copy inlined; the whole struct's was a memcpy call).
        let last = &last.sums;
        let pose = self.pose.insert(Sums::new(last.reference, last.start_index));
        (pose.sum, pose.sum_sq) = (last.sum, last.sum_sq);
        (pose.n, pose.end_index, pose.saturated) = (last.n, last.end_index, last.saturated);
        Some(Event::StillnessDetected)
    }

    fn close_pose(&mut self) -> Result<Option<Event>, AccumulatorError> {
        let Some(sums) = &self.pose else {
            return Ok(None);
        };
        let (pose, saturated) = (sums.pose(), sums.saturated);
        self.pose = None;
        // Above this total variance the pose moved.
        let moving = self.config.exit_factor * self.noise_variance;
        let rejection = if saturated {
            Some(Rejection::Saturated)
        } else if pose.n < self.config.min_pose_samples {
            Some(Rejection::TooShort)
        } else if pose.variance[0] + pose.variance[1] + pose.variance[2] > moving {
            Some(Rejection::Moving)
        } else {
            None
        };
        if let Some(reason) = rejection {
            let counter = match reason {
                Rejection::TooShort => &mut self.rejections.too_short,
                Rejection::Saturated => &mut self.rejections.saturated,
                Rejection::Moving => &mut self.rejections.moving,
            };
            *counter = counter.saturating_add(1);
            return Ok(Some(Event::PoseRejected(reason)));
        }
        self.poses.push(pose).map_err(|_| AccumulatorError::Full)?;
        // At most POSES <= 2^16 poses (VALID): the index fits.
        Ok(Some(Event::PoseCaptured((self.poses.len() - 1) as u16)))
    }

    /// The poses captured so far.
    pub fn poses(&self) -> &[Pose] {
        &self.poses
    }

    /// Removes pose `index` (e.g. a duplicate orientation); `None` if there is no such pose.
    pub fn remove_pose(&mut self, index: usize) -> Option<Pose> {
        (index < self.poses.len()).then(|| self.poses.remove(index))
    }

    /// Rejected intervals so far.
    pub fn rejections(&self) -> Rejections {
        self.rejections
    }

    /// The noise variance (sum over axes, input unit squared) the thresholds are scaled to; infinite
    /// before the first block.
    pub fn noise_variance(&self) -> f32 {
        self.noise_variance
    }

    /// Samples pushed so far (including skipped non-finite ones).
    pub fn samples_seen(&self) -> u32 {
        self.counted.saturating_add(self.buffered as u32)
    }

    /// `true` while a pose is being averaged.
    pub fn is_capturing(&self) -> bool {
        self.pose.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    extern crate std;
    use std::vec::Vec;

    #[test]
    fn pose_count_saturates_and_its_sums_stay_exact() {
        // A pose that has averaged nearly MAX_POSE_SAMPLES samples (2^31 would take 124 days at 200 Hz).
        let mut pose = Sums::<i16>::new([0; 3], 0);
        pose.n = MAX_POSE_SAMPLES - 10;
        pose.sum = [5; 3];
        pose.sum_sq = [7; 3];
        // i16 sums are raw: a block of samples at 100.
        let mut block = Sums::<i16>::new([0; 3], 50);
        (block.n, block.sum, block.sum_sq) = (32, [3200; 3], [320_000; 3]);
        block.end_index = 82;
        pose.merge(&block);
        assert_eq!(pose.n, MAX_POSE_SAMPLES - 10, "a merge past the limit is not made");
        assert_eq!((pose.sum, pose.sum_sq), ([5; 3], [7; 3]));
        (block.n, block.sum, block.sum_sq) = (10, [1000; 3], [100_000; 3]);
        pose.merge(&block);
        assert_eq!(pose.n, MAX_POSE_SAMPLES);
        assert_eq!((pose.sum[0], pose.sum_sq[0]), (5 + 10 * 100, 7 + 10 * 100 * 100));
        assert_eq!(pose.end_index, 82);
        pose.merge(&block);
        assert_eq!(pose.n, MAX_POSE_SAMPLES, "the count saturates");
    }

    #[test]
    fn configs_with_nan_infinite_or_negative_values_are_refused() {
        assert_eq!(AccumulatorConfig::DEFAULT.validate(), Ok(()));
        let fields: [fn(&mut AccumulatorConfig) -> &mut f32; 7] = [
            |c| &mut c.enter_factor,
            |c| &mut c.exit_factor,
            |c| &mut c.drift_enter_factor,
            |c| &mut c.drift_exit_factor,
            |c| &mut c.full_scale,
            |c| &mut c.min_noise_variance,
            |c| &mut c.noise_rise_per_block,
        ];
        for (i, field) in fields.iter().enumerate() {
            for bad in [f32::NAN, -1.0, f32::NEG_INFINITY] {
                let mut config = AccumulatorConfig::DEFAULT;
                *field(&mut config) = bad;
                assert_eq!(config.validate(), Err(AccumulatorError::InvalidConfig), "field {i} = {bad}");
            }
            let mut config = AccumulatorConfig::DEFAULT;
            *field(&mut config) = f32::INFINITY;
            // Only the saturation limit may be infinite (no limit).
            assert_eq!(config.validate().is_ok(), i == 4, "field {i} infinite");
        }
    }

    #[test]
    fn sample_index_saturates() {
        let mut acc: Accumulator<i16, 4, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
        acc.counted = u32::MAX - 40;
        for _ in 0..64 {
            acc.push([1, 2, 3]).unwrap();
        }
        assert_eq!(acc.samples_seen(), u32::MAX);
        acc.finish().unwrap();
    }

    /// The `f32` nearest to `total / n` (ties to even), found exactly: of the `f64` quotient's `f32`
    /// and its two neighbours, the one whose distance `|v n - total|` is least, compared in `i128`.
    fn nearest_f32(total: i64, n: u32) -> f32 {
        let parts = |v: f32| -> (i128, i32) {
            let bits = v.to_bits();
            let (exponent, fraction) = ((bits >> 23) & 0xFF, i128::from(bits & 0x7F_FFFF));
            let m = if exponent == 0 { fraction } else { fraction | 0x80_0000 };
            (if v < 0.0 { -m } else { m }, exponent.max(1) as i32 - 150)
        };
        if total == 0 {
            return 0.0;
        }
        let guess = (total as f64 / f64::from(n)) as f32;
        let candidates = [guess.next_down(), guess, guess.next_up()];
        let lowest = candidates.iter().map(|&v| parts(v).1).min().unwrap().min(0);
        let distance = |v: f32| {
            let (m, e) = parts(v);
            (m * i128::from(n) * (1i128 << (e - lowest)) - i128::from(total) * (1i128 << -lowest)).abs()
        };
        let best = |a: f32, b: f32| match distance(a).cmp(&distance(b)) {
            core::cmp::Ordering::Less => a,
            core::cmp::Ordering::Greater => b,
            core::cmp::Ordering::Equal => {
                if parts(a).0 % 2 == 0 {
                    a
                } else {
                    b
                }
            }
        };
        best(best(candidates[0], candidates[1]), candidates[2])
    }

    /// The `i16` pose statistics as first written (the floor division by the compiler's 64-bit
    /// division, the squares about `q` as `sum_sq - 2 q sum + n q^2`): the oracle of the variance.
    fn reference_variance(sum: i64, sum_sq: i64, n: u32) -> f32 {
        let count = n.max(1);
        let n = i64::from(count);
        let (q, rem) = (sum.div_euclid(n), sum.rem_euclid(n));
        let about_q = sum_sq.wrapping_sub(q.wrapping_mul(sum).wrapping_mul(2)).wrapping_add(n.wrapping_mul(q * q));
        let fraction = rem as f32 / count as f32;
        let variance = u64_to_f32_halves(about_q as u64) / count as f32 - fraction * fraction;
        if variance > 0.0 { variance } else { 0.0 }
    }

    /// Sums `(total, sum of squares, n)` of `i16` readings to check the pose statistics with: full
    /// scale (the rails, the longest pose), exact ties, both sides of `2^32`, random sums.
    fn pose_sums() -> Vec<(i64, i64, u32)> {
        let longest = MAX_POSE_SAMPLES;
        let full = 1i64 << 30;
        let mut cases = std::vec![
            (0, 0, 1),
            (0, 0, longest),
            (-(1 << 15), full, 1),
            (32_767, 32_767 * 32_767, 1),
            (i64::from(longest) << 15, i64::from(longest) * full, longest),
            (-(i64::from(longest) << 15), i64::from(longest) * full, longest),
            (i64::from(longest) * 32_767, i64::from(longest) * 32_767 * 32_767, longest),
            (i64::from(longest) * 32_767 - 1, i64::from(longest) * 32_767 * 32_767, longest),
            (1, 1, longest),
            (-1, 1, longest),
            (-3, 5, 7),
            (1, 1, 3),
            (2, 2, 3),
            // Ties: 16384 + 2^-10 and + 3 2^-10 lie halfway between two f32 (ulp 2^-9).
            ((1 << 24) + 1, 1 << 38, 1 << 10),
            ((1 << 24) + 3, 1 << 38, 1 << 10),
            (-(1 << 24) - 1, 1 << 38, 1 << 10),
            (-(1 << 24) - 3, 1 << 38, 1 << 10),
            ((1 << 32) - 1, 1 << 47, 1 << 17),
            (1 << 32, 1 << 47, 1 << 17),
            ((1 << 32) + 1, 1 << 47, (1 << 17) + 1),
            (-(1 << 32), 1 << 47, 1 << 17),
            (-(1 << 32) - 1, 1 << 47, (1 << 17) + 1),
        ];
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move || {
            x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            x
        };
        for round in 0..20_000 {
            let n = match round % 4 {
                0 => 1 + (next() >> 54) as u32,
                1 => 1 + (next() >> 48) as u32,
                2 => 1 + (next() >> 33) as u32 % longest,
                _ => longest - (next() >> 60) as u32,
            };
            // A mean anywhere in [-2^15, 2^15], or within a few LSB of 0.
            let bound = i64::from(n) << if round % 3 == 0 { 2 } else { 15 };
            let total = (next() >> 1) as i64 % (2 * bound + 1) - bound;
            let sum_sq = (total.unsigned_abs() as i128 * 32_768).min(i128::from(n) << 30) as i64;
            cases.push((total, sum_sq, n));
        }
        cases
    }

    #[test]
    fn pose_means_are_rounded_once_and_variances_are_the_original_ones() {
        for (total, sum_sq, n) in pose_sums() {
            let (mean, variance) = i16::mean_and_variance(0, total, sum_sq, n);
            assert_eq!(mean.to_bits(), nearest_f32(total, n).to_bits(), "{total} / {n}");
            assert_eq!(variance.to_bits(), reference_variance(total, sum_sq, n).to_bits(), "{total} {sum_sq} {n}");
            let (_, q, rem) = mean_and_floor_div(total, n);
            assert_eq!((q, i64::from(rem)), (total.div_euclid(i64::from(n)), total.rem_euclid(i64::from(n))));
            // Relative to a reference (the sum of the deviations from it): the same statistics.
            let reference = -12_345i16;
            let relative = total - i64::from(n) * i64::from(reference);
            let about_reference = sum_sq - 2 * i64::from(reference) * total + i64::from(n) * 12_345 * 12_345;
            let (mean_r, variance_r) = i16::mean_and_variance(reference, relative, about_reference, n);
            assert_eq!(mean_r.to_bits(), mean.to_bits(), "{total} / {n} about {reference}");
            let expected = reference_variance(relative, about_reference, n);
            assert_eq!(variance_r.to_bits(), expected.to_bits(), "{total} {sum_sq} {n} about {reference}");
        }
    }

    #[test]
    fn the_long_division_matches_the_compiler_up_to_full_scale() {
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        for d in [1u32, 2, 3, 7, 997, 65_535, 65_536, 65_537, 1 << 17, (1 << 31) - 1] {
            let top = u64::from(d) << 15;
            for _ in 0..2000 {
                x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                for m in [x % (top + 1), top, top - 1, (1 << 32).min(top), ((1 << 32) - 1).min(top), 0] {
                    let (q, r) = div_rem_sum(m, d);
                    assert_eq!((u64::from(q), u64::from(r)), (m / u64::from(d), m % u64::from(d)), "{m} / {d}");
                }
            }
        }
        // Beyond full scale the quotient is clamped: no overflow, a remainder below the divisor.
        assert_eq!(div_rem_sum(u64::MAX, 1 << 17), (1 << 15, 0));
        assert_eq!(div_rem_sum(1 << 40, 0), (1 << 15, 0));
    }

    #[test]
    fn fractions_round_to_nearest_even() {
        // Every remainder of small divisors, and the largest divisor with the smallest fraction.
        for d in 1..200u32 {
            for q in [0u32, 1, 2, 3, 1000, 32_767, 32_768] {
                for r in 0..d {
                    let total = i64::from(q) * i64::from(d) + i64::from(r);
                    assert_eq!(fraction_to_f32(q, r, d).to_bits(), nearest_f32(total, d).to_bits(), "{q} + {r}/{d}");
                }
            }
        }
        for (q, r, d) in [(0, 1, u32::MAX), (0, u32::MAX - 1, u32::MAX), (32_768, 1, u32::MAX), (0, 1, 3)] {
            let exact = (f64::from(q) + f64::from(r) / f64::from(d)) as f32;
            assert_eq!(fraction_to_f32(q, r, d), exact, "{q} + {r}/{d}");
        }
    }

    #[test]
    fn the_saturation_bound_never_clears_a_saturated_block() {
        // Blocks near the rails and near a limit: whenever a sample is saturated, the bound must send the
        // block to the sample-by-sample check (it may also do so for a clear block).
        let mut x = 0x2545_F491_4F6C_DD1Du64;
        let (mut saturated_blocks, mut cleared) = (0, 0);
        for round in 0..4000 {
            let limit = [32_769, 32_767, 30_000, 16_384][round % 4];
            let centre = [32_760i32, -32_760, 29_990, 16_380, 0][round % 5];
            let spread = [1u64, 3, 12, 400][round % 4];
            let mut samples = [[0i16; 3]; 32];
            for sample in &mut samples {
                for v in sample.iter_mut() {
                    x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                    let offset = (x >> 33) % (2 * spread + 1);
                    *v = (centre + offset as i32 - spread as i32).clamp(-32_768, 32_767) as i16;
                }
            }
            let (mut sum, mut sum_sq) = ([0i64; 3], [0i64; 3]);
            let saturated = i16::full_block(&samples, limit, &mut sum, &mut sum_sq).2;
            let spread = (0..3).map(|a| (32 * sum_sq[a] - sum[a] * sum[a]) as u64).sum();
            let truth = samples.iter().flatten().any(|v| v.saturated(limit));
            assert_eq!(saturated, truth, "round {round}");
            if truth {
                saturated_blocks += 1;
                assert!(i16_may_saturate(largest_magnitude(&sum), spread, 32, limit), "round {round}");
            } else if !i16_may_saturate(largest_magnitude(&sum), spread, 32, limit) {
                cleared += 1;
            }
        }
        assert!(saturated_blocks > 500 && cleared > 500, "{saturated_blocks} saturated, {cleared} cleared");
    }

    #[test]
    fn block_sums_of_a_slice_longer_than_2_to_the_16_are_exact() {
        // 3 2^16 + 5 samples near a rail: an i32 sum of one axis would overflow; the one saturated
        // sample is the last one, in the short final chunk.
        let n = 3 * (1usize << 16) + 5;
        let x: Vec<i16> = (0..n).map(|i| if i + 1 == n { i16::MAX } else { 32_000 - (i % 7) as i16 }).collect();
        let y: Vec<i16> = (0..n).map(|i| i16::MIN + 1 + (i % 5) as i16).collect();
        let z: Vec<i16> = (0..n).map(|i| (i % 1_001) as i16 - 500).collect();
        let limit = i16::saturation_limit(f32::INFINITY);
        let out = i16::block_sums([&x, &y, &z], limit);
        for (a, values) in [&x, &y, &z].iter().enumerate() {
            let sum: i128 = values.iter().map(|&v| i128::from(v)).sum();
            let sum_sq: i128 = values.iter().map(|&v| i128::from(v) * i128::from(v)).sum();
            assert_eq!(i128::from(out.sum[a]), sum, "axis {a}");
            assert_eq!(i128::from(out.sum_sq[a]), sum_sq, "axis {a}");
        }
        assert!(out.saturated);
        let clear = i16::block_sums([&x[..n - 1], &y[..n - 1], &z[..n - 1]], limit);
        assert!(!clear.saturated);
    }

    #[test]
    fn block_sums_and_spread_are_exact_for_the_longest_full_scale_block() {
        // 2^16 samples (the longest block): rails and near-rails, where every term is largest.
        let samples: Vec<[i16; 3]> = (0..1usize << 16)
            .map(|i| match i % 3 {
                0 => [i16::MIN, i16::MAX, i16::MIN],
                1 => [i16::MAX, i16::MIN, i16::MIN + 1],
                _ => [i16::MIN, i16::MIN, (i % 65_521) as i16],
            })
            .collect();
        for len in [32, 1 << 16] {
            let block = &samples[..len];
            let (mut sum, mut sum_sq) = ([0i64; 3], [0i64; 3]);
            let spread = i16_block_sums(block, &mut sum, &mut sum_sq);
            let mut expected = 0i128;
            for a in 0..3 {
                let s: i128 = block.iter().map(|v| i128::from(v[a])).sum();
                let q: i128 = block.iter().map(|v| i128::from(v[a]).pow(2)).sum();
                assert_eq!((i128::from(sum[a]), i128::from(sum_sq[a])), (s, q), "len {len} axis {a}");
                expected += len as i128 * q - s * s;
            }
            assert_eq!(i128::from(spread), expected, "len {len}");
        }
    }

    /// The noise update as first written (NaN-safe min and max, the relative floor always computed).
    fn reference_noise(previous: f32, mean: [f32; 3], variance: f32, config: &AccumulatorConfig, quantum: f32) -> f32 {
        let min = |a: f32, b: f32| if b < a || a.is_nan() { b } else { a };
        let magnitude_sq = mean[0] * mean[0] + mean[1] * mean[1] + mean[2] * mean[2];
        let risen = if previous.is_finite() { previous * (1.0 + config.noise_rise_per_block) } else { f32::INFINITY };
        let floor = max_f32(max_f32(config.min_noise_variance, quantum), 1e-12 * magnitude_sq);
        max_f32(min(risen, variance), floor)
    }

    /// Every block's noise update of `acc` fed `samples` one at a time, against [`reference_noise`].
    fn check_noise<R: Reading, const B: usize>(acc: &mut Accumulator<R, 8, B>, samples: &[[R; 3]], what: &str) {
        let mut previous = acc.noise_variance();
        for (i, &s) in samples.iter().enumerate() {
            let _ = acc.push(s);
            if (i + 1) % B == 0 {
                let block = &acc.blocks[acc.previous_slot % 2];
                let expected = reference_noise(previous, block.mean, block.variance, &acc.config, R::QUANTUM_VARIANCE);
                assert_eq!(acc.noise_variance().to_bits(), expected.to_bits(), "{what}: block {}", i / B);
                previous = acc.noise_variance();
            }
        }
    }

    #[test]
    fn the_noise_update_is_the_leaky_minimum_bit_for_bit() {
        let floor =
            AccumulatorConfig { min_noise_variance: 30.0, noise_rise_per_block: 0.3, ..AccumulatorConfig::DEFAULT };
        for (k, config) in [AccumulatorConfig::DEFAULT, floor].into_iter().enumerate() {
            // i16 at full scale too (the relative floor term is skipped for i16: it stays below the quantum).
            let raw: Vec<[i16; 3]> = stream(k as u64 + 40, 12, 400, 9.0)
                .enumerate()
                .map(|(i, s)| if i % 1000 < 100 { [i16::MAX, i16::MIN, i16::MAX] } else { s.map(|v| v.round() as i16) })
                .collect();
            check_noise(&mut Accumulator::<i16, 8, 32>::new(config).unwrap(), &raw, "i16");
            // f32 in g: the relative floor term decides for quiet blocks without a configured floor.
            let scaled: Vec<[f32; 3]> =
                stream(k as u64 + 50, 12, 400, 0.002).map(|s| s.map(|v| v / 16_384.0)).collect();
            check_noise(&mut Accumulator::<f32, 8, 16>::new(config).unwrap(), &scaled, "f32");
            let still = [[0.0f32, 0.0, 1.0]; 64];
            check_noise(&mut Accumulator::<f32, 8, 16>::new(config).unwrap(), &still, "f32 still");
        }
    }

    #[test]
    fn the_block_saturation_check_is_the_per_sample_one() {
        // Every reading at every kind of limit (saturation_limit gives 0 ..= 32_769).
        for limit in [0, 1, 2, 100, 16_384, 32_766, 32_767, 32_768, 32_769] {
            for v in i16::MIN..=i16::MAX {
                assert_eq!(i16_any_saturated(&[v], limit), v.saturated(limit), "{v} at {limit}");
            }
        }
        assert!(!i16_any_saturated(&[], 0));
    }

    /// A stream of still holds (noise `noise`) and moves, with `hold` samples per hold, from `seed`.
    fn stream(seed: u64, holds: usize, hold: usize, noise: f32) -> impl Iterator<Item = [f32; 3]> {
        let mut x = seed;
        let mut next = move || {
            x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (x >> 40) as f32 / (1u64 << 24) as f32 - 0.5
        };
        (0..holds * hold).map(move |i| {
            let (h, t) = (i / hold, i % hold);
            let moving = t < hold / 5;
            let base = [(h % 3) as f32 * 9000.0 - 9000.0, (h % 5) as f32 * 5000.0 - 10_000.0, 16_000.0];
            let swing = if moving { 3000.0 * (t as f32 * 0.1).sin() } else { 0.0 };
            [base[0] + swing + noise * next(), base[1] - swing + noise * next(), base[2] + noise * next()]
        })
    }

    /// Every event with the number of samples taken when it came, pushing one at a time.
    fn one_by_one<R: Reading, const P: usize, const B: usize>(
        acc: &mut Accumulator<R, P, B>,
        samples: &[[R; 3]],
    ) -> Vec<(usize, Result<Option<Event>, AccumulatorError>)> {
        let events = samples.iter().enumerate().map(|(i, &s)| (i + 1, acc.push(s)));
        events.filter(|(_, e)| !matches!(e, Ok(None))).collect()
    }

    /// The same through `push_slice`, the stream cut into slices of the lengths `cuts` in turn.
    fn by_slices<R: Reading, const P: usize, const B: usize>(
        acc: &mut Accumulator<R, P, B>,
        samples: &[[R; 3]],
        cuts: &[usize],
    ) -> Vec<(usize, Result<Option<Event>, AccumulatorError>)> {
        let (mut events, mut start, mut cut) = (Vec::new(), 0, 0);
        while start < samples.len() {
            let end = (start + cuts[cut % cuts.len()]).min(samples.len());
            cut += 1;
            while start < end {
                let (taken, event) = acc.push_slice(&samples[start..end]);
                assert!(taken >= 1 && start + taken <= end, "{taken} taken of {}", end - start);
                start += taken;
                if !matches!(event, Ok(None)) {
                    events.push((start, event));
                } else {
                    assert_eq!(start, end, "Ok(None) before the slice's end");
                }
            }
        }
        events
    }

    fn assert_same<R: Reading, const P: usize, const B: usize>(
        a: &Accumulator<R, P, B>,
        b: &Accumulator<R, P, B>,
        what: &str,
    ) {
        assert_eq!(a.poses(), b.poses(), "{what}");
        assert_eq!(a.rejections(), b.rejections(), "{what}");
        assert_eq!(a.noise_variance().to_bits(), b.noise_variance().to_bits(), "{what}");
        assert_eq!((a.samples_seen(), a.is_capturing()), (b.samples_seen(), b.is_capturing()), "{what}");
    }

    #[test]
    fn push_slice_is_bit_for_bit_pushing_one_at_a_time() {
        let cuts: [&[usize]; 5] = [&[32], &[1], &[64, 7, 32, 31, 33], &[100], &[5, 3, 200, 17]];
        let limit = AccumulatorConfig { full_scale: 20_000.0, ..AccumulatorConfig::DEFAULT };
        for (round, &cut) in cuts.iter().enumerate() {
            for config in [AccumulatorConfig::DEFAULT, limit] {
                let raw: Vec<[i16; 3]> =
                    stream(round as u64, 30, 700, 6.0).map(|s| s.map(|v| v.round() as i16)).collect();
                let mut a: Accumulator<i16, 8, 32> = Accumulator::new(config).unwrap();
                let mut b: Accumulator<i16, 8, 32> = Accumulator::new(config).unwrap();
                let events = one_by_one(&mut a, &raw);
                assert!(events.iter().any(|e| e.1 == Err(AccumulatorError::Full)), "round {round}: fills up");
                assert_eq!(events, by_slices(&mut b, &raw, cut), "i16 round {round}");
                assert_same(&a, &b, "i16");
                assert_eq!(a.finish(), b.finish());
                assert_same(&a, &b, "i16 finished");
            }
            // f32, with non-finite samples (skipped, an error each) at places inside and across blocks.
            let mut scaled: Vec<[f32; 3]> = stream(round as u64 + 9, 12, 500, 0.004).collect();
            for (k, i) in [40usize, 41, 700, 1999, 2000, 3333].into_iter().enumerate() {
                scaled[i][k % 3] = [f32::NAN, f32::INFINITY, f32::NEG_INFINITY][k % 3];
            }
            let mut a: Accumulator<f32, 24, 16> = Accumulator::new(limit).unwrap();
            let mut b: Accumulator<f32, 24, 16> = Accumulator::new(limit).unwrap();
            let events = one_by_one(&mut a, &scaled);
            let skipped = events.iter().filter(|e| e.1 == Err(AccumulatorError::NonFiniteSample)).count();
            assert_eq!(skipped, 6, "round {round}");
            assert_eq!(events, by_slices(&mut b, &scaled, cut), "f32 round {round}");
            assert_same(&a, &b, "f32");
            assert!(a.poses().len() >= 8, "round {round}: {} poses", a.poses().len());
        }
    }

    #[test]
    fn push_slice_sums_full_scale_blocks_exactly() {
        // Whole blocks at the rails and at full scale through the slice path: exact sums, saturation seen.
        let mut acc: Accumulator<i16, 4, 32> = Accumulator::new(AccumulatorConfig::DEFAULT).unwrap();
        let block = [[i16::MAX, i16::MIN, i16::MAX - 1]; 32];
        assert_eq!(acc.push_slice(&block), (32, Ok(None)));
        let stats = &acc.blocks[acc.previous_slot % 2];
        let n = 32i64;
        assert_eq!(stats.sums.sum, [n * 32_767, -n * 32_768, n * 32_766]);
        assert_eq!(stats.sums.sum_sq, [n * 32_767 * 32_767, n * 32_768 * 32_768, n * 32_766 * 32_766]);
        assert!(stats.sums.saturated && stats.variance == 0.0);
        let inside = [[i16::MAX - 1, i16::MIN + 1, 0]; 32];
        assert_eq!(acc.push_slice(&inside), (32, Ok(None)));
        assert!(!acc.blocks[acc.previous_slot % 2].sums.saturated);
    }

    #[test]
    fn large_sums_convert_to_f32_within_an_ulp() {
        for v in [0u64, 3, 1 << 31, (1 << 32) - 1, 3 << 40, (5 << 50) + 12_345, u64::MAX] {
            let exact = v as f64;
            let got = f64::from(u64_to_f32_halves(v));
            assert!((got - exact).abs() <= exact.abs() * 2.0 * f64::from(f32::EPSILON), "{v}: {got}");
        }
    }
}
