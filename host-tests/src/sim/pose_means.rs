//! The Monte Carlo fast path of the simulator: pose means drawn from their exact distribution
//! instead of averaging simulated samples.

use accelcal::accumulator::Pose;

use super::config::SimConfig;
use super::model::Model64;
use super::plan::{placement_rotations, up_in_body};
use super::random::{Stream, standard_normal, stream_rng};
use super::record::Layout;

/// The Monte Carlo fast path: for each pose, the exact distribution of the mean of its
/// `n = round(rate_hz * seconds)` white-noise samples, drawn directly as `N(true_reading, σ²/n)` per
/// axis, with `variance = σ²` and `n`, `start_index`, `end_index` as [`simulate`](super::simulate) lays them out.
///
/// `σ` is the noise in the output unit; for counts the rounding is added as independent uniform
/// noise (`σ² + 1/12` LSB²), which holds when the noise is at least about 0.5 LSB (1 mg is 16 LSB at
/// 16384 LSB/g). Moves, clamping and effects are not simulated. Deterministic by `cfg.seed` (its own
/// noise stream; the directions are those of [`simulate`](super::simulate)). An invalid configuration gives no poses.
pub fn simulate_pose_means(cfg: &SimConfig) -> Vec<Pose> {
    if cfg.validate().is_err() {
        return Vec::new();
    }
    let rotations = placement_rotations(&cfg.plan, cfg.seed, cfg.tilt_deg, cfg.flip_deg);
    let layout = Layout::new(cfg, rotations.len());
    let model = Model64::from(&cfg.truth);
    let mut noise = stream_rng(cfg.seed, Stream::PoseMeans);
    let sigma = cfg.units.noise_std(cfg.noise_mg, cfg.gravity);
    let variance = sigma * sigma + if cfg.units.is_counts() { 1.0 / 12.0 } else { 0.0 };
    rotations
        .iter()
        .zip(&layout.pose_ranges)
        .map(|(rotation, &(start, end))| {
            let n = end - start;
            let std_of_mean = (variance / n as f64).sqrt();
            let f_s = model.reading((up_in_body(*rotation) * cfg.gravity).to_array());
            Pose {
                mean: f_s
                    .map(|v| (cfg.units.from_mps2(v, cfg.gravity) + std_of_mean * standard_normal(&mut noise)) as f32),
                variance: [variance as f32; 3],
                n: n as u32,
                start_index: start as u32,
                end_index: end as u32,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::simulate;

    #[test]
    fn pose_means_have_the_right_statistics() {
        let base = SimConfig { noise_mg: 3.0, ..SimConfig::paper(0) };
        let sigma = base.units.noise_std(base.noise_mg, base.gravity);
        let n: f64 = 1000.0;
        let draws = 2000;
        let reference = simulate_pose_means(&base);
        let truth: Vec<_> = simulate(&SimConfig { noise_mg: 0.0, ..base.clone() }).poses;
        let (mut sum, mut sum_sq, mut count) = (0.0, 0.0, 0.0);
        for seed in 0..draws {
            let means = simulate_pose_means(&SimConfig { seed, ..base.clone() });
            assert_eq!(means.len(), 24);
            for (p, mean) in means.iter().enumerate() {
                assert_eq!((mean.n, mean.variance), (1000, [(sigma * sigma) as f32; 3]));
                let expected = simulate_pose_means(&SimConfig { noise_mg: 0.0, seed, ..base.clone() })[p].mean;
                for a in 0..3 {
                    let z = (f64::from(mean.mean[a]) - f64::from(expected[a])) / (sigma / n.sqrt());
                    sum += z;
                    sum_sq += z * z;
                    count += 1.0;
                }
            }
        }
        let mean_z = sum / count;
        let var_z = sum_sq / count - mean_z * mean_z;
        // 144000 standard-normal values (up to f32 rounding of the means: ~1e-6 / 3e-4 of a sigma).
        assert!(mean_z.abs() < 0.02, "{mean_z}");
        assert!((var_z - 1.0).abs() < 0.03, "{var_z}");
        // Same layout and true readings as simulate.
        for (pose, sim_pose) in reference.iter().zip(&truth) {
            assert_eq!((pose.start_index as usize, pose.end_index as usize), (sim_pose.start, sim_pose.end));
            for a in 0..3 {
                let z = (f64::from(pose.mean[a]) - sim_pose.true_reading[a]) / (sigma / n.sqrt());
                assert!(z.abs() < 6.0);
            }
        }
    }

    #[test]
    fn pose_means_are_fast() {
        let start = std::time::Instant::now();
        let mut checksum = 0.0f64;
        for seed in 0..500 {
            let means = simulate_pose_means(&SimConfig::paper(seed));
            checksum += f64::from(means[23].mean[2]);
        }
        let elapsed = start.elapsed();
        println!("500 paper24 pose-mean simulations: {elapsed:?} (checksum {checksum})");
        assert!(checksum.is_finite());
        #[cfg(not(debug_assertions))]
        assert!(elapsed.as_secs_f64() < 0.5, "{elapsed:?}");
    }
}
