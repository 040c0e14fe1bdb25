//! A guided session on a simulated hand-held MPU-6050, shared by `examples/qemu_calibrate.rs` and
//! `tests/qemu_parity.rs` (same samples, same code, same report).
//!
//! The person starts anywhere: nine free-hand orientations, no face, in no particular order. The
//! firmware finishes early: the fit runs but fails the device's verdict (tight bounds), no blob comes
//! out and the session keeps its poses. The person then follows the session's next-pose advice until
//! it says ready, and the same session finishes with a passing verdict and a blob.

use core::fmt;

use accelcal::blob;
use accelcal::calibrate::CalibrationConfig;
use accelcal::model::STANDARD_GRAVITY_MPS2;
use accelcal::session::{Session, SessionConfig, SessionError, State};
use accelcal::verdict::VerdictBounds;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro128PlusPlus;

use crate::sim_sensor::{LSB_PER_G, NOISE_MG, TRUTH};

/// Seed of the hand's noise.
pub const HAND_SEED: u64 = 0x4A4D;
/// Seed of the genetic algorithm.
pub const GA_SEED: u64 = 11;
/// Samples held per orientation (2.5 s at 200 Hz).
const HOLD: u32 = 500;
/// Samples of turning between orientations.
const TURN: u32 = 100;

/// The device's bounds: tighter than the library's defaults, so that nine poses are not enough.
const BOUNDS: VerdictBounds =
    VerdictBounds { max_bias_std_mg: 0.05, max_scale_std_rel: 5e-5, ..VerdictBounds::DEFAULT };

/// Nine free-hand orientations (unit vectors to turn up): no face, edge or corner among them.
const FREE: [[f32; 3]; 9] = [
    [0.301, 0.904, 0.301],
    [-0.796, 0.498, 0.343],
    [0.100, -0.700, 0.707],
    [0.597, 0.100, -0.796],
    [-0.208, -0.312, -0.927],
    [0.905, -0.402, 0.139],
    [-0.496, -0.794, 0.351],
    [0.050, 0.600, -0.798],
    [-0.700, 0.150, -0.698],
];

/// A board held by hand: still along `up`, or turning from `from` to `up`.
struct Hand {
    rng: Xoshiro128PlusPlus,
    from: [f32; 3],
    up: [f32; 3],
    /// Samples since the turn to `up` began.
    at: u32,
}

impl Hand {
    fn turn_to(&mut self, up: [f32; 3]) {
        self.from = self.up;
        self.up = up;
        self.at = 0;
    }

    /// The next reading, raw counts: the truth's errors, 1 mg of noise.
    fn read(&mut self) -> [i16; 3] {
        let g = STANDARD_GRAVITY_MPS2;
        let s = (self.at as f32 / TURN as f32).min(1.0);
        // The hand's push: while turning, and when lifting the board off after the hold.
        let lift = self.at.saturating_sub(TURN + HOLD) as f32 / TURN as f32;
        let push = if self.at < TURN {
            libm::sinf(core::f32::consts::PI * s) * 0.3 * g
        } else if self.at >= TURN + HOLD {
            libm::sinf(2.0 * core::f32::consts::PI * lift) * 0.3 * g
        } else {
            0.0
        };
        self.at = self.at.saturating_add(1);
        let f: [f32; 3] = core::array::from_fn(|a| g * ((1.0 - s) * self.from[a] + s * self.up[a]) + push);
        let reading = TRUTH.invert(f).unwrap_or_default();
        let k = LSB_PER_G / g;
        core::array::from_fn(|a| {
            let noise = (self.rng.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0) - 0.5;
            libm::roundf(reading[a] * k + NOISE_MG * 1e-3 * LSB_PER_G * 3.4 * noise) as i16
        })
    }
}

type Guided = Session<i16, 24, 32, 40>;

/// Turns to `up`, holds it until the session has captured it; `false` on an error.
fn capture(session: &mut Guided, hand: &mut Hand, up: [f32; 3], out: &mut dyn FnMut(fmt::Arguments<'_>)) -> bool {
    // Turn, hold, lift the board off (the motion closes the pose).
    hand.turn_to(up);
    for _ in 0..TURN + HOLD + 2 * TURN {
        match session.push(hand.read()) {
            Ok(p) => {
                if let State::PoseCaptured { index, .. } = p.state {
                    let g = p.guidance;
                    out(format_args!(
                        "guided: pose {index:2} captured, guidance {:?}: next {}, worst std/bound {:.3}, ready {}",
                        g.basis, g.next, g.worst_std, p.ready
                    ));
                    return true;
                }
            }
            Err(e) => {
                out(format_args!("error: guided push: {e}"));
                return false;
            }
        }
    }
    out(format_args!("error: guided: pose not captured"));
    false
}

/// Runs the guided scenario, writes the report to `out`; `true` when it went as described above.
pub fn run(out: &mut dyn FnMut(fmt::Arguments<'_>)) -> bool {
    let calibration = CalibrationConfig { bounds: BOUNDS, ..CalibrationConfig::DEFAULT };
    // 200 Hz, a pose held 2 s, still intervals under 0.5 s not kept.
    let config = SessionConfig { calibration, min_poses: 9, ..SessionConfig::at_rate(200.0, 2.0, 0.5) };
    let Ok(mut session) = Guided::new(config) else {
        out(format_args!("error: guided: session configuration"));
        return false;
    };
    let mut hand = Hand { rng: Xoshiro128PlusPlus::seed_from_u64(HAND_SEED), from: FREE[0], up: FREE[0], at: TURN };
    out(format_args!("guided: nine free-hand orientations, hand seed {HAND_SEED:#x}, GA seed {GA_SEED}"));
    for up in FREE {
        if !capture(&mut session, &mut hand, up, out) {
            return false;
        }
    }
    let early = session.finish(Xoshiro128PlusPlus::seed_from_u64(GA_SEED));
    let failed_early = matches!(early, Err(SessionError::Verdict(_))) && session.result().is_none();
    if let Some(c) = session.last_calibration() {
        out(format_args!(
            "guided: finish with {} poses: verdict pass {}, undetermined {:?}; blob {}, poses kept {}",
            session.poses().len(),
            c.verdict.pass(),
            c.verdict.failures.undetermined,
            if session.result().is_some() { "made" } else { "none" },
            session.poses().len()
        ));
    }
    let mut added = 0;
    while !session.progress().ready && added < 15 {
        let next = session.guidance().next.unit();
        if !capture(&mut session, &mut hand, next, out) {
            return false;
        }
        added += 1;
    }
    let result = match session.finish(Xoshiro128PlusPlus::seed_from_u64(GA_SEED)) {
        Ok(result) => result,
        Err(e) => {
            out(format_args!("error: guided: finish after {added} more poses: {e}"));
            return false;
        }
    };
    let v = &result.calibration.verdict;
    let crc = blob::crc32(&result.blob[..blob::BLOB_LEN - 4]);
    out(format_args!(
        "guided: finish with {} poses ({added} added): verdict pass {}, RMSE {:.4} mg; blob crc32 {crc:#010x}",
        result.poses,
        v.pass(),
        v.rmse_after_mg
    ));
    let pass = failed_early && v.pass();
    out(format_args!("guided: result {}", if pass { "PASS" } else { "FAIL" }));
    pass
}
