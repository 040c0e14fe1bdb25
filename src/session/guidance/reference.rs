//! The session's guidance as it was computed in `f64` (a Jacobi-scaled Cholesky inverse of the
//! information matrix, rank-one updates of the covariance): the oracle the `f32` square-root form is
//! tested against. Test-only; computed as it was (the candidate score now one function, [`score`]), plus
//! [`reference`] which also returns every candidate.

use crate::accumulator::Pose;
use crate::frame::{Frame, NormPose, modulus_error_gradient};
use crate::model::PARAM_COUNT;
use crate::session::{CubeDirection, Guidance, GuidanceBasis};
use crate::verdict::VerdictBounds;

const PRIOR_STD: f64 = 0.5;
const NOISE_FLOOR: f64 = 1e-14;
const TIE: f64 = 1e-6;

/// The reference's decision and what it was made from.
pub(super) struct Reference {
    /// The guidance, as the `f64` code gave it.
    pub guidance: Guidance,
    /// Current normalised variances.
    pub current: [f64; PARAM_COUNT],
    /// Every candidate: direction, key, worst, sum.
    pub candidates: [(CubeDirection, f64, f64, f64); 26],
}

/// The `f64` guidance and its candidates; `None` when the `f64` inverse fails.
pub(super) fn reference(frame: &Frame, poses: &[Pose], bounds: &VerdictBounds) -> Option<Reference> {
    let guidance = information_guidance(frame, poses, bounds);
    let (info, noise) = pose_information(frame, poses);
    let cov = spd_inverse_f64(&info)?;
    let rows = normalised_rows(frame, bounds);
    let current = rows.map(|r| r.quadratic(&cov));
    let worst_now = current.iter().fold(0.0f64, |m, &v| if v > m { v } else { m });
    let d_optimal = worst_now > 1.0;
    let candidates = CubeDirection::ALL.map(|direction| {
        let (key, worst, sum) = score(direction, &cov, &rows, &current, noise, d_optimal);
        (direction, key, worst, sum)
    });
    Some(Reference { guidance, current, candidates })
}

type Matrix64 = [[f64; PARAM_COUNT]; PARAM_COUNT];
type Vector64 = [f64; PARAM_COUNT];

/// Variance of the normalised modulus error `E / g^2` of a pose along `u` at the coarse estimate:
/// `4 sum u_a^2 sigma_a^2 / (n (k_a g)^2)`; `relative` holds `sigma_a^2 / (n (k_a g)^2)`.
fn error_variance(u: [f32; 3], relative: [f64; 3]) -> f64 {
    let mut v = 0.0;
    for a in 0..3 {
        v += 4.0 * f64::from(u[a]) * f64::from(u[a]) * relative[a];
    }
    v.max(4.0 * NOISE_FLOOR)
}

/// Gradient of `E / g^2` with respect to the deviation vector at the coarse estimate.
fn gradient(u: [f32; 3]) -> Vector64 {
    let q = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] - 1.0;
    modulus_error_gradient(&[0.0; PARAM_COUNT], &NormPose { u, q }).1.map(f64::from)
}

/// One paper-convention parameter divided by its verdict bound, as a sparse combination of the
/// deviation coordinates (at most four terms: the bias couples to `Ka c`).
#[derive(Clone, Copy)]
struct SparseRow {
    index: [u8; PARAM_COUNT],
    value: [f64; PARAM_COUNT],
    len: usize,
}

impl SparseRow {
    fn terms(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        self.index.iter().zip(&self.value).take(self.len).map(|(&i, &v)| (usize::from(i), v))
    }

    fn dot(&self, v: &Vector64) -> f64 {
        self.terms().map(|(i, r)| r * v.get(i).copied().unwrap_or(0.0)).sum()
    }

    /// `r^T m r`.
    fn quadratic(&self, m: &Matrix64) -> f64 {
        let at = |i: usize, j: usize| m.get(i).and_then(|row| row.get(j)).copied().unwrap_or(0.0);
        self.terms().map(|(i, r)| r * self.terms().map(|(j, q)| at(i, j) * q).sum::<f64>()).sum()
    }
}

/// The parameters divided by their verdict bounds (as [`crate::verdict::judge`] sets them), at the
/// coarse estimate.
fn normalised_rows(frame: &Frame, bounds: &VerdictBounds) -> [SparseRow; PARAM_COUNT] {
    let x0 = [0.0; PARAM_COUNT];
    let t = frame.params_jacobian();
    let params = frame.to_params(&x0);
    let g = frame.gravity;
    let limits = crate::verdict::param_limits(&params, bounds, g);
    let mut rows = [SparseRow { index: [0; PARAM_COUNT], value: [0.0; PARAM_COUNT], len: 0 }; PARAM_COUNT];
    for (i, row) in rows.iter_mut().enumerate() {
        let limit = limits[i];
        for j in 0..PARAM_COUNT {
            if t[i][j] == 0.0 {
                continue;
            }
            let v = f64::from(t[i][j]) / f64::from(limit);
            if let (true, Some(index), Some(value)) =
                (v.is_finite() && v != 0.0, row.index.get_mut(row.len), row.value.get_mut(row.len))
            {
                *index = j as u8;
                *value = v;
                row.len += 1;
            }
        }
    }
    rows
}

/// The information matrix of the poses (with the prior; lower triangle, which is all
/// `spd_inverse_f64` reads) and the noise to expect of one more pose (per axis, relative to
/// `(k g)^2`, for the mean number of samples).
fn pose_information(frame: &Frame, poses: &[Pose]) -> (Matrix64, [f64; 3]) {
    let scale_sq: [f64; 3] = core::array::from_fn(|a| {
        let s = f64::from(frame.gain[a]) * f64::from(frame.gravity);
        s * s
    });
    let mut info = [[0.0f64; PARAM_COUNT]; PARAM_COUNT];
    for (i, row) in info.iter_mut().enumerate() {
        row[i] = 1.0 / (PRIOR_STD * PRIOR_STD);
    }
    let mut noise_sum = [0.0f64; 3];
    let mut n_sum = 0.0f64;
    for p in poses {
        let n = f64::from(p.n.max(1));
        let mut relative = [0.0; 3];
        for a in 0..3 {
            let v = (f64::from(p.variance[a]) / scale_sq[a]).max(NOISE_FLOOR);
            noise_sum[a] += v;
            relative[a] = v / n;
        }
        n_sum += n;
        let u = frame.normalize(p.mean).u;
        let g = gradient(u);
        let w = 1.0 / error_variance(u, relative);
        for i in 0..PARAM_COUNT {
            let gi = g[i] * w;
            for j in 0..=i {
                info[i][j] += gi * g[j];
            }
        }
    }
    let count = poses.len().max(1) as f64;
    let n_mean = (n_sum / count).max(1.0);
    (info, noise_sum.map(|v| (v / count).max(NOISE_FLOOR) / n_mean))
}

/// A candidate orientation and what adding it would give.
#[derive(Clone, Copy)]
struct Candidate {
    direction: CubeDirection,
    /// What the choice minimises (see [`best_candidate`]).
    key: f64,
    /// Largest normalised variance after adding it.
    worst: f64,
    /// Sum of the normalised variances after adding it.
    sum: f64,
}

/// The best of the 26 cube directions, by a rank-one update of the covariance. While some parameter
/// is above its bound (`d_optimal`) the candidate adding the most information wins (D-optimal: the
/// largest determinant growth, `1 + g^T C g / var`), which always prefers a new direction; near the
/// bound, the one that minimises the worst normalised variance; ties by the sum.
fn best_candidate(cov: &Matrix64, rows: &[SparseRow; PARAM_COUNT], noise: [f64; 3], d_optimal: bool) -> Candidate {
    let current = rows.map(|r| r.quadratic(cov));
    let infinite = f64::INFINITY;
    let mut best = Candidate { direction: CubeDirection::face(2, true), key: infinite, worst: infinite, sum: infinite };
    for direction in CubeDirection::ALL {
        let (key, worst, sum) = score(direction, cov, rows, &current, noise, d_optimal);
        let tie = (key - best.key).abs() <= TIE * best.key.abs();
        if (key < best.key && !tie) || (tie && sum < best.sum) {
            best = Candidate { direction, key, worst, sum };
        }
    }
    best
}

/// `(key, worst, sum)` of adding a pose along `direction`: the worst and the sum of the normalised
/// variances after a rank-one update of `cov`; the key is the worst, or, `d_optimal`, minus the
/// information gained.
fn score(
    direction: CubeDirection,
    cov: &Matrix64,
    rows: &[SparseRow; PARAM_COUNT],
    current: &[f64; PARAM_COUNT],
    noise: [f64; 3],
    d_optimal: bool,
) -> (f64, f64, f64) {
    let u = direction.unit();
    let g = gradient(u);
    let w = mat_vec(cov, &g);
    let pose_noise = error_variance(u, noise);
    let denominator = pose_noise + dot(&g, &w);
    let (mut worst, mut sum) = (0.0f64, 0.0f64);
    for (row, &now) in rows.iter().zip(current) {
        let tw = row.dot(&w);
        let v = now - tw * tw / denominator;
        worst = if v > worst { v } else { worst };
        sum += v;
    }
    (if d_optimal { -denominator / pose_noise } else { worst }, worst, sum)
}

/// Scores the 26 cube directions by the predicted normalised parameter variances after adding each
/// and returns the best with the current state.
pub(super) fn information_guidance(frame: &Frame, poses: &[Pose], bounds: &VerdictBounds) -> Guidance {
    let (info, candidate_noise) = pose_information(frame, poses);
    let Some(cov) = spd_inverse_f64(&info) else {
        return Guidance::UNKNOWN;
    };
    let rows = normalised_rows(frame, bounds);
    let current = rows.map(|r| r.quadratic(&cov));
    let worst_now = current.iter().fold(0.0f64, |m, &v| if v > m { v } else { m });
    let best = best_candidate(&cov, &rows, candidate_noise, worst_now > 1.0);
    Guidance {
        next: best.direction,
        basis: GuidanceBasis::Information,
        poorly_determined: current.map(|v| !(v <= 1.0)),
        worst_std: libm::sqrt(worst_now) as f32,
        worst_std_after_next: libm::sqrt(best.worst) as f32,
    }
}

fn dot(a: &Vector64, b: &Vector64) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn mat_vec(m: &Matrix64, v: &Vector64) -> Vector64 {
    let mut out = [0.0; PARAM_COUNT];
    for (o, row) in out.iter_mut().zip(m) {
        *o = dot(row, v);
    }
    out
}

/// Inverse of a symmetric positive definite matrix in `f64` (Jacobi-scaled Cholesky): the information
/// matrix spans about ten decades between determined terms and the prior, too many for `f32`.
fn spd_inverse_f64(a: &Matrix64) -> Option<Matrix64> {
    const N: usize = PARAM_COUNT;
    let mut d = [0.0; N];
    for i in 0..N {
        if !(a[i][i] > 0.0 && a[i][i].is_finite()) {
            return None;
        }
        d[i] = 1.0 / libm::sqrt(a[i][i]);
    }
    let mut l = [[0.0f64; N]; N];
    for i in 0..N {
        for j in 0..=i {
            let mut s = a[i][j] * d[i] * d[j];
            for k in 0..j {
                s -= l[i][k] * l[j][k];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return None;
                }
                l[i][i] = libm::sqrt(s);
            } else {
                l[i][j] = s / l[j][j];
            }
        }
    }
    let mut inv = [[0.0; N]; N];
    for col in 0..N {
        // Solve L L^T x = e_col.
        let mut y = [0.0; N];
        for i in 0..N {
            let mut s = if i == col { 1.0 } else { 0.0 };
            for k in 0..i {
                s -= l[i][k] * y[k];
            }
            y[i] = s / l[i][i];
        }
        let mut x = [0.0; N];
        for i in (0..N).rev() {
            let mut s = y[i];
            for k in i + 1..N {
                s -= l[k][i] * x[k];
            }
            x[i] = s / l[i][i];
        }
        for i in 0..N {
            inv[i][col] = x[i] * d[i] * d[col];
        }
    }
    Some(inv)
}

/// A second opinion for disputed cases: the same choice by the square-root form (Givens rotations,
/// triangular solves) in `f64`, which does not lose the undetermined terms to cancellation.
pub(super) fn square_root_reference(frame: &Frame, poses: &[Pose], bounds: &VerdictBounds) -> Reference {
    let (r, noise) = square_root_f64(frame, poses);
    let solve = |b: &Vector64| {
        let mut y = [0.0f64; PARAM_COUNT];
        for i in 0..PARAM_COUNT {
            let s: f64 = (0..i).map(|k| r[k][i] * y[k]).sum();
            y[i] = (b[i] - s) / r[i][i];
        }
        y
    };
    let ys = normalised_rows(frame, bounds).map(|row| {
        let mut t = [0.0f64; PARAM_COUNT];
        for (i, v) in row.terms() {
            t[i] = v;
        }
        solve(&t)
    });
    let current = ys.map(|y| dot(&y, &y));
    let worst_now = current.iter().fold(0.0f64, |m, &v| if v > m { v } else { m });
    let d_optimal = worst_now > 1.0;
    let candidates = CubeDirection::ALL.map(|direction| {
        let u = direction.unit();
        let z = solve(&gradient(u));
        let pose_noise = error_variance(u, noise);
        let denominator = pose_noise + dot(&z, &z);
        let (mut worst, mut sum) = (0.0f64, 0.0f64);
        for (y, now) in ys.iter().zip(current) {
            let yz = dot(y, &z);
            let v = now - yz * yz / denominator;
            worst = if v > worst { v } else { worst };
            sum += v;
        }
        let key = if d_optimal { -denominator / pose_noise } else { worst };
        (direction, key, worst, sum)
    });
    let mut best = (CubeDirection::face(2, true), f64::INFINITY, f64::INFINITY, f64::INFINITY);
    for c in candidates {
        let tie = (c.1 - best.1).abs() <= TIE * best.1.abs();
        if (c.1 < best.1 && !tie) || (tie && c.3 < best.3) {
            best = c;
        }
    }
    let guidance = Guidance {
        next: best.0,
        basis: GuidanceBasis::Information,
        poorly_determined: current.map(|v| !(v <= 1.0)),
        worst_std: worst_now.sqrt() as f32,
        worst_std_after_next: best.2.sqrt() as f32,
    };
    Reference { guidance, current, candidates }
}

/// The square-root information in `f64` and the candidates' noise (as [`pose_information`]).
fn square_root_f64(frame: &Frame, poses: &[Pose]) -> (Matrix64, [f64; 3]) {
    let scale_sq: [f64; 3] = core::array::from_fn(|a| {
        let s = f64::from(frame.gain[a]) * f64::from(frame.gravity);
        s * s
    });
    let mut r = [[0.0f64; PARAM_COUNT]; PARAM_COUNT];
    for (i, row) in r.iter_mut().enumerate() {
        row[i] = 1.0 / PRIOR_STD;
    }
    for p in poses {
        let n = f64::from(p.n.max(1));
        let relative: [f64; 3] =
            core::array::from_fn(|a| (f64::from(p.variance[a]) / scale_sq[a]).max(NOISE_FLOOR) / n);
        let u = frame.normalize(p.mean).u;
        let w = 1.0 / error_variance(u, relative).sqrt();
        let mut a = gradient(u).map(|g| g * w);
        for i in 0..PARAM_COUNT {
            let rho = r[i][i].hypot(a[i]);
            let (c, s) = (r[i][i] / rho, a[i] / rho);
            r[i][i] = rho;
            for j in i + 1..PARAM_COUNT {
                let (r_ij, a_j) = (r[i][j], a[j]);
                r[i][j] = c * r_ij + s * a_j;
                a[j] = c * a_j - s * r_ij;
            }
        }
    }
    (r, pose_information(frame, poses).1)
}
