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
//! use accelcal::ellipsoid::{fit_ellipsoid, OutlierRule};
//! use accelcal::model::Params;
//! let truth = Params { bias: [0.2, -0.1, 0.3], scale: [0.98, 1.01, 0.99], nonorth: [0.01, -0.02, 0.015] };
//! let dirs = [[0.3f32, 0.9, 0.3], [-0.8, 0.5, 0.33], [0.1, -0.7, 0.7], [0.6, 0.0, -0.8], [-0.2, -0.3, -0.93],
//!     [0.9, -0.4, 0.17], [-0.5, -0.8, 0.33], [0.0, 0.6, -0.8], [-0.7, 0.1, -0.7], [0.57, 0.57, 0.57],
//!     [0.95, 0.3, -0.1], [-0.3, 0.95, -0.1]];
//! let means = dirs.map(|d| {
//!     let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
//!     truth.invert(d.map(|v| v / n * 9.80665)).unwrap()
//! });
//! let mut keep = [true; 12];
//! let fit = fit_ellipsoid(&means, &mut keep, 9.80665, &OutlierRule::DEFAULT).unwrap();
//! assert!((fit.params.scale[1] - 1.01).abs() < 1e-3);
//! assert!((fit.params.nonorth[1] + 0.02).abs() < 1e-3);
//! ```

use crate::linalg::{
    DETERMINED_PIVOT, Matrix, add_outer_product, larger, smaller, solve_spd_holding_in_place, weak_pivots,
};
use crate::model::{PARAM_COUNT, Params};

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
    /// A pose mean is not finite.
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

    /// `true` when the list is empty.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn push(&mut self, i: usize) {
        if let Some(slot) = self.index.get_mut(usize::from(self.len)) {
            *slot = u16::try_from(i).unwrap_or(u16::MAX);
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
    /// Poses left out as far off the ellipsoid.
    pub excluded: PoseList,
    /// Non-orthogonality terms held at 0 because the directions do not determine them
    /// (`[Mxx, Myy, Mzz]`).
    pub held: [bool; 3],
    /// Modulus RMSE of the poses kept, fraction of gravity.
    pub rmse_g: f32,
}

/// Fits the ellipsoid to the pose means (input unit) flagged in `keep` (same length as `means`;
/// poses found far off per `rule` are set to `false` there and listed in the result).
pub fn fit_ellipsoid(
    means: &[[f32; 3]],
    keep: &mut [bool],
    gravity: f32,
    rule: &OutlierRule,
) -> Result<EllipsoidFit, EllipsoidError> {
    if !(gravity.is_finite() && gravity > 0.0) {
        return Err(EllipsoidError::InvalidGravity);
    }
    if means.iter().zip(keep.iter()).any(|(m, &k)| k && m.iter().any(|v| !v.is_finite())) {
        return Err(EllipsoidError::NonFinitePose);
    }
    let mut excluded = PoseList::default();
    loop {
        let kept = keep.iter().take(means.len()).filter(|&&k| k).count();
        let room = usize::from(excluded.len) < MAX_EXCLUDED && kept > COEFFS + 1;
        let fitted = fit_once(means, keep, gravity);
        // A gross outlier can bend the quadric into a non-ellipsoid, or into an ellipsoid no
        // accelerometer has: then look for the pose without which the rest fit.
        let bent = match &fitted {
            Ok(fit) => !plausible(&fit.0),
            Err(e) => matches!(e, EllipsoidError::Degenerate { .. }),
        };
        if bent
            && room
            && rule.floor_g.is_finite()
            && let Some(i) = best_left_out(means, keep, gravity)
        {
            if let Some(k) = keep.get_mut(i) {
                *k = false;
            }
            excluded.push(i);
            continue;
        }
        let (params, held) = fitted?;
        let errors = ModulusErrors { means, keep, params: &params, gravity };
        let (worst, worst_abs) = errors.worst();
        let limit = crate::linalg::larger(rule.floor_g, rule.robust_sigmas * 1.4826 * errors.median_abs());
        if !(worst_abs > limit) || !room {
            return Ok(EllipsoidFit { params, excluded, held, rmse_g: errors.rms() });
        }
        if let Some(k) = keep.get_mut(worst) {
            *k = false;
        }
        excluded.push(worst);
    }
}

/// The kept pose without which the others fit an ellipsoid best (smallest modulus RMS).
fn best_left_out(means: &[[f32; 3]], keep: &mut [bool], gravity: f32) -> Option<usize> {
    let mut best: Option<(usize, f32)> = None;
    for i in 0..means.len().min(keep.len()) {
        if !keep[i] {
            continue;
        }
        keep[i] = false;
        if let Some((params, _)) = fit_once(means, keep, gravity).ok().filter(|f| plausible(&f.0)) {
            let rms = ModulusErrors { means, keep, params: &params, gravity }.rms();
            if best.is_none_or(|(_, b)| rms < b) {
                best = Some((i, rms));
            }
        }
        keep[i] = true;
    }
    best.map(|(i, _)| i)
}

/// Smallest share of the total variance of the pose means that their thinnest direction must carry:
/// poses in one plane, or in one cap narrower than about 30 deg, carry less and do not determine an
/// ellipsoid (the fit would be an extrapolation).
const MIN_THIN_VARIANCE: f32 = 0.01;

/// Refuses poses in one plane or one narrow cap (the smallest eigenvalue of the covariance of the
/// means below [`MIN_THIN_VARIANCE`] of its trace), naming the half-axes not visited.
fn check_spread(means: &[[f32; 3]], keep: &[bool]) -> Result<(), EllipsoidError> {
    let (m0, s, n) = reference(means, keep);
    let mut cov: Matrix<3> = [[0.0; 3]; 3];
    for (m, _) in means.iter().zip(keep).filter(|(_, k)| **k) {
        let v = [(m[0] - m0[0]) / s, (m[1] - m0[1]) / s, (m[2] - m0[2]) / s];
        for i in 0..3 {
            for j in 0..3 {
                cov[i][j] += v[i] * v[j] / n as f32;
            }
        }
    }
    // Positive definite after removing tau * trace from the diagonal <=> smallest eigenvalue above it.
    let shift = MIN_THIN_VARIANCE * (cov[0][0] + cov[1][1] + cov[2][2]);
    for (i, row) in cov.iter_mut().enumerate() {
        row[i] -= shift;
    }
    match lower_factor(&cov) {
        Some(_) => Ok(()),
        None => Err(EllipsoidError::Degenerate { missing: missing_directions(means, keep) }),
    }
}

/// Bits of the half-axes of axis `a` that the direction `f` (of length `norm`) lies within 60 deg of.
fn visited(f: [f32; 3], norm: f32, a: usize) -> u8 {
    // cos 60 deg = 0.5.
    let up = u8::from(f[a] >= 0.5 * norm) << (2 * a);
    let down = u8::from(-f[a] >= 0.5 * norm) << (2 * a + 1);
    up | down
}

/// Largest ratio between two axes' scale factors, and largest non-orthogonality relative to its
/// scale, of any accelerometer: a fit beyond them has been bent by a bad pose.
const PLAUSIBLE_SCALE_RATIO: f32 = 1.3;
const PLAUSIBLE_NONORTH: f32 = 0.1;

/// `true` for an ellipsoid an accelerometer can have.
fn plausible(p: &Params) -> bool {
    let s = p.scale;
    let (lo, hi) = (smaller(smaller(s[0], s[1]), s[2]), larger(larger(s[0], s[1]), s[2]));
    let m = p.nonorth;
    hi <= PLAUSIBLE_SCALE_RATIO * lo
        && m[0].abs() <= PLAUSIBLE_NONORTH * s[0]
        && m[1].abs() <= PLAUSIBLE_NONORTH * s[0]
        && m[2].abs() <= PLAUSIBLE_NONORTH * s[1]
}

/// The modulus errors `|f_b| / g - 1` of the kept poses under `params`.
struct ModulusErrors<'a> {
    means: &'a [[f32; 3]],
    keep: &'a [bool],
    params: &'a Params,
    gravity: f32,
}

impl ModulusErrors<'_> {
    /// The error of pose `i`; `None` when it is not kept. Out of line: every statistic below calls it.
    #[inline(never)]
    fn of(&self, i: usize) -> Option<f32> {
        let (m, &kept) = (self.means.get(i)?, self.keep.get(i)?);
        let f = self.params.apply(*m);
        kept.then(|| crate::linalg::sqrt_f32(crate::model::norm_squared(f)) / self.gravity - 1.0)
    }

    fn iter(&self) -> impl Iterator<Item = (usize, f32)> + '_ {
        (0..self.means.len()).filter_map(|i| self.of(i).map(|e| (i, e)))
    }

    fn worst(&self) -> (usize, f32) {
        self.iter().map(|(i, e)| (i, e.abs())).fold((0, -1.0), |a, b| if b.1 > a.1 { b } else { a })
    }

    fn rms(&self) -> f32 {
        let (sum, n) = self.iter().fold((0.0f32, 0u32), |(s, n), (_, e)| (s + e * e, n + 1));
        crate::linalg::sqrt_f32(sum / n.max(1) as f32)
    }

    /// Lower median of `|e|` without a buffer: the smallest value with at least half the values at or
    /// below it (quadratic in the pose count, which is small).
    fn median_abs(&self) -> f32 {
        let n = self.iter().count();
        let mut best = f32::INFINITY;
        for (_, e) in self.iter() {
            let v = e.abs();
            if v < best && 2 * self.iter().filter(|(_, o)| o.abs() <= v).count() >= n {
                best = v;
            }
        }
        best
    }
}

/// Reference point and spread of the kept means: the numbers the quadric is fitted in.
fn reference(means: &[[f32; 3]], keep: &[bool]) -> ([f32; 3], f32, usize) {
    let mut sum = [0.0f32; 3];
    let mut n = 0usize;
    for (m, _) in means.iter().zip(keep).filter(|(_, k)| **k) {
        for a in 0..3 {
            sum[a] += m[a];
        }
        n += 1;
    }
    let center = sum.map(|s| s / n.max(1) as f32);
    let mut spread = 0.0f32;
    for (m, _) in means.iter().zip(keep).filter(|(_, k)| **k) {
        spread += crate::model::norm_squared([m[0] - center[0], m[1] - center[1], m[2] - center[2]]);
    }
    (center, crate::linalg::sqrt_f32(spread / n.max(1) as f32), n)
}

/// One least-squares fit of the quadric to the kept poses, factored into the model.
fn fit_once(means: &[[f32; 3]], keep: &[bool], gravity: f32) -> Result<(Params, [bool; 3]), EllipsoidError> {
    let (m0, s, n) = reference(means, keep);
    if n < COEFFS {
        return Err(EllipsoidError::TooFewPoses { got: n });
    }
    check_spread(means, keep)?;
    let degenerate = || EllipsoidError::Degenerate { missing: missing_directions(means, keep) };
    if !(s > 0.0 && s.is_finite()) {
        return Err(degenerate());
    }
    let mut ata: Matrix<COEFFS> = [[0.0; COEFFS]; COEFFS];
    let mut atb = [0.0f32; COEFFS];
    for (m, _) in means.iter().zip(keep).filter(|(_, k)| **k) {
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
        for i in 0..COEFFS {
            atb[i] += row[i];
        }
        add_outer_product(&mut ata, &row, 1.0);
    }
    let held = weak_pivots(&ata, DETERMINED_PIVOT);
    if held[..6].iter().any(|&h| h) {
        return Err(degenerate());
    }
    // `atb` becomes the quadric coefficients.
    solve_spd_holding_in_place(&mut ata, &mut atb, &held).map_err(|_| degenerate())?;
    let params = factor(&atb, m0, s, gravity).ok_or_else(degenerate)?;
    // Quadric cross terms xy, xz, yz map to Mxx, Myy, Mzz.
    Ok((params, [held[6], held[7], held[8]]))
}

/// `v^T A v + b^T v = 1` in `v = (m - m0) / s` to the paper's `Ka`, `B`; `None` unless an ellipsoid.
fn factor(theta: &[f32; COEFFS], m0: [f32; 3], s: f32, gravity: f32) -> Option<Params> {
    let a = [[theta[0], theta[6], theta[7]], [theta[6], theta[1], theta[8]], [theta[7], theta[8], theta[2]]];
    let b = [theta[3], theta[4], theta[5]];
    // A = L^T L, L lower-triangular; the centre solves A v0 = -b / 2: L^T y = -b / 2, then L v0 = y.
    let l = lower_factor(&a)?;
    let (sx, sy, sz) = (l.scale[0], l.scale[1], l.scale[2]);
    let (mx, my, mz) = (l.nonorth[0], l.nonorth[1], l.nonorth[2]);
    let y2 = -0.5 * b[2] / sz;
    let y1 = (-0.5 * b[1] - mz * y2) / sy;
    let y0 = (-0.5 * b[0] - mx * y1 - my * y2) / sx;
    let v0 = l.invert([y0, y1, y2])?;
    let k = 1.0 - 0.5 * (b[0] * v0[0] + b[1] * v0[1] + b[2] * v0[2]);
    if !(k > 0.0) {
        return None;
    }
    // Ka^T Ka = g^2 A / (k s^2): Ka = L g / (s sqrt(k)).
    let w = gravity / (s * crate::linalg::sqrt_f32(k));
    let ka = Params { bias: [0.0; 3], scale: l.scale.map(|v| w * v), nonorth: l.nonorth.map(|v| w * v) };
    let center = [m0[0] + s * v0[0], m0[1] + s * v0[1], m0[2] + s * v0[2]];
    let params = Params { bias: ka.ka_times(center), ..ka };
    params.is_finite().then_some(params)
}

/// The lower-triangular `L` with `L^T L = a` (a Cholesky factorisation in reversed order, bottom row
/// first), as the `Ka` of a model without bias; `None` unless `a` is positive definite.
fn lower_factor(a: &Matrix<3>) -> Option<Params> {
    let szz = sqrt_positive(a[2][2])?;
    let mzz = a[1][2] / szz;
    let myy = a[0][2] / szz;
    let syy = sqrt_positive(a[1][1] - mzz * mzz)?;
    let mxx = (a[0][1] - myy * mzz) / syy;
    let sxx = sqrt_positive(a[0][0] - mxx * mxx - myy * myy)?;
    Some(Params { bias: [0.0; 3], scale: [sxx, syy, szz], nonorth: [mxx, myy, mzz] })
}

fn sqrt_positive(v: f32) -> Option<f32> {
    (v > 0.0 && v.is_finite()).then(|| crate::linalg::sqrt_f32(v))
}

/// Half-axes with no kept pose within 60 deg, seen from the per-axis mid-range of the readings
/// (the centre is unknown when the fit fails).
pub fn missing_directions(means: &[[f32; 3]], keep: &[bool]) -> Directions {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for (m, _) in means.iter().zip(keep).filter(|(_, k)| **k) {
        for a in 0..3 {
            lo[a] = if m[a] < lo[a] { m[a] } else { lo[a] };
            hi[a] = if m[a] > hi[a] { m[a] } else { hi[a] };
        }
    }
    let half = (0..3).map(|a| 0.5 * (hi[a] - lo[a])).fold(0.0f32, |x, y| if y > x { y } else { x });
    let mut seen = 0u8;
    for (m, _) in means.iter().zip(keep).filter(|(_, k)| **k) {
        let u: [f32; 3] = core::array::from_fn(|a| (m[a] - 0.5 * (hi[a] + lo[a])) / larger(half, f32::MIN_POSITIVE));
        let norm = crate::linalg::sqrt_f32(crate::model::norm_squared(u));
        for a in 0..3 {
            seen |= visited(u, norm, a);
        }
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

    fn means(p: &Params, dirs: impl Iterator<Item = [f32; 3]>) -> heapless::Vec<[f32; 3], 64> {
        dirs.map(|d| p.invert(d.map(|v| v * G)).unwrap()).collect()
    }

    #[test]
    fn recovers_raw_count_model_from_free_directions() {
        let p = truth();
        let m = means(&p, sphere_dirs(15));
        let mut keep = [true; 15];
        let fit = fit_ellipsoid(&m, &mut keep, G, &OutlierRule::DEFAULT).unwrap();
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
        m[5] = [0.0, 0.0, 0.0];
        let mut keep = [true; 16];
        let fit = fit_ellipsoid(&m, &mut keep, G, &OutlierRule::DEFAULT).unwrap();
        assert_eq!(fit.excluded.as_slice(), &[5]);
        assert!(!keep[5]);
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
        let mut keep = [true; 26];
        let fit = fit_ellipsoid(&m, &mut keep, G, &OutlierRule::DEFAULT).unwrap();
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
        let mut keep = [true; 9];
        match fit_ellipsoid(&m, &mut keep, G, &OutlierRule::DEFAULT) {
            Err(EllipsoidError::Degenerate { missing }) => assert!(missing.0 & (1 << 5) != 0, "{missing}"),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn refuses_bad_input() {
        let mut keep = [true; 3];
        assert_eq!(
            fit_ellipsoid(&[[1.0; 3]; 3], &mut keep, G, &OutlierRule::DEFAULT),
            Err(EllipsoidError::TooFewPoses { got: 3 })
        );
        assert_eq!(
            fit_ellipsoid(&[[1.0; 3]; 3], &mut keep, 0.0, &OutlierRule::DEFAULT),
            Err(EllipsoidError::InvalidGravity)
        );
        let mut m = [[1.0f32; 3]; 10];
        m[2][1] = f32::NAN;
        assert_eq!(fit_ellipsoid(&m, &mut [true; 10], G, &OutlierRule::DEFAULT), Err(EllipsoidError::NonFinitePose));
    }
}
