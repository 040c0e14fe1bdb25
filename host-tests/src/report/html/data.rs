//! The per-pose numbers the report draws that the calibration itself does not return: the modulus
//! residual of each pose before and after calibration, and its mean temperature. They go into the
//! `calibrate --json` document, and the page draws them from there.

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, NormalizedPoses};
use accelcal::model::{PARAM_COUNT, Params, norm_squared};

use crate::calib::MAX_POSES;
use crate::csvio::{PoseSpan, Table};

/// Modulus residual of one pose, `(|f_b| - g) / g`, in mg.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseResidual {
    /// With the "before" model (the readings at face value, or the initial estimate for counts).
    pub before_mg: f32,
    /// With the calibrated parameters.
    pub after_mg: f32,
}

/// The model the library computes its "before" RMSE with: `config.before`, or else the initial
/// estimate (zero deviation in the normalised frame). `None` when the poses cannot be normalised.
pub fn before_params(poses: &[Pose], config: &CalibrationConfig) -> Option<Params> {
    if let Some(before) = config.before {
        return Some(before);
    }
    let norm = NormalizedPoses::<MAX_POSES>::prepare(poses, config.init, config.gravity, &config.outliers).ok()?;
    Some(norm.frame().to_params(&[0.0; PARAM_COUNT]))
}

/// `(|params(mean)| - g) / g` in mg (NaN for a non-positive gravity).
pub fn modulus_residual_mg(params: &Params, mean: [f32; 3], gravity: f32) -> f32 {
    (norm_squared(params.apply(mean)).sqrt() - gravity) / gravity * 1000.0
}

/// Direction of the calibrated reading of a pose (unit vector; `None` for a zero or non-finite one).
pub fn calibrated_direction(params: &Params, mean: [f32; 3]) -> Option<[f32; 3]> {
    let f = params.apply(mean);
    let norm = norm_squared(f).sqrt();
    (norm > 0.0 && norm.is_finite()).then(|| f.map(|v| v / norm))
}

/// The residual of every pose before and after calibration with `params` (the "before" residual is
/// NaN when no "before" model exists).
pub fn pose_residuals_mg(poses: &[Pose], config: &CalibrationConfig, params: &Params) -> Vec<PoseResidual> {
    let before = before_params(poses, config);
    poses
        .iter()
        .map(|p| PoseResidual {
            before_mg: before.map_or(f32::NAN, |b| modulus_residual_mg(&b, p.mean, config.gravity)),
            after_mg: modulus_residual_mg(params, p.mean, config.gravity),
        })
        .collect()
}

/// Mean temperature (deg C) of each pose: over its rows for a raw log (`spans`), its own row for a
/// means file. All `None` without a temperature column; `None` for a pose whose rows the table does
/// not hold (a streamed log keeps only its first rows).
pub fn pose_temperatures_c(table: &Table, spans: Option<&[PoseSpan]>, pose_count: usize) -> Vec<Option<f64>> {
    let Some(temps) = table.temps_c.as_deref() else {
        return vec![None; pose_count];
    };
    (0..pose_count)
        .map(|i| {
            let rows = match spans {
                Some(spans) => spans.get(i).map(|s| s.first_row..s.last_row + 1),
                None => Some(i..i + 1),
            };
            rows.and_then(|r| temps.get(r)).and_then(mean_finite)
        })
        .collect()
}

/// Mean of the finite values, `None` when there are none.
fn mean_finite(values: &[f64]) -> Option<f64> {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    (!finite.is_empty()).then(|| finite.iter().sum::<f64>() / finite.len() as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn residual_of_a_reading_on_the_sphere_is_zero_and_off_it_is_in_mg() {
        let p = Params::IDENTITY;
        assert!(modulus_residual_mg(&p, [0.0, 0.0, 1.0], 1.0).abs() < 1e-4);
        assert!((modulus_residual_mg(&p, [0.0, 0.0, 1.002], 1.0) - 2.0).abs() < 1e-3);
        assert!((modulus_residual_mg(&p, [0.6, 0.0, -0.8 * 0.999], 1.0) + 0.64).abs() < 0.01);
    }

    #[test]
    fn direction_is_the_unit_calibrated_reading() {
        let p = Params { bias: [1.0, 0.0, 0.0], ..Params::IDENTITY };
        assert_eq!(calibrated_direction(&p, [1.0, 0.0, 2.0]), Some([0.0, 0.0, 1.0]));
        assert_eq!(calibrated_direction(&p, [1.0, 0.0, 0.0]), None);
    }

    #[test]
    fn mean_finite_skips_nan_and_is_none_when_empty() {
        assert_eq!(mean_finite(&[1.0, f64::NAN, 3.0]), Some(2.0));
        assert_eq!(mean_finite(&[f64::NAN]), None);
    }
}
