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

/// Fewest disturbed holds for a common frequency: one hold's oscillation has a frequency of its own
/// (a tap rings the mount too, once); a mount that rings after every placement rings in several.
const MIN_HOLDS: usize = 2;

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
    if held.len() < MIN_HOLDS || shortest < MIN_HALF || !(rate > 0.0) {
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

#[cfg(test)]
mod tests {
    use rand_core::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    use super::*;
    use crate::diagnose::SEGMENTS;

    const RATE_HZ: f64 = 200.0;
    const HOLD: usize = 600;

    /// Three holds of white noise (1 unit) plus `signal(t)` (t in s from each hold's start).
    fn holds(signal: &dyn Fn(f64) -> f64) -> (Vec<[f64; 3]>, Vec<PoseData>) {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let mut samples = Vec::new();
        let mut poses = Vec::new();
        for _ in 0..3 {
            let start = samples.len();
            for n in 0..HOLD {
                let s = signal(n as f64 / RATE_HZ);
                samples.push(std::array::from_fn(|a| noise.sample(&mut rng) + if a == 0 { s } else { 0.0 }));
            }
            poses.push(PoseData {
                mean: [0.0; 3],
                var: [1.0; 3],
                n: HOLD,
                t_start: 0.0,
                t_end: HOLD as f64 / RATE_HZ,
                temp: None,
                seg: [[0.0; 3]; SEGMENTS],
                seg_n: HOLD / SEGMENTS,
                rows: start..start + HOLD,
            });
        }
        (samples, poses)
    }

    #[test]
    fn a_damped_oscillation_at_one_frequency_rings_and_noise_or_a_steady_one_does_not() {
        let all = [true; 3];
        let damped = |t: f64| 3.0 * (-t / 1.0).exp() * (std::f64::consts::TAU * 7.0 * t).sin();
        let (s, p) = holds(&damped);
        assert!(rings(&s, &p, &all, RATE_HZ));
        let (s, p) = holds(&|_| 0.0);
        assert!(!rings(&s, &p, &all, RATE_HZ), "white noise");
        let steady = |t: f64| 3.0 * (std::f64::consts::TAU * 7.0 * t).sin();
        let (s, p) = holds(&steady);
        assert!(!rings(&s, &p, &all, RATE_HZ), "a steady pickup is not damped");
        assert!(!rings(&s, &p, &[false; 3], RATE_HZ), "no disturbed hold");
        let (s, p) = holds(&damped);
        assert!(!rings(&s, &p, &[true, false, false], RATE_HZ), "one hold: a tap's ringing, no common frequency");
    }
}
