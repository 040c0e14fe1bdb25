//! Position averaging: feed samples one at a time; static intervals are found and averaged into [`Pose`]s.
//!
//! Samples are grouped in blocks of `BLOCK`. Each block's per-axis variance and its mean's change from
//! the previous block are compared with the *measured* noise (a leaky minimum of the block variances:
//! a low percentile of them, never below the quantisation floor), with hysteresis: a pose opens after two quiet blocks and closes at the
//! first block that moves. The block in which motion starts and the one before it are never averaged
//! in (a one-block delay line). A closed pose is kept if it is long enough, never touched the rails and
//! its own variance is noise-like; otherwise it is counted as rejected with the reason.
//!
//! Sums are exact: `i16` counts are summed in `i64` relative to the pose's first sample, `f32` samples
//! in `f64`; the hot path has no division and no float for `i16`.
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

/// A per-axis sample type the accumulator can sum exactly.
pub trait Reading: Copy + Default {
    /// Exact running-sum type.
    type Sum: Copy + Default + AddAssign + Add<Output = Self::Sum> + Sub<Output = Self::Sum> + Mul<Output = Self::Sum>;
    /// Variance (sum over axes) below which no noise can be resolved: the quantisation floor.
    const QUANTUM_VARIANCE: f32;
    /// `self - reference` in the sum type (exact).
    fn delta(self, reference: Self) -> Self::Sum;
    /// `n` in the sum type.
    fn count(n: u32) -> Self::Sum;
    /// A sum as `f64` (pose close) .
    fn sum_to_f64(s: Self::Sum) -> f64;
    /// A (small, relative) sum as `f32` (block statistics).
    fn sum_to_f32(s: Self::Sum) -> f32;
    /// The value as `f64`.
    fn to_f64(self) -> f64;
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

impl Reading for i16 {
    type Sum = i64;
    const QUANTUM_VARIANCE: f32 = 3.0 / 12.0;
    #[inline]
    fn delta(self, reference: Self) -> i64 {
        i64::from(self) - i64::from(reference)
    }
    fn count(n: u32) -> i64 {
        i64::from(n)
    }
    fn sum_to_f64(s: i64) -> f64 {
        s as f64
    }
    fn sum_to_f32(s: i64) -> f32 {
        s as f32
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
    }
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
        if full_scale > 32_768.0 { 32_769 } else { libm::ceilf(full_scale.max(0.0)) as i32 }
    }
    #[inline]
    fn saturated(self, limit: i32) -> bool {
        self == i16::MIN || self == i16::MAX || i32::from(self).abs() >= limit
    }
}

impl Reading for f32 {
    type Sum = f64;
    const QUANTUM_VARIANCE: f32 = 0.0;
    #[inline]
    fn delta(self, reference: Self) -> f64 {
        f64::from(self) - f64::from(reference)
    }
    fn count(n: u32) -> f64 {
        f64::from(n)
    }
    fn sum_to_f64(s: f64) -> f64 {
        s
    }
    fn sum_to_f32(s: f64) -> f32 {
        s as f32
    }
    fn to_f64(self) -> f64 {
        f64::from(self)
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

/// One static position: the average of its samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
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
    /// A pose was captured and stored at this index of [`Accumulator::poses`].
    PoseCaptured(usize),
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
        let positive = |v: f32| v.is_finite() && v > 0.0;
        let ok = positive(self.enter_factor)
            && positive(self.drift_enter_factor)
            && self.exit_factor >= self.enter_factor
            && self.exit_factor.is_finite()
            && self.drift_exit_factor >= self.drift_enter_factor
            && self.drift_exit_factor.is_finite()
            && self.full_scale > 0.0
            && self.min_noise_variance.is_finite()
            && self.min_noise_variance >= 0.0
            && self.noise_rise_per_block.is_finite()
            && self.noise_rise_per_block >= 0.0;
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
            saturated: false,
        }
    }

    /// Adds `other` (relative to its own reference) to these sums, exactly.
    fn merge(&mut self, other: &Self) {
        let n = R::count(other.n);
        for a in 0..3 {
            let shift = other.reference[a].delta(self.reference[a]);
            self.sum_sq[a] += other.sum_sq[a] + (other.sum[a] * shift + other.sum[a] * shift) + n * shift * shift;
            self.sum[a] += other.sum[a] + n * shift;
        }
        self.n += other.n;
        self.saturated |= other.saturated;
    }

    /// Per-axis mean offset from the reference and variance, in `f32` (block statistics).
    fn mean_offset_and_variance(&self) -> ([f32; 3], [f32; 3]) {
        let n = self.n.max(1) as f32;
        let mut mean = [0.0; 3];
        let mut var = [0.0; 3];
        for a in 0..3 {
            let m = R::sum_to_f32(self.sum[a]) / n;
            mean[a] = m;
            var[a] = (R::sum_to_f32(self.sum_sq[a]) / n - m * m).max(0.0);
        }
        (mean, var)
    }

    fn pose(&self) -> Pose {
        let n = f64::from(self.n.max(1));
        let mut pose = Pose {
            n: self.n,
            start_index: self.start_index,
            end_index: self.start_index.saturating_add(self.n),
            ..Pose::default()
        };
        for a in 0..3 {
            let m = R::sum_to_f64(self.sum[a]) / n;
            pose.mean[a] = (self.reference[a].to_f64() + m) as f32;
            pose.variance[a] = (R::sum_to_f64(self.sum_sq[a]) / n - m * m).max(0.0) as f32;
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
    /// The open block (`n == 0`: none yet).
    block: Sums<R>,
    saturation_limit: R::Limit,
    previous: Option<BlockStats<R>>,
    pending: Option<Sums<R>>,
    pose: Option<Sums<R>>,
    noise_variance: f32,
    samples_seen: u32,
}

impl<R: Reading, const POSES: usize, const BLOCK: usize> Accumulator<R, POSES, BLOCK> {
    const VALID: () = assert!(BLOCK >= 4, "a block needs at least 4 samples to estimate a variance");

    /// An empty accumulator.
    pub fn new(config: AccumulatorConfig) -> Result<Self, AccumulatorError> {
        let () = Self::VALID;
        config.validate()?;
        Ok(Self {
            config,
            poses: heapless::Vec::new(),
            rejections: Rejections::default(),
            block: Sums::new([R::default(); 3], 0),
            saturation_limit: R::saturation_limit(config.full_scale),
            previous: None,
            pending: None,
            pose: None,
            noise_variance: f32::INFINITY,
            samples_seen: 0,
        })
    }

    /// Feeds one sample (x, y, z in the input unit).
    #[inline]
    pub fn push(&mut self, sample: [R; 3]) -> Result<Option<Event>, AccumulatorError> {
        if !(sample[0].is_finite() && sample[1].is_finite() && sample[2].is_finite()) {
            self.samples_seen = self.samples_seen.saturating_add(1);
            return Err(AccumulatorError::NonFiniteSample);
        }
        let index = self.samples_seen;
        self.samples_seen = self.samples_seen.saturating_add(1);
        if self.block.n == 0 {
            self.open_block(sample, index);
        }
        let block = &mut self.block;
        for a in 0..3 {
            let d = sample[a].delta(block.reference[a]);
            block.sum[a] += d;
            block.sum_sq[a] += d * d;
        }
        let limit = self.saturation_limit;
        block.saturated |= sample[0].saturated(limit) | sample[1].saturated(limit) | sample[2].saturated(limit);
        block.n += 1;
        if block.n as usize >= BLOCK {
            return self.close_block();
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
        self.block.n = 0;
        self.previous = None;
        self.pending = None;
        self.close_pose()
    }

    /// Ends the stream: a pose still open is closed with every quiet block it has (no motion followed).
    pub fn finish(&mut self) -> Result<Option<Event>, AccumulatorError> {
        self.block.n = 0;
        self.previous = None;
        if let (Some(pose), Some(pending)) = (self.pose.as_mut(), self.pending.take()) {
            pose.merge(&pending);
        }
        self.close_pose()
    }

    /// Starts a block at `sample` (once per `BLOCK` samples; out of line so that `push` updates the
    /// open block in place).
    #[inline(never)]
    fn open_block(&mut self, sample: [R; 3], index: u32) {
        self.block = Sums::new(sample, index);
    }

    // Once per BLOCK samples: kept out of line so that `push`, inlined into the caller's sample loop, stays
    // small (inlined, its register pressure made every push save and restore all FPU registers).
    #[inline(never)]
    fn close_block(&mut self) -> Result<Option<Event>, AccumulatorError> {
        let sums = self.block;
        self.block.n = 0;
        let (offset, var) = sums.mean_offset_and_variance();
        let mut mean = [0.0; 3];
        for a in 0..3 {
            mean[a] = sums.reference[a].to_f32() + offset[a];
        }
        let stats = BlockStats { sums, mean, variance: var[0] + var[1] + var[2] };
        let magnitude_sq = mean.iter().map(|m| m * m).sum::<f32>();
        let risen = if self.noise_variance.is_finite() {
            self.noise_variance * (1.0 + self.config.noise_rise_per_block)
        } else {
            f32::INFINITY
        };
        self.noise_variance = risen
            .min(stats.variance)
            .max(self.config.min_noise_variance)
            .max(R::QUANTUM_VARIANCE)
            .max(1e-12 * magnitude_sq);
        let noise = self.noise_variance;
        let drift_unit = 2.0 * noise / BLOCK as f32;
        let drift = self.previous.map(|p| {
            let d = [stats.mean[0] - p.mean[0], stats.mean[1] - p.mean[1], stats.mean[2] - p.mean[2]];
            (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / drift_unit
        });
        let previous = self.previous.replace(stats);

        if self.pose.is_some() {
            let still = stats.variance <= self.config.exit_factor * noise
                && drift.is_some_and(|d| d <= self.config.drift_exit_factor);
            if still {
                if let (Some(pose), Some(pending)) = (self.pose.as_mut(), self.pending.replace(sums)) {
                    pose.merge(&pending);
                }
                return Ok(None);
            }
            self.pending = None;
            return self.close_pose();
        }

        let quiet = stats.variance <= self.config.enter_factor * noise
            && drift.is_some_and(|d| d <= self.config.drift_enter_factor);
        match previous {
            // Two quiet blocks in a row with little change between them open a pose.
            Some(prev) if quiet && prev.variance <= self.config.enter_factor * noise => {
                let mut pose = Sums::new(prev.sums.reference, prev.sums.start_index);
                pose.merge(&prev.sums);
                self.pose = Some(pose);
                self.pending = Some(sums);
                Ok(Some(Event::StillnessDetected))
            }
            _ => Ok(None),
        }
    }

    fn close_pose(&mut self) -> Result<Option<Event>, AccumulatorError> {
        let Some(sums) = self.pose.take() else {
            return Ok(None);
        };
        let pose = sums.pose();
        let rejection = if sums.saturated {
            Some(Rejection::Saturated)
        } else if sums.n < self.config.min_pose_samples {
            Some(Rejection::TooShort)
        } else if pose.variance.iter().sum::<f32>() > self.config.exit_factor * self.noise_variance {
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
        Ok(Some(Event::PoseCaptured(self.poses.len() - 1)))
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
        self.samples_seen
    }

    /// `true` while a pose is being averaged.
    pub fn is_capturing(&self) -> bool {
        self.pose.is_some()
    }
}
