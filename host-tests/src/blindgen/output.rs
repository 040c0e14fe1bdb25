//! Output: the CSV text of a log, per-hold means for checks, and the manifest entry of a log.

use std::fmt::Write as _;

use serde_json::{Value, json};

use super::session::G_MPS2;
use super::vec3::{V3, add, norm, scale, sub};
use super::{Log, LogSpec};

impl Log {
    /// The log as CSV: `t,ax,ay,az[,temp]` with a unit suffix on the acceleration columns
    /// (`_mps2`, `_g` or `_raw`), time in s, temperature in deg C.
    pub fn to_csv_string(&self) -> String {
        let has_temp = self.samples.first().is_some_and(|s| s.temp_c.is_some());
        let u = self.units.column_suffix();
        let mut out = format!("t,ax{u},ay{u},az{u}{}\n", if has_temp { ",temp" } else { "" });
        for s in &self.samples {
            let [x, y, z] = s.accel.map(|v| self.units.format(v));
            let _ = write!(out, "{:.6},{x},{y},{z}", s.t_s);
            if let Some(c) = s.temp_c {
                let _ = write!(out, ",{c:.2}");
            }
            out.push('\n');
        }
        out
    }

    /// Readings converted back to m/s^2.
    pub fn accel_mps2(&self, index: usize) -> V3 {
        scale(self.samples[index].accel, 1.0 / self.units.per_mps2())
    }

    /// Mean reading (m/s^2) of each hold, leaving out `margin_s` at both ends.
    pub fn hold_means_mps2(&self, margin_s: f64) -> Vec<V3> {
        self.holds.iter().map(|h| self.window_mean_mps2(h.start_s + margin_s, h.end_s - margin_s)).collect()
    }

    /// Mean reading (m/s^2) over samples with `from_s <= t < to_s` (NaN when there are none).
    pub fn window_mean_mps2(&self, from_s: f64, to_s: f64) -> V3 {
        let (mut sum, mut n) = ([0.0; 3], 0usize);
        for (i, s) in self.samples.iter().enumerate() {
            if s.t_s >= from_s && s.t_s < to_s {
                sum = add(sum, self.accel_mps2(i));
                n += 1;
            }
        }
        scale(sum, 1.0 / n as f64)
    }

    /// RMS over samples and axes of `self - other` (mg).
    pub fn rms_difference_mg(&self, other: &Log) -> f64 {
        let n = self.samples.len().min(other.samples.len());
        let sum: f64 = (0..n)
            .map(|i| {
                let d = sub(self.accel_mps2(i), other.accel_mps2(i));
                d.iter().map(|v| v * v).sum::<f64>()
            })
            .sum();
        (sum / (3 * n.max(1)) as f64).sqrt() / G_MPS2 * 1e3
    }
}

/// The largest change of a hold mean by the effect, calibrated with the truth (`|Ka (log - twin)|`,
/// mg): how visible the effect is in the pose means.
pub fn max_hold_effect_mg(spec: &LogSpec, log: &Log, twin: &Log) -> f64 {
    let pairs = log.hold_means_mps2(0.0).into_iter().zip(twin.hold_means_mps2(0.0));
    let largest = pairs.map(|(a, b)| norm(sub(spec.truth.apply(a), spec.truth.apply(b)))).fold(0.0, f64::max);
    largest / G_MPS2 * 1e3
}

/// The manifest entry of a log written as `file` (its twin as `twin_file`); `log` and `twin` are
/// the generated logs (for the measured difference).
pub fn manifest_entry(spec: &LogSpec, file: &str, twin_file: &str, log: &Log, twin: &Log) -> Value {
    let model = spec.effect.as_ref().map(|e| e.model());
    let magnitude = model.map(|m| m.magnitude());
    json!({
        "file": file,
        "twin": twin_file,
        "family": spec.family.name(),
        "shape": spec.shape,
        "params": model.map_or(Value::Null, |m| m.params()),
        "magnitude": magnitude.map(|m| m.value),
        "magnitude_unit": magnitude.map(|m| m.unit),
        "magnitude_what": magnitude.map(|m| m.what),
        "rms_effect_mg": log.rms_difference_mg(twin),
        "max_hold_effect_mg": max_hold_effect_mg(spec, log, twin),
        "seed": spec.seed,
        "held_out": spec.held_out(),
        "units": spec.units.name(),
        "lsb_per_g": spec.units.lsb_per_g(),
        "sample_rate_hz": spec.session.rate_hz,
        "noise_mg": spec.noise_mg,
        "truth": spec.truth.to_json(spec.units),
        "pose_count": spec.session.poses.len(),
        "rest_s": spec.session.rest_s,
        "duration_s": spec.session.total_s(),
        "samples": log.samples.len(),
        "temperature": spec.session.temperature.map(|p| p.to_json()),
    })
}
