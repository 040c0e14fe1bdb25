//! A mount that rings after each rotation, told from motion: the disturbed holds oscillate at one
//! common frequency (the mount's resonance, the same after every rotation), more in the first half
//! of the hold than in the second (the ringing is damped). Taps and sway have no common frequency;
//! a pickup (mains) does not decay.
//!
//! Each disturbed hold's first `2 m` samples are cut in two halves of `m`; each half's periodogram
//! (mean removed, summed over the axes) is normalised by the median of the first half's, and the
//! normalised first halves are summed over the holds.

use crate::diagnose::gap::PoseData;
use crate::diagnose::math::median;

/// Longest half-window, samples.
const MAX_HALF: usize = 512;

/// Fewest samples per half-window.
const MIN_HALF: usize = 32;

/// Lowest resonance looked for, Hz (slower is sway, not a ringing mount).
const MIN_HZ: f64 = 1.5;

/// Highest resonance looked for, Hz.
const MAX_HZ: f64 = 40.0;

/// Frequency grid step, Hz.
const STEP_HZ: f64 = 0.25;

/// The summed periodogram's peak over its median for a common frequency.
const PEAK_OVER_MEDIAN: f64 = 8.0;

/// The first half's power at the peak over the second half's for a damped ringing.
const DAMPED_RATIO: f64 = 1.2;

/// Power at the frequencies `cycles` (per sample) of `m` samples from `start` (mean removed, axes
/// summed).
fn periodogram(samples: &[[f64; 3]], start: usize, m: usize, cycles: &[f64]) -> Vec<f64> {
    let part = &samples[start..start + m];
    let mean: [f64; 3] = std::array::from_fn(|a| part.iter().map(|s| s[a]).sum::<f64>() / m as f64);
    cycles
        .iter()
        .map(|c| {
            let w = std::f64::consts::TAU * c;
            (0..3)
                .map(|a| {
                    let (mut re, mut im) = (0.0, 0.0);
                    for (n, s) in part.iter().enumerate() {
                        let (sin, cos) = (w * n as f64).sin_cos();
                        (re, im) = (re + (s[a] - mean[a]) * cos, im - (s[a] - mean[a]) * sin);
                    }
                    (re * re + im * im) / m as f64
                })
                .sum()
        })
        .collect()
}

/// The disturbed holds ring at a common frequency and the ringing is damped.
pub(crate) fn rings(samples: &[[f64; 3]], poses: &[PoseData], disturbed: &[bool], rate: f64) -> bool {
    let held: Vec<&PoseData> = poses.iter().zip(disturbed).filter(|(_, d)| **d).map(|(p, _)| p).collect();
    let half = |p: &PoseData| (p.rows.len() / 2).min(MAX_HALF);
    let shortest = held.iter().map(|p| half(p)).min().unwrap_or(0);
    if held.is_empty() || shortest < MIN_HALF || !(rate > 0.0) {
        return false;
    }
    // A grid from MIN_HZ to MAX_HZ (or near the Nyquist frequency), evaluated on every hold's own
    // halves.
    let top_hz = MAX_HZ.min(0.45 * rate);
    let cycles: Vec<f64> =
        (0..).map(|j| MIN_HZ + STEP_HZ * j as f64).take_while(|f| *f <= top_hz).map(|f| f / rate).collect();
    let (mut early, mut late) = (vec![0.0; cycles.len()], vec![0.0; cycles.len()]);
    for p in held {
        let m = half(p);
        let first = periodogram(samples, p.rows.start, m, &cycles);
        let second = periodogram(samples, p.rows.start + m, m, &cycles);
        let level = median(&first);
        if !(level > 0.0) {
            return false;
        }
        for k in 0..cycles.len() {
            early[k] += first[k] / level;
            late[k] += second[k] / level;
        }
    }
    let Some(peak) = (0..cycles.len()).max_by(|&a, &b| early[a].total_cmp(&early[b])) else { return false };
    early[peak] >= PEAK_OVER_MEDIAN * median(&early) && early[peak] >= DAMPED_RATIO * late[peak]
}
