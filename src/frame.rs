//! The normalised problem the optimisers solve: small numbers where the arithmetic happens.
//!
//! Raw pose means can be near 33 000 counts; fitting `Ka` and `B` to them directly in `f32` loses most
//! digits to cancellation. A [`Frame`] (from the coarse calibration) maps each pose mean `m` to a unit
//! vector `u = (m - c) / (k * g)` and the model to the *deviation* vector
//! `x = [beta0, beta1, beta2, a0, a1, a2, m0, m1, m2]` with `A = I + diag(a) + lower(m)`,
//! `f_b / g = A u - beta`. Every entry of `x` is near 0, and the per-pose modulus error is evaluated as
//! `E = q + 2 u.d + |d|^2` with `d = (A - I) u - beta` and `q = |u|^2 - 1` precomputed, so no term is
//! formed from two nearly equal large numbers.
//!
//! In the paper's convention: `Ka = A diag(1/k)`, `B = g beta + Ka c`.
//!
//! ```
//! use accelcal::frame::Frame;
//! use accelcal::model::Params;
//! let frame = Frame::new([32768.0; 3], [836.0; 3], 9.80665).unwrap();
//! let p = Params { bias: [0.1; 3], scale: [0.0012; 3], nonorth: [1e-5, 0.0, 2e-5] };
//! let back = frame.to_params(&frame.to_deviation(&p));
//! assert!((back.bias[0] - 0.1).abs() < 1e-4);
//! ```

use crate::model::{PARAM_COUNT, Params};

/// Deviation vector `x` of the normalised model (see the [module docs](self)).
pub type Deviation = [f32; PARAM_COUNT];

/// One pose in the normalised frame: the unit-gravity direction estimate `u` and `q = |u|^2 - 1`.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NormPose {
    /// `(m - c) / (k g)`, dimensionless, near unit length.
    pub u: [f32; 3],
    /// `|u|^2 - 1`.
    pub q: f32,
}

/// Offsets and gains that normalise pose means (from the coarse calibration).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Frame {
    /// Per-axis offset `c`, input unit.
    pub offset: [f32; 3],
    /// Per-axis gain `k`, input unit per output unit.
    pub gain: [f32; 3],
    /// Gravity `g`, output unit.
    pub gravity: f32,
}

/// Why a [`Frame`] cannot be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum FrameError {
    /// Gravity must be finite and positive.
    InvalidGravity,
    /// A gain is zero or not finite (the up/down readings of that axis coincide).
    DegenerateGain {
        /// Axis index 0..3 (x, y, z).
        axis: u8,
    },
    /// An offset is not finite.
    NonFiniteOffset,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::InvalidGravity => f.write_str("gravity must be finite and positive"),
            Self::DegenerateGain { axis } => {
                write!(f, "axis {} has a zero or non-finite gain", crate::axis_name(*axis))
            }
            Self::NonFiniteOffset => f.write_str("an axis offset is not finite"),
        }
    }
}

impl core::error::Error for FrameError {}

/// `a + b` as `(sum, error)` with `sum + error` exact (Knuth's two-sum).
#[inline]
fn two_sum(a: f32, b: f32) -> (f32, f32) {
    let sum = a + b;
    let b_part = sum - a;
    (sum, (a - (sum - b_part)) + (b - b_part))
}

/// The high and low halves of `a` (Veltkamp's split: 12 significant bits each).
#[inline]
fn split(a: f32) -> (f32, f32) {
    let c = 4097.0 * a;
    let high = c - (c - a);
    (high, a - high)
}

/// `a b` as `(product, error)` with `product + error` exact (Dekker's two-product, no fused multiply-add).
#[inline]
fn two_product(a: f32, b: f32) -> (f32, f32) {
    let product = a * b;
    let ((ah, al), (bh, bl)) = (split(a), split(b));
    (product, ((ah * bh - product) + ah * bl + al * bh) + al * bl)
}

/// `(n_hi + n_lo) / (d_hi + d_lo)` to about twice `f32` precision, as `(high, low)`.
#[inline]
fn quotient((n_hi, n_lo): (f32, f32), (d_hi, d_lo): (f32, f32)) -> (f32, f32) {
    let high = n_hi / d_hi;
    let (p, p_error) = two_product(high, d_hi);
    // n_hi - p is exact (the two are within a rounding of each other).
    let remainder = (n_hi - p) - p_error + n_lo - high * d_lo;
    (high, remainder / d_hi)
}

impl Frame {
    /// A frame with per-axis `offset` and `gain` (input unit per output unit) and `gravity` (output unit).
    pub fn new(offset: [f32; 3], gain: [f32; 3], gravity: f32) -> Result<Self, FrameError> {
        let frame = Self { offset, gain, gravity };
        frame.validate()?;
        Ok(frame)
    }

    /// The checks of [`Frame::new`].
    #[inline]
    fn validate(&self) -> Result<(), FrameError> {
        if !crate::linalg::positive_finite(self.gravity) {
            return Err(FrameError::InvalidGravity);
        }
        self.validate_axes()
    }

    /// The checks of [`Frame::new`] but gravity's, on a frame written in place with a gravity
    /// checked before.
    #[inline]
    pub(crate) fn validate_axes(&self) -> Result<(), FrameError> {
        for (axis, &k) in self.gain.iter().enumerate() {
            if !crate::linalg::nonzero_finite(k) {
                return Err(FrameError::DegenerateGain { axis: axis as u8 });
            }
        }
        if !self.offset.iter().all(|&c| crate::linalg::finite(c)) {
            return Err(FrameError::NonFiniteOffset);
        }
        Ok(())
    }

    /// Normalises one pose mean (input unit). `u` and `q` are formed in double-`f32` arithmetic (exact
    /// sums and products by error-free transformations; once per pose, not per cost evaluation, and no
    /// software `f64` on a Cortex-M4F): `q = |u|^2 - 1` is the small number every modulus error starts
    /// from, and rounding `u` to `f32` first would cost it about 1e-7 absolute.
    pub fn normalize(&self, mean: [f32; 3]) -> NormPose {
        let mut u = [0.0f32; 3];
        // q = sum(hi) - 1 + sum(lo), the large part summed without error.
        let (mut q_hi, mut q_lo) = (-1.0f32, 0.0f32);
        for i in 0..3 {
            let (u_hi, u_lo) = quotient(two_sum(mean[i], -self.offset[i]), two_product(self.gain[i], self.gravity));
            u[i] = u_hi + u_lo;
            let (square_hi, square_lo) = two_product(u_hi, u_hi);
            let (sum, error) = two_sum(q_hi, square_hi);
            q_hi = sum;
            q_lo += error + square_lo + 2.0 * u_hi * u_lo;
        }
        NormPose { u, q: q_hi + q_lo }
    }

    /// Paper-convention parameters for a deviation vector.
    pub fn to_params(&self, x: &Deviation) -> Params {
        let k = self.gain;
        let scale = [(1.0 + x[3]) / k[0], (1.0 + x[4]) / k[1], (1.0 + x[5]) / k[2]];
        let nonorth = [x[6] / k[0], x[7] / k[0], x[8] / k[1]];
        let ka_only = Params { bias: [0.0; 3], scale, nonorth };
        let kc = ka_only.ka_times(self.offset);
        let g = self.gravity;
        Params { bias: [g * x[0] + kc[0], g * x[1] + kc[1], g * x[2] + kc[2]], scale, nonorth }
    }

    /// Deviation vector for paper-convention parameters (inverse of [`Frame::to_params`]).
    pub fn to_deviation(&self, p: &Params) -> Deviation {
        let k = self.gain;
        let kc = p.ka_times(self.offset);
        let g = self.gravity;
        [
            (p.bias[0] - kc[0]) / g,
            (p.bias[1] - kc[1]) / g,
            (p.bias[2] - kc[2]) / g,
            p.scale[0] * k[0] - 1.0,
            p.scale[1] * k[1] - 1.0,
            p.scale[2] * k[2] - 1.0,
            p.nonorth[0] * k[0],
            p.nonorth[1] * k[0],
            p.nonorth[2] * k[1],
        ]
    }

    /// Jacobian of the paper-convention parameters with respect to the deviation vector:
    /// `J[i][j] = d params[i] / d x[j]` (both in [`Params::to_array`] order). The mapping is affine.
    pub fn params_jacobian(&self) -> [[f32; PARAM_COUNT]; PARAM_COUNT] {
        let k = self.gain;
        let c = self.offset;
        let g = self.gravity;
        let mut j = [[0.0; PARAM_COUNT]; PARAM_COUNT];
        // Scale and non-orthogonality: linear in a and m.
        j[3][3] = 1.0 / k[0];
        j[4][4] = 1.0 / k[1];
        j[5][5] = 1.0 / k[2];
        j[6][6] = 1.0 / k[0];
        j[7][7] = 1.0 / k[0];
        j[8][8] = 1.0 / k[1];
        // Bias: B = g beta + Ka c.
        for i in 0..3 {
            j[i][i] = g;
        }
        j[0][3] = c[0] / k[0];
        j[1][6] = c[0] / k[0];
        j[1][4] = c[1] / k[1];
        j[2][7] = c[0] / k[0];
        j[2][8] = c[1] / k[1];
        j[2][5] = c[2] / k[2];
        j
    }

    /// Row `i` of [`Frame::params_jacobian`] (the same values, bit for bit), built alone (no 9x9 matrix
    /// on the stack: the verdict's standard deviations). Deviation
    /// entry `j >= 3` is the `Ka` entry at row `KA_ROW[j]`, column `KA_COLUMN[j]`, over that column's
    /// gain: `d Ka / d x_j = 1 / k` (parameter `j` itself) and, through `B = g beta + Ka c`,
    /// `d B / d x_j = c / k` (bias `KA_ROW[j]`); `d B_i / d beta_i = g`.
    #[inline]
    pub fn params_jacobian_row(&self, i: usize) -> [f32; PARAM_COUNT] {
        const KA_ROW: [usize; PARAM_COUNT] = [0, 1, 2, 0, 1, 2, 1, 2, 2];
        const KA_COLUMN: [usize; PARAM_COUNT] = [0, 1, 2, 0, 1, 2, 0, 0, 1];
        core::array::from_fn(|j| {
            let column = KA_COLUMN[j];
            if j < 3 {
                if i == j { self.gravity } else { 0.0 }
            } else if i == j {
                1.0 / self.gain[column]
            } else if i == KA_ROW[j] {
                self.offset[column] / self.gain[column]
            } else {
                0.0
            }
        })
    }
}

/// `d = (A - I) u - beta` for deviation `x`.
#[inline]
pub fn deviation_residual(x: &Deviation, u: [f32; 3]) -> [f32; 3] {
    [x[3] * u[0] - x[0], x[6] * u[0] + x[4] * u[1] - x[1], x[7] * u[0] + x[8] * u[1] + x[5] * u[2] - x[2]]
}

/// Normalised modulus error of one pose, `E / g^2 = |A u - beta|^2 - 1`, evaluated without cancellation.
#[inline]
pub fn modulus_error(x: &Deviation, pose: &NormPose) -> f32 {
    let u = pose.u;
    let d = deviation_residual(x, u);
    pose.q + 2.0 * (u[0] * d[0] + u[1] * d[1] + u[2] * d[2]) + (d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
}

/// Normalised objective `fE / g^4 = mean(E^2)` (the function every optimiser here minimises).
/// `f32::INFINITY` for no poses.
pub fn objective(x: &Deviation, poses: &[NormPose]) -> f32 {
    if poses.is_empty() {
        return f32::INFINITY;
    }
    let mut sum = 0.0;
    for pose in poses {
        let e = modulus_error(x, pose);
        sum += e * e;
    }
    sum / poses.len() as f32
}

/// Modulus error of one pose and its gradient with respect to `x`. Out of line: the Levenberg-Marquardt
/// normal equations and the verdict's passes over the poses share one copy.
#[inline(never)]
pub fn modulus_error_gradient(x: &Deviation, pose: &NormPose) -> (f32, Deviation) {
    let u = pose.u;
    let d = deviation_residual(x, u);
    let r = [u[0] + d[0], u[1] + d[1], u[2] + d[2]];
    let e = modulus_error(x, pose);
    let grad = [
        -2.0 * r[0],
        -2.0 * r[1],
        -2.0 * r[2],
        2.0 * r[0] * u[0],
        2.0 * r[1] * u[1],
        2.0 * r[2] * u[2],
        2.0 * r[1] * u[0],
        2.0 * r[2] * u[0],
        2.0 * r[2] * u[1],
    ];
    (e, grad)
}

/// Rows of `d r / d x` (3 x 9) for one pose; `r = A u - beta` is linear in `x`.
#[inline]
pub fn residual_jacobian(u: [f32; 3]) -> [[f32; PARAM_COUNT]; 3] {
    let mut j = [[0.0; PARAM_COUNT]; 3];
    j[0][0] = -1.0;
    j[0][3] = u[0];
    j[1][1] = -1.0;
    j[1][4] = u[1];
    j[1][6] = u[0];
    j[2][2] = -1.0;
    j[2][5] = u[2];
    j[2][7] = u[0];
    j[2][8] = u[1];
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn error_matches_direct_evaluation() {
        let frame = Frame::new([32768.0, 32700.0, 32900.0], [830.0, 840.0, 850.0], 9.80665).unwrap();
        let p = Params { bias: [40.0, 39.0, 38.0], scale: [0.0012, 0.00119, 0.00118], nonorth: [1e-5, -2e-5, 3e-5] };
        let x = frame.to_deviation(&p);
        let mean = [33500.0, 32000.0, 33100.0];
        let pose = frame.normalize(mean);
        let e_norm = modulus_error(&x, &pose) * 9.80665f32 * 9.80665;
        let e_direct = p.modulus_error(mean, 9.80665);
        assert!((e_norm - e_direct).abs() < 1e-3 * e_direct.abs().max(1.0), "{e_norm} vs {e_direct}");
    }

    #[test]
    fn normalize_matches_double_precision() {
        let frame = Frame::new([32768.0, -412.5, 1903.25], [1671.3, 1669.9, 1675.1], 9.80665).unwrap();
        for k in 0..500 {
            let t = k as f32 * 0.0137;
            let mean = [32768.0 + 16000.0 * libm::cosf(t), -412.5 + 16000.0 * libm::sinf(t), 1903.25 + 37.3 * t];
            let pose = frame.normalize(mean);
            let u: [f64; 3] = core::array::from_fn(|i| {
                (f64::from(mean[i]) - f64::from(frame.offset[i]))
                    / (f64::from(frame.gain[i]) * f64::from(frame.gravity))
            });
            let q = u[0] * u[0] + u[1] * u[1] + u[2] * u[2] - 1.0;
            for i in 0..3 {
                assert_eq!(pose.u[i], u[i] as f32, "k {k} axis {i}");
            }
            // Within one rounding of the double-precision value.
            assert!((f64::from(pose.q) - q).abs() <= f64::from(f32::EPSILON) * q.abs() + 1e-13, "k {k}");
        }
    }

    #[test]
    fn gradient_matches_finite_differences() {
        let pose = NormPose { u: [0.3, -0.5, 0.8], q: 0.3f32 * 0.3 + 0.25 + 0.64 - 1.0 };
        let x = [0.01, -0.02, 0.005, 0.01, -0.01, 0.02, 0.003, -0.004, 0.002];
        let (_, g) = modulus_error_gradient(&x, &pose);
        for i in 0..PARAM_COUNT {
            let h = 1e-3;
            let (mut xp, mut xm) = (x, x);
            xp[i] += h;
            xm[i] -= h;
            let fd = (modulus_error(&xp, &pose) - modulus_error(&xm, &pose)) / (2.0 * h);
            assert!((fd - g[i]).abs() < 1e-3, "param {i}: {fd} vs {}", g[i]);
        }
    }

    #[test]
    fn params_jacobian_matches_differences_of_to_params() {
        let frame = Frame::new([32768.0, -412.5, 1903.25], [1671.3, 1669.9, 1675.1], 9.80665).unwrap();
        let t = frame.params_jacobian();
        for (i, row) in t.iter().enumerate() {
            assert_eq!(frame.params_jacobian_row(i).map(f32::to_bits), row.map(f32::to_bits), "row {i}");
        }
        let base = frame.to_params(&[0.0; PARAM_COUNT]).to_array();
        for j in 0..PARAM_COUNT {
            let mut x = [0.0; PARAM_COUNT];
            x[j] = 1e-2;
            let moved = frame.to_params(&x).to_array();
            for i in 0..PARAM_COUNT {
                let slope = (moved[i] - base[i]) / 1e-2;
                let tolerance = 1e-3 * t[i][j].abs() + 1e-3 * base[i].abs();
                assert!((slope - t[i][j]).abs() <= tolerance, "d p{i} / d x{j}: {slope} vs {}", t[i][j]);
            }
        }
    }

    #[test]
    fn rejects_bad_frames() {
        assert_eq!(Frame::new([0.0; 3], [1.0; 3], 0.0), Err(FrameError::InvalidGravity));
        assert_eq!(Frame::new([0.0; 3], [1.0, 0.0, 1.0], 9.8), Err(FrameError::DegenerateGain { axis: 1 }));
        assert_eq!(Frame::new([f32::NAN, 0.0, 0.0], [1.0; 3], 9.8), Err(FrameError::NonFiniteOffset));
    }
}
