//! A steady line in the holds: one frequency above the tremor test's floor (2 Hz), of the same
//! amplitude on each sensor axis in every hold. Mains pickup on the supply or the signal lines, or a
//! machine's vibration aliased by the ADC, adds a sinusoid along a fixed direction of the board,
//! whatever the pose and for the whole log. A hand's tremor or a vibrating support moves the
//! sensor: its spectrum is a band a few hertz wide, its strength changes from hold to hold, and a
//! vibration fixed in the room reaches the sensor axes differently in each pose. The tremor test
//! ([`super::tremor`]) sees both as power near 10 Hz; this one tells the steady line apart, so that
//! it is not named motion.

use std::f64::consts::TAU;

use rustfft::num_complex::Complex;
use rustfft::{Fft, FftPlanner};

use crate::csvio::Table;
use crate::diagnose::gap::PoseData;
use crate::diagnose::math::{mean_of, median};

/// Longest window taken from a hold, samples (a power of two).
const MAX_WINDOW: usize = 1 << 14;

/// Widest frequency bin, Hz: a tremor band of 8-12 Hz then spreads over eight bins or more, where
/// a line's main lobe takes three. Holds too short for it (a hand-held log the pose finder cuts
/// into pieces of a fraction of a second) are not searched.
const MAX_BIN_HZ: f64 = 0.5;

/// Fewest holds with a window each.
const MIN_HOLDS: usize = 6;

/// Lowest frequency searched, Hz (the tremor test's floor).
const LOWEST_HZ: f64 = 2.0;

/// Bins on each side of the peak that hold a line's main lobe (Hann window: 2 bins; the line lies
/// between bins).
const LOBE: usize = 1;

/// Bins beside the main lobe compared with it, from `LOBE + 2` to `LOBE + 1 + SKIRT` away.
const SKIRT: usize = 6;

/// Pooled power of the line's lobe over the floor of as many bins (the median bin over the band):
/// a line stands out of the white noise.
const LINE_OVER_FLOOR: f64 = 20.0;

/// ... and over as many bins of its skirt: a pure tone's skirt bins lie 31 dB or more below its peak
/// bin (measured with numpy on a 512-reading Hann window, tone offsets 0-0.5 bin: -30.9 dB at worst,
/// lobe over skirt 7 700 or more); a tremor band a few hertz wide puts about as much beside its peak
/// as in it.
const LINE_OVER_SKIRT: f64 = 10.0;

/// Factor within which a hold's line power lies of the median hold's for the hold to carry the same
/// line.
const SAME_POWER: f64 = 2.0;

/// Least cosine between a hold's amplitudes per axis and the median hold's for the hold to carry the
/// same line.
const SAME_DIRECTION: f64 = 0.9;

/// Share of the holds that must carry the same line.
const SAME_SHARE: f64 = 0.75;

/// The line found: its frequency (Hz) and its amplitude per sensor axis (input unit, the median
/// hold's).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SteadyLine {
    pub(crate) hz: f64,
    pub(crate) amplitude: [f64; 3],
}

impl SteadyLine {
    /// Where the gap lies, for an `unexplained` verdict (`to_mg` converts an axis's input unit).
    pub(crate) fn describe(&self, to_mg: impl Fn(usize, f64) -> f64) -> String {
        let a: [f64; 3] = std::array::from_fn(|axis| to_mg(axis, self.amplitude[axis]));
        format!(
            "a steady line at {:.2} Hz in every hold ({:.3}/{:.3}/{:.3} mg on x/y/z): mains pickup or a vibration \
             aliased by the ADC, not motion of the sensor",
            self.hz, a[0], a[1], a[2]
        )
    }
}

/// The line, if the holds carry one ([`LINE_OVER_FLOOR`], [`LINE_OVER_SKIRT`], in
/// [`SAME_SHARE`] of the holds with [`SAME_POWER`] and [`SAME_DIRECTION`]).
pub(crate) fn in_holds(table: &Table, poses: &[PoseData], rate: f64) -> Option<SteadyLine> {
    let lengths: Vec<f64> = poses.iter().map(|p| p.rows.len() as f64).collect();
    let width = window_width(median(&lengths), rate)?;
    let lowest = (LOWEST_HZ * width as f64 / rate).ceil() as usize;
    let bins = lowest..(width / 2).saturating_sub(LOBE + 1 + SKIRT);
    if bins.len() < 2 * (LOBE + 1 + SKIRT) {
        return None;
    }
    let top = bins.end + LOBE + 1 + SKIRT;
    let spectra = hold_spectra(table, poses, width, top);
    if spectra.len() < MIN_HOLDS {
        return None;
    }
    let pooled: Vec<f64> =
        (0..top).map(|k| spectra.iter().map(|s| s.iter().map(|axis| axis[k]).sum::<f64>()).sum()).collect();
    let peak = bins.clone().max_by(|&a, &b| lobe(&pooled, a).total_cmp(&lobe(&pooled, b)))?;
    let floor = median(&pooled[bins]) * (2 * LOBE + 1) as f64;
    let line = lobe(&pooled, peak);
    let stands_out =
        line >= LINE_OVER_FLOOR * floor.max(f64::MIN_POSITIVE) && line >= LINE_OVER_SKIRT * skirt(&pooled, peak);
    let amplitude = stands_out.then(|| steady(&spectra, peak, width)).flatten()?;
    Some(SteadyLine { hz: peak as f64 * rate / width as f64, amplitude })
}

/// The spectra ([`hold_spectrum`], bins `0..top`) of the central `width` readings of every hold
/// that long.
fn hold_spectra(table: &Table, poses: &[PoseData], width: usize, top: usize) -> Vec<[Vec<f64>; 3]> {
    let fft = FftPlanner::new().plan_fft_forward(width);
    let hann: Vec<f64> = (0..width).map(|i| 0.5 - 0.5 * (TAU * i as f64 / width as f64).cos()).collect();
    poses
        .iter()
        .filter(|p| p.rows.len() >= width)
        .map(|p| {
            let start = p.rows.start + (p.rows.len() - width) / 2;
            hold_spectrum(fft.as_ref(), &hann, &table.samples[start..start + width], top)
        })
        .collect()
}

/// The power of two windows are taken at: at most the median hold's length and [`MAX_WINDOW`], at
/// least `rate / MAX_BIN_HZ`.
fn window_width(median_hold: f64, rate: f64) -> Option<usize> {
    let width = (MAX_WINDOW as f64).min(median_hold);
    let width = 1usize << (width.max(1.0).log2().floor() as u32);
    (width as f64 >= rate / MAX_BIN_HZ).then_some(width)
}

/// Power of a hold's window (its mean removed, Hann-weighted) per axis, bins `0..top`.
fn hold_spectrum(fft: &dyn Fft<f64>, hann: &[f64], window: &[[f64; 3]], top: usize) -> [Vec<f64>; 3] {
    let mean = mean_of(window);
    std::array::from_fn(|a| {
        let mut x: Vec<Complex<f64>> =
            window.iter().zip(hann).map(|(s, h)| Complex::new((s[a] - mean[a]) * h, 0.0)).collect();
        fft.process(&mut x);
        x[..top].iter().map(|c| c.norm_sqr()).collect()
    })
}

/// Power in the main lobe around bin `k`.
fn lobe(power: &[f64], k: usize) -> f64 {
    power[k - LOBE..=k + LOBE].iter().sum()
}

/// Power of [`SKIRT`] bins on each side beside the main lobe around `k`, per lobe's width.
fn skirt(power: &[f64], k: usize) -> f64 {
    let near = k.saturating_sub(LOBE + 1 + SKIRT)..k.saturating_sub(LOBE + 1);
    let far = k + LOBE + 2..=k + LOBE + 1 + SKIRT;
    let (sum, count) = near.chain(far).fold((0.0, 0), |(sum, count), j| (sum + power[j], count + 1));
    if count == 0 { f64::INFINITY } else { sum / count as f64 * (2 * LOBE + 1) as f64 }
}

/// The median hold's amplitude per axis at the line (bin `peak`) when [`SAME_SHARE`] of the holds
/// carry the same line: their power within [`SAME_POWER`] of the median hold's, their amplitudes
/// per axis within [`SAME_DIRECTION`] of its pattern.
fn steady(spectra: &[[Vec<f64>; 3]], peak: usize, width: usize) -> Option<[f64; 3]> {
    let per_hold: Vec<[f64; 3]> = spectra.iter().map(|s| std::array::from_fn(|a| lobe(&s[a], peak))).collect();
    let total = |p: &[f64; 3]| p.iter().sum::<f64>();
    let median_power: [f64; 3] = std::array::from_fn(|a| median(&per_hold.iter().map(|p| p[a]).collect::<Vec<f64>>()));
    let typical = total(&median_power);
    let cosine = |p: &[f64; 3]| {
        let dot: f64 = (0..3).map(|a| (p[a] * median_power[a]).sqrt()).sum();
        dot / (total(p) * typical).sqrt()
    };
    let same = per_hold
        .iter()
        .filter(|p| {
            let ratio = total(p) / typical;
            (1.0 / SAME_POWER..=SAME_POWER).contains(&ratio) && cosine(p) >= SAME_DIRECTION
        })
        .count();
    // A sinusoid of amplitude `A` puts `(A n / 4)^2` in its Hann lobe's peak, 1.5 times that over
    // the lobe's three bins when on a bin (measured with numpy: read within 1 % at offsets 0-0.5 bin).
    let to_amplitude = |power: f64| 4.0 * (power / 1.5).sqrt() / width as f64;
    (typical > 0.0 && same as f64 >= SAME_SHARE * spectra.len() as f64).then(|| median_power.map(to_amplitude))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::gap::pose_data;
    use rand_core::SeedableRng;

    /// Twelve holds of 4 s at 100 Hz, 2 s apart, white noise of 1 mg and `extra(t, hold)` (g) per
    /// axis, gravity on z.
    fn holds(extra: &dyn Fn(f64, usize) -> [f64; 3]) -> (Table, Vec<PoseData>) {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(5);
        let mut text = String::from("t,ax,ay,az\n");
        for hold in 0..12 {
            for i in 0..400 {
                let t = (hold * 600 + i) as f64 / 100.0;
                let e = extra(t, hold);
                let n: Vec<f64> = (0..3).map(|_| 0.001 * crate::sim::random::standard_normal(&mut rng)).collect();
                text += &format!("{t},{},{},{}\n", n[0] + e[0], n[1] + e[1], 1.0 + n[2] + e[2]);
            }
        }
        let table = crate::csvio::read_csv_str("holds", &text, &crate::csvio::ReadOptions::default()).unwrap();
        let poses = (0..12).map(|k| pose_data(&table, 400 * k, 400 * (k + 1), 100.0)).collect();
        (table, poses)
    }

    #[test]
    fn mains_aliased_along_one_board_direction_is_a_steady_line() {
        // 50.3 Hz sampled at 100 Hz: a 0.3 Hz alias is below the search; 59.6 Hz aliases to 40.4 Hz.
        let (table, poses) = holds(&|t, _| {
            let s = 0.002 * (TAU * 59.6 * t + 0.4).sin();
            [0.3 * s, 0.5 * s, 0.8 * s]
        });
        let line = in_holds(&table, &poses, 100.0).expect("a steady line");
        assert!((line.hz - 40.4).abs() < 0.5, "{line:?}");
        assert!((line.amplitude[2] - 0.0016).abs() < 0.0004, "{line:?}");
    }

    #[test]
    fn a_tremor_band_a_vibration_in_some_holds_or_turning_with_the_pose_is_not() {
        // A band 8-12 Hz: the sum of sinusoids of random phases across it.
        let band = |t: f64, hold: usize| -> [f64; 3] {
            let s: f64 = (0..20).map(|j| (TAU * (8.0 + 0.2 * j as f64) * t + (hold * 7 + j * 3) as f64).sin()).sum();
            [0.001 * s, 0.0005 * s, 0.0002 * s]
        };
        let (table, poses) = holds(&band);
        assert!(in_holds(&table, &poses, 100.0).is_none(), "tremor band");
        // A fan running in 4 holds of 12.
        let (table, poses) =
            holds(&|t, hold| if hold % 3 == 0 { [0.003 * (TAU * 25.0 * t).sin(); 3] } else { [0.0; 3] });
        assert!(in_holds(&table, &poses, 100.0).is_none(), "bursts");
        // A steady vibration of the room, reaching each pose's sensor axes differently.
        let (table, poses) = holds(&|t, hold| {
            let s = 0.003 * (TAU * 25.0 * t).sin();
            let turn = hold as f64 * 0.9;
            [s * turn.cos(), s * turn.sin(), 0.2 * s]
        });
        assert!(in_holds(&table, &poses, 100.0).is_none(), "turning with the pose");
    }
}
