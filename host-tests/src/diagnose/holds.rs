//! Holds found without the still-pose detector, for a log of which it keeps too few poses to
//! calibrate. A calibration session still shows its hold structure when the holds move: stretches of
//! at least [`MIN_HOLD_S`] during which the orientation stays put (short-window means within
//! [`HOLD_SPREAD_G`] of the stretch's first). When most of those holds move — their short windows
//! vary far more than the log's quietest windows (shaking), a window jumps (a tap), the window means
//! wander (sway), or the holds carry power in the tremor band (`family/tremor.rs`) — the answer is
//! `motion`, with that evidence, instead of a refusal. A log whose holds are as quiet as its quietest
//! windows gets no answer here: the caller keeps the detector's error.

use std::ops::Range;

use super::gap::pose_data;
use super::math::median;
use crate::csvio::Table;
use crate::diagnose::family::tremor;

/// Window of the scan, s: several periods of a hand's tremor, far shorter than a hold.
const WINDOW_S: f64 = 0.25;

/// Shortest hold, s.
const MIN_HOLD_S: f64 = 1.0;

/// How far (fraction of the log's median |a|, about 1 g: ~3 deg) a hold's window means may lie from
/// its first window's: larger than a sway or a tremor moves a 0.25 s mean, smaller than a rotation.
const HOLD_SPREAD_G: f64 = 0.05;

/// Share of [`HOLD_SPREAD_G`] the means of a steady window's two neighbours may differ by (a move
/// turns the orientation by far more in half a second; a sway or a tremor by less).
const STEADY_SHARE: f64 = 0.4;

/// Holds closer in time than this many windows, at the same orientation, are one hold split by a
/// disturbance.
const MERGE_GAP_WINDOWS: usize = 2;

/// A hold shakes when its median window variance exceeds the log's quietest windows' (10th
/// percentile) by this factor.
const SHAKE_FACTOR: f64 = 3.0;

/// A hold has a tap when one window's variance exceeds the quietest windows' by this factor.
const TAP_FACTOR: f64 = 20.0;

/// A hold sways when its window means scatter this many times more than the quietest holds' do.
const SWAY_FACTOR: f64 = 6.0;

/// Fewest holds for a hold structure (what `diagnose` needs of still poses).
const MIN_HOLDS: usize = 6;

/// One window: its mean and the variance of its high-pass part (half the mean square of successive
/// differences, axes summed; a slow trend, as at the ends of a move, hardly enters), input unit.
struct Window {
    mean: [f64; 3],
    variance: f64,
}

/// What moves in the holds, counted per hold.
#[derive(Debug, Default, PartialEq)]
pub(crate) struct HoldMotion {
    pub(crate) holds: usize,
    pub(crate) split: usize,
    pub(crate) shaking: usize,
    pub(crate) taps: usize,
    pub(crate) sway: usize,
    pub(crate) tremor: usize,
    /// Holds with at least one of the above.
    pub(crate) disturbed: usize,
    /// RMS of the disturbed holds' motion beyond the quietest windows' noise, mg.
    pub(crate) motion_rms_mg: f64,
}

impl HoldMotion {
    /// Most holds move: the still-pose detector had reason to keep few.
    pub(crate) fn explains_few_poses(&self) -> bool {
        self.holds >= MIN_HOLDS && self.disturbed >= 3 && 2 * self.disturbed >= self.holds
    }

    /// The evidence, for the report.
    pub(crate) fn describe(&self, still_poses: usize) -> String {
        format!(
            "the still-pose detector kept {still_poses} poses, too few to calibrate; the log holds {} orientations for \
             >= {MIN_HOLD_S} s and {} of them move (~{:.2} mg RMS beyond the quietest windows): {} shake, {} in the \
             2-20 Hz band, {} with taps, {} sway, {} split",
            self.holds, self.disturbed, self.motion_rms_mg, self.shaking, self.tremor, self.taps, self.sway, self.split
        )
    }
}

/// The holds of the table and how they move; `None` without a usable sample rate.
pub(crate) fn scan(table: &Table, rate: f64) -> Option<HoldMotion> {
    let width = (WINDOW_S * rate).round() as usize;
    let one_g = table.median_magnitude;
    if width < 4 || !(one_g > 0.0) {
        return None;
    }
    let windows = windows(&table.samples, width);
    let min_windows = (MIN_HOLD_S / WINDOW_S).ceil() as usize;
    let (holds, split) = merged(hold_runs(&windows, HOLD_SPREAD_G * one_g, min_windows), &windows, one_g);
    let quiet = quietest_variance(&windows, &holds)?;
    // The quietest holds' scatter of window means: a hold sways when its means scatter far more.
    let calm_scatter = low_decile(holds.iter().map(|h| mean_scatter(&windows[settled(h)])).collect())?;
    let mut motion = HoldMotion { holds: holds.len(), ..HoldMotion::default() };
    let mut excess = Vec::new();
    for (hold, was_split) in holds.iter().zip(split) {
        let late = &windows[settled(hold)];
        let variances: Vec<f64> = late.iter().map(|w| w.variance).collect();
        let shakes = median(&variances) > SHAKE_FACTOR * quiet;
        let tapped = variances.iter().any(|v| *v > TAP_FACTOR * quiet);
        let sways = mean_scatter(late) > SWAY_FACTOR * calm_scatter;
        let rows = settled(hold).start * width..settled(hold).end * width;
        let tremble = tremor_ratio(table, rows, rate).is_some_and(|r| r > tremor::TREMOR_RATIO);
        let flags = [shakes, tremble, tapped, sways, was_split];
        for (count, flag) in
            [&mut motion.shaking, &mut motion.tremor, &mut motion.taps, &mut motion.sway, &mut motion.split]
                .into_iter()
                .zip(flags)
        {
            *count += usize::from(flag);
        }
        if flags.iter().any(|f| *f) {
            motion.disturbed += 1;
            excess.push((median(&variances) - quiet).max(0.0));
        }
    }
    motion.motion_rms_mg = (excess.iter().sum::<f64>() / excess.len().max(1) as f64).sqrt() / one_g * 1000.0;
    Some(motion)
}

/// The windows of a hold looked at: its first third (a settling transient) and its last window (the
/// start of the next move) left out.
fn settled(hold: &Range<usize>) -> Range<usize> {
    hold.start + hold.len() / 3..hold.end - 1
}

/// Consecutive windows of `width` samples (a partial last window dropped).
fn windows(samples: &[[f64; 3]], width: usize) -> Vec<Window> {
    samples
        .chunks_exact(width)
        .map(|chunk| {
            let n = chunk.len() as f64;
            let mean: [f64; 3] = std::array::from_fn(|a| chunk.iter().map(|s| s[a]).sum::<f64>() / n);
            let variance = chunk.windows(2).map(|p| distance(&p[1], &p[0]).powi(2)).sum::<f64>() / (2.0 * (n - 1.0));
            Window { mean, variance }
        })
        .collect()
}

fn distance(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt()
}

/// Runs of at least `min_windows` steady windows (their neighbours' means within [`STEADY_SHARE`] of [`HOLD_SPREAD_G`] of each
/// other: not part of a move) whose means stay within `spread` of the run's first.
fn hold_runs(windows: &[Window], spread: f64, min_windows: usize) -> Vec<Range<usize>> {
    let steady = |k: usize| {
        k > 0 && k + 1 < windows.len() && distance(&windows[k + 1].mean, &windows[k - 1].mean) <= spread * STEADY_SHARE
    };
    let mut runs = Vec::new();
    let mut start = 0;
    for k in 0..=windows.len() {
        let continues = k < windows.len() && steady(k) && distance(&windows[k].mean, &windows[start].mean) <= spread;
        if continues {
            continue;
        }
        if k - start >= min_windows {
            runs.push(start..k);
        }
        start = if k < windows.len() && steady(k) { k } else { k + 1 };
    }
    runs
}

/// `runs` with neighbours at one orientation (means within [`HOLD_SPREAD_G`]) and at most
/// [`MERGE_GAP_WINDOWS`] apart joined; whether each was split.
fn merged(runs: Vec<Range<usize>>, windows: &[Window], one_g: f64) -> (Vec<Range<usize>>, Vec<bool>) {
    let mean_of = |r: &Range<usize>| -> [f64; 3] {
        std::array::from_fn(|a| windows[r.clone()].iter().map(|w| w.mean[a]).sum::<f64>() / r.len() as f64)
    };
    let (mut holds, mut split): (Vec<Range<usize>>, Vec<bool>) = (Vec::new(), Vec::new());
    for run in runs {
        if let Some(last) = holds.last_mut()
            && run.start - last.end <= MERGE_GAP_WINDOWS
            && distance(&mean_of(last), &mean_of(&run)) <= HOLD_SPREAD_G * one_g
        {
            last.end = run.end;
            if let Some(s) = split.last_mut() {
                *s = true;
            }
            continue;
        }
        holds.push(run);
        split.push(false);
    }
    (holds, split)
}

/// The 10th percentile of the holds' window variances (settled part): the noise of the log's
/// quietest stretches.
fn quietest_variance(windows: &[Window], holds: &[Range<usize>]) -> Option<f64> {
    low_decile(holds.iter().flat_map(|h| &windows[settled(h)]).map(|w| w.variance).collect())
}

/// Variance of the window means about their mean (axes summed): the hold's slow motion plus the
/// noise of a window mean.
fn mean_scatter(windows: &[Window]) -> f64 {
    if windows.len() < 2 {
        return 0.0;
    }
    let n = windows.len() as f64;
    let mean: [f64; 3] = std::array::from_fn(|a| windows.iter().map(|w| w.mean[a]).sum::<f64>() / n);
    windows.iter().map(|w| distance(&w.mean, &mean).powi(2)).sum::<f64>() / (n - 1.0)
}

/// The 10th percentile of `values` (`None` when empty or zero).
fn low_decile(mut values: Vec<f64>) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let q = values[values.len() / 10];
    (q > 0.0).then_some(q)
}

/// The hold's tremor-band density ratio (the smaller of its halves'), see `family/tremor.rs`.
fn tremor_ratio(table: &Table, rows: Range<usize>, rate: f64) -> Option<f64> {
    let end = rows.end.min(table.samples.len());
    let hold = [pose_data(table, rows.start, end, rate)];
    // One hold's flag among many: no least number of pairs of blocks (the flags are counted).
    tremor::band_ratios(table, &hold, rate, 1).map(|(first, second)| first.min(second))
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A log of `holds` poses (4 s each at 100 Hz, 1 s moves between them) in g, with white noise of
    /// 1 mg and `shake(hold, t)` added to x during the holds.
    pub(crate) fn log(holds: usize, shake: impl Fn(usize, f64) -> f64) -> Table {
        use rand_core::SeedableRng;
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let mut noise = || 0.001 * crate::sim::random::standard_normal(&mut rng);
        let mut text = String::from("t,ax,ay,az\n");
        let dirs = |k: usize| {
            let (theta, phi) = (0.3 + 1.1 * k as f64, 0.7 * k as f64);
            [theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos()]
        };
        let mut i = 0;
        for k in 0..holds {
            for j in 0..500 {
                let t = j as f64 / 100.0;
                let (d, moving) = if j < 100 {
                    let (a, b) = (dirs(k.max(1) - 1), dirs(k));
                    let f = t;
                    (std::array::from_fn(|c| a[c] + (b[c] - a[c]) * f), true)
                } else {
                    (dirs(k), false)
                };
                let extra = if moving { 0.0 } else { shake(k, t) };
                let s: [f64; 3] = std::array::from_fn(|c| d[c] + noise() + if c == 0 { extra } else { 0.0 });
                text.push_str(&format!("{},{},{},{}\n", i as f64 / 100.0, s[0], s[1], s[2]));
                i += 1;
            }
        }
        crate::csvio::read_csv_str("holds", &text, &crate::csvio::ReadOptions::default()).unwrap()
    }

    #[test]
    fn quiet_holds_are_found_and_not_called_moving() {
        let m = scan(&log(10, |_, _| 0.0), 100.0).unwrap();
        assert_eq!(m.holds, 10, "{m:?}");
        assert_eq!(m.disturbed, 0, "{m:?}");
        assert!(!m.explains_few_poses());
    }

    #[test]
    fn a_tremor_in_most_holds_is_motion() {
        // 10 Hz, 8 mg in the odd holds and in three of the even ones.
        let m =
            scan(&log(10, |k, t| if k % 2 == 1 || k < 6 { 0.008 * (62.83 * t).sin() } else { 0.0 }), 100.0).unwrap();
        assert_eq!(m.holds, 10, "{m:?}");
        assert!(m.disturbed >= 7 && m.explains_few_poses(), "{m:?}");
        assert!(m.tremor >= 7, "{m:?}");
    }

    #[test]
    fn a_sway_in_most_holds_is_motion() {
        // 2 Hz, 5 mg (about 0.3 deg) in six holds of eight; the two others are still.
        let m = scan(&log(8, |k, t| if k % 4 == 0 { 0.0 } else { 0.005 * (12.57 * t).sin() }), 100.0).unwrap();
        assert_eq!(m.holds, 8, "{m:?}");
        assert!(m.sway == 6 && m.disturbed == 6 && m.explains_few_poses(), "{m:?}");
    }
}
