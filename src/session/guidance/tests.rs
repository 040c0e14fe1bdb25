//! The `f32` square-root guidance against the `f64` reference it replaced ([`super::reference`]):
//! the same next direction and poorly determined flags wherever the reference's decision is not a
//! near tie, the same worst standard deviation to 1e-3 relative. Every guidance the session's own tests
//! compute is checked ([`check_against_reference`]); `random_logs_agree_with_the_f64_reference` adds
//! random orientations, noise levels and pose counts, six-face logs and logs that leave the
//! non-orthogonality undetermined.

extern crate std;

use std::vec::Vec;

use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use super::reference::{Reference, reference};
use super::*;
use crate::calibrate::CalibrationConfig;
use crate::model::Params;

/// A reference decision closer than this (relative) to another candidate, or a variance this close to
/// the bound, is a near tie: either answer is right, it is not compared.
const NEAR_TIE: f64 = 1e-3;

/// Tolerance on `worst_std` (relative).
const STD_TOLERANCE: f64 = 1e-3;

/// The reference's own tie tolerance (exact ties in exact arithmetic, decided by the sum).
const REFERENCE_TIE: f64 = 1e-6;

/// How one `f32` guidance compares with the reference.
#[derive(Debug, Default, Clone, Copy)]
struct Comparison {
    /// `Some(agreed)` when the reference's next direction is not a near tie.
    next: Option<bool>,
    /// Flags compared (not near the bound) and agreed.
    flags_compared: usize,
    flags_agreed: usize,
    /// Largest distance from the bound (relative) of a variance whose flag differs.
    flag_miss: f64,
    /// Relative difference of `worst_std`, and of `worst_std_after_next` when the same direction won.
    std_error: f64,
    after_error: Option<f64>,
}

fn relative(a: f32, b: f32) -> f64 {
    let (a, b) = (f64::from(a), f64::from(b));
    if a == b { 0.0 } else { (a - b).abs() / b.abs() }
}

/// Whether the reference's choice is clear: every other candidate's key is larger by more than
/// [`NEAR_TIE`], or ties it (within the reference's tie tolerance) with a sum larger by more than
/// [`NEAR_TIE`].
fn clear_choice(r: &Reference) -> bool {
    let Some(&(chosen, key, _, sum)) = r.candidates.iter().find(|c| c.0 == r.guidance.next) else {
        return false;
    };
    r.candidates.iter().filter(|c| c.0 != chosen).all(|&(_, k, _, s)| {
        let gap = (k - key) / key.abs();
        gap > NEAR_TIE || (gap.abs() <= REFERENCE_TIE && (s - sum) / sum.abs() > NEAR_TIE)
    })
}

fn compare(g: &Guidance, r: &Reference) -> Comparison {
    let mut c = Comparison { std_error: relative(g.worst_std, r.guidance.worst_std), ..Comparison::default() };
    if clear_choice(r) {
        c.next = Some(g.next == r.guidance.next);
    }
    if g.next == r.guidance.next {
        c.after_error = Some(relative(g.worst_std_after_next, r.guidance.worst_std_after_next));
    }
    for ((&flag, &reference_flag), &v) in g.poorly_determined.iter().zip(&r.guidance.poorly_determined).zip(&r.current)
    {
        if (v - 1.0).abs() > NEAR_TIE {
            c.flags_compared += 1;
            c.flags_agreed += usize::from(flag == reference_flag);
            if flag != reference_flag {
                c.flag_miss = c.flag_miss.max((v - 1.0).abs());
            }
        }
    }
    c
}

/// The `f32` guidance against the `f64` reference and the `f64` square-root form. Returns the two
/// comparisons and what fails: a clear next direction or a flag of the square-root form not
/// reproduced, `worst_std` off by more than 1e-3 (unless both are above the bound), a clear next
/// direction of the reference not reproduced (excused where the two `f64` forms disagree, or where
/// the square-root form finds a near tie: the reference loses undetermined terms to cancellation).
fn check(
    frame: &Frame,
    poses: &[Pose],
    bounds: &VerdictBounds,
    g: &Guidance,
) -> Option<(Comparison, Comparison, Failed)> {
    let cholesky = reference(frame, poses, bounds)?;
    let oracle = super::reference::square_root_reference(frame, poses, bounds);
    let (c, o) = (compare(g, &cholesky), compare(g, &oracle));
    let above = |r: &Reference| g.worst_std > 1.0 && r.guidance.worst_std > 1.0;
    let excused = cholesky.guidance.next != oracle.guidance.next || o.next.is_none();
    let failed = Failed {
        next: o.next == Some(false) || (c.next == Some(false) && !excused),
        flags: o.flags_agreed != o.flags_compared || c.flags_agreed != c.flags_compared,
        std: !(o.std_error <= STD_TOLERANCE || above(&oracle)) || !(c.std_error <= STD_TOLERANCE || above(&cholesky)),
        excused: c.next == Some(false) && excused,
    };
    if failed.next || failed.flags || failed.std {
        std::println!(
            "{} poses, f32 {g:?}, reference {:?}, square root f64 {:?}",
            poses.len(),
            cholesky.guidance,
            oracle.guidance
        );
    }
    Some((c, o, failed))
}

/// What [`check`] found wrong.
#[derive(Debug, Default, Clone, Copy)]
struct Failed {
    next: bool,
    flags: bool,
    std: bool,
    /// A reference's next direction not reproduced, excused.
    excused: bool,
}

/// Called by every guidance computed in the library's tests: the session's tests are checked against
/// the references as they run.
pub(super) fn check_against_reference(frame: &Frame, poses: &[Pose], bounds: &VerdictBounds, g: &Guidance) {
    if let Some((_, _, failed)) = check(frame, poses, bounds, g) {
        assert!(!(failed.next || failed.flags || failed.std), "{failed:?}");
    }
}

/// Tally of comparisons.
#[derive(Debug, Default)]
struct Tally {
    compared: usize,
    agreed: usize,
    near_ties: usize,
    flags: usize,
    flags_agreed: usize,
    std_error: f64,
    std_error_below_bound: f64,
    after_error: f64,
    flag_miss: f64,
}

impl Tally {
    fn add(&mut self, c: &Comparison, worst_std: f32) {
        match c.next {
            Some(ok) => (self.compared, self.agreed) = (self.compared + 1, self.agreed + usize::from(ok)),
            None => self.near_ties += 1,
        }
        (self.flags, self.flags_agreed) = (self.flags + c.flags_compared, self.flags_agreed + c.flags_agreed);
        self.std_error = self.std_error.max(c.std_error);
        if worst_std <= 1.0 {
            self.std_error_below_bound = self.std_error_below_bound.max(c.std_error);
        }
        self.after_error = self.after_error.max(c.after_error.unwrap_or(0.0));
        self.flag_miss = self.flag_miss.max(c.flag_miss);
    }
}

/// A uniformly random unit vector.
fn random_unit(rng: &mut Xoshiro256PlusPlus) -> [f32; 3] {
    loop {
        let v: [f32; 3] = core::array::from_fn(|_| uniform(rng) * 2.0 - 1.0);
        let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        if n > 0.1 && n <= 1.0 {
            return v.map(|x| x / n);
        }
    }
}

fn uniform(rng: &mut Xoshiro256PlusPlus) -> f32 {
    (rng.next_u32() >> 8) as f32 / 16_777_216.0
}

fn gaussian(rng: &mut Xoshiro256PlusPlus) -> f32 {
    let (a, b) = (f64::from(uniform(rng)).max(1e-12), f64::from(uniform(rng)));
    ((-2.0 * a.ln()).sqrt() * (core::f64::consts::TAU * b).cos()) as f32
}

/// Log kinds: random orientations, the six faces (each 1-4 times, tilted up to 2 deg), the six faces
/// exactly (non-orthogonality undetermined), orientations in the sensor's x-y plane (the z couplings
/// undetermined).
const KINDS: usize = 4;

fn direction(kind: usize, i: usize, rng: &mut Xoshiro256PlusPlus) -> [f32; 3] {
    let face = |i: usize| {
        let mut d = [0.0f32; 3];
        d[(i / 2) % 3] = if i.is_multiple_of(2) { 1.0 } else { -1.0 };
        d
    };
    match kind {
        0 => random_unit(rng),
        1 => {
            let tilt = random_unit(rng).map(|t| t * 0.035 * uniform(rng));
            let d = face(i);
            let v = [d[0] + tilt[0], d[1] + tilt[1], d[2] + tilt[2]];
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
            v.map(|x| x / n)
        }
        2 => face(i),
        _ => {
            let a = uniform(rng) * core::f32::consts::TAU;
            [a.cos(), a.sin(), 0.0]
        }
    }
}

/// A random log of `kind`: random model errors, unit (m/s^2 or counts), noise and pose count.
fn random_log(kind: usize, rng: &mut Xoshiro256PlusPlus) -> Vec<Pose> {
    let r = |rng: &mut Xoshiro256PlusPlus| uniform(rng) * 2.0 - 1.0;
    let truth = Params {
        bias: core::array::from_fn(|_| 0.5 * r(rng)),
        scale: core::array::from_fn(|_| 1.0 + 0.1 * r(rng)),
        nonorth: core::array::from_fn(|_| 0.03 * r(rng)),
    };
    let counts_per_unit = if rng.next_u32().is_multiple_of(2) { 1.0 } else { 100.0 + 2000.0 * uniform(rng) };
    let count = 1 + (rng.next_u32() % 40) as usize;
    let sigma = 10f32.powf(-5.0 + 4.5 * uniform(rng)) * counts_per_unit;
    (0..count)
        .filter_map(|i| {
            let d = direction(kind, i, rng);
            let reading = truth.invert([d[0] * 9.80665, d[1] * 9.80665, d[2] * 9.80665])?;
            let n = 20 + rng.next_u32() % 3000;
            let axis_sigma: [f32; 3] = core::array::from_fn(|_| sigma * (0.5 + uniform(rng)));
            let mean = core::array::from_fn(|a| {
                reading[a] * counts_per_unit + axis_sigma[a] / (n as f32).sqrt() * gaussian(rng)
            });
            Some(Pose { mean, variance: axis_sigma.map(|s| s * s), n, start_index: 0, end_index: 0 })
        })
        .collect()
}

/// Agreement over many logs, per kind: decisions compared, agreed, near ties; flags; worst errors.
/// Asserted on random orientations and six-face logs; measured and printed (not asserted) on the
/// logs that leave the non-orthogonality undetermined (exact faces, one plane), where `f32` loses up
/// to a few per cent on the prior-dominated variances (`cargo test -p accelcal --lib random_logs --
/// --nocapture`).
#[test]
fn random_logs_agree_with_the_f64_reference() {
    let config = CalibrationConfig::DEFAULT;
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(13);
    let logs_per_kind = 400;
    for kind in 0..KINDS {
        let (mut cholesky, mut oracle, mut guidances) = (Tally::default(), Tally::default(), 0);
        let (mut excused, mut failed_next, mut failed_flags, mut failed_std) = (0, 0, 0, 0);
        for _ in 0..logs_per_kind {
            let log = random_log(kind, &mut rng);
            for end in 1..=log.len() {
                let poses = &log[..end];
                let (frame, _) = crate::session::guidance_frame::<40>(poses, &config);
                let g = square_root_guidance(&frame, poses, &config.bounds);
                let Some((c, o, failed)) = check(&frame, poses, &config.bounds, &g) else { continue };
                cholesky.add(&c, g.worst_std);
                oracle.add(&o, g.worst_std);
                excused += usize::from(failed.excused);
                failed_next += usize::from(failed.next);
                failed_flags += usize::from(failed.flags);
                failed_std += usize::from(failed.std);
                guidances += 1;
            }
        }
        std::println!("kind {kind} (seed 13, {logs_per_kind} logs, {guidances} guidances):");
        std::println!("  vs f64 reference: {cholesky:?}, disagreements excused {excused}");
        std::println!("  vs f64 square root: {oracle:?}");
        std::println!("  guidances failing: next {failed_next}, flags {failed_flags}, worst_std {failed_std}");
        if kind < 2 {
            assert_eq!((failed_next, failed_flags, failed_std), (0, 0, 0), "kind {kind}");
        }
    }
}
