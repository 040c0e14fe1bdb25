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

/// A zero matrix, copied from a constant: one `memclr` call (an array literal is one per row on a
/// Cortex-M4F).
#[inline(always)]
pub(crate) const fn zero_matrix<const N: usize>() -> Matrix<N> {
    Zero::<N>::MATRIX
}

/// The constant of [`zero_matrix`].
struct Zero<const N: usize>;

impl<const N: usize> Zero<N> {
    const MATRIX: Matrix<N> = [[0.0; N]; N];
}

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

/// A set of indices (each below 16) held out of a solve: a bit mask, small enough to pass in a register
/// (a `[bool; 9]` by value was a `memcpy` call at every pass on a Cortex-M4F).
///
/// ```
/// use accelcal::linalg::Held;
/// let held = Held::NONE.with(6).with(8);
/// assert!(held.contains(6) && !held.contains(7));
/// assert_eq!((held.count(), held.to_flags::<9>()[8]), (2, true));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Held(u16);

impl Held {
    /// Nothing held.
    pub const NONE: Self = Self(0);

    /// The indices flagged in `flags` (those from 16 on are ignored).
    pub fn from_flags(flags: &[bool]) -> Self {
        let mut out = Self::NONE;
        for (i, _) in flags.iter().enumerate().filter(|(_, f)| **f) {
            out.insert(i);
        }
        out
    }

    /// One flag per index below `N`.
    pub fn to_flags<const N: usize>(self) -> [bool; N] {
        core::array::from_fn(|i| self.contains(i))
    }

    /// `true` when index `i` is held (`false` from 16 on).
    #[inline]
    pub fn contains(self, i: usize) -> bool {
        self.0.checked_shr(i as u32).unwrap_or(0) & 1 != 0
    }

    /// Holds index `i` too (nothing from 16 on).
    #[inline]
    pub fn insert(&mut self, i: usize) {
        self.0 |= 1u16.checked_shl(i as u32).unwrap_or(0);
    }

    /// `self` with index `i` held too.
    #[inline]
    pub fn with(mut self, i: usize) -> Self {
        self.insert(i);
        self
    }

    /// The indices held in `self` or in `other`.
    #[inline]
    pub fn union(self, other: Self) -> Self {
        Self(self.0 | other.0)
    }

    /// How many indices are held (a loop over the set bits, out of line: `count_ones` is a longer bit
    /// trick on a Cortex-M).
    #[inline(never)]
    pub fn count(self) -> usize {
        let (mut bits, mut n) = (self.0, 0);
        while bits != 0 {
            bits &= bits - 1;
            n += 1;
        }
        n
    }

    /// `true` when nothing is held.
    #[inline]
    pub fn is_empty(self) -> bool {
        self.0 == 0
    }
}

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
    if x.iter().all(|&v| finite(v)) { Ok(x) } else { Err(LinalgError::Singular) }
}

/// The larger of `a` and `b`; `b` when either is NaN. Inline comparisons: `f32::max` and `f32::min`
/// are out-of-line library calls on a Cortex-M4F.
#[inline]
pub(crate) fn larger(a: f32, b: f32) -> f32 {
    if a > b { a } else { b }
}

/// The smaller of `a` and `b`; `b` when either is NaN (see [`larger`]).
#[inline]
pub(crate) fn smaller(a: f32, b: f32) -> f32 {
    if a < b { a } else { b }
}

/// [`sqrt_f32`] of `x` clamped at 0 (`larger(x, 0)`: 0 for a negative or NaN `x`), the standard
/// deviation of a variance that rounding may have made negative. Out of line: the verdict's three
/// callers share the clamp.
#[inline(never)]
pub(crate) fn sqrt_clamped(x: f32) -> f32 {
    sqrt_f32(larger(x, 0.0))
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

/// Adds `w g g^T` to the lower triangle of `m` (`m[i][j]`, `j <= i`): the information matrix of rows
/// with gradient `g` and weight `w` ([`add_normal_row`] without a right-hand side).
#[inline]
pub fn add_outer_product(m: &mut Matrix<9>, g: &[f32; 9], w: f32) {
    add_normal_row(m, &mut [0.0; 9], g, w, 0.0);
}

/// Adds one row of residual `e`, gradient `g` and weight `w` to the normal equations `m x = rhs`:
/// `w g g^T` to the lower triangle of `m` (`m[i][j]`, `j <= i`) and `w e g` to `rhs`. The one place the
/// library builds an information matrix or normal equations (the 9 model parameters, or the 9 quadric
/// coefficients of the ellipsoid fit). In blocks of three rows (`add_block_rows`), `rhs` a fourth row of
/// the last block's loop: 476 bytes and LM 91.6 k cycles on the bench (Cortex-M4F); with `rhs` summed
/// straight-line in the caller, 400 bytes here and 176 there, 89.7 k. Measured with the former factorisation: straight-line 798
/// bytes and 83.9 k, one loop over the triangle 82 bytes and 121 k, rows in pairs 210 bytes and 106 k
/// (budget 100 k).
#[inline(never)]
pub fn add_normal_row(m: &mut Matrix<9>, rhs: &mut [f32; 9], g: &[f32; 9], w: f32, e: f32) {
    let [r0, r1, r2, r3, r4, r5, r6, r7, r8] = m;
    let [g0, g1, g2, g3, g4, g5, g6, g7, g8] = *g;
    let we = w * e;
    add_block_rows::<false>([r0, r1, r2], [w * g0, w * g1, w * g2], g, 0, rhs, we);
    add_block_rows::<false>([r3, r4, r5], [w * g3, w * g4, w * g5], g, 3, rhs, we);
    add_block_rows::<true>([r6, r7, r8], [w * g6, w * g7, w * g8], g, 6, rhs, we);
    rhs[7] += g7 * we;
    rhs[8] += g8 * we;
}

/// Rows `start..start + 3` of [`add_normal_row`] (`wg` their `w g[i]`), and with `RHS` the first
/// `start + 1` entries of `rhs` (`we` its `w e`): the entries up to the diagonal block's first column in
/// a loop (each `g[j]` loaded once for all the rows), the three left of the block's lower triangle
/// straight.
#[inline(always)]
fn add_block_rows<const RHS: bool>(
    [a, b, c]: [&mut [f32; 9]; 3],
    wg: [f32; 3],
    g: &[f32; 9],
    start: usize,
    rhs: &mut [f32; 9],
    we: f32,
) {
    let rows = a.iter_mut().zip(b.iter_mut()).zip(c.iter_mut()).zip(rhs.iter_mut());
    for ((((x, y), z), r), gj) in rows.zip(g).take(start + 1) {
        *x += wg[0] * gj;
        *y += wg[1] * gj;
        *z += wg[2] * gj;
        if RHS {
            *r += gj * we;
        }
    }
    if let (Some([_, b1, ..]), Some([_, c1, c2, ..]), Some([_, g1, g2, ..])) =
        (b.get_mut(start..), c.get_mut(start..), g.get(start..))
    {
        *b1 += wg[1] * g1;
        *c1 += wg[2] * g1;
        *c2 += wg[2] * g2;
    }
}

/// The one factorisation of the library, in place in `a`'s lower triangle (only that triangle is read),
/// in one of two forms. Scaled (`cholesky`): the Cholesky factor `L` of the Jacobi-scaled `a` (`D a D`
/// with `D = diag(1 / sqrt(a_ii))`, so every pivot starts at 1), with `1 / L_ii` on the diagonal.
/// Unscaled (`D = I`): `L P L^T` with unit `L` below the diagonal and the pivots `P` on it, no square
/// roots (the Levenberg-Marquardt step). Entries flagged in `held` get an identity row and column; a
/// column whose diagonal is not positive and finite, or whose remaining pivot is not above `min_pivot`
/// (it is, to that precision, a combination of the columns before it), is flagged in `held` and treated
/// the same. Returns the scaling `D` (0 where held). With `below`, the entries below the diagonal are
/// read from it instead of from `a` (whose diagonal is still read): a factorisation into scratch
/// without copying the matrix there first.
#[inline(never)]
fn factor<const N: usize>(
    below: Option<&Matrix<N>>,
    a: &mut Matrix<N>,
    held: &mut Held,
    min_pivot: f32,
    cholesky: bool,
) -> [f32; N] {
    const { assert!(N <= 16, "a `Held` mask has 16 entries") };
    let mut d = [0.0f32; N];
    for i in 0..N {
        if !positive_finite(a[i][i]) {
            held.insert(i);
        }
        // Row `i` reads only the columns `j <= i`: its scaling is due now.
        d[i] = if held.contains(i) {
            0.0
        } else if cholesky {
            1.0 / sqrt_f32(a[i][i])
        } else {
            1.0
        };
        for j in 0..=i {
            if held.contains(i) {
                break;
            }
            let entry = match below {
                Some(m) if j < i => m[i][j],
                _ => a[i][j],
            };
            let scaled = if held.contains(j) { 0.0 } else { entry * d[i] * d[j] };
            // The Cholesky form subtracts the sum, the other each term: kept as they were measured.
            let mut s = if cholesky { 0.0 } else { scaled };
            for k in 0..j {
                // The weight of column `k` in the elimination: its pivot (unscaled, in place on the
                // diagonal; 1 for a held row), 1 (Cholesky).
                let weight = if cholesky { 1.0 } else { a[k][k] };
                s -= a[i][k] * a[j][k] * weight;
            }
            if cholesky {
                s += scaled;
            }
            if j < i {
                a[i][j] = if cholesky { s * a[j][j] } else { s / a[j][j] };
            } else if s > min_pivot && positive_finite(s) {
                a[i][i] = if cholesky { 1.0 / sqrt_f32(s) } else { s };
            } else {
                // Found weak just now: held from here on.
                held.insert(i);
                d[i] = 0.0;
            }
        }
        if held.contains(i) {
            // Out of the factorisation: zeros and a unit diagonal (what the elimination gives a held row).
            a[i].iter_mut().take(i).for_each(|v| *v = 0.0);
            a[i][i] = 1.0;
        }
    }
    d
}

/// `x > 0.0 && x.is_finite()` in one integer comparison of the bits (the float comparisons took 136
/// bytes in [`factor`] on a Cortex-M4F).
#[inline]
pub(crate) fn positive_finite(x: f32) -> bool {
    // Positive zero wraps to the top; negatives have the sign bit; infinity and NaN are at or above it.
    x.to_bits().wrapping_sub(1) < f32::INFINITY.to_bits() - 1
}

/// `x.is_finite()` as one integer comparison of the bits (the library's float classification calls
/// otherwise compile to several comparisons each on a Cortex-M4F). Always inlined: the hint left an
/// out-of-line copy on the calibration path (18 bytes more).
#[inline(always)]
pub(crate) fn finite(x: f32) -> bool {
    x.to_bits() & 0x7FFF_FFFF < f32::INFINITY.to_bits()
}

/// `x != 0.0 && x.is_finite()` in one integer comparison (see [`finite`]).
#[inline]
pub(crate) fn nonzero_finite(x: f32) -> bool {
    (x.to_bits() & 0x7FFF_FFFF).wrapping_sub(1) < f32::INFINITY.to_bits() - 1
}

/// `b` becomes `D (L L^T)^-1 D b` (or `(L P L^T)^-1 b`) for the factors in `l` and the scaling `d` of
/// [`factor`] in the same form (0 where `d` is 0).
#[inline(never)]
fn factor_solve<const N: usize>(l: &Matrix<N>, d: &[f32; N], b: &mut [f32; N], cholesky: bool) {
    for i in 0..N {
        let scaled = if d[i] == 0.0 { 0.0 } else { b[i] * d[i] };
        let mut s = if cholesky { 0.0 } else { scaled };
        for k in 0..i {
            s -= l[i][k] * b[k];
        }
        b[i] = if cholesky { (scaled + s) * l[i][i] } else { s };
    }
    for i in (0..N).rev() {
        let mut s = if cholesky { b[i] } else { b[i] / l[i][i] };
        for k in i + 1..N {
            s -= l[k][i] * b[k];
        }
        b[i] = if cholesky { s * l[i][i] } else { s };
    }
    for i in 0..N {
        b[i] *= d[i];
    }
}

/// Solves `a x = b` for a symmetric positive definite `a` given by its lower triangle, in place, with
/// the entries of `x` flagged in `held` fixed at 0: `a`'s lower triangle is overwritten by its unscaled
/// `L P L^T` factors (`factor`) and `b` by `x`. No square roots, no scaling, no copies: the Levenberg-Marquardt
/// step on the device (f32 rounding decides where the LM stops: the scaled form took it 10 iterations
/// instead of 4 from the coarse start on the bench).
pub fn ldlt_solve_holding_in_place<const N: usize>(
    a: &mut Matrix<N>,
    b: &mut [f32; N],
    held: Held,
) -> Result<(), LinalgError> {
    solve_in_place(None, a, b, held, false)
}

/// [`ldlt_solve_holding_in_place`] of the matrix whose diagonal is `a`'s and whose entries below it are
/// `below`'s (its diagonal and upper triangle are not read), without assembling it: `a`'s lower triangle is
/// overwritten by the factors, `below` is left as it is (a damped system solved again and again).
pub fn ldlt_solve_holding_split<const N: usize>(
    below: &Matrix<N>,
    a: &mut Matrix<N>,
    b: &mut [f32; N],
    held: Held,
) -> Result<(), LinalgError> {
    solve_in_place(Some(below), a, b, held, false)
}

/// [`ldlt_solve_holding_in_place`] with nothing held.
pub fn ldlt_solve_in_place<const N: usize>(a: &mut Matrix<N>, b: &mut [f32; N]) -> Result<(), LinalgError> {
    solve_in_place(None, a, b, Held::NONE, false)
}

/// [`factor`] (in the `cholesky` form or not, holding `held`, entries below the diagonal from `below` when
/// given) and [`factor_solve`]; an error when the
/// factorisation flagged an entry not held or the solution is not finite.
fn solve_in_place<const N: usize>(
    below: Option<&Matrix<N>>,
    a: &mut Matrix<N>,
    b: &mut [f32; N],
    held: Held,
    cholesky: bool,
) -> Result<(), LinalgError> {
    let mut flagged = held;
    let d = factor(below, a, &mut flagged, 0.0, cholesky);
    if flagged != held {
        return Err(LinalgError::Singular);
    }
    factor_solve(a, &d, b, cholesky);
    if b.iter().all(|&v| finite(v)) { Ok(()) } else { Err(LinalgError::Singular) }
}

/// Inverse of a symmetric positive definite matrix (lower triangle read), Jacobi-scaled for
/// conditioning.
pub fn spd_inverse<const N: usize>(a: &Matrix<N>) -> Result<Matrix<N>, LinalgError> {
    let mut inv = *a;
    spd_inverse_in_place(&mut inv)?;
    Ok(inv)
}

/// [`spd_inverse`] in place: `a` is replaced by its inverse (left unchanged on an error). One matrix of
/// scratch (the factor) besides `a`.
pub fn spd_inverse_in_place<const N: usize>(a: &mut Matrix<N>) -> Result<(), LinalgError> {
    spd_inverse_holding_in_place(a, Held::NONE)
}

/// [`spd_inverse_in_place`] of `a` with the rows and columns flagged in `held` replaced by the identity;
/// those rows and columns of the result are 0. `a` is left unchanged on an error.
#[inline(never)]
pub fn spd_inverse_holding_in_place<const N: usize>(a: &mut Matrix<N>, held: Held) -> Result<(), LinalgError> {
    // The factors go to scratch that only receives `a`'s diagonal: no copy of the matrix (and no memcpy).
    let mut l = zero_matrix::<N>();
    for i in 0..N {
        l[i][i] = a[i][i];
    }
    let mut flagged = held;
    let d = factor(Some(a), &mut l, &mut flagged, 0.0, true);
    if flagged != held {
        return Err(LinalgError::Singular);
    }
    // Column `j` of the inverse solved in place in row `j` (the inverse is symmetric: `a` holds its
    // transpose as computed, `a[j][i]` the solve for unit vector `j`; no copy of each column).
    for (j, row) in a.iter_mut().enumerate() {
        *row = [0.0; N];
        row[j] = 1.0;
        factor_solve(&l, &d, row, true);
    }
    if a.iter().flatten().all(|&v| finite(v)) { Ok(()) } else { Err(LinalgError::Singular) }
}

/// Smallest share of a column's information not explained by the columns before it (the pivot of
/// the Jacobi-scaled Cholesky factorisation) for it to count as determined.
pub const DETERMINED_PIVOT: f32 = 1e-5;

/// Columns of the symmetric matrix `a` that are (to f32 precision) combinations of the columns before
/// them: a Cholesky factorisation of the Jacobi-scaled `a` in column order, where a column whose
/// remaining pivot is below `min_pivot` is flagged and then left out. Only the lower triangle
/// (`a[i][j]`, `j <= i`) is read. A zero or non-finite diagonal is flagged too.
pub fn weak_pivots<const N: usize>(a: &Matrix<N>, min_pivot: f32) -> Held {
    weak_pivots_in_place(&mut a.clone(), min_pivot)
}

/// [`weak_pivots`] without a copy: `a`'s lower triangle is overwritten by the factors.
pub fn weak_pivots_in_place<const N: usize>(a: &mut Matrix<N>, min_pivot: f32) -> Held {
    let mut weak = Held::NONE;
    factor(None, a, &mut weak, min_pivot, true);
    weak
}

/// Solves `a x = b` in place (as [`solve_spd_holding_in_place`]) with the entries held that
/// [`weak_pivots`] flags at `min_pivot`, found and solved in one factorisation (the same factors and
/// the same solution, bit for bit, as flagging on a copy and then solving). Returns the held entries.
pub fn solve_spd_holding_weak_in_place<const N: usize>(
    a: &mut Matrix<N>,
    b: &mut [f32; N],
    min_pivot: f32,
) -> Result<Held, LinalgError> {
    let mut held = Held::NONE;
    let d = factor(None, a, &mut held, min_pivot, true);
    factor_solve(a, &d, b, true);
    if b.iter().all(|&v| finite(v)) { Ok(held) } else { Err(LinalgError::Singular) }
}

/// Solves `a x = b` (`a` symmetric positive semi-definite, lower triangle read) with the entries of
/// `x` flagged in `held` fixed at 0: their rows and columns are replaced by the identity.
pub fn solve_spd_holding<const N: usize>(a: &Matrix<N>, b: &[f32; N], held: Held) -> Result<[f32; N], LinalgError> {
    let (mut m, mut x) = (*a, *b);
    solve_spd_holding_in_place(&mut m, &mut x, held)?;
    Ok(x)
}

/// [`solve_spd_holding`] without copies: `a`'s lower triangle is overwritten by the scaled factors and
/// `b` by the solution `x`.
pub fn solve_spd_holding_in_place<const N: usize>(
    a: &mut Matrix<N>,
    b: &mut [f32; N],
    held: Held,
) -> Result<(), LinalgError> {
    solve_in_place(None, a, b, held, true)
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
    fn sqrt_clamped_is_zero_below_zero_and_sqrt_f32_above() {
        for x in [-f32::MAX, -1.0, -f32::MIN_POSITIVE, -0.0, f32::NAN, f32::NEG_INFINITY] {
            assert_eq!(sqrt_clamped(x).to_bits(), 0.0f32.to_bits(), "{x}");
        }
        for x in [0.0, f32::MIN_POSITIVE, 1e-20, 2.0, 9.80665, f32::MAX, f32::INFINITY] {
            assert_eq!(sqrt_clamped(x).to_bits(), sqrt_f32(x).to_bits(), "{x}");
        }
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
    fn scaled_factor_reproduces_the_scaled_matrix() {
        let a = spd4();
        let mut l = a;
        let mut held = Held::NONE;
        let d = factor(None, &mut l, &mut held, 0.0, true);
        assert_eq!(held, Held::NONE);
        // The factor's diagonal is stored as its reciprocal.
        let factor = |i: usize, k: usize| if i == k { 1.0 / l[i][i] } else { l[i][k] };
        for i in 0..4 {
            for j in 0..=i {
                let llt: f32 = (0..=j).map(|k| factor(i, k) * factor(j, k)).sum();
                assert!((llt - a[i][j] * d[i] * d[j]).abs() < 1e-5, "{i} {j}: {llt}");
            }
        }
    }

    #[test]
    fn in_place_forms_equal_the_copying_ones_bit_for_bit() {
        let a = spd4();
        let (b, held) = ([1.0, -2.0, 0.5, 3.0], Held::NONE.with(1));
        let (mut m, mut x) = (a, b);
        solve_spd_holding_in_place(&mut m, &mut x, held).unwrap();
        assert_eq!(x, solve_spd_holding(&a, &b, held).unwrap());
        assert_eq!(x[1], 0.0);
        for i in [0, 2, 3] {
            let r: f32 = [0, 2, 3].iter().map(|&k| a[i.max(k)][i.min(k)] * x[k]).sum();
            assert!((r - b[i]).abs() < 1e-4, "{i}: {r}");
        }
        let mut inv = a;
        spd_inverse_in_place(&mut inv).unwrap();
        assert_eq!(inv, spd_inverse(&a).unwrap());
    }

    #[test]
    fn weak_entries_found_while_solving_equal_flagging_then_solving_bit_for_bit() {
        // Column 3 a combination of columns 0 and 1 (plus a tiny part): weak at a pivot of 1e-3.
        let g: [[f32; 4]; 4] =
            [[1.0, 0.3, -0.2, 0.0], [0.1, 2.0, 0.5, 0.0], [-0.6, 0.2, 1.5, 0.0], [0.4, -0.9, 0.1, 0.0]];
        let g: [[f32; 4]; 4] = core::array::from_fn(|i| {
            let mut r = g[i];
            r[3] = 0.5 * r[0] - 0.25 * r[1] + if i == 2 { 1e-3 } else { 0.0 };
            r
        });
        let weak: Matrix<4> =
            core::array::from_fn(|i| core::array::from_fn(|j| (0..4).map(|k| g[k][i] * g[k][j]).sum()));
        for (a, min_pivot) in [(spd4(), 1e-3), (weak, 1e-3), (weak, 0.0)] {
            let b = [1.0, -2.0, 0.5, 3.0];
            let held = weak_pivots(&a, min_pivot);
            let (mut expected_m, mut expected_x) = (a, b);
            let expected = solve_spd_holding_in_place(&mut expected_m, &mut expected_x, held);
            let (mut m, mut x) = (a, b);
            let found = solve_spd_holding_weak_in_place(&mut m, &mut x, min_pivot);
            assert_eq!(found.ok(), expected.ok().map(|()| held));
            assert_eq!(x.map(f32::to_bits), expected_x.map(f32::to_bits));
        }
        assert!(weak_pivots(&weak, 1e-3).contains(3), "the test matrix has a weak pivot");
    }

    #[test]
    fn held_inverse_is_the_inverse_of_the_rest_with_zeros() {
        let a = spd4();
        let mut inv = a;
        spd_inverse_holding_in_place(&mut inv, Held::NONE.with(2)).unwrap();
        let free = [0, 1, 3];
        for &i in &free {
            assert_eq!((inv[i][2], inv[2][i]), (0.0, 0.0));
            for &j in &free {
                let v: f32 = free.iter().map(|&k| a[i][k] * inv[k][j]).sum();
                assert!((v - if i == j { 1.0 } else { 0.0 }).abs() < 1e-5, "{i} {j}: {v}");
            }
        }
        assert_eq!(inv[2][2], 0.0);
    }

    /// The LDLT elimination weighs each column by the pivot stored on its diagonal (1 for a held
    /// row): holding a row solves the rest as the system without it, bit for bit, and the free
    /// solution satisfies the equations.
    #[test]
    fn ldlt_holding_a_row_solves_the_rest_bit_for_bit() {
        let a = spd4();
        let b = [1.0, -2.0, 0.5, 3.0];
        let mut held = a;
        let mut x = b;
        ldlt_solve_holding_in_place(&mut held, &mut x, Held::NONE.with(1)).unwrap();
        let free = [0, 2, 3];
        let mut reduced: Matrix<3> = core::array::from_fn(|i| core::array::from_fn(|j| a[free[i]][free[j]]));
        let mut y = free.map(|i| b[i]);
        ldlt_solve_in_place(&mut reduced, &mut y).unwrap();
        assert_eq!(x[1], 0.0);
        assert_eq!(free.map(|i| x[i].to_bits()), y.map(f32::to_bits));
        let mut full = a;
        let mut z = b;
        ldlt_solve_in_place(&mut full, &mut z).unwrap();
        for i in 0..4 {
            let v: f32 = (0..4).map(|k| a[i][k] * z[k]).sum();
            assert!((v - b[i]).abs() < 1e-5 * (1.0 + b[i].abs()), "{i}: {v}");
        }
    }

    #[test]
    fn weak_pivots_flag_a_combination_of_earlier_columns() {
        // Rows of 9 with column 4 = column 0 + column 1: the Gram matrix has a dependent column.
        let mut m = [[0.0f32; 9]; 9];
        let mut full = [[0.0f32; 9]; 9];
        for r in 0..12 {
            let mut g: [f32; 9] = core::array::from_fn(|c| ((r * 7 + c * 3) % 11) as f32 - 5.0 + 0.1 * c as f32);
            g[4] = g[0] + g[1];
            add_outer_product(&mut m, &g, 2.0);
            for i in 0..9 {
                for j in 0..9 {
                    full[i][j] += 2.0 * g[i] * g[j];
                }
            }
        }
        for i in 0..9 {
            assert_eq!(m[i][..=i], full[i][..=i], "row {i}");
            assert!(m[i][i + 1..].iter().all(|&v| v == 0.0), "row {i}: upper triangle untouched");
        }
        assert_eq!(weak_pivots(&m, DETERMINED_PIVOT), Held::NONE.with(4));
        assert_eq!(weak_pivots(&spd4(), DETERMINED_PIVOT), Held::NONE);
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
        assert_eq!(spd_inverse(&a), Err(LinalgError::Singular));
        assert_eq!(solve_lu([[f32::NAN, 0.0], [0.0, 1.0]], [1.0, 1.0]), Err(LinalgError::Singular));
    }
}
