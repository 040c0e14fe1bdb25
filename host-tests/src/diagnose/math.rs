//! Small `f64` helpers: vector algebra, the 9-parameter model, least squares and cross-validation.

use accelcal::model::{PARAM_COUNT, Params};

pub(crate) type V3 = [f64; 3];

/// `v` along axis `a`.
pub(crate) fn axis(a: usize, v: f64) -> V3 {
    std::array::from_fn(|i| if i == a { v } else { 0.0 })
}

pub(crate) use crate::vec3::{dot, norm};

pub(crate) fn mean(v: &[f64]) -> f64 {
    if v.is_empty() { f64::NAN } else { v.iter().sum::<f64>() / v.len() as f64 }
}

pub(crate) fn rms(v: &[f64]) -> f64 {
    mean_square(v).sqrt()
}

/// The mean of the squares (NaN without values).
pub(crate) fn mean_square(v: &[f64]) -> f64 {
    if v.is_empty() { f64::NAN } else { v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64 }
}

pub(crate) fn std_dev(v: &[f64]) -> f64 {
    let m = mean(v);
    if v.len() < 2 { 0.0 } else { (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt() }
}

pub(crate) use crate::stats::median;

/// Running sums of a series, `S[0] = 0`, `S[i + 1] = S[i] + x[i]`: any block's mean in one step.
pub(crate) struct PrefixSums(Vec<f64>);

impl PrefixSums {
    pub(crate) fn new(x: impl IntoIterator<Item = f64>) -> Self {
        let mut sums = vec![0.0];
        let mut total = 0.0;
        for v in x {
            total += v;
            sums.push(total);
        }
        PrefixSums(sums)
    }

    /// Number of samples summed.
    pub(crate) fn len(&self) -> usize {
        self.0.len() - 1
    }

    /// Mean over every start `i` of `S[i + 2m] - 2 S[i + m] + S[i]`: `m` times the difference of two
    /// successive clusters' means, averaged (`m` at most half the series).
    pub(crate) fn mean_second_difference(&self, m: usize) -> f64 {
        let count = self.len() + 1 - 2 * m;
        self.second_differences(m).sum::<f64>() / count as f64
    }

    /// Overlapping Allan variance of clusters of `m` samples, `var(mean[i + m] - mean[i]) / 2`
    /// over every start `i`, in the series' units squared (`m` at most half the series).
    pub(crate) fn allan_variance(&self, m: usize) -> f64 {
        let count = self.len() + 1 - 2 * m;
        let sum: f64 = self.second_differences(m).map(|d| d.powi(2)).sum();
        sum / (2.0 * count as f64 * (m * m) as f64)
    }

    /// `S[i + 2m] - 2 S[i + m] + S[i]` for every start `i`: `m` times the difference of two
    /// successive clusters' means.
    fn second_differences(&self, m: usize) -> impl Iterator<Item = f64> + '_ {
        let s = &self.0;
        (0..self.len() + 1 - 2 * m).map(move |k| s[k + 2 * m] - 2.0 * s[k + m] + s[k])
    }
}

pub(crate) fn correlation(x: &[f64], y: &[f64]) -> Option<f64> {
    let (mx, my) = (mean(x), mean(y));
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx).powi(2)).sum();
    let syy: f64 = y.iter().map(|b| (b - my).powi(2)).sum();
    (sxx > 0.0 && syy > 0.0).then(|| sxy / (sxx * syy).sqrt())
}

/// The 9-parameter model in `f64`: `f = Ka m - B`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Model {
    pub(crate) ka: [[f64; 3]; 3],
    pub(crate) bias: V3,
}

impl Model {
    pub(crate) fn from_params(p: &Params) -> Self {
        let (s, m) = (p.scale.map(f64::from), p.nonorth.map(f64::from));
        Self { ka: [[s[0], 0.0, 0.0], [m[0], s[1], 0.0], [m[1], m[2], s[2]]], bias: p.bias.map(f64::from) }
    }

    pub(crate) fn apply(&self, m: V3) -> V3 {
        std::array::from_fn(|i| (0..3).map(|j| self.ka[i][j] * m[j]).sum::<f64>() - self.bias[i])
    }

    /// The reading for calibrated `f`: `Ka^-1 (f + B)`.
    pub(crate) fn invert(&self, f: V3) -> V3 {
        self.ka_inverse_times([f[0] + self.bias[0], f[1] + self.bias[1], f[2] + self.bias[2]])
    }

    /// `Ka^-1 y`: the reading change that moves the calibrated reading by `y` (forward substitution).
    pub(crate) fn ka_inverse_times(&self, y: V3) -> V3 {
        let k = &self.ka;
        let x0 = y[0] / k[0][0];
        let x1 = (y[1] - k[1][0] * x0) / k[1][1];
        let x2 = (y[2] - k[2][0] * x0 - k[2][1] * x1) / k[2][2];
        [x0, x1, x2]
    }

    /// `Ka^T u`: how a reading error (input unit) moves the modulus along `u`.
    pub(crate) fn kt_times(&self, u: V3) -> V3 {
        std::array::from_fn(|j| (0..3).map(|i| self.ka[i][j] * u[i]).sum())
    }
}

/// `d residual / d [B, S, M]` at reading `m` with calibrated direction `u`.
pub(crate) fn jacobian_row(m: V3, u: V3) -> [f64; PARAM_COUNT] {
    [-u[0], -u[1], -u[2], u[0] * m[0], u[1] * m[1], u[2] * m[2], u[1] * m[0], u[2] * m[0], u[2] * m[1]]
}

/// The lower triangle of `X^T X` over `poses` (unscaled).
pub(crate) fn normals(rows: &[Vec<f64>], poses: impl IntoIterator<Item = usize>) -> Vec<Vec<f64>> {
    let p = rows.first().map_or(0, Vec::len);
    let mut a = vec![vec![0.0; p]; p];
    for i in poses {
        let x = &rows[i];
        for ((j, aj), xj) in a.iter_mut().enumerate().zip(x) {
            for (ajk, xk) in aj[..=j].iter_mut().zip(x) {
                *ajk += xj * xk;
            }
        }
    }
    a
}

/// `-X^T r` over `poses` (unscaled).
pub(crate) fn rhs(rows: &[Vec<f64>], r: &[f64], poses: impl IntoIterator<Item = usize>) -> Vec<f64> {
    let mut b = vec![0.0; rows.first().map_or(0, Vec::len)];
    for i in poses {
        for (bj, v) in b.iter_mut().zip(&rows[i]) {
            *bj -= v * r[i];
        }
    }
    b
}

/// The column scales (root mean square over `count` poses, 1 for a column that is zero) of the
/// normal matrix `a` (lower triangle, unscaled), and `a` with its columns scaled by them.
pub(crate) fn scaled(mut a: Vec<Vec<f64>>, count: usize) -> (Vec<f64>, Vec<Vec<f64>>) {
    let scale: Vec<f64> = (0..a.len())
        .map(|j| {
            let s = (a[j][j] / count as f64).sqrt();
            if s > 0.0 && s.is_finite() { s } else { 1.0 }
        })
        .collect();
    for (aj, sj) in a.iter_mut().zip(&scale) {
        for (ajk, sk) in aj.iter_mut().zip(&scale) {
            *ajk /= sj * sk;
        }
    }
    (scale, a)
}

/// For each part, the sum of all the others (sums of per-fold normal matrices or right-hand
/// sides), by prefix and suffix sums: no subtraction, so a column only the left-out part holds
/// stays exactly zero.
pub(crate) fn sums_without<T: Clone>(parts: &[T], zero: T, add: impl Fn(&T, &T) -> T) -> Vec<T> {
    let mut prefix = vec![zero.clone()];
    for part in parts {
        prefix.push(add(&prefix[prefix.len() - 1], part));
    }
    let mut suffix = zero;
    let mut out = vec![None; parts.len()];
    for f in (0..parts.len()).rev() {
        out[f] = Some(add(&prefix[f], &suffix));
        suffix = add(&suffix, &parts[f]);
    }
    out.into_iter().flatten().collect()
}

pub(crate) fn add_vectors(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(x, y)| x + y).collect()
}

pub(crate) fn add_matrices(a: &[Vec<f64>], b: &[Vec<f64>]) -> Vec<Vec<f64>> {
    a.iter().zip(b).map(|(x, y)| add_vectors(x, y)).collect()
}

/// Attempts at a ridge that lets the scaled normal matrix factor, each 100 times the last.
const RIDGE_ATTEMPTS: usize = 6;

/// Least squares on fixed training poses, factored once: the fit of any residual vector over them
/// costs one right-hand side and two substitutions (the noise draws share a design).
pub(crate) struct Design {
    train: Vec<usize>,
    scale: Vec<f64>,
    /// The scaled normal matrix (lower triangle), kept for a larger ridge.
    a: Vec<Vec<f64>>,
    /// Lower Cholesky factor of `a` plus `ridge`.
    l: Vec<Vec<f64>>,
    ridge: f64,
    /// Ridges tried before `ridge` factored.
    attempt: usize,
}

impl Design {
    /// Columns scaled, a tiny ridge keeps collinear columns finite; `None` when `train` has fewer
    /// poses than columns or no ridge tried factors.
    pub(crate) fn new(rows: &[Vec<f64>], train: Vec<usize>) -> Option<Self> {
        rows.first()?;
        let a = normals(rows, train.iter().copied());
        Self::from_normals(a, train)
    }

    /// [`Design::new`] from the training poses' normal matrix (lower triangle, unscaled).
    fn from_normals(a: Vec<Vec<f64>>, train: Vec<usize>) -> Option<Self> {
        let p = a.len();
        if train.len() < p {
            return None;
        }
        let (scale, a) = scaled(a, train.len());
        let trace: f64 = (0..p).map(|j| a[j][j]).sum();
        let mut ridge = 1e-11 * trace / p as f64;
        for attempt in 0..RIDGE_ATTEMPTS {
            if let Some(l) = cholesky(&a, ridge) {
                return Some(Self { train, scale, a, l, ridge, attempt });
            }
            ridge = next_ridge(ridge);
        }
        None
    }

    /// The `x` minimising `sum over train of (r_i + rows_i . x)^2`; a solution that is not finite
    /// tries the larger ridges left.
    pub(crate) fn solve(&self, rows: &[Vec<f64>], r: &[f64]) -> Option<Vec<f64>> {
        self.solve_rhs(&rhs(rows, r, self.train.iter().copied()))
    }

    /// [`Design::solve`] from the training poses' `-X^T r` (unscaled).
    fn solve_rhs(&self, b: &[f64]) -> Option<Vec<f64>> {
        let b: Vec<f64> = b.iter().zip(&self.scale).map(|(v, s)| v / s).collect();
        let mut y = solve_factored(&self.l, &b);
        let mut ridge = self.ridge;
        for _ in self.attempt + 1..RIDGE_ATTEMPTS {
            if y.is_some() {
                break;
            }
            ridge = next_ridge(ridge);
            y = cholesky(&self.a, ridge).and_then(|l| solve_factored(&l, &b));
        }
        Some(y?.iter().zip(&self.scale).map(|(v, s)| v / s).collect())
    }

    /// The variance of the fit's prediction at `row` in units of one training pose's variance
    /// (`row^T (X^T X)^-1 row`; the leave-one-out `h / (1 - h)` of a pose's own leverage `h`).
    pub(crate) fn variance_factor(&self, row: &[f64]) -> f64 {
        self.whiten(row).iter().map(|v| v * v).sum()
    }

    /// `L^-1` of the scaled `row`: two whitened rows' dot product is `row_i^T (X^T X)^-1 row_j`.
    fn whiten(&self, row: &[f64]) -> Vec<f64> {
        let scaled: Vec<f64> = row.iter().zip(&self.scale).map(|(v, s)| v / s).collect();
        forward_substitute(&self.l, &scaled)
    }

    /// The residuals of the fit at every pose, a training pose or not; `None` when `r` cannot be
    /// fitted.
    pub(crate) fn residuals_everywhere(&self, rows: &[Vec<f64>], r: &[f64]) -> Option<Vec<f64>> {
        let x = self.solve(rows, r)?;
        Some((0..r.len()).map(|i| predict(rows, r, &x, i)).collect())
    }

    /// In-sample residuals at the training poses, one per entry of `r` (`None` elsewhere); `None`
    /// when `r` cannot be fitted.
    pub(crate) fn residuals(&self, rows: &[Vec<f64>], r: &[f64]) -> Option<Vec<Option<f64>>> {
        let everywhere = self.residuals_everywhere(rows, r)?;
        let mut out = vec![None; r.len()];
        for &i in &self.train {
            out[i] = Some(everywhere[i]);
        }
        Some(out)
    }
}

fn next_ridge(ridge: f64) -> f64 {
    ridge * 100.0 + 1e-300
}

/// The fit on every pose not dropped.
pub(crate) fn kept_design(rows: &[Vec<f64>], dropped: &[bool]) -> Option<Design> {
    Design::new(rows, (0..dropped.len()).filter(|&i| !dropped[i]).collect())
}

/// A fold of `fold_rows` rows is withheld through the full fit's hat matrix rather than refitted
/// when they are no more than the design's `columns`: whitening them (`rows x columns^2 / 2`) and
/// factoring `I - H_FF` then cost about what refitting the others does (their normal matrix, then
/// `columns^3 / 6`), and a log of up to 40 poses leaves one pose and its segments out at a time.
pub(crate) fn fold_is_small(fold_rows: usize, columns: usize) -> bool {
    fold_rows <= columns
}

/// The lower triangle of `I - H_FF` for a fold's whitened rows `z` (`H_FF = Z Z^T`, the fold's
/// block of the hat matrix).
pub(crate) fn identity_less_hat(z: &[Vec<f64>]) -> Vec<Vec<f64>> {
    let hat = |j: usize, k: usize| z[j].iter().zip(&z[k]).map(|(a, b)| a * b).sum::<f64>();
    (0..z.len()).map(|j| (0..=j).map(|k| f64::from(u8::from(j == k)) - hat(j, k)).collect()).collect()
}

/// Cross-validation folds, factored once: the held-out residuals of many residual vectors (noise
/// draws) over one design.
pub(crate) struct CvDesign {
    /// The fit to every kept pose, when small folds are withheld through its hat matrix.
    full: Option<Design>,
    folds: Vec<Fold>,
}

/// One fold with poses: how it is withheld, and its withheld poses with their prediction variance
/// factor.
enum Fold {
    /// Its fit on the other folds.
    Refit(Design, Vec<(usize, f64)>),
    /// Through the full fit's hat matrix `H` ([`fold_is_small`]): the residuals of fold `F`'s poses
    /// under the others' fit are `(I - H_FF)^-1 e_F` (`e` the full fit's residuals): one
    /// factorisation per design instead of one per fold. Kept: the lower Cholesky factor of
    /// `I - H_FF`.
    Hat(Vec<Vec<f64>>, Vec<(usize, f64)>),
}

impl CvDesign {
    /// `None` when a fold with poses leaves too few others to fit.
    pub(crate) fn new(rows: &[Vec<f64>], fold: &[usize], folds: usize, dropped: &[bool]) -> Option<Self> {
        let p = rows.first()?.len();
        let n = fold.len();
        let kept = (0..n).filter(|&i| !dropped[i]).count();
        let mut present = vec![false; folds];
        fold.iter().filter(|&&f| f < folds).for_each(|&f| present[f] = true);
        let withheld: Vec<(usize, Vec<usize>)> = (0..folds)
            .filter(|&f| present[f])
            .map(|f| (f, (0..n).filter(|&i| fold[i] == f && !dropped[i]).collect()))
            .collect();
        if withheld.iter().any(|(_, poses)| kept - poses.len() < p) {
            return None;
        }
        let train = |f: usize| -> Vec<usize> { (0..n).filter(|&i| fold[i] != f && !dropped[i]).collect() };
        let full = withheld
            .iter()
            .all(|(_, poses)| fold_is_small(poses.len(), p))
            .then(|| kept_design(rows, dropped))
            .flatten();
        let folds = match &full {
            Some(full) => withheld
                .into_iter()
                .map(|(f, poses)| {
                    Fold::through_hat(full, rows, &poses).or_else(|| {
                        let train = train(f);
                        Fold::refit(rows, normals(rows, train.iter().copied()), train, poses)
                    })
                })
                .collect::<Option<_>>()?,
            None => {
                // Each fold's normal matrix is the sum of the others' ([`sums_without`]): the poses
                // are summed once, not once per fold.
                let parts: Vec<_> = withheld.iter().map(|(_, poses)| normals(rows, poses.iter().copied())).collect();
                sums_without(&parts, vec![vec![0.0; p]; p], |a, b| add_matrices(a, b))
                    .into_iter()
                    .zip(withheld)
                    .map(|(a, (f, poses))| Fold::refit(rows, a, train(f), poses))
                    .collect::<Option<_>>()?
            }
        };
        Some(Self { full, folds })
    }

    /// Each withheld pose predicted by its fold's fit of `r`; `None` for dropped poses and for one
    /// whose prediction's variance exceeds `max_variance_factor` times one pose's (see
    /// [`cv_residuals_predictable`]); all `None` when a fold cannot fit `r`.
    pub(crate) fn residuals(&self, rows: &[Vec<f64>], r: &[f64], max_variance_factor: f64) -> Option<Vec<Option<f64>>> {
        let full_residuals = match &self.full {
            Some(full) => Some(full.residuals_everywhere(rows, r)?),
            None => None,
        };
        let mut out = vec![None; r.len()];
        for fold in &self.folds {
            let (withheld, predicted) = match fold {
                Fold::Refit(design, withheld) => {
                    let x = design.solve(rows, r)?;
                    (withheld, withheld.iter().map(|&(i, _)| predict(rows, r, &x, i)).collect())
                }
                Fold::Hat(l, withheld) => {
                    let e = full_residuals.as_ref()?;
                    (withheld, solve_factored(l, &withheld.iter().map(|&(i, _)| e[i]).collect::<Vec<_>>())?)
                }
            };
            for (&(i, factor), value) in withheld.iter().zip(predicted) {
                if factor <= max_variance_factor {
                    out[i] = Some(value);
                }
            }
        }
        Some(out)
    }
}

impl Fold {
    /// Fold `poses` refitted on the poses `train`, whose normal matrix is `a` (lower triangle,
    /// unscaled).
    fn refit(rows: &[Vec<f64>], a: Vec<Vec<f64>>, train: Vec<usize>, poses: Vec<usize>) -> Option<Self> {
        let design = Design::from_normals(a, train)?;
        let factors = poses.into_iter().map(|i| (i, design.variance_factor(&rows[i]))).collect();
        Some(Fold::Refit(design, factors))
    }

    /// Fold `poses` withheld through the fit `full` to every kept pose; `None` when they leave the
    /// others' fit undetermined (`I - H_FF` not positive definite).
    fn through_hat(full: &Design, rows: &[Vec<f64>], poses: &[usize]) -> Option<Self> {
        let z: Vec<Vec<f64>> = poses.iter().map(|&i| full.whiten(&rows[i])).collect();
        let l = cholesky(&identity_less_hat(&z), 0.0)?;
        // The variance factor of a withheld pose's prediction: the diagonal of H (I - H)^-1, that is
        // of (I - H)^-1 less one (h / (1 - h) for a fold of one pose).
        let factors = (0..z.len())
            .map(|j| {
                let unit: Vec<f64> = (0..z.len()).map(|k| f64::from(u8::from(j == k))).collect();
                Some((poses[j], solve_factored(&l, &unit)?[j] - 1.0))
            })
            .collect::<Option<_>>()?;
        Some(Fold::Hat(l, factors))
    }
}

/// Least squares: the `x` minimising `sum over train of (r_i + rows_i . x)^2` (columns scaled, a tiny
/// ridge keeps collinear columns finite).
pub(crate) fn lstsq(rows: &[Vec<f64>], r: &[f64], train: &[usize]) -> Option<Vec<f64>> {
    Design::new(rows, train.to_vec())?.solve(rows, r)
}

/// `min |r + X c|` with the covariance of `c` per unit residual variance (`(X^T X)^-1`) and the
/// residual mean square over its degrees of freedom; `None` when `X` is rank deficient or has no
/// more rows than columns.
pub(crate) fn lstsq_with_covariance(rows: &[Vec<f64>], r: &[f64]) -> Option<(Vec<f64>, Vec<Vec<f64>>, f64)> {
    let p = rows.first()?.len();
    if rows.len() <= p {
        return None;
    }
    let (scale, a) = scaled(normals(rows, 0..rows.len()), rows.len());
    let b: Vec<f64> = rhs(rows, r, 0..rows.len()).iter().zip(&scale).map(|(v, s)| v / s).collect();
    let unit: Vec<Vec<f64>> = (0..p).map(|j| (0..p).map(|k| f64::from(u8::from(j == k))).collect()).collect();
    let mut rhs: Vec<&[f64]> = vec![&b];
    rhs.extend(unit.iter().map(Vec::as_slice));
    let mut solved = cholesky_solve_many(&a, &rhs, 1e-12 * (0..p).map(|j| a[j][j]).sum::<f64>() / p as f64)?;
    let inverse = solved.split_off(1);
    let c: Vec<f64> = solved[0].iter().zip(&scale).map(|(v, s)| v / s).collect();
    let cov = (0..p).map(|j| (0..p).map(|k| inverse[j][k] / (scale[j] * scale[k])).collect()).collect();
    let ss: f64 =
        rows.iter().zip(r).map(|(x, ri)| (ri + x.iter().zip(&c).map(|(a, b)| a * b).sum::<f64>()).powi(2)).sum();
    Some((c, cov, ss / (rows.len() - p) as f64))
}

/// A symmetric positive definite system (lower triangle given), its columns scaled by the square
/// roots of its diagonal and factored once, `ridge` added to the scaled diagonal.
pub(crate) struct ScaledFactor {
    scale: Vec<f64>,
    l: Vec<Vec<f64>>,
}

impl ScaledFactor {
    /// `None`: not positive definite.
    pub(crate) fn new(a: Vec<Vec<f64>>, ridge: f64) -> Option<Self> {
        let (scale, a) = scaled(a, 1);
        Some(Self { l: cholesky(&a, ridge)?, scale })
    }

    /// The solution `x` of `a x = b` (`None` when not finite).
    pub(crate) fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let b: Vec<f64> = b.iter().zip(&self.scale).map(|(v, s)| v / s).collect();
        Some(solve_factored(&self.l, &b)?.iter().zip(&self.scale).map(|(v, s)| v / s).collect())
    }

    /// `ln det a` (of the system factored, its ridge included).
    pub(crate) fn log_det(&self) -> f64 {
        2.0 * self.scale.iter().chain(self.l.iter().enumerate().map(|(i, row)| &row[i])).map(|v| v.ln()).sum::<f64>()
    }

    /// `row` whitened: `L^-1` of the scaled row, so that two whitened rows' dot product is
    /// `row_i^T a^-1 row_j`.
    pub(crate) fn whiten(&self, row: &[f64]) -> Vec<f64> {
        let scaled: Vec<f64> = row.iter().zip(&self.scale).map(|(v, s)| v / s).collect();
        forward_substitute(&self.l, &scaled)
    }
}

pub(crate) fn cholesky_solve(a: &[Vec<f64>], b: &[f64], ridge: f64) -> Option<Vec<f64>> {
    cholesky_solve_many(a, &[b], ridge)?.pop()
}

/// `a x = b` for each right-hand side `b` (`a` symmetric positive definite, its lower triangle
/// read, plus `ridge` on the diagonal), one factorisation.
pub(crate) fn cholesky_solve_many(a: &[Vec<f64>], rhs: &[&[f64]], ridge: f64) -> Option<Vec<Vec<f64>>> {
    let l = cholesky(a, ridge)?;
    rhs.iter().map(|b| solve_factored(&l, b)).collect()
}

/// `L L^T x = b` by forward and back substitution (`None` when not finite).
fn solve_factored(l: &[Vec<f64>], b: &[f64]) -> Option<Vec<f64>> {
    let p = l.len();
    let y = forward_substitute(l, b);
    let mut x = vec![0.0; p];
    for i in (0..p).rev() {
        x[i] = (y[i] - (i + 1..p).map(|k| l[k][i] * x[k]).sum::<f64>()) / l[i][i];
    }
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// `L y = b` for a lower-triangular `L`.
fn forward_substitute(l: &[Vec<f64>], b: &[f64]) -> Vec<f64> {
    let mut y = vec![0.0; l.len()];
    for (i, li) in l.iter().enumerate() {
        y[i] = (b[i] - li[..i].iter().zip(&y[..i]).map(|(a, v)| a * v).sum::<f64>()) / li[i];
    }
    y
}

/// The lower Cholesky factor of `a + ridge I` (`None`: not positive definite), row by row: each
/// entry subtracts its products in order, so slices replace the indexing of the inner loop.
fn cholesky(a: &[Vec<f64>], ridge: f64) -> Option<Vec<Vec<f64>>> {
    let p = a.len();
    let mut l: Vec<Vec<f64>> = Vec::with_capacity(p);
    for (i, ai) in a.iter().enumerate() {
        let mut row = vec![0.0; p];
        for (j, lj) in l.iter().enumerate() {
            let s = lj[..j].iter().zip(&row[..j]).fold(ai[j], |s, (x, y)| s - y * x);
            row[j] = s / lj[j];
        }
        let s = row[..i].iter().fold(ai[i] + ridge, |s, x| s - x * x);
        if !(s > 0.0) {
            return None;
        }
        row[i] = s.sqrt();
        l.push(row);
    }
    Some(l)
}

pub(crate) fn predict(rows: &[Vec<f64>], r: &[f64], x: &[f64], i: usize) -> f64 {
    r[i] + rows[i].iter().zip(x).map(|(a, b)| a * b).sum::<f64>()
}

/// Cross-validated residuals: pose `i` predicted by the fit on the other folds; `None` for dropped
/// poses (and everywhere when a fold leaves too few poses).
pub(crate) fn cv_residuals(
    rows: &[Vec<f64>],
    r: &[f64],
    fold: &[usize],
    folds: usize,
    dropped: &[bool],
) -> Option<Vec<Option<f64>>> {
    cv_residuals_predictable(rows, r, fold, folds, dropped, f64::INFINITY)
}

/// [`cv_residuals`], with `None` also for a withheld pose its fold's fit cannot predict: the
/// prediction's variance exceeds `max_variance_factor` times one pose's (the other folds leave the
/// pose's row almost outside what they determine, and the prediction is the ridge's choice).
pub(crate) fn cv_residuals_predictable(
    rows: &[Vec<f64>],
    r: &[f64],
    fold: &[usize],
    folds: usize,
    dropped: &[bool],
    max_variance_factor: f64,
) -> Option<Vec<Option<f64>>> {
    let n = r.len();
    CvDesign::new(rows, &fold[..n], folds, &dropped[..n])?.residuals(rows, r, max_variance_factor)
}

/// In-sample residuals of the fit on the kept poses (`None` for dropped ones).
pub(crate) fn fit_residuals(rows: &[Vec<f64>], r: &[f64], dropped: &[bool]) -> Option<Vec<Option<f64>>> {
    kept_design(rows, &dropped[..r.len()])?.residuals(rows, r)
}

pub(crate) fn sum_sq(v: &[Option<f64>]) -> (f64, usize) {
    v.iter().flatten().fold((0.0, 0), |(s, n), x| (s + x * x, n + 1))
}

/// The mean of segment means.
pub(crate) fn mean_of(segs: &[V3]) -> V3 {
    std::array::from_fn(|a| segs.iter().map(|s| s[a]).sum::<f64>() / segs.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_design_factored_once_gives_every_draw_its_own_fits_residuals() {
        // 10 poses, 3 columns, one pose dropped; residual vectors of different sizes. 4 folds of at
        // most 3 poses are withheld through the hat matrix, 2 folds of 5 refitted.
        for folds in [4, 2] {
            each_draw_gets_its_own_fits_residuals(folds);
        }
    }

    fn each_draw_gets_its_own_fits_residuals(folds: usize) {
        let n = 10;
        let rows: Vec<Vec<f64>> =
            (0..n).map(|i| vec![1.0, i as f64 * 0.3, ((i * 7) % 5) as f64 - 2.0 + 0.1 * i as f64]).collect();
        let fold: Vec<usize> = (0..n).map(|i| i % folds).collect();
        let mut dropped = vec![false; n];
        dropped[6] = true;
        let design = CvDesign::new(&rows, &fold, folds, &dropped).unwrap();
        let through_hat = design.folds.iter().filter(|f| matches!(f, Fold::Hat(..))).count();
        assert_eq!(through_hat, if folds == 4 { 4 } else { 0 }, "{folds} folds");
        let kept = kept_design(&rows, &dropped).unwrap();
        for draw in 0..3 {
            let r: Vec<f64> = (0..n).map(|i| ((i * 13 + draw * 5) % 11) as f64 * 0.01 * (draw + 1) as f64).collect();
            let cv = design.residuals(&rows, &r, f64::INFINITY).unwrap();
            // Each fold's fit by its own normal equations (unscaled, no ridge).
            let fit = |train: &[usize]| {
                let a: Vec<Vec<f64>> = (0..3)
                    .map(|j| (0..3).map(|k| train.iter().map(|&t| rows[t][j] * rows[t][k]).sum()).collect())
                    .collect();
                let b: Vec<f64> = (0..3).map(|j| -train.iter().map(|&t| rows[t][j] * r[t]).sum::<f64>()).collect();
                cholesky_solve(&a, &b, 0.0).unwrap()
            };
            for i in 0..n {
                let train: Vec<usize> = (0..n).filter(|&j| fold[j] != fold[i] && !dropped[j]).collect();
                let x = fit(&train);
                let expected = (!dropped[i]).then(|| predict(&rows, &r, &x, i));
                assert_eq!(cv[i].is_some(), expected.is_some(), "draw {draw} pose {i}");
                if let (Some(a), Some(b)) = (cv[i], expected) {
                    assert!((a - b).abs() <= 1e-9, "draw {draw} pose {i}: {a} vs {b}");
                }
            }
            let x = fit(&(0..n).filter(|&j| !dropped[j]).collect::<Vec<_>>());
            let fitted = kept.residuals(&rows, &r).unwrap();
            for i in 0..n {
                let expected = (!dropped[i]).then(|| predict(&rows, &r, &x, i));
                assert_eq!(fitted[i].is_some(), expected.is_some(), "draw {draw} pose {i}");
                if let (Some(a), Some(b)) = (fitted[i], expected) {
                    assert!((a - b).abs() <= 1e-9, "draw {draw} pose {i}: {a} vs {b}");
                }
            }
        }
    }

    #[test]
    fn a_withheld_pose_its_fold_barely_touches_is_not_predicted() {
        // Residual r = 2 x1 + 3 x2 - noise, the second column tiny on every pose but the last:
        // without it the training poses leave its coefficient to the ridge.
        let n = 12;
        let rows: Vec<Vec<f64>> = (0..n)
            .map(|i| vec![1.0 + i as f64 * 0.1, if i == n - 1 { 1.0 } else { 1e-7 * (i as f64 - 5.0) }])
            .collect();
        let noise = |i: usize| 0.01 * ((i * 7 % 5) as f64 - 2.0);
        let r: Vec<f64> = rows.iter().enumerate().map(|(i, x)| -(2.0 * x[0] + 3.0 * x[1]) + noise(i)).collect();
        let fold: Vec<usize> = (0..n).collect();
        let dropped = vec![false; n];
        let all = cv_residuals(&rows, &r, &fold, n, &dropped).unwrap();
        assert!(all[n - 1].unwrap().abs() > 1.0, "the ridge's guess: {:?}", all[n - 1]);
        let predictable = cv_residuals_predictable(&rows, &r, &fold, n, &dropped, 1e6).unwrap();
        assert_eq!(predictable[n - 1], None);
        for i in 0..n - 1 {
            assert_eq!(predictable[i], all[i], "pose {i}");
            assert!(all[i].unwrap().abs() < 0.1, "pose {i}: {:?}", all[i]);
        }
    }
}
