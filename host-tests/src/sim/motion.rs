//! The hand's carry between two poses: a minimum-jerk slerp of the orientation (`glam`) plus the
//! hand's linear acceleration and the set-down jolt (see the [module documentation](super)).

use glam::{DQuat, DVec3};
use rand_core::Rng;

use super::config::{LANDING_JOLT_MPS2, MOVE_SHAKE_MPS2, SHAKE_ONSET_S};
use super::random::uniform_in;

/// Sinusoids of the hand's shake per world axis.
const SHAKE_TONES: usize = 3;

/// One carry between two poses: a minimum-jerk slerp plus the hand's linear acceleration.
pub(crate) struct HandMove {
    /// Body-to-world rotation at lift-off.
    from: DQuat,
    /// Body-to-world rotation at set-down.
    to: DQuat,
    /// `(amplitude m/s^2, frequency Hz, phase rad)` per world axis and tone.
    shake: [[(f64, f64, f64); SHAKE_TONES]; 3],
    /// Upward acceleration on the last moving sample, m/s^2.
    landing_jolt_mps2: f64,
}

impl HandMove {
    /// A carry from `from` to `to` (body-to-world rotations) with a random shake and jolt.
    pub(crate) fn new(from: DQuat, to: DQuat, rng: &mut impl Rng) -> Self {
        let shake = std::array::from_fn(|_| {
            std::array::from_fn(|_| {
                let amplitude = MOVE_SHAKE_MPS2 * uniform_in(rng, 0.25, 0.5);
                let frequency = uniform_in(rng, 1.5, 6.0);
                let phase = uniform_in(rng, 0.0, std::f64::consts::TAU);
                (amplitude, frequency, phase)
            })
        });
        Self { from, to, shake, landing_jolt_mps2: LANDING_JOLT_MPS2 * uniform_in(rng, 0.5, 1.5) }
    }

    /// True specific force in the body frame, m/s^2, at `progress` in (0, 1), `elapsed_s` after
    /// lift-off; `landing` on the last moving sample.
    pub(crate) fn specific_force(&self, progress: f64, elapsed_s: f64, gravity: f64, landing: bool) -> [f64; 3] {
        let u = progress.clamp(0.0, 1.0);
        let eased = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u);
        let rotation = self.from.slerp(self.to, eased);
        let onset = (elapsed_s / SHAKE_ONSET_S).min(1.0);
        let window = (onset * std::f64::consts::FRAC_PI_2).sin();
        let mut world = DVec3::new(0.0, 0.0, gravity);
        for (axis, tones) in self.shake.iter().enumerate() {
            let acceleration: f64 = tones
                .iter()
                .map(|&(amp, freq, phase)| amp * (std::f64::consts::TAU * freq * elapsed_s + phase).sin())
                .sum();
            world[axis] += window * acceleration;
        }
        if landing {
            world.z += self.landing_jolt_mps2;
        }
        (rotation.inverse() * world).to_array()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::random::{Stream, stream_rng};

    #[test]
    fn a_carry_starts_and_ends_at_its_poses() {
        let (from, to) = (DQuat::IDENTITY, DQuat::from_rotation_x(std::f64::consts::FRAC_PI_2));
        let carry = HandMove::new(from, to, &mut stream_rng(1, Stream::Motion));
        // At lift-off the shake has not started: gravity alone, in the starting pose.
        let start = carry.specific_force(0.0, 0.0, 9.8, false);
        assert!((DVec3::from_array(start) - DVec3::new(0.0, 0.0, 9.8)).length() < 1e-12, "{start:?}");
        // Near the end the body has turned 90° about x: world up is body +y (within the shake).
        let end = DVec3::from_array(carry.specific_force(1.0, 2.0, 9.8, false));
        assert!(end.y > 9.8 - 3.0 * MOVE_SHAKE_MPS2 && end.z.abs() < 3.0 * MOVE_SHAKE_MPS2, "{end}");
        let jolt = DVec3::from_array(carry.specific_force(1.0, 2.0, 9.8, true));
        assert!((jolt.y - end.y - carry.landing_jolt_mps2).abs() < 1e-9);
    }
}
