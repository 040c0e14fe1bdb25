//! The sensor model in `f64`: what the sensor reads for a true specific force (Zou et al. 2020,
//! eq. 2, inverted), and the parameters a perfect calibration finds in another output unit.

use accelcal::model::Params;

use super::units::OutputUnits;

type Vec3 = [f64; 3];

/// The 9-parameter model in `f64`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Model64 {
    bias: Vec3,
    scale: Vec3,
    nonorth: Vec3,
}

impl From<&Params> for Model64 {
    fn from(p: &Params) -> Self {
        Self { bias: p.bias.map(f64::from), scale: p.scale.map(f64::from), nonorth: p.nonorth.map(f64::from) }
    }
}

impl Model64 {
    /// `Ka f_s`.
    pub(crate) fn ka_times(&self, f_s: Vec3) -> Vec3 {
        let (s, m) = (self.scale, self.nonorth);
        [s[0] * f_s[0], m[0] * f_s[0] + s[1] * f_s[1], m[1] * f_s[0] + m[2] * f_s[1] + s[2] * f_s[2]]
    }

    /// The reading for true specific force `f_b`: `f_s = Ka^-1 (f_b + B)` (forward substitution).
    pub(crate) fn reading(&self, f_b: Vec3) -> Vec3 {
        let (s, m) = (self.scale, self.nonorth);
        let y = [f_b[0] + self.bias[0], f_b[1] + self.bias[1], f_b[2] + self.bias[2]];
        let x0 = y[0] / s[0];
        let x1 = (y[1] - m[0] * x0) / s[1];
        let x2 = (y[2] - m[1] * x0 - m[2] * x1) / s[2];
        [x0, x1, x2]
    }

    /// Calibrated specific force `f_b = Ka f_s - B`.
    #[cfg(test)]
    pub(crate) fn apply(&self, f_s: Vec3) -> Vec3 {
        let k = self.ka_times(f_s);
        [k[0] - self.bias[0], k[1] - self.bias[1], k[2] - self.bias[2]]
    }
}

/// The parameters a perfect calibration of readings in `units` finds when it calibrates against
/// `|f_b| = target_gravity` (e.g. 9.80665 for m/s^2 out, 1.0 for g out), given the `truth` in m/s^2
/// and `1 g = gravity_mps2`. With `f_s[m/s^2] = c (r - offset)` (`c = g / lsb_per_g`, `g` or 1) and
/// `k = target_gravity / g`: `Ka' = k c Ka`, `B' = k (B + c Ka offset)`.
pub fn equivalent_params(truth: &Params, units: OutputUnits, gravity_mps2: f64, target_gravity: f64) -> Params {
    let model = Model64::from(truth);
    let (c, offset) = match units {
        OutputUnits::Counts { lsb_per_g, offset } => (gravity_mps2 / lsb_per_g, offset),
        OutputUnits::G => (gravity_mps2, 0.0),
        OutputUnits::Mps2 => (1.0, 0.0),
    };
    let k = target_gravity / gravity_mps2;
    let ka_offset = model.ka_times([offset; 3]);
    Params {
        bias: std::array::from_fn(|a| (k * (model.bias[a] + c * ka_offset[a])) as f32),
        scale: std::array::from_fn(|a| (k * c * model.scale[a]) as f32),
        nonorth: std::array::from_fn(|a| (k * c * model.nonorth[a]) as f32),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{Plan, SimConfig, random_truth, simulate};

    #[test]
    fn equivalent_params_calibrate_the_output_units() {
        let truth = random_truth(9);
        for (units, target) in [
            (OutputUnits::Mps2, 9.80665),
            (OutputUnits::G, 1.0),
            (OutputUnits::Counts { lsb_per_g: 4096.0, offset: 2048.0 }, 1.0),
        ] {
            let cfg = SimConfig { noise_mg: 0.0, units, truth, plan: Plan::Cube26, ..SimConfig::paper(1) };
            let rec = simulate(&cfg);
            let model = Model64::from(&equivalent_params(&truth, units, cfg.gravity, target));
            for pose in &rec.poses {
                let f_b = model.apply(pose.true_reading);
                for a in 0..3 {
                    // f32 parameters: relative precision ~1e-7.
                    assert!((f_b[a] - target * pose.direction[a]).abs() < 1e-5 * target, "{units}: {f_b:?}");
                }
            }
        }
    }
}
