//! The session's guidance in single precision: predicted parameter variances from a square-root
//! information matrix.
//!
//! The information matrix `J^T J` of the poses (with a weak prior) spans some ten decades between the
//! prior and the determined terms: formed and factorised in `f32` its Schur complements cancel. The
//! square-root form never forms it: an upper-triangular `R` with `R^T R = information` starts as the
//! prior (`1 / PRIOR_STD` on the diagonal) and takes each pose's row `g / sigma` by Givens rotations.
//! `R`'s entries span the square root of that range. With `y = R^-T t` (one triangular solve) the
//! variance of a parameter combination `t` is `|y|^2`; adding a candidate pose with `z = R^-T g`
//! changes it to `|y|^2 - (y.z)^2 / (s + |z|^2)`, evaluated without cancellation (see
//! [`variance_after`]).

use crate::accumulator::Pose;
use crate::frame::{Frame, NormPose, modulus_error_gradient};
use crate::linalg::{larger, sqrt_f32};
use crate::model::PARAM_COUNT;
use crate::verdict::VerdictBounds;

use super::{CubeDirection, Guidance, GuidanceBasis};

#[cfg(test)]
mod reference;
#[cfg(test)]
mod tests;

/// Prior standard deviation of every deviation coordinate (bias 0.5 g, scale 50 %, non-orthogonality
/// 0.5 rad): keeps the information matrix invertible before every term is determined.
const PRIOR_STD: f32 = 0.5;

/// Smallest per-axis noise variance assumed, relative to `(k g)^2` (a standard deviation of 1e-7 g,
/// the resolution of the normalised `f32` pose).
const NOISE_FLOOR: f32 = 1e-14;

/// Relative tolerance under which two candidates' keys tie (symmetric directions tie exactly in exact
/// arithmetic; `f32` rounding separates them by a few 1e-7).
const TIE: f32 = 1e-5;

type Vector = [f32; PARAM_COUNT];

/// Upper-triangular square root `R` of the information matrix, `R^T R = information`: `r[i][j]` for
/// `j >= i` (the rest stays 0).
type SquareRoot = [[f32; PARAM_COUNT]; PARAM_COUNT];

/// Variance of the normalised modulus error `E / g^2` of a pose along `u` at the coarse estimate:
/// `4 sum u_a^2 sigma_a^2 / (n (k_a g)^2)`; `relative` holds `sigma_a^2 / (n (k_a g)^2)`.
fn error_variance(u: [f32; 3], relative: [f32; 3]) -> f32 {
    let v = 4.0 * (u[0] * u[0] * relative[0] + u[1] * u[1] * relative[1] + u[2] * u[2] * relative[2]);
    larger(v, 4.0 * NOISE_FLOOR)
}

/// Gradient of `E / g^2` with respect to the deviation vector at the coarse estimate.
fn gradient(u: [f32; 3]) -> Vector {
    let q = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] - 1.0;
    modulus_error_gradient(&[0.0; PARAM_COUNT], &NormPose { u, q }).1
}

/// The parameters divided by their verdict bounds (as [`crate::verdict::judge`] sets them), at the
/// coarse estimate: row `i` gives parameter `i` over its bound in the deviation coordinates.
fn normalised_rows(frame: &Frame, bounds: &VerdictBounds) -> [Vector; PARAM_COUNT] {
    let t = frame.params_jacobian();
    let params = frame.to_params(&[0.0; PARAM_COUNT]);
    let limits = crate::verdict::param_limits(&params, bounds, frame.gravity);
    let mut rows = [[0.0; PARAM_COUNT]; PARAM_COUNT];
    for ((row, t_row), limit) in rows.iter_mut().zip(&t).zip(limits) {
        for (out, &t_ij) in row.iter_mut().zip(t_row) {
            let v = t_ij / limit;
            *out = if v.is_finite() { v } else { 0.0 };
        }
    }
    rows
}

/// Adds the row `a` to `r` by Givens rotations: afterwards `R^T R` has grown by `a a^T`. The diagonal
/// only grows (it starts at the prior's `1 / PRIOR_STD`), so no rotation divides by zero.
fn add_row(r: &mut SquareRoot, mut a: Vector) {
    for i in 0..PARAM_COUNT {
        let (r_ii, a_i) = (r[i][i], a[i]);
        if a_i == 0.0 {
            continue;
        }
        let rho = sqrt_f32(r_ii * r_ii + a_i * a_i);
        let (c, s) = (r_ii / rho, a_i / rho);
        r[i][i] = rho;
        for j in i + 1..PARAM_COUNT {
            let (r_ij, a_j) = (r[i][j], a[j]);
            r[i][j] = c * r_ij + s * a_j;
            a[j] = c * a_j - s * r_ij;
        }
    }
}

/// `R^-T b`: forward substitution (`R^T` is lower triangular).
fn solve_transposed(r: &SquareRoot, b: &Vector) -> Vector {
    let mut y = [0.0; PARAM_COUNT];
    for i in 0..PARAM_COUNT {
        let mut s = b[i];
        for k in 0..i {
            s -= r[k][i] * y[k];
        }
        y[i] = s / r[i][i];
    }
    y
}

fn dot(a: &Vector, b: &Vector) -> f32 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The square-root information of the poses (with the prior) and the noise to expect of one more pose
/// (per axis, relative to `(k g)^2`, for the mean number of samples).
fn square_root_information(frame: &Frame, poses: &[Pose]) -> (SquareRoot, [f32; 3]) {
    let scale_sq = frame.gain.map(|k| (k * frame.gravity) * (k * frame.gravity));
    let mut r = [[0.0; PARAM_COUNT]; PARAM_COUNT];
    for (i, row) in r.iter_mut().enumerate() {
        row[i] = 1.0 / PRIOR_STD;
    }
    let (mut noise_sum, mut n_sum) = ([0.0f32; 3], 0.0f32);
    for p in poses {
        let n = p.n.max(1) as f32;
        let mut relative = [0.0; 3];
        for a in 0..3 {
            let v = larger(p.variance[a] / scale_sq[a], NOISE_FLOOR);
            noise_sum[a] += v;
            relative[a] = v / n;
        }
        n_sum += n;
        let u = frame.normalize(p.mean).u;
        let weight = 1.0 / sqrt_f32(error_variance(u, relative));
        add_row(&mut r, gradient(u).map(|g| g * weight));
    }
    let count = poses.len().max(1) as f32;
    let n_mean = larger(n_sum / count, 1.0);
    (r, noise_sum.map(|v| larger(v / count, NOISE_FLOOR) / n_mean))
}

/// `|y|^2 - (y.z)^2 / d` (the variance `|y|^2` after adding a pose with `R^-T g = z` and noise variance
/// `noise`, `d = noise + |z|^2`) as `|y - c w|^2 + c^2 noise / d` with `w = z / sqrt(d)`, `c = y.w`: two
/// non-negative terms, so the large variance of an undetermined term does not cancel in `f32`.
fn variance_after(y: &Vector, w: &Vector, noise_over_d: f32) -> f32 {
    let c = dot(y, w);
    let mut v = c * c * noise_over_d;
    for (y_i, w_i) in y.iter().zip(w) {
        let e = y_i - c * w_i;
        v += e * e;
    }
    v
}

/// A candidate orientation and what adding it would give.
#[derive(Clone, Copy)]
struct Candidate {
    direction: CubeDirection,
    /// What the choice minimises (see [`best_candidate`]).
    key: f32,
    /// Largest normalised variance after adding it.
    worst: f32,
    /// Sum of the normalised variances after adding it.
    sum: f32,
}

/// Direction `direction` scored against the parameters' `ys = R^-T t`.
fn score(r: &SquareRoot, ys: &[Vector; PARAM_COUNT], noise: [f32; 3], direction: CubeDirection) -> (f32, f32, f32) {
    let u = direction.unit();
    let z = solve_transposed(r, &gradient(u));
    let pose_noise = error_variance(u, noise);
    let d = pose_noise + dot(&z, &z);
    let scale = 1.0 / sqrt_f32(d);
    let w = z.map(|v| v * scale);
    let (mut worst, mut sum) = (0.0f32, 0.0f32);
    for y in ys {
        let v = variance_after(y, &w, pose_noise / d);
        worst = if v > worst { v } else { worst };
        sum += v;
    }
    (d / pose_noise, worst, sum)
}

/// The best of the 26 cube directions. While some parameter is above its bound (`d_optimal`) the
/// candidate adding the most information wins (D-optimal: the largest determinant growth,
/// `1 + g^T C g / var`), which always prefers a new direction; near the bound, the one that minimises
/// the worst normalised variance; ties by the sum.
fn best_candidate(r: &SquareRoot, ys: &[Vector; PARAM_COUNT], noise: [f32; 3], d_optimal: bool) -> Candidate {
    let infinite = f32::INFINITY;
    let mut best = Candidate { direction: CubeDirection::face(2, true), key: infinite, worst: infinite, sum: infinite };
    for direction in CubeDirection::ALL {
        let (growth, worst, sum) = score(r, ys, noise, direction);
        let key = if d_optimal { -growth } else { worst };
        let tie = (key - best.key).abs() <= TIE * best.key.abs();
        if (key < best.key && !tie) || (tie && sum < best.sum) {
            best = Candidate { direction, key, worst, sum };
        }
    }
    best
}

/// Scores the 26 cube directions by the predicted normalised parameter variances after adding each
/// and returns the best with the current state (in the library's tests, checked against the `f64`
/// reference).
pub(super) fn information_guidance(frame: &Frame, poses: &[Pose], bounds: &VerdictBounds) -> Guidance {
    let guidance = square_root_guidance(frame, poses, bounds);
    #[cfg(test)]
    tests::check_against_reference(frame, poses, bounds, &guidance);
    guidance
}

fn square_root_guidance(frame: &Frame, poses: &[Pose], bounds: &VerdictBounds) -> Guidance {
    let (r, candidate_noise) = square_root_information(frame, poses);
    if !r.iter().enumerate().all(|(i, row)| row[i].is_finite()) {
        return Guidance::UNKNOWN;
    }
    let ys = normalised_rows(frame, bounds).map(|t| solve_transposed(&r, &t));
    let current = ys.map(|y| dot(&y, &y));
    let worst_now = current.iter().fold(0.0f32, |m, &v| if v > m { v } else { m });
    let best = best_candidate(&r, &ys, candidate_noise, worst_now > 1.0);
    Guidance {
        next: best.direction,
        basis: GuidanceBasis::Information,
        poorly_determined: current.map(|v| !(v <= 1.0)),
        worst_std: sqrt_f32(worst_now),
        worst_std_after_next: sqrt_f32(best.worst),
    }
}
