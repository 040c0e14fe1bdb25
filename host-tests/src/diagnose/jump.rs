//! A jump inside a hold: where a step in a hold's segment means fits them best, against a constant
//! and a line in time. Asked by the bias-step probe (a hold beside the step shows it as a jump) and
//! by the telegraph noise's test (jumps inside holds the pose finder did not cut).

use super::SEGMENTS;

/// Fewest readings per segment of a hold searched for a jump.
pub(crate) const MIN_SEGMENT_READINGS: usize = 4;

/// The jump that fits a hold's segment means best, on every channel at one place.
pub(crate) struct HoldJump<const N: usize> {
    /// By how much less residual chi-square a constant and the jump leave than a constant alone.
    pub(crate) over_constant: f64,
    /// By how much less residual chi-square a constant and the jump leave than a line in time.
    pub(crate) over_line: f64,
    /// The jump's size per channel (after less before).
    pub(crate) size: [f64; N],
    /// The share of the hold's samples after the jump.
    pub(crate) share_after: f64,
}

/// The jump in `y` (per channel the segment means, of variance `var`) on a quarter-segment grid that
/// fits best, its place common to the channels: the segment it falls in takes its share.
pub(crate) fn jump_in_hold<const N: usize>(y: &[[f64; SEGMENTS]; N], var: [f64; N]) -> HoldJump<N> {
    let share = |j: usize, at: f64| (j as f64 + 1.0 - at).clamp(0.0, 1.0);
    let fit = |shape: &dyn Fn(usize) -> f64| -> (f64, [f64; N]) {
        let fits: [(f64, f64); N] = std::array::from_fn(|c| shape_fit(&y[c], var[c], shape));
        (fits.iter().map(|f| f.0).sum(), fits.map(|f| f.1))
    };
    let (constant, _) = fit(&|_| 0.0);
    let (line, _) = fit(&|j| j as f64);
    let first =
        HoldJump { over_constant: f64::NEG_INFINITY, over_line: f64::NEG_INFINITY, size: [0.0; N], share_after: 1.0 };
    (1..4 * SEGMENTS).fold(first, |best, q| {
        let at = q as f64 / 4.0;
        let (chi2, size) = fit(&|j| share(j, at));
        let over_line = line - chi2;
        if over_line > best.over_line {
            HoldJump { over_constant: constant - chi2, over_line, size, share_after: 1.0 - at / SEGMENTS as f64 }
        } else {
            best
        }
    })
}

/// Least squares of `y` (variance `var`) on a constant and one shape over the segments: the
/// residual chi-square and the shape's coefficient.
pub(crate) fn shape_fit(y: &[f64; SEGMENTS], var: f64, shape: &dyn Fn(usize) -> f64) -> (f64, f64) {
    let n = SEGMENTS as f64;
    let (sx, sy) = ((0..SEGMENTS).map(shape).sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = (0..SEGMENTS).map(|j| (shape(j) - sx).powi(2)).sum();
    let sxy: f64 = (0..SEGMENTS).map(|j| (shape(j) - sx) * (y[j] - sy)).sum();
    let c = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    ((0..SEGMENTS).map(|j| (y[j] - sy - c * (shape(j) - sx)).powi(2)).sum::<f64>() / var, c)
}
