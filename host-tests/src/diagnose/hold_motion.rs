//! A second answer (after `holds.rs`) for logs the pose detector cannot calibrate although they have a hold structure: the sensor was put
//! in several orientations and held, but the holds were not still (sway, tremor, taps). They get the
//! verdict `motion` with what a user needs to redo them: how many holds, how many the still
//! detector rejected, the band and the size of the motion in mg. A log with no hold structure is
//! still an error.
//!
//! Holds are found by a plain orientation detector that does not ask for stillness: runs of
//! 0.25 s windows whose mean stays within [`HOLD_TOLERANCE_G`] of the run's first window, at least
//! [`MIN_HOLD_S`] long. A hold is disturbed when the pose detector kept less than half of it.

use crate::csvio::{self, AccumulateOptions, Table};

use super::math::median;
use super::report::{Allan, Candidate, Diagnosis, Gap};
use super::{DiagnoseOptions, EFFECT_NAMES};

/// Window the hold detector averages, seconds.
const WINDOW_S: f64 = 0.25;

/// Largest change of a window mean from a hold's first window, in g (about 6 deg of tilt): sway
/// stays within, a rotation to the next orientation does not.
const HOLD_TOLERANCE_G: f64 = 0.1;

/// Shortest hold, seconds.
const MIN_HOLD_S: f64 = 2.0;

/// Fewest holds for a hold structure (the six faces).
const MIN_HOLDS: usize = 6;

/// Lowest and highest frequency of the motion spectrum, Hz, and its step.
const BAND_HZ: (f64, f64, f64) = (0.25, 25.0, 0.25);

/// Motion RMS over the noise RMS below which the holds are not clearly moving (a filtered sensor's
/// correlated noise can also split holds): the log is then refused as before.
const MIN_MOTION_OVER_NOISE: f64 = 2.0;

/// Smallest motion named, mg RMS: a digital low-pass (5 Hz bandwidth) makes the successive
/// differences understate the noise, whose correlated part then reads as sub-mg motion.
const MIN_MOTION_MG: f64 = 2.0;

/// A window whose RMS exceeds this many times the hold's median window RMS is a tap.
const TAP_FACTOR: f64 = 4.0;

/// One hold: its rows `[first, end)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Hold {
    pub(crate) first: usize,
    pub(crate) end: usize,
}

/// The holds of a log: runs of windows of `window` rows whose means stay near the first one.
pub(crate) fn find_holds(samples: &[[f64; 3]], window: usize, tolerance: f64, min_windows: usize) -> Vec<Hold> {
    let means: Vec<[f64; 3]> = samples.chunks_exact(window).map(window_mean).collect();
    let mut holds = Vec::new();
    let mut start = 0;
    while start < means.len() {
        let anchor = means[start];
        let len = means[start..].iter().take_while(|m| distance(**m, anchor) < tolerance).count();
        if len >= min_windows {
            holds.push(Hold { first: start * window, end: (start + len) * window });
        }
        start += len.max(1);
    }
    holds
}

fn window_mean(w: &[[f64; 3]]) -> [f64; 3] {
    let n = w.len() as f64;
    std::array::from_fn(|a| w.iter().map(|s| s[a]).sum::<f64>() / n)
}

fn distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt()
}

/// Windows left out at each end of a hold (the end of the rotation into it, the start of the next).
const EDGE_WINDOWS: usize = 2;

/// The residual of a hold about its mean, per sample and axis, its [`EDGE_WINDOWS`] left out.
fn residual(samples: &[[f64; 3]], h: Hold, window: usize) -> Vec<[f64; 3]> {
    let rows = &samples[h.first + EDGE_WINDOWS * window..h.end - EDGE_WINDOWS * window];
    let m = window_mean(rows);
    rows.iter().map(|s| std::array::from_fn(|a| s[a] - m[a])).collect()
}

fn mean_square(r: &[[f64; 3]]) -> f64 {
    r.iter().map(|v| v.iter().map(|x| x * x).sum::<f64>()).sum::<f64>() / r.len().max(1) as f64
}

/// White variance (3 axes summed) from successive differences, which a slow motion barely moves.
fn white_variance(r: &[[f64; 3]]) -> f64 {
    let d: Vec<[f64; 3]> = r.windows(2).map(|w| std::array::from_fn(|a| w[1][a] - w[0][a])).collect();
    mean_square(&d) / 2.0
}

/// Power of the residual (axes summed) at frequency `f_hz`.
fn power_at(r: &[[f64; 3]], rate: f64, f_hz: f64) -> f64 {
    let w = std::f64::consts::TAU * f_hz / rate;
    (0..3)
        .map(|a| {
            let (c, s) = r.iter().enumerate().fold((0.0, 0.0), |(c, s), (i, v)| {
                let p = w * i as f64;
                (c + v[a] * p.cos(), s + v[a] * p.sin())
            });
            (c * c + s * s) / r.len().max(1) as f64
        })
        .sum()
}

/// The frequency of the largest motion power, pooled over the holds.
fn peak_frequency(parts: &[Vec<[f64; 3]>], rate: f64) -> f64 {
    let (lo, hi, step) = BAND_HZ;
    let top = hi.min(0.45 * rate);
    let count = ((top - lo) / step).floor().max(0.0) as usize + 1;
    (0..count)
        .map(|k| lo + step * k as f64)
        .map(|f| (f, parts.iter().map(|r| power_at(r, rate, f)).sum::<f64>()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(f64::NAN, |(f, _)| f)
}

/// Holds whose motion comes in short bursts (taps, nudges): one window far above the hold's median.
fn tapped(r: &[[f64; 3]], window: usize) -> bool {
    let rms: Vec<f64> = r.chunks_exact(window).map(|w| mean_square(w).sqrt()).collect();
    let typical = median(&rms);
    rms.len() >= 4 && rms.iter().any(|v| *v > TAP_FACTOR * typical)
}

/// How the motion was measured.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct HoldMotion {
    pub(crate) holds: usize,
    pub(crate) disturbed: usize,
    pub(crate) kept_poses: usize,
    pub(crate) peak_hz: f64,
    pub(crate) motion_mg: f64,
    pub(crate) white_mg: f64,
    pub(crate) tapped: usize,
}

impl HoldMotion {
    /// What a user reads.
    pub(crate) fn detail(&self) -> String {
        let kind = if self.tapped * 2 > self.disturbed {
            "short bursts (taps, nudges)"
        } else if self.peak_hz < 2.0 {
            "a slow sway"
        } else {
            "tremor or vibration"
        };
        format!(
            "the holds were not still: {} of {} holds had motion ({kind}, strongest near {:.1} Hz) of ~{:.1} mg RMS \
             over {:.1} mg of noise; the still detector kept {} poses, too few to calibrate: hold the sensor on a rigid support",
            self.disturbed, self.holds, self.peak_hz, self.motion_mg, self.white_mg, self.kept_poses
        )
    }
}

/// The motion in a log's holds, or `None` when it has no hold structure or no disturbed hold.
pub(crate) fn measure(table: &Table) -> Option<HoldMotion> {
    let rate = table.sample_rate_hz().filter(|r| r.is_finite() && *r > 0.0)?;
    let window = ((WINDOW_S * rate).round() as usize).max(4);
    let g = table.samples.iter().map(|s| distance(*s, [0.0; 3])).collect::<Vec<_>>();
    let g = median(&g);
    if !(g.is_finite() && g > 0.0) {
        return None;
    }
    let min_windows = (MIN_HOLD_S / WINDOW_S).ceil() as usize;
    let holds = find_holds(&table.samples, window, HOLD_TOLERANCE_G * g, min_windows);
    if holds.len() < MIN_HOLDS {
        return None;
    }
    let spans = csvio::accumulate(table, &AccumulateOptions::default()).map(|a| a.spans).unwrap_or_default();
    let kept = |h: &Hold| {
        let covered: usize =
            spans.iter().map(|s| (s.last_row + 1).min(h.end).saturating_sub(s.first_row.max(h.first))).sum();
        2 * covered >= h.end - h.first
    };
    let disturbed: Vec<Hold> = holds.iter().filter(|h| !kept(h)).copied().collect();
    summarise(table, &holds, &disturbed, spans.len(), window, rate, g)
}

/// The evidence from the disturbed holds (`None` when none is).
fn summarise(
    t: &Table,
    holds: &[Hold],
    disturbed: &[Hold],
    kept: usize,
    window: usize,
    rate: f64,
    g: f64,
) -> Option<HoldMotion> {
    if disturbed.is_empty() {
        return None;
    }
    let parts: Vec<Vec<[f64; 3]>> = disturbed.iter().map(|h| residual(&t.samples, *h, window)).collect();
    let white = median(&holds.iter().map(|h| white_variance(&residual(&t.samples, *h, window))).collect::<Vec<_>>());
    let total = median(&parts.iter().map(|r| mean_square(r)).collect::<Vec<_>>());
    let mg = |v: f64| v.max(0.0).sqrt() / g * 1000.0;
    if mg(total - white) < (MIN_MOTION_OVER_NOISE * mg(white)).max(MIN_MOTION_MG) {
        return None;
    }
    Some(HoldMotion {
        holds: holds.len(),
        disturbed: disturbed.len(),
        kept_poses: kept,
        peak_hz: peak_frequency(&parts, rate),
        motion_mg: mg(total - white),
        white_mg: mg(white),
        tapped: parts.iter().filter(|r| tapped(r, window)).count(),
    })
}

/// The `motion` verdict for a log whose holds were too disturbed to calibrate.
pub(crate) fn motion_diagnosis(table: &Table, opts: &DiagnoseOptions, motion: &HoldMotion) -> Diagnosis {
    let nan = f64::NAN;
    let gap = Gap::UNMEASURED;
    let candidates = EFFECT_NAMES.iter().map(|e| candidate(e, motion)).collect();
    Diagnosis {
        file: table.file.clone(),
        samples: table.samples.len(),
        units: table.units.to_string(),
        gravity: opts.gravity,
        seed: opts.seed,
        repeats: 0,
        params: accelcal::model::Params::IDENTITY,
        white_mg: [motion.white_mg / 3f64.sqrt(); 3],
        gap,
        poses: Vec::new(),
        allan: Allan { rest_s: nan, tau_s: Vec::new(), adev_mg: Vec::new(), white_mg: Vec::new() },
        candidates,
        probes: Vec::new(),
        heldout_ratio_nominal: nan,
        verdict: "motion",
        unexplained_where: None,
        explained: true,
        shrink: 0.0,
        not_calibrated: Some(format!("{} still poses: too few to calibrate", motion.kept_poses)),
    }
}

fn candidate(effect: &'static str, motion: &HoldMotion) -> Candidate {
    let is_motion = effect == "motion";
    Candidate {
        effect,
        applicable: is_motion,
        heldout_ratio: f64::NAN,
        heldout_gain: f64::NAN,
        ratio_after: f64::NAN,
        extra_params: 0,
        detail: if is_motion { motion.detail() } else { String::new() },
        within_gain: f64::NAN,
        within_detail: String::new(),
        variants: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Six faces held 3 s each at 100 Hz with 1 mg noise, joined by 0.5 s rotations; `shake(i, t)`
    /// adds motion to hold `i`.
    fn faces(shake: impl Fn(usize, f64) -> f64) -> Table {
        let faces =
            [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
        let mut text = String::from("t,ax,ay,az\n");
        let (mut row, mut seed) = (0usize, 7u64);
        let mut noise = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.0035
        };
        for (i, f) in faces.iter().enumerate() {
            let next = faces[(i + 1) % 6];
            for k in 0..350 {
                let t = k as f64 / 100.0;
                let s = if k < 300 { 0.0 } else { (k - 300) as f64 / 50.0 };
                let v: [f64; 3] = std::array::from_fn(|a| f[a] * (1.0 - s) + next[a] * s);
                let x = v[0] + noise() + if k < 300 { shake(i, t) } else { 0.0 };
                text += &format!("{},{x},{},{}\n", row as f64 / 100.0, v[1] + noise(), v[2] + noise());
                row += 1;
            }
        }
        crate::csvio::read_csv_str("faces", &text, &crate::csvio::ReadOptions::default()).unwrap()
    }

    pub(super) fn shaken() -> Table {
        faces(|i, s| if i == 0 { 0.0 } else { 0.03 * (std::f64::consts::TAU * 0.75 * s).sin() })
    }

    #[test]
    fn the_plain_detector_finds_six_holds() {
        let t = faces(|_, _| 0.0);
        let holds = find_holds(&t.samples, 25, 0.1, 6);
        assert_eq!(holds.len(), 6, "{holds:?}");
    }

    #[test]
    fn a_slow_sway_in_five_holds_is_motion_near_its_frequency() {
        let t = shaken();
        let m = measure(&t).expect("five swaying holds");
        assert_eq!((m.holds, m.disturbed, m.kept_poses), (6, 5, 1), "{m:?}");
        assert!((m.peak_hz - 0.75).abs() <= 0.25, "{m:?}");
        // A 30 mg sine is 21 mg RMS.
        assert!(m.motion_mg > 15.0 && m.motion_mg < 25.0, "{m:?}");
        let d = motion_diagnosis(&t, &DiagnoseOptions::DEFAULT, &m);
        assert_eq!(d.verdict, "motion");
        let detail = &d.candidates.iter().find(|c| c.effect == "motion").unwrap().detail;
        assert!(detail.contains("5 of 6 holds") && detail.contains("slow sway"), "{detail}");
        let full = crate::diagnose::diagnose(&t, &DiagnoseOptions::DEFAULT).unwrap();
        assert_eq!(full.verdict, "motion");
    }

    #[test]
    fn no_hold_structure_stays_an_error() {
        let text: String = std::iter::once("t,ax,ay,az\n".to_string())
            .chain((0..2000).map(|i| format!("{},0.0,{},1.0\n", i as f64 * 0.01, (i as f64 * 0.05).sin())))
            .collect();
        let t = crate::csvio::read_csv_str("turning", &text, &crate::csvio::ReadOptions::default()).unwrap();
        assert!(measure(&t).is_none());
        assert!(crate::diagnose::diagnose(&t, &DiagnoseOptions::DEFAULT).is_err());
    }

    #[test]
    fn still_holds_are_not_motion() {
        assert!(measure(&faces(|_, _| 0.0)).is_none());
    }
}
