//! A simulated MPU-6050 in the paper's 24-position experiment (Zou et al. 2020, section 4, fig. 4).
//!
//! Shared, via `#[path]`, by the QEMU firmware example `examples/qemu_calibrate.rs` and the host test
//! `tests/qemu_parity.rs`, so both feed the calibration the very same samples: `no_std`, no allocation,
//! `f32` with `libm` only (bit-identical on the host and on a Cortex-M4F).
//!
//! The sensor has the paper's table 1 errors ([`TRUTH`], input in m/s^2), reads raw counts at
//! 16384 LSB/g (the MPU-6050 at +-2 g) with about 1 mg of noise per axis, at 200 Hz. It is turned through
//! the paper's sequence: Z up, Y up, Z down, X up, X down, Y down, each face turned clockwise four times
//! by 90 degrees in the horizontal plane, [`STATIC_SAMPLES`] per position and [`MOTION_SAMPLES`] of
//! turning between them. As in the paper, the platform is tilted by 1.5 degrees and each face is set down
//! with an error of up to 2 degrees: without them the four turns of a face would give the same reading
//! and the non-orthogonality could not be determined.

use accelcal::model::{Params, STANDARD_GRAVITY_MPS2};
use accelcal::sensor::AccelSensor;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128PlusPlus;

/// The paper's table 1: B (m/s^2), S, M (its digits, beyond `f32` precision).
#[allow(clippy::excessive_precision)]
pub const TRUTH: Params = Params {
    bias: [0.124_886_392; 3],
    scale: [0.97, 0.970_119_681, 0.970_239_377],
    nonorth: [-0.015_237_98, -0.015_000_48, -0.015_239_86],
};
/// Sample rate, Hz.
pub const SAMPLE_RATE_HZ: f32 = 200.0;
/// Sensitivity, LSB per g (MPU-6050 at +-2 g).
pub const LSB_PER_G: f32 = 16384.0;
/// Noise standard deviation per axis, mg.
pub const NOISE_MG: f32 = 1.0;
/// Positions.
pub const POSITIONS: usize = 24;
/// Samples held still per position (5 s, as in the paper).
pub const STATIC_SAMPLES: u32 = 1000;
/// Samples of turning between two positions (0.5 s).
pub const MOTION_SAMPLES: u32 = 100;
/// Samples in the whole stream: the last position is not followed by motion.
pub const TOTAL_SAMPLES: u32 = POSITIONS as u32 * STATIC_SAMPLES + (POSITIONS as u32 - 1) * MOTION_SAMPLES;
/// Platform tilt, degrees (about a horizontal axis 30 degrees from the platform's x).
pub const PLATFORM_TILT_DEG: f32 = 1.5;
/// Each face's set-down error, degrees about the sensor's x then y axis (within +-2 degrees).
pub const FLIP_ERROR_DEG: [[f32; 2]; 6] = [[2.0, -1.0], [-1.5, 2.0], [1.0, 1.5], [-2.0, -0.5], [0.5, -2.0], [1.5, 1.0]];

type Mat3 = [[f32; 3]; 3];

fn rotation(axis: usize, deg: f32) -> Mat3 {
    let (s, c) = (libm::sinf(deg.to_radians()), libm::cosf(deg.to_radians()));
    match axis {
        0 => [[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]],
        1 => [[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]],
        _ => [[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]],
    }
}

fn mul(a: &Mat3, b: &Mat3) -> Mat3 {
    let mut out = [[0.0; 3]; 3];
    for (i, row) in out.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            *v = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
        }
    }
    out
}

/// `a^T v`.
fn transpose_times(a: &Mat3, v: [f32; 3]) -> [f32; 3] {
    let mut out = [0.0; 3];
    for (j, o) in out.iter_mut().enumerate() {
        *o = a[0][j] * v[0] + a[1][j] * v[1] + a[2][j] * v[2];
    }
    out
}

fn scaled(v: [f32; 3], k: f32) -> [f32; 3] {
    [v[0] * k, v[1] * k, v[2] * k]
}

fn norm(v: [f32; 3]) -> f32 {
    libm::sqrtf(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
}

/// The true specific force (m/s^2, sensor frame) at each of the 24 positions.
pub fn positions() -> [[f32; 3]; POSITIONS] {
    // Face to platform: the face's axis up, in the paper's order (fig. 4).
    let faces: [Mat3; 6] = [
        rotation(0, 0.0),   // Z up
        rotation(0, 90.0),  // Y up
        rotation(0, 180.0), // Z down
        rotation(1, -90.0), // X up
        rotation(1, 90.0),  // X down
        rotation(0, -90.0), // Y down
    ];
    let platform = mul(&mul(&rotation(2, 30.0), &rotation(0, PLATFORM_TILT_DEG)), &rotation(2, -30.0));
    let up = [0.0, 0.0, STANDARD_GRAVITY_MPS2];
    let mut out = [[0.0; 3]; POSITIONS];
    for (i, f) in out.iter_mut().enumerate() {
        let (face, turn) = (i / 4, i % 4);
        let Some((&face_to_platform, &[ex, ey])) = faces.get(face).zip(FLIP_ERROR_DEG.get(face)) else {
            continue;
        };
        let error = mul(&rotation(0, ex), &rotation(1, ey));
        // Clockwise seen from above: negative about the vertical.
        let sensor_to_platform = mul(&mul(&rotation(2, -90.0 * turn as f32), &face_to_platform), &error);
        *f = transpose_times(&mul(&platform, &sensor_to_platform), up);
    }
    out
}

/// The stream has ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct End;

/// The simulated sensor: [`TOTAL_SAMPLES`] samples, then [`End`].
pub struct SimSensor {
    positions: [[f32; 3]; POSITIONS],
    rng: Xoshiro128PlusPlus,
    index: u32,
}

impl SimSensor {
    /// A sensor at the start of the stream, its noise seeded with `seed`.
    pub fn new(seed: u64) -> Self {
        Self { positions: positions(), rng: Xoshiro128PlusPlus::seed_from_u64(seed), index: 0 }
    }

    /// The true specific force (m/s^2, sensor frame) of sample `index`.
    pub fn specific_force(&self, index: u32) -> [f32; 3] {
        let period = STATIC_SAMPLES + MOTION_SAMPLES;
        let (position, at) = ((index / period) as usize, index % period);
        let here = self.positions.get(position).copied().unwrap_or_default();
        if at < STATIC_SAMPLES {
            return here;
        }
        let next = self.positions.get(position + 1).copied().unwrap_or(here);
        // Turning: from here to next along a path bulging sideways (also for a 180 degree flip), with
        // the magnitude kept at g plus a hand's push and pull of 0.15 g.
        let s = (at - STATIC_SAMPLES + 1) as f32 / (MOTION_SAMPLES + 1) as f32;
        let smooth = s * s * (3.0 - 2.0 * s);
        let g = STANDARD_GRAVITY_MPS2;
        let side = {
            let a = here;
            // The unit axis least aligned with `a`, crossed with `a`: perpendicular to it.
            let e = if a[0].abs() <= a[1].abs() && a[0].abs() <= a[2].abs() {
                [1.0, 0.0, 0.0]
            } else if a[1].abs() <= a[2].abs() {
                [0.0, 1.0, 0.0]
            } else {
                [0.0, 0.0, 1.0]
            };
            let c = [a[1] * e[2] - a[2] * e[1], a[2] * e[0] - a[0] * e[2], a[0] * e[1] - a[1] * e[0]];
            scaled(c, 1.0 / norm(c).max(1e-6))
        };
        let bulge = libm::sinf(core::f32::consts::PI * s) * 0.6 * g;
        let mut v = [0.0; 3];
        for a in 0..3 {
            v[a] = (1.0 - smooth) * here[a] + smooth * next[a] + bulge * side[a];
        }
        let v = scaled(v, g / norm(v).max(1e-6));
        let push = libm::sinf(2.0 * core::f32::consts::PI * s) * 0.15 * g;
        [v[0] + push * side[0], v[1] + push * side[1], v[2] + push * side[2]]
    }

    /// Approximately normal noise of unit variance: the centred sum of four uniforms, scaled.
    fn unit_noise(&mut self) -> f32 {
        let mut sum = 0.0;
        for _ in 0..4 {
            sum += (self.rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0);
        }
        (sum - 2.0) * libm::sqrtf(3.0)
    }
}

impl AccelSensor for SimSensor {
    type Error = End;

    fn read_raw(&mut self) -> Result<[i16; 3], End> {
        if self.index >= TOTAL_SAMPLES {
            return Err(End);
        }
        let f_true = self.specific_force(self.index);
        self.index += 1;
        // What the sensor with the truth's errors reads, in m/s^2, then in counts with noise.
        let reading = TRUTH.invert(f_true).unwrap_or_default();
        let counts_per_mps2 = LSB_PER_G / STANDARD_GRAVITY_MPS2;
        let noise_counts = NOISE_MG * 1e-3 * LSB_PER_G;
        let mut out = [0i16; 3];
        for (o, r) in out.iter_mut().zip(reading) {
            // Saturating cast: the rails are the sensor's too.
            *o = libm::roundf(r * counts_per_mps2 + noise_counts * self.unit_noise()) as i16;
        }
        Ok(out)
    }
}
