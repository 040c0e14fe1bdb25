//! Small dense linear algebra on the stack: `N x N` solves for the 9-parameter normal equations.
//!
//! ```
//! use accelcal::linalg::solve_lu;
//! let a = [[4.0, 1.0], [1.0, 3.0]];
//! let x = solve_lu(a, [1.0, 2.0]).unwrap();
//! assert!((4.0 * x[0] + x[1] - 1.0).abs() < 1e-6);
//! ```

/// A square matrix, row-major.
pub type Matrix<const N: usize> = [[f32; N]; N];

/// Why a linear solve failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum LinalgError {
    /// The matrix is singular (or not positive definite, for Cholesky) to working precision.
    Singular,
}

impl core::fmt::Display for LinalgError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("matrix is singular to working precision")
    }
}

impl core::error::Error for LinalgError {}

/// Solves `a x = b` by Gaussian elimination with partial pivoting.
pub fn solve_lu<const N: usize>(mut a: Matrix<N>, mut b: [f32; N]) -> Result<[f32; N], LinalgError> {
    let scale = a.iter().flatten().fold(0.0f32, |m, v| m.max(v.abs()));
    if !(scale.is_finite() && scale > 0.0) {
        return Err(LinalgError::Singular);
    }
    let tiny = scale * f32::EPSILON * N as f32;
    for col in 0..N {
        let mut pivot = col;
        for row in col + 1..N {
            if a[row][col].abs() > a[pivot][col].abs() {
                pivot = row;
            }
        }
        if !(a[pivot][col].abs() > tiny) {
            return Err(LinalgError::Singular);
        }
        if pivot != col {
            // Element by element: a row swap of the array links the library's large `memmove`.
            for k in 0..N {
                (a[col][k], a[pivot][k]) = (a[pivot][k], a[col][k]);
            }
            b.swap(col, pivot);
        }
        for row in col + 1..N {
            let factor = a[row][col] / a[col][col];
            for k in col..N {
                a[row][k] -= factor * a[col][k];
            }
            b[row] -= factor * b[col];
        }
    }
    let mut x = [0.0; N];
    for row in (0..N).rev() {
        let mut s = b[row];
        for k in row + 1..N {
            s -= a[row][k] * x[k];
        }
        x[row] = s / a[row][row];
    }
    if x.iter().all(|v| v.is_finite()) { Ok(x) } else { Err(LinalgError::Singular) }
}

/// Square root to within 2 ulp for normal `x >= 0`, in a dozen single-precision operations (reciprocal
/// square root from the exponent bits, three Newton steps): `libm::sqrtf` is a bit-by-bit software
/// routine on targets without a stable square-root instruction in `core` (Cortex-M4F: ~100 cycles).
/// NaN for negative or NaN input, 0 for 0 and subnormals, infinity for infinity.
pub fn sqrt_f32(x: f32) -> f32 {
    if x == f32::INFINITY {
        return x;
    }
    if !(x >= f32::MIN_POSITIVE) {
        return if x >= 0.0 { 0.0 } else { f32::NAN };
    }
    let mut y = f32::from_bits(0x5F37_59DF - (x.to_bits() >> 1));
    for _ in 0..3 {
        y *= 1.5 - 0.5 * x * y * y;
    }
    x * y
}

/// Cholesky factor `L` (lower) of a symmetric positive definite matrix, with `a = L L^T`.
pub fn cholesky<const N: usize>(a: &Matrix<N>) -> Result<Matrix<N>, LinalgError> {
    let mut l = *a;
    cholesky_in_place(&mut l)?;
    for (i, row) in l.iter_mut().enumerate() {
        row[i + 1..].iter_mut().for_each(|v| *v = 0.0);
    }
    Ok(l)
}

/// [`cholesky`] without a copy: the lower triangle of `a` (the only part read) is overwritten by `L`;
/// the upper triangle is left as it was. On an error `a` is partly overwritten.
pub fn cholesky_in_place<const N: usize>(a: &mut Matrix<N>) -> Result<(), LinalgError> {
    for i in 0..N {
        for j in 0..i + 1 {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k];
            }
            if i == j {
                if !(s > 0.0 && s.is_finite()) {
                    return Err(LinalgError::Singular);
                }
                a[i][i] = sqrt_f32(s);
            } else {
                a[i][j] = s / a[j][j];
            }
        }
    }
    Ok(())
}

/// Solves `a x = b` for a symmetric positive definite `a` given by its lower triangle, in place: `a`'s
/// lower triangle is overwritten by its `L D L^T` factors (unit `L` below the diagonal, `D` on it) and `b`
/// by `x`. No square roots and no copies (the Levenberg-Marquardt step on the device).
pub fn ldlt_solve_in_place<const N: usize>(a: &mut Matrix<N>, b: &mut [f32; N]) -> Result<(), LinalgError> {
    for i in 0..N {
        for j in 0..i {
            let mut s = a[i][j];
            for k in 0..j {
                s -= a[i][k] * a[j][k] * a[k][k];
            }
            a[i][j] = s / a[j][j];
        }
        let mut d = a[i][i];
        for k in 0..i {
            d -= a[i][k] * a[i][k] * a[k][k];
        }
        if !(d > 0.0 && d.is_finite()) {
            return Err(LinalgError::Singular);
        }
        a[i][i] = d;
    }
    for i in 0..N {
        for k in 0..i {
            b[i] -= a[i][k] * b[k];
        }
    }
    for i in (0..N).rev() {
        b[i] /= a[i][i];
        for k in i + 1..N {
            b[i] -= a[k][i] * b[k];
        }
    }
    if b.iter().all(|v| v.is_finite()) { Ok(()) } else { Err(LinalgError::Singular) }
}

/// Solves `L L^T x = b` given the Cholesky factor `L`.
pub fn cholesky_solve<const N: usize>(l: &Matrix<N>, b: [f32; N]) -> [f32; N] {
    let mut y = [0.0; N];
    for i in 0..N {
        let mut s = b[i];
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
    x
}

/// Inverse of a symmetric positive definite matrix, with Jacobi (diagonal) scaling for conditioning.
pub fn spd_inverse<const N: usize>(a: &Matrix<N>) -> Result<Matrix<N>, LinalgError> {
    let mut inv = *a;
    spd_inverse_in_place(&mut inv)?;
    Ok(inv)
}

/// [`spd_inverse`] in place: `a` is replaced by its inverse (left unchanged on an error). One matrix of
/// scratch (the factor) besides `a`.
pub fn spd_inverse_in_place<const N: usize>(a: &mut Matrix<N>) -> Result<(), LinalgError> {
    let mut d = [0.0; N];
    for i in 0..N {
        if !(a[i][i] > 0.0 && a[i][i].is_finite()) {
            return Err(LinalgError::Singular);
        }
        d[i] = 1.0 / sqrt_f32(a[i][i]);
    }
    let mut l: Matrix<N> = core::array::from_fn(|i| core::array::from_fn(|j| a[i][j] * d[i] * d[j]));
    cholesky_in_place(&mut l)?;
    for j in 0..N {
        let mut e = [0.0; N];
        e[j] = 1.0;
        let col = cholesky_solve(&l, e);
        for i in 0..N {
            a[i][j] = col[i] * d[i] * d[j];
        }
    }
    Ok(())
}

/// Smallest share of a column's information not explained by the columns before it (the pivot of
/// the Jacobi-scaled Cholesky factorisation) for it to count as determined.
pub const DETERMINED_PIVOT: f32 = 1e-5;

/// Columns of the symmetric matrix `a` that are (to f32 precision) combinations of the columns before
/// them, taken in the order `order`: a Cholesky factorisation of the Jacobi-scaled `a` in that order,
/// where a column whose remaining pivot is below `min_pivot` is flagged and then left out. Only the
/// lower triangle (`a[i][j]`, `j <= i`) is read. A zero or non-finite diagonal is flagged too.
pub fn weak_pivots<const N: usize>(a: &Matrix<N>, order: &[usize; N], min_pivot: f32) -> [bool; N] {
    let entry = |i: usize, j: usize| a[i.max(j)][i.min(j)];
    let mut weak = [false; N];
    // l[p][q]: factor in permuted positions p, q.
    let mut l = [[0.0f32; N]; N];
    for p in 0..N {
        let j = order[p];
        if j >= N {
            continue; // not a permutation of 0..N: ignored (and no bounds check below)
        }
        let diag = entry(j, j);
        if !(diag > 0.0 && diag.is_finite()) {
            weak[j] = true;
            continue;
        }
        let mut pivot = 1.0;
        for q in 0..p {
            pivot -= l[p][q] * l[p][q];
        }
        if !(pivot > min_pivot) {
            weak[j] = true;
            continue;
        }
        let root = sqrt_f32(pivot);
        l[p][p] = root;
        for r in p + 1..N {
            let i = order[r];
            if i >= N {
                continue;
            }
            let di = entry(i, i);
            if !(di > 0.0 && di.is_finite()) {
                continue;
            }
            let mut s = entry(i, j) / sqrt_f32(di * diag);
            for q in 0..p {
                s -= l[r][q] * l[p][q];
            }
            l[r][p] = s / root;
        }
    }
    weak
}

/// Solves `a x = b` (`a` symmetric positive semi-definite, lower triangle read) with the entries of
/// `x` flagged in `held` fixed at 0: their rows and columns are replaced by the identity.
pub fn solve_spd_holding<const N: usize>(
    a: &Matrix<N>,
    b: &[f32; N],
    held: &[bool; N],
) -> Result<[f32; N], LinalgError> {
    let (mut m, mut x) = (*a, *b);
    solve_spd_holding_in_place(&mut m, &mut x, held)?;
    Ok(x)
}

/// [`solve_spd_holding`] without copies: `a`'s lower triangle is overwritten by the scaled factor and
/// `b` by the solution `x`.
pub fn solve_spd_holding_in_place<const N: usize>(
    a: &mut Matrix<N>,
    b: &mut [f32; N],
    held: &[bool; N],
) -> Result<(), LinalgError> {
    for i in 0..N {
        for j in 0..=i {
            if held[i] || held[j] {
                a[i][j] = if i == j { 1.0 } else { 0.0 };
            }
        }
        if held[i] {
            b[i] = 0.0;
        }
    }
    let mut d = [0.0f32; N];
    for i in 0..N {
        if !(a[i][i] > 0.0 && a[i][i].is_finite()) {
            return Err(LinalgError::Singular);
        }
        d[i] = 1.0 / sqrt_f32(a[i][i]);
    }
    for i in 0..N {
        for j in 0..=i {
            a[i][j] *= d[i] * d[j];
        }
        b[i] *= d[i];
    }
    cholesky_in_place(a)?;
    *b = cholesky_solve(a, *b);
    for i in 0..N {
        b[i] *= d[i];
    }
    if b.iter().all(|v| v.is_finite()) { Ok(()) } else { Err(LinalgError::Singular) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sqrt_is_within_two_ulp() {
        let mut x = f32::MIN_POSITIVE;
        while x < 1e30 {
            for k in 0..7 {
                let v = x * (1.0 + k as f32 * 0.13);
                let exact = libm::sqrtf(v);
                assert!((sqrt_f32(v) - exact).abs() <= 2.0 * f32::EPSILON * exact, "{v}");
            }
            x *= 3.7;
        }
        assert_eq!(sqrt_f32(0.0), 0.0);
        assert!((sqrt_f32(4.0) - 2.0).abs() <= 2.0 * f32::EPSILON * 2.0);
        assert!(sqrt_f32(-1.0).is_nan() && sqrt_f32(f32::NAN).is_nan());
        assert_eq!(sqrt_f32(f32::INFINITY), f32::INFINITY);
    }

    #[test]
    fn inverse_times_matrix_is_identity() {
        let a = [[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 2.0]];
        let inv = spd_inverse(&a).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let v: f32 = (0..3).map(|k| a[i][k] * inv[k][j]).sum();
                assert!((v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-5);
            }
        }
    }

    /// A symmetric positive definite 4x4 with spread-out entries (Gram matrix plus a ridge).
    fn spd4() -> Matrix<4> {
        let g = [[1.0, 0.3, -0.2, 0.7], [0.1, 2.0, 0.5, -0.4], [-0.6, 0.2, 1.5, 0.3], [0.4, -0.9, 0.1, 0.8]];
        core::array::from_fn(|i| {
            core::array::from_fn(|j| (0..4).map(|k| g[i][k] * g[j][k]).sum::<f32>() + if i == j { 0.1 } else { 0.0 })
        })
    }

    #[test]
    fn in_place_forms_equal_the_copying_ones_bit_for_bit() {
        let a = spd4();
        let mut l = a;
        cholesky_in_place(&mut l).unwrap();
        let copied = cholesky(&a).unwrap();
        for i in 0..4 {
            assert_eq!(l[i][..=i], copied[i][..=i], "row {i}");
            assert!(copied[i][i + 1..].iter().all(|&v| v == 0.0));
        }
        let (b, held) = ([1.0, -2.0, 0.5, 3.0], [false, true, false, false]);
        let (mut m, mut x) = (a, b);
        solve_spd_holding_in_place(&mut m, &mut x, &held).unwrap();
        assert_eq!(x, solve_spd_holding(&a, &b, &held).unwrap());
        assert_eq!(x[1], 0.0);
        for i in [0, 2, 3] {
            let r: f32 = [0, 2, 3].iter().map(|&k| a[i.max(k)][i.min(k)] * x[k]).sum();
            assert!((r - b[i]).abs() < 1e-4, "{i}: {r}");
        }
    }

    #[test]
    fn in_place_inverse_leaves_a_singular_matrix_unchanged() {
        let mut a = spd4();
        a[3] = [0.0; 4];
        let before = a;
        assert_eq!(spd_inverse_in_place(&mut a), Err(LinalgError::Singular));
        assert_eq!(a, before);
        // Positive diagonal, indefinite: the factorisation (not the diagonal check) fails.
        let mut a = [[1.0, 2.0, 0.0, 0.0], [2.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]];
        let before = a;
        assert_eq!(spd_inverse_in_place(&mut a), Err(LinalgError::Singular));
        assert_eq!(a, before);
    }

    #[test]
    fn singular_is_an_error() {
        let a = [[1.0, 2.0], [2.0, 4.0]];
        assert_eq!(solve_lu(a, [1.0, 1.0]), Err(LinalgError::Singular));
        assert_eq!(cholesky(&a).map(|_| ()), Err(LinalgError::Singular));
        assert_eq!(solve_lu([[f32::NAN, 0.0], [0.0, 1.0]], [1.0, 1.0]), Err(LinalgError::Singular));
    }
}
