//! The diagnosis's text report and its SVG figure files (`diagnose --plots DIR`); its JSON is
//! [`DiagnosisDocument`](crate::diagnose::DiagnosisDocument), beside the result types.

use std::path::Path;

use crate::diagnose::{Diagnosis, PoseReport, orientation_label};
use crate::report::plots::{Scale, Series, line_chart};

impl Diagnosis {
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

    /// The report's first line: the log, its poses and what the pose finder left out or changed.
    fn header(&self) -> String {
        let short = match self.short_poses {
            0 => String::new(),
            n => format!(" ({n} still intervals shorter than {} s left out)", crate::diagnose::MIN_POSE_S),
        };
        let tails = match self.tails_trimmed {
            0 => String::new(),
            n => format!(" ({n} poses trimmed: a move's tail at their start or end)"),
        };
        let fragments = match self.moving_fragments {
            0 => String::new(),
            n => format!(" ({n} short poses moving within themselves left out: fragments of moves)"),
        };
        let widened = self.mean_change_widened.map_or(String::new(), |c| {
            format!(" (readings correlated: the still test's limit on a block's mean change widened {c:.1}x)")
        });
        let disturbed = self.disturbed_left_out.as_ref().map_or(String::new(), |d| format!(" ({d})"));
        format!(
            "{}: {} rows ({}), {} poses{short}{tails}{fragments}{widened}{disturbed}, seed {}",
            self.file,
            self.samples,
            self.units,
            self.poses.len(),
            self.seed
        )
    }

    /// The human-readable report, one block per step.
    pub fn to_text(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let g = &self.gap;
        let _ = writeln!(s, "{}", self.header());
        if let Some(why) = &self.not_calibrated {
            let _ = writeln!(s, "1. gap: not measured ({why})");
            for c in &self.candidates {
                let _ = writeln!(s, "3. {}: {}", c.effect, c.detail);
            }
            let _ = writeln!(s, "   verdict: {}", self.verdict);
            return s;
        }
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
            g.significance()
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
                let agreement = if c.within_disagreement.is_finite() {
                    format!(", pose means {:.1} chi2/coef away", c.within_disagreement)
                } else {
                    String::new()
                };
                let _ = writeln!(
                    s,
                    "   {:<19} within-pose gain {:>6.2}  {}{agreement}",
                    "", c.within_gain, c.within_detail
                );
            }
        }
        let _ = writeln!(s, "   verdict: {}{}", self.verdict, self.located_text());
        let _ = writeln!(
            s,
            "4. ratio {:.2} -> {:.2} (real {:.4} mg, simulated {:.4} mg): shrink {:.2}",
            g.ratio_before, g.ratio_after, g.real_rmse_after_mg, g.sim_rmse_after_mg, self.shrink
        );
        s
    }

    /// What the verdict line adds: where an unexplained gap lies, or what supports a verdict the
    /// withheld poses do not test.
    fn located_text(&self) -> String {
        self.located.as_ref().map_or(String::new(), |w| match self.verdict {
            "unexplained" => format!(" (significant gap, no family explains it; it lies in: {w})"),
            _ => format!(" ({w})"),
        })
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
        let by_time: Vec<(f64, f64)> = self.poses.iter().map(|p| (p.t_mid_s, p.residual_mg)).collect();
        residual_against(&dir.join("residual_vs_time.svg"), "time", "time (s)", by_time)?;
        let by_temp: Vec<(f64, f64)> = self.poses.iter().filter_map(|p| p.temp_c.map(|t| (t, p.residual_mg))).collect();
        if by_temp.len() == self.poses.len() && !by_temp.is_empty() {
            residual_against(&dir.join("residual_vs_temperature.svg"), "temperature", "temperature (C)", by_temp)?;
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

/// The nominal modulus residual (mg) against `what` (the x axis, sorted), one line chart.
fn residual_against(path: &Path, what: &str, x_label: &str, mut points: Vec<(f64, f64)>) -> Result<(), String> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    let title = format!("Modulus residual against {what}");
    line_chart(path, &title, x_label, "residual (mg)", &[Series { name: "nominal", points }], Scale::Linear)
}
