//! A periodic bias in the holds: a sinusoid of one frequency, in phase across every hold of the
//! log (an aliased vibration, a pickup), moves the holds as a noise of that period would, but a
//! noise's phase wanders from hold to hold. Scanned as a periodogram of the holds' block means,
//! each hold's own mean left out.

use std::ops::Range;

use crate::csvio::Table;
use crate::diagnose::gap::row_time;
use crate::diagnose::math::{V3, mean_of, median};

/// Length of a block mean, s.
const BLOCK_S: f64 = 0.1;

/// Fewest cycles over the holds' span of a frequency scanned.
const LOWEST_CYCLES: f64 = 4.0;

/// Highest frequency scanned, Hz (a faster line averages out of a pose mean).
const HIGHEST_HZ: f64 = 1.0;

/// Frequencies scanned per independent one (`1 / span`).
const OVERSAMPLING: f64 = 4.0;

/// Most block means: longer logs average longer blocks (and scan up to a quarter of the block
/// rate), so that the scan's work stays bounded.
const MAX_BLOCKS: usize = 10_000;

/// Most frequencies scanned: beyond it the grid is coarser than [`OVERSAMPLING`] (a log of hours).
const MAX_FREQUENCIES: f64 = 1000.0;

/// Frequencies of the scan between two of its sines and cosines computed afresh ([`Blocks::scan`]).
const EXACT_EVERY: usize = 32;

/// The holds' block means about each hold's mean, per axis in white-noise standard deviations of a
/// block mean, with their times (s) and holds.
struct Blocks {
    t: Vec<f64>,
    y: Vec<V3>,
    hold: Vec<usize>,
    holds: usize,
    /// A block's duration, s.
    block_s: f64,
}

impl Blocks {
    fn new(table: &Table, holds: &[Range<usize>], rate: f64, white: V3) -> Self {
        let total_rows: usize = holds.iter().map(Range::len).sum();
        let n = ((rate * BLOCK_S).round() as usize).max(total_rows.div_ceil(MAX_BLOCKS)).max(1);
        let sd: V3 = std::array::from_fn(|a| (white[a] / n as f64).sqrt());
        let mut out = Self { t: Vec::new(), y: Vec::new(), hold: Vec::new(), holds: 0, block_s: n as f64 / rate };
        for rows in holds {
            let first = out.y.len();
            let blocks = table.samples[rows.clone()].chunks_exact(n);
            if blocks.len() < 4 {
                continue;
            }
            for (k, block) in blocks.enumerate() {
                out.t.push(row_time(table, rows.start + k * n + n / 2, rate));
                out.y.push(mean_of(block));
                out.hold.push(out.holds);
            }
            let centre = mean_of(&out.y[first..]);
            for v in &mut out.y[first..] {
                *v = std::array::from_fn(|a| if sd[a] > 0.0 { (v[a] - centre[a]) / sd[a] } else { 0.0 });
            }
            out.holds += 1;
        }
        out
    }

    /// `(f, line chi-square at f)` for `f = lowest + k step` up to `highest`. From one frequency to
    /// the next each block's sine and cosine turn by the step's angle (two products, not a
    /// `sin_cos`), computed afresh every [`EXACT_EVERY`] steps so that rounding cannot build up.
    fn scan(&self, lowest: f64, step: f64, highest: f64) -> Vec<(f64, f64)> {
        let angles =
            |f: f64| -> Vec<(f64, f64)> { self.t.iter().map(|t| (std::f64::consts::TAU * f * t).sin_cos()).collect() };
        let turn = angles(step);
        let (mut at, mut out) = (Vec::new(), Vec::new());
        for k in 0.. {
            let f = lowest + k as f64 * step;
            if f > highest {
                break;
            }
            at = if k % EXACT_EVERY == 0 {
                angles(f)
            } else {
                at.iter().zip(&turn).map(|(&(s, c), &(ds, dc))| (s * dc + c * ds, c * dc - s * ds)).collect()
            };
            out.push((f, self.line_chi2(&at)));
        }
        out
    }

    /// Chi-square a sinusoid (sine and cosine per axis, each centred within its hold; `phases`: their
    /// values at each block) takes out of the blocks, summed over the axes. One pass: the blocks are
    /// centred within their hold, so a centred column's products with them are the raw column's, and its squares are the
    /// raw squares less each hold's `n mean^2`.
    fn line_chi2(&self, phases: &[(f64, f64)]) -> f64 {
        // Per hold: count, sum of sine, sum of cosine.
        let mut per_hold = vec![[0.0; 3]; self.holds];
        let (mut ss, mut sc, mut cc) = (0.0, 0.0, 0.0);
        let (mut sy, mut cy) = ([0.0; 3], [0.0; 3]);
        for ((&(s, c), &h), y) in phases.iter().zip(&self.hold).zip(&self.y) {
            per_hold[h] = [per_hold[h][0] + 1.0, per_hold[h][1] + s, per_hold[h][2] + c];
            (ss, sc, cc) = (ss + s * s, sc + s * c, cc + c * c);
            for a in 0..3 {
                (sy[a], cy[a]) = (sy[a] + s * y[a], cy[a] + c * y[a]);
            }
        }
        for [n, s, c] in per_hold {
            (ss, sc, cc) = (ss - s * s / n, sc - s * c / n, cc - c * c / n);
        }
        let det = ss * cc - sc * sc;
        if !(det > 0.0) {
            return 0.0;
        }
        (0..3).map(|a| (cc * sy[a] * sy[a] - 2.0 * sc * sy[a] * cy[a] + ss * cy[a] * cy[a]) / det).sum()
    }
}

/// A line in the holds' periodogram: its frequency and its height over the median of the
/// periodogram beside it.
#[derive(Clone, Copy)]
pub(crate) struct Line {
    pub(crate) f_hz: f64,
    pub(crate) over_neighbours: f64,
}

/// Height over its neighbours ([`Line::over_neighbours`]) from which the strongest line is a periodic
/// bias. A smooth noise spectrum leaves each periodogram ordinate a chi-square of 2 to 6 degrees of
/// freedom (one to three axes) about its level: one axis alone exceeds 20 times its median (1.39)
/// with probability `exp(-13.9) = 1e-6` at one frequency, 1e-3 over a scan of 1000. Colored noises of
/// the development sets reached 7.9; aliased motor vibrations 9-115.
const LINE_OVER_NEIGHBOURS: f64 = 20.0;

/// The strongest line of the holds' periodogram, from [`LOWEST_CYCLES`] over their span to
/// [`HIGHEST_HZ`] (at most [`MAX_FREQUENCIES`] of them), if it stands [`LINE_OVER_NEIGHBOURS`] times
/// over the median of the frequencies within a factor of two of it (more than two independent
/// frequencies away): a sinusoid in phase over the whole log.
pub(crate) fn periodic_bias(table: &Table, holds: &[Range<usize>], rate: f64, white: V3) -> Option<Line> {
    let blocks = Blocks::new(table, holds, rate, white);
    let span = blocks.t.last()? - blocks.t.first()?;
    if blocks.holds < 3 || !(span > 0.0) {
        return None;
    }
    let (lowest, highest) = (LOWEST_CYCLES / span, HIGHEST_HZ.min(0.25 / blocks.block_s));
    let step = (1.0 / (OVERSAMPLING * span)).max((highest - lowest) / MAX_FREQUENCIES);
    let scan = blocks.scan(lowest, step, highest);
    let &(f_hz, peak) = scan.iter().max_by(|a, b| a.1.total_cmp(&b.1))?;
    let beside: Vec<f64> = scan
        .iter()
        .filter(|(g, _)| *g >= 0.5 * f_hz && *g <= 2.0 * f_hz && (g - f_hz).abs() > 2.0 / span)
        .map(|(_, x)| *x)
        .collect();
    let over_neighbours = if beside.is_empty() { 0.0 } else { peak / median(&beside) };
    (over_neighbours >= LINE_OVER_NEIGHBOURS).then_some(Line { f_hz, over_neighbours })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_scan_turning_each_phase_matches_a_sin_cos_at_every_frequency() {
        // Three holds of 0.1 s blocks over 300 s, a sinusoid of 0.05 Hz plus a ramp in them.
        let mut blocks = Blocks { t: Vec::new(), y: Vec::new(), hold: Vec::new(), holds: 3, block_s: 0.1 };
        for (h, start) in [0.0, 120.0, 250.0].into_iter().enumerate() {
            for k in 0..400 {
                let t = start + 0.1 * k as f64;
                let s = (std::f64::consts::TAU * 0.05 * t).sin();
                blocks.t.push(t);
                blocks.y.push([s, 0.3 * s + 0.001 * k as f64, -0.5 * s]);
                blocks.hold.push(h);
            }
        }
        let (lowest, step) = (4.0 / 290.0, 1.0 / (4.0 * 290.0));
        let scan = blocks.scan(lowest, step, 0.5);
        assert!(scan.len() > 10 * EXACT_EVERY, "{} frequencies", scan.len());
        for (k, &(f, chi2)) in scan.iter().enumerate() {
            assert!((f - (lowest + k as f64 * step)).abs() < 1e-12);
            let phases: Vec<(f64, f64)> = blocks.t.iter().map(|t| (std::f64::consts::TAU * f * t).sin_cos()).collect();
            let direct = blocks.line_chi2(&phases);
            assert!((chi2 - direct).abs() <= 1e-9 * direct.max(1.0), "{f} Hz: {chi2} vs {direct}");
        }
    }
}
