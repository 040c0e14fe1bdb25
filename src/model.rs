//! The 9-parameter error model of Zou et al. (2020), eq. (2), and the modulus objective, eq. (5).
//!
//! `f_b = Ka * f_s - B` with `Ka = [[Sxx, 0, 0], [Mxx, Syy, 0], [Myy, Mzz, Szz]]`: `f_s` is the sensor
//! output (any unit: raw counts, g, m/s^2), `f_b` the calibrated specific force in the unit of gravity
//! you calibrate against (m/s^2 with the default [`STANDARD_GRAVITY_MPS2`]).
//!
//! ```
//! use accelcal::model::Params;
//! let p = Params::IDENTITY;
//! assert_eq!(p.apply([0.0, 0.0, 9.8]), [0.0, 0.0, 9.8]);
//! ```

/// Standard gravity in m/s^2 (the default `g` of the modulus principle).
pub const STANDARD_GRAVITY_MPS2: f32 = 9.806_65;

/// Number of model parameters.
pub const PARAM_COUNT: usize = 9;

/// Parameter names in the order of [`Params::to_array`].
pub const PARAM_NAMES: [&str; PARAM_COUNT] = ["Bx", "By", "Bz", "Sxx", "Syy", "Szz", "Mxx", "Myy", "Mzz"];

/// Calibration parameters in the paper's convention.
///
/// `bias` is in the output unit (that of gravity), `scale` and `nonorth` in output unit per input unit.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Params {
    /// `B = [Bx, By, Bz]`, subtracted after `Ka`.
    pub bias: [f32; 3],
    /// Diagonal of `Ka`: `[Sxx, Syy, Szz]`.
    pub scale: [f32; 3],
    /// Lower off-diagonal of `Ka`: `[Mxx, Myy, Mzz]` at rows/columns (1,0), (2,0), (2,1).
    pub nonorth: [f32; 3],
}

impl Params {
    /// No correction: `Ka = I`, `B = 0`.
    pub const IDENTITY: Self = Self { bias: [0.0; 3], scale: [1.0; 3], nonorth: [0.0; 3] };

    /// The parameters as `[Bx, By, Bz, Sxx, Syy, Szz, Mxx, Myy, Mzz]` (see [`PARAM_NAMES`]).
    pub const fn to_array(&self) -> [f32; PARAM_COUNT] {
        let (b, s, m) = (self.bias, self.scale, self.nonorth);
        [b[0], b[1], b[2], s[0], s[1], s[2], m[0], m[1], m[2]]
    }

    /// Inverse of [`Params::to_array`].
    pub const fn from_array(a: [f32; PARAM_COUNT]) -> Self {
        Self { bias: [a[0], a[1], a[2]], scale: [a[3], a[4], a[5]], nonorth: [a[6], a[7], a[8]] }
    }

    /// `true` when every parameter is finite.
    #[inline(never)]
    pub fn is_finite(&self) -> bool {
        // Read in place (`to_array` first copied the nine values to the stack).
        [&self.bias, &self.scale, &self.nonorth].iter().all(|a| a.iter().all(|&v| crate::linalg::finite(v)))
    }

    /// `Ka * f_s` (no bias).
    #[inline]
    pub fn ka_times(&self, f_s: [f32; 3]) -> [f32; 3] {
        let (s, m) = (self.scale, self.nonorth);
        [s[0] * f_s[0], m[0] * f_s[0] + s[1] * f_s[1], m[1] * f_s[0] + m[2] * f_s[1] + s[2] * f_s[2]]
    }

    /// Calibrates one sample: `f_b = Ka * f_s - B`. Inlined: the per-sample path of a firmware.
    #[inline]
    pub fn apply(&self, f_s: [f32; 3]) -> [f32; 3] {
        self.calibrated(f_s)
    }

    /// [`Params::apply`] through one out-of-line copy of the arithmetic ([`Params::apply_to`]): for the
    /// library's once-per-pose callers (flash first; not a per-sample path).
    #[inline]
    pub(crate) fn apply_shared(&self, f_s: [f32; 3]) -> [f32; 3] {
        let mut sample = f_s;
        self.apply_to(&mut sample);
        sample
    }

    /// `|f_b|`, the modulus of the reading `f_s` calibrated. Out of line: the ellipsoid fit's statistics,
    /// the verdict's RMSE before calibration and [`modulus_rmse_mg`] share one copy.
    #[inline(never)]
    pub(crate) fn modulus(&self, f_s: [f32; 3]) -> f32 {
        crate::linalg::sqrt_f32(norm_squared(self.apply_shared(f_s)))
    }

    /// [`Params::apply`] in place. Out of line: one copy of the arithmetic for the library's
    /// once-per-pose callers and the odd last sample of a batch (the batch loop inlines its own,
    /// [`Params::calibrated`]).
    #[inline(never)]
    fn apply_to(&self, sample: &mut [f32; 3]) {
        *sample = self.calibrated(*sample);
    }

    /// [`Params::apply`], inlined.
    #[inline(always)]
    fn calibrated(&self, f_s: [f32; 3]) -> [f32; 3] {
        let k = self.ka_times(f_s);
        [k[0] - self.bias[0], k[1] - self.bias[1], k[2] - self.bias[2]]
    }

    /// [`Params::apply`] on every sample of a batch, in place: the parameters stay in registers and two
    /// samples are calibrated per iteration (the fast path for a stream).
    pub fn apply_in_place(&self, samples: &mut [[f32; 3]]) {
        let mut pairs = samples.chunks_exact_mut(2);
        for pair in &mut pairs {
            let (a, b) = (self.calibrated(pair[0]), self.calibrated(pair[1]));
            pair[0] = a;
            pair[1] = b;
        }
        // At most one sample is left: no loop.
        if let [last] = pairs.into_remainder() {
            self.apply_to(last);
        }
    }

    /// [`Params::apply`] on micromath's `F32x3`.
    #[cfg(feature = "micromath")]
    #[inline]
    pub fn apply_vector(&self, f_s: micromath::vector::F32x3) -> micromath::vector::F32x3 {
        let [x, y, z] = self.apply([f_s.x, f_s.y, f_s.z]);
        micromath::vector::F32x3 { x, y, z }
    }

    /// Modulus error of one pose, eq. (4): `E = |f_b|^2 - g^2` (output unit squared).
    #[inline]
    pub fn modulus_error(&self, f_s: [f32; 3], gravity: f32) -> f32 {
        norm_squared(self.apply_shared(f_s)) - gravity * gravity
    }

    /// The paper's objective, eq. (5): `fE = (1/N) sum E_L^2` over the pose means `poses`
    /// (output unit to the fourth). Empty input gives `None`.
    pub fn objective(&self, poses: &[[f32; 3]], gravity: f32) -> Option<f32> {
        if poses.is_empty() {
            return None;
        }
        let sum: f32 = poses.iter().map(|&p| square(self.modulus_error(p, gravity))).sum();
        Some(sum / poses.len() as f32)
    }

    /// The sensor reading this model predicts for the true specific force `f_b`: `f_s = Ka^-1 (f_b + B)`.
    /// `None` when `Ka` is singular.
    pub fn invert(&self, f_b: [f32; 3]) -> Option<[f32; 3]> {
        let (s, m) = (self.scale, self.nonorth);
        if s.iter().any(|&v| v == 0.0 || !v.is_finite()) {
            return None;
        }
        let y = [f_b[0] + self.bias[0], f_b[1] + self.bias[1], f_b[2] + self.bias[2]];
        let x0 = y[0] / s[0];
        let x1 = (y[1] - m[0] * x0) / s[1];
        let x2 = (y[2] - m[1] * x0 - m[2] * x1) / s[2];
        Some([x0, x1, x2])
    }
}

impl Default for Params {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// `|v|^2`.
#[inline]
pub fn norm_squared(v: [f32; 3]) -> f32 {
    v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
}

#[inline]
pub(crate) fn square(x: f32) -> f32 {
    x * x
}

/// Modulus RMSE of calibrated poses, `sqrt(mean((|f_b| - g)^2))`, in milli-g. `None` for no poses.
pub fn modulus_rmse_mg(params: &Params, poses: &[[f32; 3]], gravity: f32) -> Option<f32> {
    if poses.is_empty() || !(gravity > 0.0) {
        return None;
    }
    let sum: f32 = poses.iter().map(|&p| square(params.modulus(p) - gravity)).sum();
    Some(crate::linalg::sqrt_f32(sum / poses.len() as f32) / gravity * 1000.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    const TRUTH: Params = Params {
        bias: [0.124_886_39; 3],
        scale: [0.97, 0.970_119_7, 0.970_239_4],
        nonorth: [-0.015_237_98, -0.015_000_48, -0.015_239_86],
    };

    #[test]
    fn invert_then_apply_is_identity() {
        let f_b = [1.0, -9.0, 3.5];
        let f_s = TRUTH.invert(f_b).unwrap();
        let back = TRUTH.apply(f_s);
        for i in 0..3 {
            assert!((back[i] - f_b[i]).abs() < 1e-5, "{back:?}");
        }
    }

    #[test]
    fn objective_is_zero_at_truth_and_none_when_empty() {
        let g = STANDARD_GRAVITY_MPS2;
        let poses = [TRUTH.invert([0.0, 0.0, g]).unwrap(), TRUTH.invert([g, 0.0, 0.0]).unwrap()];
        assert!(TRUTH.objective(&poses, g).unwrap() < 1e-6);
        assert!(Params::IDENTITY.objective(&poses, g).unwrap() > 1e-3);
        assert_eq!(TRUTH.objective(&[], g), None);
        assert_eq!(modulus_rmse_mg(&TRUTH, &[], g), None);
    }

    #[test]
    fn apply_in_place_matches_apply_for_odd_and_even_batches() {
        let samples: [[f32; 3]; 5] =
            core::array::from_fn(|i| [i as f32 - 2.5, 9.8 - i as f32 * 0.3, (i * i) as f32 * 0.7 - 3.0]);
        for n in 0..=samples.len() {
            let mut batch = samples;
            TRUTH.apply_in_place(&mut batch[..n]);
            for i in 0..samples.len() {
                let expected = if i < n { TRUTH.apply(samples[i]) } else { samples[i] };
                assert_eq!(batch[i], expected, "batch of {n}, sample {i}");
            }
        }
    }

    #[test]
    fn singular_model_does_not_invert() {
        let mut p = TRUTH;
        p.scale[1] = 0.0;
        assert_eq!(p.invert([1.0, 2.0, 3.0]), None);
    }
}
