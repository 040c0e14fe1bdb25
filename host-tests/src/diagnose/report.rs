//! The report: the result types, the JSON (every candidate with its held-out evidence, ranked),
//! the text and the plots.

use std::path::Path;

use accelcal::model::Params;
use serde_json::{Value, json};

use super::locate::orientation_label;
use crate::calib;
use crate::plots::{Scale, Series, line_chart};

/// Step 1 and 4: the gap before and after the winning effect.
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// Real modulus RMSE of the nominal fit, mg.
    pub real_rmse_mg: f64,
    /// Mean simulated RMSE, mg.
    pub sim_rmse_mg: f64,
    /// Standard deviation of the simulated RMSE over the repeats, mg.
    pub sim_spread_mg: f64,
    /// `(real - sim) / spread`.
    pub z: f64,
    /// See [`SIGNIFICANT_Z`](super::SIGNIFICANT_Z).
    pub significant: bool,
    /// `real / sim` with the nominal model.
    pub ratio_before: f64,
    /// Real RMSE after adding the winning effect, mg.
    pub real_rmse_after_mg: f64,
    /// Simulated RMSE after adding the winning effect, mg.
    pub sim_rmse_after_mg: f64,
    /// `real / sim` after adding the winning effect (= before for `none`).
    pub ratio_after: f64,
}

/// One pose in the report.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseReport {
    /// Mid time, s.
    pub t_mid_s: f64,
    /// Static duration, s.
    pub duration_s: f64,
    /// Mean temperature, deg C.
    pub temp_c: Option<f64>,
    /// Calibrated unit direction (sensor axes).
    pub direction: [f64; 3],
    /// Modulus residual of the nominal fit, mg.
    pub residual_mg: f64,
    /// Its white-noise standard deviation, mg.
    pub expected_mg: f64,
    /// Modulus residual after the winning effect, mg (`None` for a pose it drops).
    pub residual_after_mg: Option<f64>,
    /// Modulus of the last-third mean minus that of the first third, mg.
    pub early_late_mg: f64,
    /// Chi-square of the within-pose segment means (white noise: about 12).
    pub within_chi2: f64,
}

/// Allan deviation of the longest rest.
#[derive(Debug, Clone, PartialEq)]
pub struct Allan {
    /// Duration of the longest rest, s.
    pub rest_s: f64,
    /// Cluster times, s.
    pub tau_s: Vec<f64>,
    /// Allan deviation (RMS over the axes), mg.
    pub adev_mg: Vec<f64>,
    /// White-noise prediction, mg.
    pub white_mg: Vec<f64>,
}

/// One candidate's result.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Effect name (see [`EFFECT_NAMES`](super::EFFECT_NAMES)).
    pub effect: &'static str,
    /// `false` when the data cannot test it (e.g. no temperature column).
    pub applicable: bool,
    /// Withheld-pose ratio (penalised), 1 = fully explained.
    pub heldout_ratio: f64,
    /// `1 - ln(heldout_ratio) / ln(nominal heldout ratio)` (a ratio below 1 weighted by
    /// [`OVERSHOOT_WEIGHT`](super::OVERSHOOT_WEIGHT)).
    pub heldout_gain: f64,
    /// The gap ratio with this effect added.
    pub ratio_after: f64,
    /// Extra parameters.
    pub extra_params: usize,
    /// The chosen variant (time constant, bias/scale, dropped poses, walk).
    pub detail: String,
    /// Gain on the within-pose channel (withheld poses' movement during their holds), as for
    /// `heldout_gain`; NaN when the channel is not significant or the family does not move there.
    pub within_gain: f64,
    /// The variant chosen on the within-pose channel (empty when none).
    pub within_detail: String,
    /// Every pose-level parametrisation tried, with its penalised held-out ratio (smaller is
    /// better; the chosen one is the smallest).
    pub variants: Vec<(String, f64)>,
}

impl Candidate {
    /// The evidence for the family: the larger of its pose-level and within-pose gains.
    pub fn evidence(&self) -> f64 {
        if self.within_gain.is_finite() { self.heldout_gain.max(self.within_gain) } else { self.heldout_gain }
    }
}

/// An out-of-catalogue probe (never a verdict; see `unexplained`).
#[derive(Debug, Clone, PartialEq)]
pub struct Probe {
    /// The shape probed.
    pub shape: &'static str,
    /// Held-out gain, as for a candidate.
    pub heldout_gain: f64,
    /// The best parametrisation.
    pub detail: String,
}

/// The whole diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    /// The file (as named in the table).
    pub file: String,
    /// Rows read.
    pub samples: usize,
    /// Units of the readings.
    pub units: String,
    /// Calibration gravity, m/s^2.
    pub gravity: f64,
    /// Seed used.
    pub seed: u64,
    /// Simulated repeats of the experiment.
    pub repeats: usize,
    /// The library's nominal parameters.
    pub params: Params,
    /// White noise per axis, mg (median within-pose standard deviation).
    pub white_mg: [f64; 3],
    /// Step 1 / 4.
    pub gap: Gap,
    /// Step 2: per pose.
    pub poses: Vec<PoseReport>,
    /// Step 2: noise.
    pub allan: Allan,
    /// Step 3.
    pub candidates: Vec<Candidate>,
    /// Out-of-catalogue probes.
    pub probes: Vec<Probe>,
    /// Held-out ratio of the nominal model.
    pub heldout_ratio_nominal: f64,
    /// Step 3 verdict: an [`EFFECT_NAMES`](super::EFFECT_NAMES) entry, `none`, or `unexplained` (a significant gap no
    /// family explains on withheld poses).
    pub verdict: &'static str,
    /// For `unexplained`: where the gap lies.
    pub unexplained_where: Option<String>,
    /// `true` when the gap is significant and a candidate explains it (gain >= [`MIN_GAIN`](super::MIN_GAIN)).
    pub explained: bool,
    /// Step 4.
    pub shrink: f64,
}

fn finite(v: f64) -> Value {
    if v.is_finite() { json!(v) } else { Value::Null }
}

impl Diagnosis {
    /// The applicable candidates, best held-out gain first.
    pub fn ranked(&self) -> Vec<&Candidate> {
        let mut v: Vec<&Candidate> = self.candidates.iter().filter(|c| c.applicable).collect();
        v.sort_by(|a, b| b.evidence().total_cmp(&a.evidence()));
        v
    }
}

impl Diagnosis {
    /// The JSON report.
    pub fn to_json(&self) -> Value {
        let (corr_t, first_half, second_half) = self.time_stats();
        let (within, within_expected) = self.within_stats();
        let allan_ratio = self.allan.adev_mg.last().zip(self.allan.white_mg.last()).map(|(a, w)| a / w);
        let best = self.candidates.iter().find(|c| c.effect == self.verdict);
        json!({
            "file": self.file,
            "samples": self.samples,
            "units": self.units,
            "gravity": self.gravity,
            "seed": self.seed,
            "repeats": self.repeats,
            "poses": self.poses.len(),
            "params": calib::params_json(&self.params),
            "noise": {"white_mg": self.white_mg.map(finite), "longest_rest_s": finite(self.allan.rest_s)},
            "gap": {
                "real_rmse_mg": finite(self.gap.real_rmse_mg),
                "sim_rmse_mg": finite(self.gap.sim_rmse_mg),
                "sim_spread_mg": finite(self.gap.sim_spread_mg),
                "z": finite(self.gap.z),
                "significant": self.gap.significant,
                "ratio_before": finite(self.gap.ratio_before),
                "real_rmse_after_mg": finite(self.gap.real_rmse_after_mg),
                "sim_rmse_after_mg": finite(self.gap.sim_rmse_after_mg),
                "ratio_after": finite(self.gap.ratio_after),
            },
            "where": {
                "per_pose": self.poses.iter().enumerate().map(|(i, p)| json!({
                    "index": i,
                    "t_mid_s": finite(p.t_mid_s),
                    "duration_s": finite(p.duration_s),
                    "temp_c": p.temp_c.map(finite),
                    "orientation": orientation_label(p.direction),
                    "direction": p.direction.map(finite),
                    "residual_mg": finite(p.residual_mg),
                    "expected_mg": finite(p.expected_mg),
                    "residual_after_mg": p.residual_after_mg.map(finite),
                    "early_late_mg": finite(p.early_late_mg),
                    "within_chi2": finite(p.within_chi2),
                })).collect::<Vec<_>>(),
                "by_orientation": self.by_orientation().into_iter().map(|(l, n, r)| json!({"orientation": l, "poses": n, "rms_mg": finite(r)})).collect::<Vec<_>>(),
                "time": {"correlation": corr_t.map(finite), "rms_first_half_mg": finite(first_half), "rms_second_half_mg": finite(second_half)},
                "temperature": self.temperature_stats().map(|(c, lo, hi)| json!({"correlation": c.map(finite), "min_c": finite(lo), "max_c": finite(hi)})),
                "within_pose": {"early_late_rms_mg": finite(within), "white_expected_mg": finite(within_expected), "ratio": finite(within / within_expected)},
                "noise": {
                    "allan_tau_s": self.allan.tau_s,
                    "allan_adev_mg": self.allan.adev_mg.iter().map(|v| finite(*v)).collect::<Vec<_>>(),
                    "allan_white_mg": self.allan.white_mg.iter().map(|v| finite(*v)).collect::<Vec<_>>(),
                    "ratio_at_longest_tau": allan_ratio.map(finite),
                },
            },
            "heldout_ratio_nominal": finite(self.heldout_ratio_nominal),
            "candidates": self.candidates.iter().map(|c| json!({
                "effect": c.effect,
                "applicable": c.applicable,
                "heldout_gain": finite(c.heldout_gain),
                "heldout_ratio": finite(c.heldout_ratio),
                "ratio_after": finite(c.ratio_after),
                "extra_params": c.extra_params,
                "detail": c.detail,
                "within_gain": finite(c.within_gain),
                "within_detail": c.within_detail,
                "variants": c.variants.iter().map(|(d, r)| json!({"detail": d, "heldout_ratio": finite(*r)})).collect::<Vec<_>>(),
            })).collect::<Vec<_>>(),
            "candidates_ranked": self.ranked().iter().map(|c| json!({"effect": c.effect, "heldout_gain": finite(c.heldout_gain), "within_gain": finite(c.within_gain), "evidence": finite(c.evidence())})).collect::<Vec<_>>(),
            "probes": self.probes.iter().map(|p| json!({"shape": p.shape, "heldout_gain": finite(p.heldout_gain), "detail": p.detail})).collect::<Vec<_>>(),
            "verdict": {
                "effect": self.verdict,
                "where": self.unexplained_where,
                "explained": self.explained,
                "heldout_gain": best.map(|c| finite(c.heldout_gain)),
                "shrink": finite(self.shrink),
            },
        })
    }

    /// Step 2 of the text report.
    fn write_where(&self, s: &mut String) {
        use std::fmt::Write as _;
        let _ = writeln!(s, "2. where:");
        let mut worst: Vec<(usize, &PoseReport)> = self.poses.iter().enumerate().collect();
        worst.sort_by(|a, b| b.1.residual_mg.abs().total_cmp(&a.1.residual_mg.abs()));
        let list: Vec<String> = worst
            .iter()
            .take(5)
            .map(|(i, p)| {
                format!("#{i} {} {:+.3} mg (noise {:.3})", orientation_label(p.direction), p.residual_mg, p.expected_mg)
            })
            .collect();
        let _ = writeln!(s, "   largest residuals: {}", list.join(", "));
        let orient: Vec<String> = self
            .by_orientation()
            .into_iter()
            .filter(|(_, n, _)| *n > 0)
            .map(|(l, n, r)| format!("{l} {r:.3} mg ({n})"))
            .collect();
        let _ = writeln!(s, "   by orientation (RMS): {}", orient.join(", "));
        let (corr_t, first_half, second_half) = self.time_stats();
        let _ = writeln!(
            s,
            "   vs time: correlation {}, RMS first half {first_half:.3} mg, second half {second_half:.3} mg",
            corr_t.map_or("n/a".into(), |c| format!("{c:+.2}"))
        );
        match self.temperature_stats() {
            Some((c, lo, hi)) => {
                let _ = writeln!(
                    s,
                    "   vs temperature ({lo:.2}..{hi:.2} C): correlation {}",
                    c.map_or("n/a".into(), |c| format!("{c:+.2}"))
                );
            }
            None => {
                let _ = writeln!(s, "   vs temperature: no temperature column");
            }
        }
        let (within, expected) = self.within_stats();
        let _ =
            writeln!(s, "   within poses (last third - first third): RMS {within:.3} mg, white noise {expected:.3} mg");
        if let (Some(a), Some(w), Some(t)) =
            (self.allan.adev_mg.last(), self.allan.white_mg.last(), self.allan.tau_s.last())
        {
            let _ = writeln!(
                s,
                "   noise: longest rest {:.1} s, Allan deviation at {t:.2} s {a:.4} mg vs white {w:.4} mg ({:.1}x)",
                self.allan.rest_s,
                a / w
            );
        }
    }

    /// The human-readable report, one block per step.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let g = &self.gap;
        let _ = writeln!(
            s,
            "{}: {} rows ({}), {} poses, seed {}",
            self.file,
            self.samples,
            self.units,
            self.poses.len(),
            self.seed
        );
        let _ = writeln!(
            s,
            "1. gap: real modulus RMSE {:.4} mg, simulated {:.4} +- {:.4} mg ({} repeats, white noise {:.3}/{:.3}/{:.3} mg): ratio {:.2}, z {:.1} -> {}",
            g.real_rmse_mg,
            g.sim_rmse_mg,
            g.sim_spread_mg,
            self.repeats,
            self.white_mg[0],
            self.white_mg[1],
            self.white_mg[2],
            g.ratio_before,
            g.z,
            if g.significant { "significant" } else { "not significant" }
        );
        self.write_where(&mut s);
        let _ = writeln!(s, "3. candidates (held-out ratio of the nominal model {:.2}):", self.heldout_ratio_nominal);
        for c in &self.candidates {
            let _ = writeln!(
                s,
                "   {:<19} gain {:>6.2}  held-out ratio {:>7.2}  ratio after {:>7.2}  +{} params  {}",
                c.effect, c.heldout_gain, c.heldout_ratio, c.ratio_after, c.extra_params, c.detail
            );
            if c.within_gain.is_finite() {
                let _ = writeln!(s, "   {:<19} within-pose gain {:>6.2}  {}", "", c.within_gain, c.within_detail);
            }
        }
        let _ = writeln!(
            s,
            "   verdict: {}{}",
            self.verdict,
            self.unexplained_where
                .as_ref()
                .map_or(String::new(), |w| format!(" (significant gap, no family explains it; it lies in: {w})"))
        );
        let _ = writeln!(
            s,
            "4. ratio {:.2} -> {:.2} (real {:.4} mg, simulated {:.4} mg): shrink {:.2}",
            g.ratio_before, g.ratio_after, g.real_rmse_after_mg, g.sim_rmse_after_mg, self.shrink
        );
        s
    }

    /// Writes the SVG plots into `dir` (created if needed): residual per pose before/after, against
    /// time, against temperature (with a temperature column) and the Allan deviation.
    pub fn write_plots(&self, dir: &Path) -> Result<(), String> {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
        let before: Vec<(f64, f64)> = self.poses.iter().enumerate().map(|(i, p)| (i as f64, p.residual_mg)).collect();
        let after: Vec<(f64, f64)> =
            self.poses.iter().enumerate().map(|(i, p)| (i as f64, p.residual_after_mg.unwrap_or(f64::NAN))).collect();
        let after_name = format!("after ({})", self.verdict);
        line_chart(
            &dir.join("residual_per_pose.svg"),
            "Modulus residual per pose",
            "pose",
            "residual (mg)",
            &[Series { name: "nominal", points: before }, Series { name: &after_name, points: after }],
            Scale::Linear,
        )?;
        let mut by_time: Vec<(f64, f64)> = self.poses.iter().map(|p| (p.t_mid_s, p.residual_mg)).collect();
        by_time.sort_by(|a, b| a.0.total_cmp(&b.0));
        line_chart(
            &dir.join("residual_vs_time.svg"),
            "Modulus residual against time",
            "time (s)",
            "residual (mg)",
            &[Series { name: "nominal", points: by_time }],
            Scale::Linear,
        )?;
        let mut by_temp: Vec<(f64, f64)> =
            self.poses.iter().filter_map(|p| p.temp_c.map(|t| (t, p.residual_mg))).collect();
        if by_temp.len() == self.poses.len() && !by_temp.is_empty() {
            by_temp.sort_by(|a, b| a.0.total_cmp(&b.0));
            line_chart(
                &dir.join("residual_vs_temperature.svg"),
                "Modulus residual against temperature",
                "temperature (C)",
                "residual (mg)",
                &[Series { name: "nominal", points: by_temp }],
                Scale::Linear,
            )?;
        }
        let tau = |v: &[f64]| -> Vec<(f64, f64)> { self.allan.tau_s.iter().copied().zip(v.iter().copied()).collect() };
        line_chart(
            &dir.join("allan_deviation.svg"),
            "Allan deviation of the longest rest",
            "tau (s)",
            "mg",
            &[
                Series { name: "measured", points: tau(&self.allan.adev_mg) },
                Series { name: "white noise", points: tau(&self.allan.white_mg) },
            ],
            Scale::LogLog,
        )
    }
}
