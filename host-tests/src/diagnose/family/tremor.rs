//! Motion in the holds at 2-20 Hz (a hand's physiological tremor at 8-12 Hz, a vibrating support):
//! no noise of a sensor at rest puts more power there than below it. White noise has a flat spectrum;
//! a digital low-pass filter, a Gauss-Markov noise, flicker and random walk all have a spectrum that
//! does not rise with frequency. Measured in both halves of every hold (a mount's ringing after
//! placement decays within the hold: that is settling) as the noise density near 10 Hz over the
//! density at and below 5 Hz: `tau * AVAR(tau)` (overlapping Allan variance, which is flat in `tau`
//! for white noise) at [`SHORT_S`] over the lower of the same at [`LONG_S`]. A tremor at 8-12 Hz
//! gives several times more at the half period than at one or two and a half periods; a filtered or
//! correlated noise gives 1 or less.
//!
//! Holds too short for those time scales (a hand-held log the pose finder cuts into fragments of a
//! few tenths of a second) are measured over the whole log instead, by the spectrum: the power
//! density in the tremor band ([`TREMOR_BAND_HZ`]) over that just below it ([`BELOW_BAND_HZ`]), the
//! median over the log's 1 s windows. The moves between holds put their power below 2 Hz and the
//! hand's slow drift below 2 Hz too; a sensor's noise at rest does not rise from 3-6 Hz to 8-12 Hz.

use std::f64::consts::TAU;
use std::ops::RangeInclusive;

use crate::csvio::Table;
use crate::diagnose::gap::PoseData;
use crate::diagnose::math::median;

/// The short time scale, s: half a period of a 10 Hz tremor.
const SHORT_S: f64 = 0.05;

/// The long time scales, s: one and two and a half periods of a 10 Hz tremor (its Allan variance
/// cancels or nearly cancels there). The noise floor below the tremor band is the lower of the two:
/// a hand's slow drift and tilt (0.1-2 Hz) raise the longer one as much as the tremor the short one,
/// and no noise of a sensor at rest has a lower density at 0.1 s than at 0.05 s.
const LONG_S: [f64; 2] = [0.1, 0.25];

/// The holds' density ratio above which they move in the tremor band.
pub(crate) const TREMOR_RATIO: f64 = 1.5;

/// Fewest independent pairs of blocks (the rows of the halves used over `2 m`) a long scale's
/// Allan variance pooled over the holds must rest on to serve as the floor ([`in_holds`]; the holds
/// scan flags each hold on its own and counts the flags): 8 pairs are 24 degrees of freedom over three
/// axes, a relative standard error of about 0.3 against a threshold 1.5 times the floor. Holds cut
/// into fragments leave the longest scale a pair or two (a flicker log's 38 holds of 0.5-1.2 s: 2,
/// whose floor came out at a third of the short scale's and read as a tremor); they are judged
/// over the log instead ([`in_log`]).
const MIN_FLOOR_PAIRS: usize = 8;

/// The density ratio (`SHORT_S` over the lower of `LONG_S`, pooled over the holds) of the first and of the
/// second half of every hold: about 1 for white noise, at most about 1 for filtered or correlated
/// noise; `None` when the sample rate or the holds are too short (no long scale resting on
/// `min_floor_pairs` independent pairs of blocks) or no noise is measurable.
pub(crate) fn band_ratios(table: &Table, poses: &[PoseData], rate: f64, min_floor_pairs: usize) -> Option<(f64, f64)> {
    let blocks = |s: f64| (s * rate).round() as usize;
    if blocks(SHORT_S) < 2 {
        return None;
    }
    // Pooled `m * AVAR` at `m` samples over one half of every hold, and the independent pairs of
    // blocks it rests on.
    let pooled = |second: bool, m: usize| {
        let (mut sum, mut terms, mut pairs) = (0.0, 0.0, 0);
        for p in poses {
            let mid = p.rows.start + p.rows.len() / 2;
            let rows = if second { &table.samples[mid..p.rows.end] } else { &table.samples[p.rows.start..mid] };
            // Only halves long enough for the longest scale take part.
            if rows.len() >= 2 * blocks(LONG_S[1])
                && let Some(a) = scaled_allan(rows, m)
            {
                (sum, terms, pairs) = (sum + a.0, terms + a.1, pairs + rows.len() / (2 * m));
            }
        }
        (terms > 0.0).then(|| (sum / terms, pairs))
    };
    let half_ratio = |second: bool| {
        let (short, _) = pooled(second, blocks(SHORT_S))?;
        let floor = LONG_S
            .iter()
            .filter_map(|s| pooled(second, blocks(*s)).filter(|(_, pairs)| *pairs >= min_floor_pairs))
            .map(|(floor, _)| floor)
            .fold(f64::INFINITY, f64::min);
        (floor > 0.0 && floor.is_finite()).then(|| short / floor)
    };
    Some((half_ratio(false)?, half_ratio(true)?))
}

/// `m * AVAR` of the rows for blocks of `m` samples (overlapping Allan variance, axes summed), as a
/// sum of terms and their count; `None` when the rows hold fewer than two blocks.
fn scaled_allan(rows: &[[f64; 3]], m: usize) -> Option<(f64, f64)> {
    let terms = (rows.len() + 1).checked_sub(2 * m).filter(|t| *t > 0)?;
    let mut cumulative = vec![[0.0; 3]; rows.len() + 1];
    for (i, r) in rows.iter().enumerate() {
        cumulative[i + 1] = std::array::from_fn(|a| cumulative[i][a] + r[a]);
    }
    let sum: f64 = (0..terms)
        .map(|i| {
            (0..3)
                .map(|a| {
                    let d = cumulative[i + 2 * m][a] - 2.0 * cumulative[i + m][a] + cumulative[i][a];
                    d * d
                })
                .sum::<f64>()
        })
        .sum();
    // (d / m)^2 / 2 per term, times m.
    Some((sum / (2.0 * m as f64), terms as f64))
}

/// Motion in the tremor band: the density ratio and where it was measured.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Tremor {
    pub(crate) ratio: f64,
    /// In the holds' second halves (Allan variances) or over the log (spectrum).
    pub(crate) over_log: bool,
}

impl Tremor {
    /// The evidence, for the report.
    pub(crate) fn describe(&self) -> String {
        if self.over_log {
            format!("power density at 8-12 Hz {:.1}x that at 3-6 Hz over the log's 1 s windows", self.ratio)
        } else {
            format!("noise density near 10 Hz {:.1}x that near 2 Hz", self.ratio)
        }
    }
}

/// The holds move in the tremor band for the whole hold: at least [`TREMOR_RATIO`] in the second
/// half and not decaying (the second half's excess at least [`NOT_DECAYING`] of the first's; a
/// ringing mount's decays). Holds too short to measure: the log-wide spectrum's ratio at least
/// [`LOG_BAND_RATIO`] ([`log_band_ratio`]).
pub(crate) fn in_holds(table: &Table, poses: &[PoseData], rate: f64) -> Option<Tremor> {
    let Some((first, second)) = band_ratios(table, poses, rate, MIN_FLOOR_PAIRS) else { return in_log(table, rate) };
    (second >= TREMOR_RATIO && second - 1.0 >= NOT_DECAYING * (first - 1.0))
        .then_some(Tremor { ratio: second, over_log: false })
}

/// The log moves in the tremor band: [`log_band_ratio`] at least [`LOG_BAND_RATIO`].
pub(crate) fn in_log(table: &Table, rate: f64) -> Option<Tremor> {
    let ratio = log_band_ratio(table, rate).filter(|r| *r >= LOG_BAND_RATIO)?;
    Some(Tremor { ratio, over_log: true })
}

/// The tremor band, Hz (bins of the 1 s windows).
const TREMOR_BAND_HZ: RangeInclusive<usize> = 8..=12;

/// The band just below it, Hz: above a hand's slow drift and the moves between holds (below 2 Hz).
const BELOW_BAND_HZ: RangeInclusive<usize> = 3..=6;

/// The log-wide ratio above which the log moves in the tremor band. A sensor at rest gives about 1
/// or less (white noise flat, filtered or correlated noise falling with frequency); on the Python
/// development sets the logs without motion reached 2.4 (a ringing mount after each placement; mains
/// and motor lines in the band aside), 80 of the 86 hand-held ones exceeded 3, 73 of them 5 (three
/// were below 1: two parts whose own low-pass filter cuts at 2.5 and 6.25 Hz, one not examined).
const LOG_BAND_RATIO: f64 = 3.0;

/// Fewest 1 s windows for the log-wide ratio.
const MIN_WINDOWS: usize = 10;

/// The median over the log's 1 s windows of the mean power density in [`TREMOR_BAND_HZ`] over that
/// in [`BELOW_BAND_HZ`] (Hann window, each window's mean removed, axes summed); `None` below 30 Hz
/// (the band's top needs the Nyquist frequency above it) or with fewer than [`MIN_WINDOWS`].
pub(crate) fn log_band_ratio(table: &Table, rate: f64) -> Option<f64> {
    let width = rate.round() as usize;
    if !(rate >= 30.0) || table.samples.len() < MIN_WINDOWS * width {
        return None;
    }
    let hann: Vec<f64> = (0..width).map(|i| 0.5 - 0.5 * (TAU * i as f64 / width as f64).cos()).collect();
    // Hann-weighted phasor of every bin used, per sample of the window.
    let phasor = |k: usize| -> Vec<(f64, f64)> {
        (0..width)
            .map(|i| {
                let (s, c) = (TAU * (k * i) as f64 / width as f64).sin_cos();
                (hann[i] * c, hann[i] * s)
            })
            .collect()
    };
    // A window whose power below the band is within rounding of nothing (a constant or stuck log) has
    // no spectrum to compare: a nano-g at the bin.
    let negligible = (1e-9 * table.median_magnitude * width as f64).powi(2);
    let below: Vec<Vec<(f64, f64)>> = BELOW_BAND_HZ.map(phasor).collect();
    let band: Vec<Vec<(f64, f64)>> = TREMOR_BAND_HZ.map(phasor).collect();
    let ratios: Vec<f64> = table
        .samples
        .chunks_exact(width)
        .filter_map(|window| {
            let n = window.len() as f64;
            let mean: [f64; 3] = std::array::from_fn(|a| window.iter().map(|s| s[a]).sum::<f64>() / n);
            let centred: Vec<[f64; 3]> = window.iter().map(|s| std::array::from_fn(|a| s[a] - mean[a])).collect();
            let density =
                |bins: &[Vec<(f64, f64)>]| bins.iter().map(|p| power(&centred, p)).sum::<f64>() / bins.len() as f64;
            let floor = density(&below);
            (floor > negligible).then(|| density(&band) / floor)
        })
        .collect();
    (ratios.len() >= MIN_WINDOWS).then(|| median(&ratios))
}

/// The power of a window (its mean removed) at the bin of `phasor`, axes summed.
fn power(centred: &[[f64; 3]], phasor: &[(f64, f64)]) -> f64 {
    (0..3)
        .map(|a| {
            let (re, im) =
                centred.iter().zip(phasor).fold((0.0, 0.0), |(re, im), (s, (c, si))| (re + s[a] * c, im + s[a] * si));
            re * re + im * im
        })
        .sum()
}

/// Share of the first half's excess the second half keeps, at least, for motion that does not decay.
const NOT_DECAYING: f64 = 0.5;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::gap::pose_data;
    use rand_core::SeedableRng;

    /// Four holds of 4 s at 200 Hz, white noise of 1 mg plus `extra(t within the hold)` on x, g.
    fn holds(extra: &dyn Fn(f64) -> f64) -> (Table, Vec<PoseData>) {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..3200 {
            let t = (i % 800) as f64 / 200.0;
            let n: Vec<f64> = (0..3).map(|_| 0.001 * crate::sim::random::standard_normal(&mut rng)).collect();
            text += &format!("{},{},{},{}\n", i as f64 / 200.0, n[0] + extra(t), n[1], 1.0 + n[2]);
        }
        let table = crate::csvio::read_csv_str("holds", &text, &crate::csvio::ReadOptions::default()).unwrap();
        let poses = (0..4).map(|k| pose_data(&table, 800 * k, 800 * (k + 1), 200.0)).collect();
        (table, poses)
    }

    #[test]
    fn a_tremor_is_motion_white_noise_and_a_decaying_ringing_are_not() {
        let (table, poses) = holds(&|_| 0.0);
        let (first, second) = band_ratios(&table, &poses, 200.0, MIN_FLOOR_PAIRS).unwrap();
        assert!((first - 1.0).abs() < 0.1 && (second - 1.0).abs() < 0.1, "white: {first} {second}");
        assert!(in_holds(&table, &poses, 200.0).is_none());
        // A 3 mg tremor at 10 Hz over 1 mg white noise per axis: (3 + 36) / (3 + 7), about 3.8.
        let tremor = |t: f64| 0.003 * (std::f64::consts::TAU * 10.0 * t).sin();
        let (table, poses) = holds(&tremor);
        assert!(
            in_holds(&table, &poses, 200.0).is_some_and(|t| !t.over_log && t.ratio > 2.0),
            "{:?}",
            band_ratios(&table, &poses, 200.0, MIN_FLOOR_PAIRS)
        );
        let ringing = |t: f64| 0.03 * (-t / 0.4).exp() * (std::f64::consts::TAU * 10.0 * t).sin();
        let (table, poses) = holds(&ringing);
        assert!(in_holds(&table, &poses, 200.0).is_none(), "{:?}", band_ratios(&table, &poses, 200.0, MIN_FLOOR_PAIRS));
    }

    #[test]
    fn a_tremor_with_the_hand_drifting_slowly_is_motion() {
        // A hand: a 3 mg tremor at 10 Hz and a 6 mg sway at 0.5 Hz. The sway raises the density at
        // 0.25 s above the tremor's at 0.05 s (ratio about 0.15); at one tremor period, 0.1 s, neither
        // moves the Allan variance much.
        let hand =
            |t: f64| 0.003 * (std::f64::consts::TAU * 10.0 * t).sin() + 0.006 * (std::f64::consts::TAU * 0.5 * t).sin();
        let (table, poses) = holds(&hand);
        assert!(in_holds(&table, &poses, 200.0).is_some(), "{:?}", band_ratios(&table, &poses, 200.0, MIN_FLOOR_PAIRS));
    }

    #[test]
    fn a_low_passed_noise_is_not_tremor() {
        // The white holds through a moving average of 8 samples (a 200 Hz sensor's ~12 Hz digital
        // low-pass): their successive differences shrink far more than their variance.
        let (mut table, _) = holds(&|_| 0.0);
        let raw = table.samples.clone();
        for (i, s) in table.samples.iter_mut().enumerate() {
            let window = &raw[i.saturating_sub(7)..=i];
            *s = std::array::from_fn(|a| window.iter().map(|r| r[a]).sum::<f64>() / window.len() as f64);
        }
        let poses: Vec<PoseData> = (0..4).map(|k| pose_data(&table, 800 * k, 800 * (k + 1), 200.0)).collect();
        let (first, second) = band_ratios(&table, &poses, 200.0, MIN_FLOOR_PAIRS).unwrap();
        assert!(first < 1.1 && second < 1.1, "low-passed: {first} {second}");
        assert!(in_holds(&table, &poses, 200.0).is_none());
    }

    /// Holds of 0.5-1.2 s at 500 Hz (the pose finder's fragments of a log whose noise wanders far
    /// above white), one per second: 1 mg white noise plus a 5 mg Gauss-Markov noise with a 7.6 Hz
    /// corner on every axis, a spectrum falling with frequency. Only the holds of 1 s or more reach
    /// the longest scale, a pair or two of blocks between them.
    fn fragmented_wander(seed: u64) -> (Table, Vec<PoseData>) {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let rate = 500.0;
        let phi = (-TAU * 7.6 / rate).exp();
        let mut level = [0.0; 3];
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..20_000 {
            let n: Vec<f64> = (0..3)
                .map(|a| {
                    let drive = 0.005 * (1.0 - phi * phi).sqrt() * crate::sim::random::standard_normal(&mut rng);
                    level[a] = phi * level[a] + drive;
                    level[a] + 0.001 * crate::sim::random::standard_normal(&mut rng)
                })
                .collect();
            text += &format!("{},{},{},{}\n", i as f64 / rate, n[0], n[1], 1.0 + n[2]);
        }
        let table = crate::csvio::read_csv_str("fragments", &text, &crate::csvio::ReadOptions::default()).unwrap();
        let lengths =
            [0.5, 0.6, 0.7, 0.8, 0.9, 0.5, 0.6, 0.7, 0.8, 1.0, 0.5, 0.6, 0.7, 0.8, 0.9, 0.5, 0.6, 0.7, 0.8, 1.2];
        let poses = lengths
            .iter()
            .enumerate()
            .map(|(k, s)| pose_data(&table, 1000 * k, 1000 * k + (s * rate) as usize, rate))
            .collect();
        (table, poses)
    }

    #[test]
    fn a_wander_in_fragments_of_holds_is_not_tremor_from_a_floor_on_two_pairs_of_blocks() {
        let mut flagged = Vec::new();
        for seed in 1..=12 {
            let (table, poses) = fragmented_wander(seed);
            // The holds' floor rests on too few blocks: judged over the log, whose spectrum falls.
            assert!(band_ratios(&table, &poses, 500.0, MIN_FLOOR_PAIRS).is_none(), "seed {seed}");
            if let Some(t) = in_holds(&table, &poses, 500.0) {
                flagged.push((seed, t.ratio));
            }
        }
        assert!(flagged.is_empty(), "flagged as tremor: {flagged:?}");
    }

    /// Poses of 0.3 s, one per second: a hand-held log's fragments, too short for the holds' test.
    fn fragments(table: &Table) -> Vec<PoseData> {
        (0..16).map(|k| pose_data(table, 200 * k, 200 * k + 60, 200.0)).collect()
    }

    #[test]
    fn fragments_of_holds_are_judged_on_the_log_spectrum() {
        // The hand of the test above: a tremor at 10 Hz and a slow sway, far above the white noise.
        let hand =
            |t: f64| 0.003 * (std::f64::consts::TAU * 10.0 * t).sin() + 0.006 * (std::f64::consts::TAU * 0.5 * t).sin();
        let (table, _) = holds(&hand);
        let poses = fragments(&table);
        assert!(band_ratios(&table, &poses, 200.0, MIN_FLOOR_PAIRS).is_none());
        let tremor = in_holds(&table, &poses, 200.0);
        assert!(tremor.is_some_and(|t| t.over_log && t.ratio > 5.0), "{tremor:?}");
        // At rest: white noise, a random walk of 1 mg/sqrt(s) on it, and the white noise through a
        // moving average of 8 samples.
        let (white, _) = holds(&|_| 0.0);
        let mut walk = white.clone();
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let mut level = [0.0; 3];
        for s in &mut walk.samples {
            for a in 0..3 {
                level[a] += 0.001 * (1.0f64 / 200.0).sqrt() * crate::sim::random::standard_normal(&mut rng);
                s[a] += level[a];
            }
        }
        let mut filtered = white.clone();
        for (i, s) in filtered.samples.iter_mut().enumerate() {
            let window = &white.samples[i.saturating_sub(7)..=i];
            *s = std::array::from_fn(|a| window.iter().map(|r| r[a]).sum::<f64>() / window.len() as f64);
        }
        // A constant log (a stuck sensor): no spectrum, not a ratio of rounding errors.
        let mut constant = white.clone();
        constant.samples.iter_mut().for_each(|s| *s = [0.01, 0.02, 0.99]);
        assert_eq!(log_band_ratio(&constant, 200.0), None);
        for (name, table) in [("white", &white), ("walk", &walk), ("filtered", &filtered)] {
            let ratio = log_band_ratio(table, 200.0).unwrap();
            assert!(ratio < 1.5, "{name}: {ratio}");
            assert!(in_holds(table, &fragments(table), 200.0).is_none(), "{name}");
        }
    }
}
