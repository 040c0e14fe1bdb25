//! Motion in the holds at 2-20 Hz (a hand's physiological tremor at 8-12 Hz, a vibrating support):
//! no noise of a sensor at rest (random walk, flicker, Gauss-Markov with a correlation time of
//! half a second or more) puts power there. Measured in the second half of every hold (a mount's
//! ringing after placement decays within the hold: that is settling) as the variance within short
//! blocks of [`BLOCK_S`] (slower motion and the hold's mean removed) over the white noise of
//! successive differences (which a tremor sampled well above its frequency barely moves).

use crate::csvio::Table;
use crate::diagnose::gap::PoseData;
use crate::diagnose::math::median;
use crate::diagnose::within::white_from_differences;

/// Block length, s: one tremor cycle (8-12 Hz); a Gauss-Markov noise of correlation time 0.5 s puts
/// a tenth of its variance or less inside it.
const BLOCK_S: f64 = 0.1;

/// Fewest samples per block (below it the blocks see no tremor cycle).
const MIN_BLOCK: usize = 4;

/// The holds' median excess ratio above which they move in the tremor band.
pub(crate) const TREMOR_RATIO: f64 = 1.5;

/// Median over the holds of the within-block variance (per sample, axes summed) of the first and
/// of the second half of each hold over the white variance of successive differences: 1 for white
/// noise; `None` when the sample rate gives blocks too short or no noise is measurable.
pub(crate) fn band_ratios(table: &Table, poses: &[PoseData], rate: f64) -> Option<(f64, f64)> {
    let block = (BLOCK_S * rate).round() as usize;
    let white: f64 = white_from_differences(table, poses).iter().sum();
    if block < MIN_BLOCK || !(white > 0.0) {
        return None;
    }
    let ratio = |rows: &[[f64; 3]]| {
        let blocks = rows.len() / block;
        (blocks > 0).then(|| {
            let total: f64 = rows.chunks_exact(block).map(block_variance).sum();
            total / (blocks * (block - 1)) as f64 / white
        })
    };
    let (mut first, mut second) = (Vec::new(), Vec::new());
    for p in poses {
        let mid = p.rows.start + p.rows.len() / 2;
        if let (Some(a), Some(b)) = (ratio(&table.samples[p.rows.start..mid]), ratio(&table.samples[mid..p.rows.end])) {
            first.push(a);
            second.push(b);
        }
    }
    (!first.is_empty()).then(|| (median(&first), median(&second)))
}

/// Sum over the axes of the squared deviations from the block's mean.
fn block_variance(block: &[[f64; 3]]) -> f64 {
    let n = block.len() as f64;
    (0..3)
        .map(|a| {
            let mean = block.iter().map(|s| s[a]).sum::<f64>() / n;
            block.iter().map(|s| (s[a] - mean).powi(2)).sum::<f64>()
        })
        .sum()
}

/// The holds' excess in the tremor band (the second halves' ratio) when they move there for the
/// whole hold: at least [`TREMOR_RATIO`] in the second half and not decaying (the second half's
/// excess at least [`NOT_DECAYING`] of the first's; a ringing mount's decays).
pub(crate) fn in_holds(table: &Table, poses: &[PoseData], rate: f64) -> Option<f64> {
    let (first, second) = band_ratios(table, poses, rate)?;
    (second >= TREMOR_RATIO && second - 1.0 >= NOT_DECAYING * (first - 1.0)).then_some(second)
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
        let (first, second) = band_ratios(&table, &poses, 200.0).unwrap();
        assert!((first - 1.0).abs() < 0.1 && (second - 1.0).abs() < 0.1, "white: {first} {second}");
        assert!(in_holds(&table, &poses, 200.0).is_none());
        // Tremor variance 4.5e-6 g^2 over white 3e-6 (three axes): a ratio of about 2.5.
        let tremor = |t: f64| 0.003 * (std::f64::consts::TAU * 10.0 * t).sin();
        let (table, poses) = holds(&tremor);
        assert!(in_holds(&table, &poses, 200.0).is_some_and(|r| r > 2.0), "{:?}", band_ratios(&table, &poses, 200.0));
        let ringing = |t: f64| 0.03 * (-t / 0.4).exp() * (std::f64::consts::TAU * 10.0 * t).sin();
        let (table, poses) = holds(&ringing);
        assert!(in_holds(&table, &poses, 200.0).is_none(), "{:?}", band_ratios(&table, &poses, 200.0));
    }
}
