//! Step 2, where the gap lies: residual per pose and per orientation, against time and
//! temperature, within each pose, in the noise (Allan deviation of the longest rest); and, for a
//! gap no family explains, a one-line description of where it is.

use super::SEGMENTS;
use super::gap::{Measured, PoseData};
use super::math::{V3, correlation, mean_of, norm, rms};
use super::report::{Allan, Diagnosis, PoseReport};
use crate::csvio::Table;

pub(crate) fn allan(table: &Table, first: usize, end: usize, rate: f64, scale: V3, white: V3, gravity: f64) -> Allan {
    let rows = &table.samples[first..end];
    let n = rows.len();
    let to_mg = |v: f64| v / gravity * 1000.0;
    let mut out = Allan { rest_s: n as f64 / rate, tau_s: Vec::new(), adev_mg: Vec::new(), white_mg: Vec::new() };
    let mut m = 1usize;
    while n / m >= 8 {
        let clusters = n / m;
        let mut avar = 0.0f64;
        let mut white_var = 0.0f64;
        for a in 0..3 {
            let means: Vec<f64> =
                (0..clusters).map(|k| rows[k * m..(k + 1) * m].iter().map(|s| s[a]).sum::<f64>() / m as f64).collect();
            let d: f64 = means.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (2 * (clusters - 1)) as f64;
            avar += d * scale[a] * scale[a] / 3.0;
            white_var += white[a] * scale[a] * scale[a] / m as f64 / 3.0;
        }
        out.tau_s.push(m as f64 / rate);
        out.adev_mg.push(to_mg(avar.sqrt()));
        out.white_mg.push(to_mg(white_var.sqrt()));
        m *= 2;
    }
    out
}

/// Chi-square of segment means 1.. (the first is left out: settling) about their mean, white noise.
pub(crate) fn within_chi2(p: &PoseData, white: &V3) -> f64 {
    within_chi2_from(p, white, 1)
}

/// [`within_chi2`] of the segments from `first` on.
pub(crate) fn within_chi2_from(p: &PoseData, white: &V3, first: usize) -> f64 {
    within_chi2_of(p, white, first..p.seg.len())
}

/// [`within_chi2`] of the segments `range` about their own mean.
pub(crate) fn within_chi2_of(p: &PoseData, white: &V3, range: std::ops::Range<usize>) -> f64 {
    if p.seg_n == 0 || range.len() < 2 || range.end > p.seg.len() {
        return 0.0;
    }
    let m = mean_of(&p.seg[range.clone()]);
    let mut chi2 = 0.0;
    for seg in &p.seg[range] {
        for a in 0..3 {
            if white[a] > 0.0 {
                chi2 += (seg[a] - m[a]).powi(2) / (white[a] / p.seg_n as f64);
            }
        }
    }
    chi2
}

pub(crate) fn orientation_label(u: V3) -> String {
    let a = (0..3).max_by(|&i, &j| u[i].abs().total_cmp(&u[j].abs())).unwrap_or(2);
    format!("{}{}", if u[a] >= 0.0 { "+" } else { "-" }, ["x", "y", "z"][a])
}

/// The change within a pose's hold (last third against first) that white noise gives, mg: two
/// thirds of n/3 samples each, `sqrt(2 * 3)` times the pose mean's noise.
fn white_change_mg(p: &PoseReport) -> f64 {
    p.expected_mg * 6f64.sqrt()
}

impl Diagnosis {
    pub(crate) fn by_orientation(&self) -> Vec<(String, usize, f64)> {
        let mut out = Vec::new();
        for label in ["+x", "-x", "+y", "-y", "+z", "-z"] {
            let v: Vec<f64> =
                self.poses.iter().filter(|p| orientation_label(p.direction) == label).map(|p| p.residual_mg).collect();
            out.push((label.to_string(), v.len(), rms(&v)));
        }
        out
    }

    pub(crate) fn time_stats(&self) -> (Option<f64>, f64, f64) {
        let t: Vec<f64> = self.poses.iter().map(|p| p.t_mid_s).collect();
        let r: Vec<f64> = self.poses.iter().map(|p| p.residual_mg).collect();
        let half = r.len() / 2;
        (correlation(&t, &r), rms(&r[..half]), rms(&r[half..]))
    }

    pub(crate) fn temperature_stats(&self) -> Option<(Option<f64>, f64, f64)> {
        let temps: Vec<f64> = self.poses.iter().filter_map(|p| p.temp_c).collect();
        if temps.len() != self.poses.len() || temps.is_empty() {
            return None;
        }
        let r: Vec<f64> = self.poses.iter().map(|p| p.residual_mg).collect();
        let lo = temps.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = temps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Some((correlation(&temps, &r), lo, hi))
    }

    pub(crate) fn within_stats(&self) -> (f64, f64) {
        let el: Vec<f64> = self.poses.iter().map(|p| p.early_late_mg).collect();
        let expected: Vec<f64> = self.poses.iter().map(white_change_mg).collect();
        (rms(&el), rms(&expected))
    }

    /// The pose whose change within its hold (last third against first, in units of its white
    /// noise) carries more than half of the poses' squared change, and that share: one hold moving
    /// (a bad pose), not the log's holds.
    fn within_carried_by_one(&self) -> Option<(usize, f64)> {
        let scaled = |p: &PoseReport| (p.early_late_mg / white_change_mg(p)).powi(2);
        let squares: Vec<f64> = self.poses.iter().map(scaled).filter(|v| v.is_finite()).collect();
        let total: f64 = squares.iter().sum();
        let (k, top) = squares.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1))?;
        (squares.len() == self.poses.len() && *top > 0.5 * total).then_some((k, top / total))
    }

    /// Step 2 in one line: the share of the squared residual in the three worst poses (and their
    /// orientations), the correlation with time and temperature, the within-pose change over white
    /// noise and the Allan deviation at the longest `tau` over white noise.
    pub fn where_summary(&self) -> String {
        let mut worst: Vec<&PoseReport> = self.poses.iter().collect();
        worst.sort_by(|a, b| b.residual_mg.abs().total_cmp(&a.residual_mg.abs()));
        let total: f64 = self.poses.iter().map(|p| p.residual_mg.powi(2)).sum();
        let top: f64 = worst.iter().take(3).map(|p| p.residual_mg.powi(2)).sum();
        let labels: Vec<String> = worst.iter().take(3).map(|p| orientation_label(p.direction)).collect();
        let (corr_t, _, _) = self.time_stats();
        let mut out = format!("worst 3 poses {:.0} % ({})", 100.0 * top / total.max(1e-300), labels.join(" "));
        if let Some(c) = corr_t {
            out += &format!("; time r {c:+.2}");
        }
        if let Some((Some(c), _, _)) = self.temperature_stats() {
            out += &format!("; temp r {c:+.2}");
        }
        let (within, expected) = self.within_stats();
        out += &format!("; within-pose {:.1}x white", within / expected);
        if let (Some(a), Some(w), Some(t)) =
            (self.allan.adev_mg.last(), self.allan.white_mg.last(), self.allan.tau_s.last())
        {
            out += &format!("; Allan {:.1}x white at {t:.0} s", a / w);
        }
        out
    }
}

/// Pose `i`'s modulus change from the first to the last third of its hold, and the white noise
/// of its mean's modulus (output unit): a transient that moves the pose mean moves its first third
/// against its last more: 1.7 (time constant a third of the hold) to 3 times the mean's shift.
pub(crate) fn early_late(m: &Measured, i: usize) -> (f64, f64) {
    let p = &m.poses[i];
    let kt = m.model.kt_times(m.directions[i]);
    let expected = (0..3).map(|a| kt[a] * kt[a] * m.white[a] / p.n as f64).sum::<f64>().sqrt();
    let early = mean_of(&p.seg[0..2]);
    let late = mean_of(&p.seg[SEGMENTS - 2..]);
    (norm(m.model.apply(late)) - norm(m.model.apply(early)), expected)
}

/// Step 2 per pose; `after` holds the residuals with the winning effect (output unit).
pub(crate) fn pose_reports(m: &Measured, after: &[Option<f64>]) -> Vec<PoseReport> {
    (0..m.poses.len())
        .map(|i| {
            let p = &m.poses[i];
            let (early_late, expected) = early_late(m, i);
            PoseReport {
                t_mid_s: p.t_mid(),
                duration_s: p.duration(),
                temp_c: p.temp,
                direction: m.directions[i],
                residual_mg: m.to_mg(m.r[i]),
                expected_mg: m.to_mg(expected),
                residual_after_mg: after[i].map(|v| m.to_mg(v)),
                early_late_mg: m.to_mg(early_late),
                within_chi2: within_chi2(p, &m.white),
            }
        })
        .collect()
}

/// The Allan deviation of the longest rest.
pub(crate) fn longest_rest_allan(table: &Table, m: &Measured) -> Allan {
    let longest = (0..m.poses.len()).max_by_key(|&i| m.poses[i].n).unwrap_or(0);
    let rows = m.poses[longest].rows.clone();
    allan(table, rows.start, rows.end, m.rate, m.scale(), m.white, m.gravity)
}

/// Where a gap no family explains lies, most specific first: one pose; one orientation; a
/// dependence on the direction of the rotation into the pose; time; within the poses; the noise;
/// else spread over the poses.
pub(crate) fn unexplained_location(d: &Diagnosis) -> String {
    let sq: Vec<f64> = d.poses.iter().map(|p| p.residual_mg.powi(2)).collect();
    let total: f64 = sq.iter().sum::<f64>().max(1e-300);
    let (worst, top) = sq.iter().enumerate().fold((0, 0.0), |b, (i, v)| if *v > b.1 { (i, *v) } else { b });
    if top / total > 0.5 {
        return format!("one pose: #{worst} holds {:.0} % of the squared residual", 100.0 * top / total);
    }
    let by_orient = d.by_orientation();
    let all_rms = rms(&d.poses.iter().map(|p| p.residual_mg).collect::<Vec<_>>());
    if let Some((l, _, r)) = by_orient.iter().filter(|(_, n, _)| *n >= 2).max_by(|a, b| a.2.total_cmp(&b.2))
        && *r > 2.0 * all_rms
    {
        return format!("one orientation: {l} ({r:.3} mg RMS against {all_rms:.3} mg overall)");
    }
    if let Some(c) = rotation_direction_correlation(d)
        && c.abs() > 0.6
    {
        return format!(
            "direction of rotation: residual correlates with the change from the previous pose (r {c:+.2})"
        );
    }
    if let (Some(c), _, _) = d.time_stats()
        && c.abs() > 0.6
    {
        return format!("time: residual correlates with time (r {c:+.2})");
    }
    let (within, expected) = d.within_stats();
    if within > 2.0 * expected {
        let one = d.within_carried_by_one().map(|(k, share)| format!(", {:.0} % of it in pose #{k}", 100.0 * share));
        return format!("within poses: {:.1}x white noise{}", within / expected, one.unwrap_or_default());
    }
    if let (Some(a), Some(w)) = (d.allan.adev_mg.last(), d.allan.white_mg.last())
        && a > &(2.0 * w)
    {
        return format!("noise: Allan deviation {:.1}x white at the longest tau", a / w);
    }
    format!("spread over the poses (worst pose {:.0} % of the squared residual)", 100.0 * top / total)
}

/// Correlation of a pose's residual with the projection of the previous pose's direction on its own
/// (how far the rotation into the pose came from).
fn rotation_direction_correlation(d: &Diagnosis) -> Option<f64> {
    let (x, y): (Vec<f64>, Vec<f64>) = d
        .poses
        .windows(2)
        .map(|w| {
            let (a, b) = (w[0].direction, w[1].direction);
            (a[0] * b[0] + a[1] * b[1] + a[2] * b[2], w[1].residual_mg)
        })
        .unzip();
    correlation(&x, &y)
}
