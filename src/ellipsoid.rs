//! An initial estimate that needs no face: a closed-form ellipsoid fit of the pose means.
//!
//! At rest the calibrated reading has modulus `g`: `|Ka (m - c)| = g` with `c = Ka^-1 B`, so the pose
//! means `m` lie on an ellipsoid. In coordinates `v = (m - m0) / s` (`m0` the mean of the means, `s`
//! their RMS spread, so every number is near 1) the ellipsoid is the quadric `v^T A v + b^T v = 1`,
//! linear in its 9 coefficients: one linear least-squares solve (9x9 normal equations). Completing the
//! square gives the centre `c` and `Ka^T Ka`, which is factored into the lower-triangular `Ka` (a
//! Cholesky factorisation in reversed order), and `B = Ka c`.
//!
//! - Any orientations will do, given a spread of directions: no face has to be found.
//! - When the directions cannot determine some quadric coefficients (poses in two planes, for example,
//!   leave the cross term between them free), the cross terms are held at 0 (no non-orthogonality)
//!   instead of being fitted to noise; [`EllipsoidFit::held`] says which.
//! - Poses far off the fitted ellipsoid (a shock, a stuck register) are left out one at a time, worst
//!   first, and named in [`EllipsoidFit::excluded`].
//!
//! ```
//! use accelcal::accumulator::Pose;
//! use accelcal::ellipsoid::{fit_ellipsoid, OutlierRule};
//! use accelcal::model::Params;
//! let truth = Params { bias: [0.2, -0.1, 0.3], scale: [0.98, 1.01, 0.99], nonorth: [0.01, -0.02, 0.015] };
//! let dirs = [[0.3f32, 0.9, 0.3], [-0.8, 0.5, 0.33], [0.1, -0.7, 0.7], [0.6, 0.0, -0.8], [-0.2, -0.3, -0.93],
//!     [0.9, -0.4, 0.17], [-0.5, -0.8, 0.33], [0.0, 0.6, -0.8], [-0.7, 0.1, -0.7], [0.57, 0.57, 0.57],
//!     [0.95, 0.3, -0.1], [-0.3, 0.95, -0.1]];
//! let poses = dirs.map(|d| {
//!     let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
//!     Pose::from_mean(truth.invert(d.map(|v| v / n * 9.80665)).unwrap(), 500)
//! });
//! let mut kept: [u16; 12] = core::array::from_fn(|i| i as u16); // every pose
//! let fit = fit_ellipsoid(&poses, &mut kept, 9.80665, &OutlierRule::DEFAULT).unwrap();
//! assert!((fit.params.scale[1] - 1.01).abs() < 1e-3);
//! assert!((fit.params.nonorth[1] + 0.02).abs() < 1e-3);
//! ```

use crate::accumulator::Pose;
use crate::linalg::{
    DETERMINED_PIVOT, Held, add_normal_row, larger, smaller, solve_spd_holding_weak_in_place, sqrt_f32, zero_matrix,
};
use crate::model::{PARAM_COUNT, Params, norm_squared};

/// Quadric coefficients `[xx, yy, zz, x, y, z, xy, xz, yz]`: the cross terms last, so that in the
/// factorisation that finds the undetermined ones they (not a scale or the centre) are held at 0.
const COEFFS: usize = 9;

/// Largest number of poses [`fit_ellipsoid`] leaves out.
pub const MAX_EXCLUDED: usize = 8;

/// Half-axis directions, as a bit set: `+x, -x, +y, -y, +z, -z` in bits 0..6.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Directions(pub u8);

impl Directions {
    /// The names of the half-axes, in bit order.
    pub const NAMES: [&'static str; 6] = ["+x", "-x", "+y", "-y", "+z", "-z"];

    /// `true` when no direction is in the set.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }
}

impl core::fmt::Display for Directions {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let mut first = true;
        for (bit, name) in Self::NAMES.iter().enumerate() {
            if self.0 & (1 << bit) != 0 {
                f.write_str(if first { "" } else { ", " })?;
                f.write_str(name)?;
                first = false;
            }
        }
        Ok(())
    }
}

/// Why no ellipsoid could be fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EllipsoidError {
    /// Fewer than 9 poses (after leaving out the ones far off).
    TooFewPoses {
        /// Poses used.
        got: usize,
    },
    /// Gravity must be finite and positive.
    InvalidGravity,
    /// A pose mean is not finite (or an index in the list of poses to fit names no pose).
    NonFinitePose,
    /// The directions do not determine an ellipsoid; no pose lies within 60 deg of these half-axes.
    Degenerate {
        /// Half-axes with no pose near them.
        missing: Directions,
    },
}

impl core::fmt::Display for EllipsoidError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooFewPoses { got } => write!(f, "{got} poses: at least 9 orientations are needed"),
            Self::InvalidGravity => f.write_str("gravity must be finite and positive"),
            Self::NonFinitePose => f.write_str("a pose mean is not finite"),
            Self::Degenerate { missing } if missing.is_empty() => {
                f.write_str("the orientations are too close together: spread them over the sphere")
            }
            Self::Degenerate { missing } => {
                write!(f, "the orientations do not determine an ellipsoid: no pose points near {missing}")
            }
        }
    }
}

impl core::error::Error for EllipsoidError {}

/// When a pose counts as far off the ellipsoid: its modulus error exceeds both `floor_g` and
/// `robust_sigmas` robust standard deviations (1.4826 median absolute error) of the poses kept.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct OutlierRule {
    /// Absolute floor, fraction of gravity. Defaults to 0.02 (20 mg).
    pub floor_g: f32,
    /// Robust standard deviations. Defaults to 8.
    pub robust_sigmas: f32,
}

impl OutlierRule {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { floor_g: 0.02, robust_sigmas: 8.0 };
    /// Never leave a pose out.
    pub const KEEP_ALL: Self = Self { floor_g: f32::INFINITY, robust_sigmas: f32::INFINITY };
}

impl Default for OutlierRule {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Up to [`MAX_EXCLUDED`] pose indices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PoseList {
    len: u8,
    index: [u16; MAX_EXCLUDED],
}

/// A list of indices is serialised as the sequence of its indices.
#[cfg(feature = "serde")]
impl serde::Serialize for PoseList {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        serializer.collect_seq(self.as_slice())
    }
}

impl PoseList {
    /// No index.
    pub const EMPTY: Self = Self { len: 0, index: [0; MAX_EXCLUDED] };

    /// The indices.
    pub fn as_slice(&self) -> &[u16] {
        &self.index[..usize::from(self.len).min(MAX_EXCLUDED)]
    }

    /// How many indices (at most [`MAX_EXCLUDED`]: [`PoseList::push`] stops there; no clamp).
    pub(crate) fn count(&self) -> usize {
        usize::from(self.len)
    }

    /// `true` when the list is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// `*self = *other` in two halves of the indices: at this alignment the whole copy is a `memcpy`
    /// call, the halves are inlined.
    pub(crate) fn copy_from(&mut self, other: &Self) {
        const HALF: usize = MAX_EXCLUDED / 2;
        self.len = other.len;
        self.index[..HALF].copy_from_slice(&other.index[..HALF]);
        self.index[HALF..].copy_from_slice(&other.index[HALF..]);
    }

    fn push(&mut self, i: u16) {
        if let Some(slot) = self.index.get_mut(usize::from(self.len)) {
            *slot = i;
            self.len += 1;
        }
    }
}

/// The fitted ellipsoid.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct EllipsoidFit {
    /// The model in the paper's convention.
    pub params: Params,
    /// The centre of the ellipsoid, `Ka^-1 B` (input unit): the reading at zero specific force.
    pub center: [f32; 3],
    /// Poses left out as far off the ellipsoid.
    pub excluded: PoseList,
    /// Non-orthogonality terms held at 0 because the directions do not determine them
    /// (`[Mxx, Myy, Mzz]`).
    pub held: [bool; 3],
    /// Modulus RMSE of the poses kept, fraction of gravity.
    pub rmse_g: f32,
}

/// `true` for a finite `v`: `v - v` is 0 for a finite `v`, NaN otherwise (on the FPU:
/// `f32::is_finite` works on the bits).
#[allow(clippy::eq_op)] // `v - v` is the test.
pub(crate) fn finite(v: f32) -> bool {
    v - v == 0.0
}

/// Checks gravity and the means, the same for both initialisations: `Ok` or which is wrong.
#[allow(clippy::eq_op)] // `x - x` is the test.
pub(crate) fn check_input<'a>(means: impl Iterator<Item = &'a [f32; 3]>, gravity: f32) -> Result<(), EllipsoidError> {
    if !(gravity > 0.0 && gravity < f32::INFINITY) {
        return Err(EllipsoidError::InvalidGravity);
    }
    for m in means {
        // `x - x` is 0 for a finite `x`, NaN otherwise.
        if (m[0] - m[0]) + (m[1] - m[1]) + (m[2] - m[2]) != 0.0 {
            return Err(EllipsoidError::NonFinitePose);
        }
    }
    Ok(())
}

/// The means of the poses listed in `kept`, in its order (an index past the end of `poses` is
/// skipped: [`fit_ellipsoid`] refuses it).
pub(crate) fn kept<'a>(poses: &'a [Pose], kept: &'a [u16]) -> impl Iterator<Item = &'a [f32; 3]> + Clone {
    kept.iter().filter_map(|&i| poses.get(usize::from(i))).map(|p| &p.mean)
}

/// Moves `list[at]` to the end of `list`, the others keeping their order. Inlined at its two calls
/// (8 bytes fewer than one shared copy on a Cortex-M4F).
#[inline(always)]
fn move_to_end(list: &mut [u16], at: usize) {
    let mut rest = list.get_mut(at..).unwrap_or_default();
    while let Some((first, tail)) = rest.split_first_mut() {
        let Some(second) = tail.first_mut() else { break };
        core::mem::swap(first, second);
        rest = tail;
    }
}

/// Fits the ellipsoid to the means of the poses listed in `kept` (indices into `poses`). The poses
/// found far off per `rule` are moved to the end of `kept` and listed in the result: the fit used the
/// first `kept.len() - fit.excluded.as_slice().len()` entries, in their order.
pub fn fit_ellipsoid(
    poses: &[Pose],
    kept: &mut [u16],
    gravity: f32,
    rule: &OutlierRule,
) -> Result<EllipsoidFit, EllipsoidError> {
    if kept.iter().any(|&i| usize::from(i) >= poses.len()) {
        return Err(EllipsoidError::NonFinitePose);
    }
    check_input(self::kept(poses, kept), gravity)?;
    let (mut params, mut excluded, mut center) = (Params::IDENTITY, PoseList::EMPTY, [0.0; 3]);
    let mut fitting = Fitting::new(poses, gravity, &mut params, &mut excluded, &mut center);
    fitting.robust(kept, rule)?;
    let (held, rmse_g) = (fitting.held, fitting.rmse_g);
    Ok(EllipsoidFit { params, center, excluded, held, rmse_g })
}

/// The state of the robust fit: the poses and gravity, and the fit so far, its model and the poses
/// left out written where the caller keeps them (the poses it uses are a list of indices, passed
/// along).
pub(crate) struct Fitting<'a> {
    poses: &'a [Pose],
    gravity: f32,
    /// The model in the paper's convention.
    params: &'a mut Params,
    /// Poses left out as far off the ellipsoid.
    excluded: &'a mut PoseList,
    /// The centre of the ellipsoid (see [`EllipsoidFit::center`]), written where the caller keeps it.
    center: &'a mut [f32; 3],
    /// Non-orthogonality terms held at 0 (see [`EllipsoidFit::held`]).
    pub(crate) held: [bool; 3],
    /// Modulus RMSE of the poses kept, fraction of gravity.
    rmse_g: f32,
}

impl<'a> Fitting<'a> {
    /// A fit of `poses` against `gravity` writing its model into `params` and the poses it leaves out
    /// into `excluded` (cleared here).
    pub(crate) fn new(
        poses: &'a [Pose],
        gravity: f32,
        params: &'a mut Params,
        excluded: &'a mut PoseList,
        center: &'a mut [f32; 3],
    ) -> Self {
        *excluded = PoseList::EMPTY;
        Self { poses, gravity, params, excluded, center, held: [false; 3], rmse_g: 0.0 }
    }
}

impl Fitting<'_> {
    /// Fits the poses listed in `kept`, leaving out poses per `rule` (moved to its end), until the
    /// fit stands.
    pub(crate) fn robust(&mut self, mut kept: &mut [u16], rule: &OutlierRule) -> Result<(), EllipsoidError> {
        loop {
            let count = kept.len();
            if count < COEFFS {
                return Err(EllipsoidError::TooFewPoses { got: count });
            }
            let room = usize::from(self.excluded.len) < MAX_EXCLUDED && count > COEFFS + 1;
            let mut fitted = self.fit_once(kept);
            // A gross outlier can bend the quadric into a non-ellipsoid, or into an ellipsoid no
            // accelerometer has: then look for the pose without which the rest fit.
            if fitted != Some(true) && room && finite(rule.floor_g) {
                if let Some(at) = self.best_left_out(kept) {
                    kept = self.leave_out(core::mem::take(&mut kept), at);
                    continue;
                }
                fitted = self.fit_once(kept);
            }
            if fitted.is_none() {
                return Err(EllipsoidError::Degenerate { missing: missing_directions(self::kept(self.poses, kept)) });
            }
            let (worst, worst_abs, rmse_g, _) = self.statistics(kept, 0.0);
            self.rmse_g = rmse_g;
            // The limit is at least the floor (or NaN): the median is needed only above the floor.
            if !(worst_abs > rule.floor_g)
                || !room
                || !(worst_abs > larger(rule.floor_g, rule.robust_sigmas * 1.4826 * self.median_abs(kept)))
            {
                return Ok(());
            }
            kept = self.leave_out(core::mem::take(&mut kept), worst);
        }
    }

    /// `kept` without its entry at `at` (moved to its end and listed as excluded). Out of line: two
    /// callers.
    #[inline(never)]
    fn leave_out<'k>(&mut self, kept: &'k mut [u16], at: usize) -> &'k mut [u16] {
        move_to_end(kept, at);
        let Some((&mut last, rest)) = kept.split_last_mut() else { return &mut [] };
        self.excluded.push(last);
        rest
    }

    /// The position in `kept` of the pose without which the others fit an ellipsoid best (smallest
    /// modulus RMS). Each candidate in turn is swapped to the end, the others keeping their order;
    /// `kept` is as it was on return.
    fn best_left_out(&mut self, kept: &mut [u16]) -> Option<usize> {
        let last = kept.len().checked_sub(1)?;
        move_to_end(kept, 0);
        let mut best: Option<(usize, f32)> = None;
        for at in 0..=last {
            let others = kept.get(..last).unwrap_or(&[]);
            if self.fit_once(others) == Some(true) {
                let rms = self.statistics(others, 0.0).2;
                if best.is_none_or(|(_, b)| rms < b) {
                    best = Some((at, rms));
                }
            }
            if at < last {
                kept.swap(at, last);
            }
        }
        best.map(|(at, _)| at)
    }

    /// Reference point (mean) and RMS spread of the kept means: the numbers the quadric is fitted in.
    fn reference(&self, kept: &[u16]) -> ([f32; 3], f32) {
        let mut sum = [0.0f32; 3];
        for m in self::kept(self.poses, kept) {
            for a in 0..3 {
                sum[a] += m[a];
            }
        }
        let n = kept.len().max(1) as f32;
        let center = [sum[0] / n, sum[1] / n, sum[2] / n];
        let spread: f32 = self::kept(self.poses, kept).map(|m| norm_squared(difference(*m, center))).sum();
        (center, sqrt_f32(spread / n))
    }

    /// One least-squares fit of the quadric to the poses listed in `kept`, factored into the model (in
    /// `self`): `None` when the poses do not determine an ellipsoid, else whether it is one an
    /// accelerometer can have.
    fn fit_once(&mut self, kept: &[u16]) -> Option<bool> {
        let (m0, s) = self.reference(kept);
        let mut ata = zero_matrix::<COEFFS>();
        let mut atb = [0.0f32; COEFFS];
        for m in self::kept(self.poses, kept) {
            let v = [(m[0] - m0[0]) / s, (m[1] - m0[1]) / s, (m[2] - m0[2]) / s];
            let row = [
                v[0] * v[0],
                v[1] * v[1],
                v[2] * v[2],
                v[0],
                v[1],
                v[2],
                2.0 * v[0] * v[1],
                2.0 * v[0] * v[2],
                2.0 * v[1] * v[2],
            ];
            // Residual 1 (the quadric's right-hand side), weight 1: `atb += row` exactly.
            add_normal_row(&mut ata, &mut atb, &row, 1.0, 1.0);
        }
        // The linear terms' block is `n` times the covariance of the means: its smallest eigenvalue
        // must carry MIN_THIN_VARIANCE of its trace (positive definite after removing that much).
        let shift = MIN_THIN_VARIANCE * (ata[3][3] + ata[4][4] + ata[5][5]);
        lower_factor([ata[3][3] - shift, ata[4][4] - shift, ata[5][5] - shift], [ata[4][3], ata[5][3], ata[5][4]])?;
        // `atb` becomes the quadric coefficients; weakly determined cross terms are held at 0.
        let held = solve_spd_holding_weak_in_place(&mut ata, &mut atb, DETERMINED_PIVOT).ok()?;
        // Only cross terms may be held.
        let cross_terms = Held::NONE.with(6).with(7).with(8);
        if held.union(cross_terms) != cross_terms {
            return None;
        }
        // Quadric cross terms xy, xz, yz map to Mxx, Myy, Mzz.
        self.held = [held.contains(6), held.contains(7), held.contains(8)];
        self.factor(&atb, m0, s)?;
        Some(plausible(self.params))
    }

    /// The quadric `v^T A v + b^T v = 1` in `v = (m - m0) / s` to the paper's `Ka`, `B` and the
    /// centre; `None` unless an ellipsoid.
    fn factor(&mut self, theta: &[f32; COEFFS], m0: [f32; 3], s: f32) -> Option<()> {
        // A = L^T L, L lower-triangular; the centre solves A v0 = -b / 2: L^T y = -b / 2, then L v0 = y.
        let l = lower_factor([theta[0], theta[1], theta[2]], [theta[6], theta[7], theta[8]])?;
        let ([sx, sy, sz], [mx, my, mz]) = (l.scale, l.nonorth);
        let b = [theta[3], theta[4], theta[5]];
        let y2 = -0.5 * b[2] / sz;
        let y1 = (-0.5 * b[1] - mz * y2) / sy;
        let y0 = (-0.5 * b[0] - mx * y1 - my * y2) / sx;
        let v0 = y0 / sx;
        let v1 = (y1 - mx * v0) / sy;
        let v2 = (y2 - my * v0 - mz * v1) / sz;
        // v^T A v + b^T v = 1 is |L (v - v0)|^2 = 1 + |y|^2 = k, and Ka^T Ka = g^2 A / (k s^2):
        // Ka = L g / (s sqrt(k)).
        let w = self.gravity / (s * sqrt_f32(1.0 + y0 * y0 + y1 * y1 + y2 * y2));
        let ka = Params { bias: [0.0; 3], scale: [w * sx, w * sy, w * sz], nonorth: [w * mx, w * my, w * mz] };
        *self.center = [m0[0] + s * v0, m0[1] + s * v1, m0[2] + s * v2];
        *self.params = Params { bias: ka.ka_times(*self.center), ..ka };
        self.params.is_finite().then_some(())
    }

    /// `| |f_b| / g - 1 |` of the mean `m` under the fit (the modulus out of line).
    #[inline(always)]
    fn abs_error(&self, m: &[f32; 3]) -> f32 {
        (self.params.modulus(*m) / self.gravity - 1.0).abs()
    }

    /// Over the poses listed in `kept`: the position and size of the largest modulus error, their RMS,
    /// and how many errors are at most `limit`. Out of line: the median calls it once per pose.
    #[inline(never)]
    fn statistics(&self, kept: &[u16], limit: f32) -> (usize, f32, f32, usize) {
        let (mut worst, mut worst_abs, mut sum, mut at_most) = (0, -1.0f32, 0.0f32, 0);
        for (at, m) in self::kept(self.poses, kept).enumerate() {
            let e = self.abs_error(m);
            if e > worst_abs {
                (worst, worst_abs) = (at, e);
            }
            sum += e * e;
            at_most += usize::from(e <= limit);
        }
        (worst, worst_abs, sqrt_f32(sum / kept.len().max(1) as f32), at_most)
    }

    /// Lower median of the `|e|` of the poses listed in `kept` without a buffer: the smallest value with
    /// at least half the values at or below it (quadratic in the pose count, which is small).
    fn median_abs(&self, kept: &[u16]) -> f32 {
        let mut best = f32::INFINITY;
        for m in self::kept(self.poses, kept) {
            let v = self.abs_error(m);
            if v < best && 2 * self.statistics(kept, v).3 >= kept.len() {
                best = v;
            }
        }
        best
    }
}

/// `a - b`.
fn difference(a: [f32; 3], b: [f32; 3]) -> [f32; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

/// Smallest share of the total variance of the pose means that their thinnest direction must carry:
/// poses in one plane, or in one cap narrower than about 30 deg, carry less and do not determine an
/// ellipsoid (the fit would be an extrapolation).
const MIN_THIN_VARIANCE: f32 = 0.01;

/// Largest ratio between two axes' scale factors, and largest non-orthogonality relative to its
/// scale, of any accelerometer: a fit beyond them has been bent by a bad pose.
const PLAUSIBLE_SCALE_RATIO: f32 = 1.3;
const PLAUSIBLE_NONORTH: f32 = 0.1;

/// `true` for an ellipsoid an accelerometer can have (its scales are positive).
fn plausible(p: &Params) -> bool {
    let (s, m) = (p.scale, p.nonorth);
    let (lo, hi) = (smaller(smaller(s[0], s[1]), s[2]), larger(larger(s[0], s[1]), s[2]));
    hi <= PLAUSIBLE_SCALE_RATIO * lo
        && m[0].abs() <= PLAUSIBLE_NONORTH * s[0]
        && m[1].abs() <= PLAUSIBLE_NONORTH * s[0]
        && m[2].abs() <= PLAUSIBLE_NONORTH * s[1]
}

/// The lower-triangular `L` with `L^T L = a` (a Cholesky factorisation in reversed order, bottom row
/// first) for the symmetric `a` given by its diagonal and its `xy, xz, yz` entries, as the `Ka` of a
/// model without bias; `None` unless `a` is positive definite. Inlined at both calls: the result is
/// not written to memory and read back (44 bytes fewer than one shared copy on a Cortex-M4F).
#[inline(always)]
fn lower_factor(diagonal: [f32; 3], off: [f32; 3]) -> Option<Params> {
    // A pivot that is not positive gives a diagonal entry that is 0 or NaN, and NaN propagates to
    // the entries after it; an infinite one makes the model infinite: one check at the end (and
    // the caller's that the model is finite).
    let szz = sqrt_f32(diagonal[2]);
    let mzz = off[2] / szz;
    let myy = off[1] / szz;
    let syy = sqrt_f32(diagonal[1] - mzz * mzz);
    let mxx = (off[0] - myy * mzz) / syy;
    let sxx = sqrt_f32(diagonal[0] - mxx * mxx - myy * myy);
    (sxx > 0.0 && syy > 0.0 && szz > 0.0).then_some(Params {
        bias: [0.0; 3],
        scale: [sxx, syy, szz],
        nonorth: [mxx, myy, mzz],
    })
}

/// Per-axis centre and half-width of the range of the means, and the largest half-width (0 if none is
/// positive).
pub(crate) fn mid_range<'a>(means: impl Iterator<Item = &'a [f32; 3]>) -> ([f32; 3], [f32; 3], f32) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for m in means {
        for a in 0..3 {
            lo[a] = smaller(m[a], lo[a]);
            hi[a] = larger(m[a], hi[a]);
        }
    }
    let mut widest = 0.0f32;
    for a in 0..3 {
        (lo[a], hi[a]) = (0.5 * (hi[a] + lo[a]), 0.5 * (hi[a] - lo[a]));
        widest = larger(hi[a], widest);
    }
    (lo, hi, widest)
}

/// [`half_axes_near`] of the mean `m` seen from `mid`, axis `a` in units of `scale[a]`: `u = (m - mid) /
/// scale`. Out of line: the six faces and the missing directions share one copy.
#[inline(never)]
pub(crate) fn half_axes_near_of(m: &[f32; 3], mid: &[f32; 3], scale: &[f32; 3], cos: f32) -> u8 {
    half_axes_near([(m[0] - mid[0]) / scale[0], (m[1] - mid[1]) / scale[1], (m[2] - mid[2]) / scale[2]], cos)
}

/// The half-axes ([`Directions`] bits) within `acos(cos)` of the direction of `u`; all six for `u = 0`.
#[inline]
pub(crate) fn half_axes_near(u: [f32; 3], cos: f32) -> u8 {
    let limit = cos * sqrt_f32(norm_squared(u));
    let mut bits = 0;
    for a in 0..3 {
        bits |= u8::from(u[a] >= limit) << (2 * a) | u8::from(-u[a] >= limit) << (2 * a + 1);
    }
    bits
}

/// Half-axes with no pose mean within 60 deg, seen from the per-axis mid-range of the means (the
/// centre is unknown when the fit fails).
pub fn missing_directions<'a>(means: impl Iterator<Item = &'a [f32; 3]> + Clone) -> Directions {
    let (mid, _, widest) = mid_range(means.clone());
    let widest = larger(widest, f32::MIN_POSITIVE);
    // cos 60 deg = 0.5.
    let mut seen = 0;
    for m in means {
        seen |= half_axes_near_of(m, &mid, &[widest; 3], 0.5);
    }
    Directions(!seen & 0x3f)
}

/// The deviation coordinates that [`EllipsoidFit::held`] holds: `Mxx, Myy, Mzz` are the last three.
pub fn held_parameters(held: &[bool; 3]) -> [bool; PARAM_COUNT] {
    let mut out = [false; PARAM_COUNT];
    out[6..].copy_from_slice(held);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f32 = 9.80665;

    /// Every pose of `N`.
    fn all<const N: usize>() -> [u16; N] {
        core::array::from_fn(|i| i as u16)
    }

    fn truth() -> Params {
        Params {
            bias: [0.3, -0.2, 0.5],
            scale: [1.0 / 16000.0, 1.0 / 16500.0, 1.0 / 16200.0],
            nonorth: [2e-7, -3e-7, 1e-7],
        }
    }

    fn sphere_dirs(n: usize) -> impl Iterator<Item = [f32; 3]> {
        // A Fibonacci sphere: well spread, no face needed.
        (0..n).map(move |i| {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = libm::sqrtf(1.0 - z * z);
            let phi = 2.399_963 * i as f32;
            [r * libm::cosf(phi), r * libm::sinf(phi), z]
        })
    }

    fn means(p: &Params, dirs: impl Iterator<Item = [f32; 3]>) -> heapless::Vec<Pose, 64> {
        dirs.map(|d| Pose::from_mean(p.invert(d.map(|v| v * G)).unwrap(), 100)).collect()
    }

    #[test]
    fn recovers_raw_count_model_from_free_directions() {
        let p = truth();
        let m = means(&p, sphere_dirs(15));
        let fit = fit_ellipsoid(&m, &mut all::<15>(), G, &OutlierRule::DEFAULT).unwrap();
        for i in 0..3 {
            assert!((fit.params.scale[i] / p.scale[i] - 1.0).abs() < 1e-3, "{fit:?}");
            assert!((fit.params.bias[i] - p.bias[i]).abs() < 1e-3, "{fit:?}");
        }
        assert!(fit.excluded.is_empty() && fit.held == [false; 3]);
    }

    #[test]
    fn a_stuck_pose_is_left_out_and_named() {
        let p = truth();
        let mut m = means(&p, sphere_dirs(16));
        m[5] = Pose::from_mean([0.0, 0.0, 0.0], 100);
        let mut kept = all::<16>();
        let fit = fit_ellipsoid(&m, &mut kept, G, &OutlierRule::DEFAULT).unwrap();
        assert_eq!(fit.excluded.as_slice(), &[5]);
        // Moved to the end, the others in their order.
        assert_eq!(kept, [0, 1, 2, 3, 4, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15, 5]);
        assert!((fit.params.scale[0] / p.scale[0] - 1.0).abs() < 1e-3);
    }

    #[test]
    fn two_planes_hold_the_cross_term() {
        let p = Params {
            nonorth: [0.0, 0.01, -0.01],
            ..Params { bias: [0.1, 0.2, 0.3], scale: [1.0; 3], nonorth: [0.0; 3] }
        };
        let arc = |plane: usize| {
            (0..13).map(move |i| {
                let a = i as f32 * 0.25;
                let mut d = [0.0; 3];
                d[plane] = libm::cosf(a);
                d[2] = libm::sinf(a) - 0.0;
                d
            })
        };
        let m = means(&p, arc(0).chain(arc(1)));
        let fit = fit_ellipsoid(&m, &mut all::<26>(), G, &OutlierRule::DEFAULT).unwrap();
        assert_eq!(fit.held, [true, false, false], "{fit:?}");
        assert!((fit.params.nonorth[1] - 0.01).abs() < 1e-3, "{fit:?}");
    }

    #[test]
    fn one_hemisphere_names_the_missing_directions() {
        let p = truth();
        // Nine poses all within 30 deg of +z: no ellipsoid.
        let dirs = (0..9).map(|i| {
            let phi = i as f32 * 0.7;
            let t = 0.1 + 0.04 * i as f32;
            [libm::sinf(t) * libm::cosf(phi), libm::sinf(t) * libm::sinf(phi), libm::cosf(t)]
        });
        let m = means(&p, dirs);
        match fit_ellipsoid(&m, &mut all::<9>(), G, &OutlierRule::DEFAULT) {
            Err(EllipsoidError::Degenerate { missing }) => assert!(missing.0 & (1 << 5) != 0, "{missing}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn a_pose_list_counts_at_most_max_excluded() {
        let mut list = PoseList::EMPTY;
        for i in 0..3 * MAX_EXCLUDED as u16 {
            list.push(i);
            assert_eq!(list.count(), list.as_slice().len());
        }
        assert_eq!(list.count(), MAX_EXCLUDED);
        let mut copy = PoseList::EMPTY;
        copy.copy_from(&list);
        assert_eq!((copy.count(), copy), (MAX_EXCLUDED, list));
    }

    #[test]
    fn refuses_bad_input() {
        let mut kept = all::<3>();
        let ones = [Pose::from_mean([1.0; 3], 100); 3];
        assert_eq!(
            fit_ellipsoid(&ones, &mut kept, G, &OutlierRule::DEFAULT),
            Err(EllipsoidError::TooFewPoses { got: 3 })
        );
        assert_eq!(fit_ellipsoid(&ones, &mut kept, 0.0, &OutlierRule::DEFAULT), Err(EllipsoidError::InvalidGravity));
        let mut m = [Pose::from_mean([1.0; 3], 100); 10];
        m[2].mean[1] = f32::NAN;
        assert_eq!(fit_ellipsoid(&m, &mut all::<10>(), G, &OutlierRule::DEFAULT), Err(EllipsoidError::NonFinitePose));
        // An index that names no pose.
        let m = [Pose::from_mean([1.0; 3], 100); 10];
        let mut kept = all::<10>();
        kept[4] = 10;
        assert_eq!(fit_ellipsoid(&m, &mut kept, G, &OutlierRule::DEFAULT), Err(EllipsoidError::NonFinitePose));
    }
}
