//! Gradient-based solvers of the normalised objective: the paper's classical Newton baseline and a
//! Levenberg-Marquardt polish. Both start from any deviation vector and work on [`NormPose`]s.
//!
//! ```
//! use accelcal::frame::{Frame, NormPose};
//! use accelcal::model::Params;
//! use accelcal::solve::{levenberg_marquardt, LmConfig};
//! let truth = Params { bias: [0.12; 3], scale: [0.97, 0.98, 0.99], nonorth: [-0.015, 0.01, 0.02] };
//! let frame = Frame::new([0.0; 3], [1.0; 3], 9.80665).unwrap();
//! let dirs = [[1.0f32, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0],
//!     [0.0, 0.0, -1.0], [0.6, 0.8, 0.0], [0.0, 0.6, -0.8], [-0.8, 0.0, 0.6], [0.57735027, 0.57735027, 0.57735027],
//!     [-0.57735027, 0.57735027, -0.57735027], [0.57735027, -0.57735027, -0.57735027]];
//! let poses = dirs.map(|d| frame.normalize(truth.invert(d.map(|v| v * 9.80665)).unwrap()));
//! let fit = levenberg_marquardt([0.0; 9], &poses, &LmConfig::DEFAULT).unwrap();
//! let p = frame.to_params(&fit.x);
//! assert!((p.nonorth[2] - 0.02).abs() < 1e-4);
//! ```

use crate::frame::{Deviation, NormPose, modulus_error_gradient, objective, residual_jacobian};
use crate::linalg::{Held, Matrix, add_normal_row, finite, larger, ldlt_solve_holding_split, solve_lu, zero_matrix};
use crate::model::PARAM_COUNT;

/// Why a solve could not produce parameters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum SolveError {
    /// Fewer poses than the 9 parameters need.
    TooFewPoses {
        /// Poses given.
        got: usize,
    },
    /// The start vector or a pose is not finite.
    NonFiniteInput,
    /// The iteration produced non-finite values (diverged).
    Diverged,
    /// The linear system of a step is singular: the poses do not determine all parameters.
    Singular,
}

impl core::fmt::Display for SolveError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Self::TooFewPoses { got } => write!(f, "{got} poses given, at least {PARAM_COUNT} are needed"),
            Self::NonFiniteInput => f.write_str("start vector or pose is not finite"),
            Self::Diverged => f.write_str("the iteration diverged to non-finite values"),
            Self::Singular => f.write_str("the poses do not determine all 9 parameters (singular system)"),
        }
    }
}

impl core::error::Error for SolveError {}

/// How an iteration ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SolveTermination {
    /// The step fell below `step_tolerance`.
    Converged,
    /// No step could lower the cost any more (f32 precision reached).
    NoFurtherDecrease,
    /// `max_iterations` reached first.
    MaxIterations,
}

/// Result of [`levenberg_marquardt`] or [`newton`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct SolveReport {
    /// Best deviation vector found.
    pub x: Deviation,
    /// Normalised objective at `x` (see [`objective`]).
    pub cost: f32,
    /// Iterations run.
    pub iterations: u32,
    /// Why it stopped.
    pub termination: SolveTermination,
}

/// Levenberg-Marquardt settings.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct LmConfig {
    /// Iteration limit. Defaults to 50.
    pub max_iterations: u32,
    /// Initial Marquardt damping (relative to the diagonal of `J^T J`). Defaults to 1e-3.
    pub initial_damping: f32,
    /// Converged when the largest step component is below this (deviation units, i.e. relative to 1).
    /// Defaults to 1e-7.
    pub step_tolerance: f32,
}

impl LmConfig {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { max_iterations: 50, initial_damping: 1e-3, step_tolerance: 1e-7 };
}

impl Default for LmConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Newton settings.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NewtonConfig {
    /// Iteration limit. Defaults to 50.
    pub max_iterations: u32,
    /// Converged when the largest step component is below this. Defaults to 1e-7.
    pub step_tolerance: f32,
}

impl NewtonConfig {
    /// The documented defaults.
    pub const DEFAULT: Self = Self { max_iterations: 50, step_tolerance: 1e-7 };
}

impl Default for NewtonConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// At least one pose per free parameter, everything finite.
fn check_input(x: &Deviation, poses: &[NormPose], held: Held) -> Result<(), SolveError> {
    check_count(poses, held)?;
    check_finite(x, poses)
}

/// At least one pose per free parameter, and one at least.
fn check_count(poses: &[NormPose], held: Held) -> Result<(), SolveError> {
    if poses.len() < PARAM_COUNT - held.count() || poses.is_empty() {
        return Err(SolveError::TooFewPoses { got: poses.len() });
    }
    Ok(())
}

/// Everything finite, and one pose at least.
fn check_finite(x: &Deviation, poses: &[NormPose]) -> Result<(), SolveError> {
    if poses.is_empty() {
        return Err(SolveError::TooFewPoses { got: 0 });
    }
    let poses_finite = poses.iter().all(|p| finite(p.q) && p.u.iter().all(|&v| finite(v)));
    if !poses_finite || !x.iter().all(|&v| finite(v)) {
        return Err(SolveError::NonFiniteInput);
    }
    Ok(())
}

/// Weight of pose `i` in [`normal_equations`]; `None` (no pose) adds nothing.
pub(crate) type PoseWeight<'a> = &'a dyn Fn(usize) -> Option<f32>;

/// The one builder of the library's information matrices: the weighted Gauss-Newton normal equations of
/// the per-pose modulus errors, `J^T W J` and `J^T W e` (one row of `J` per pose: the gradient of its
/// modulus error; `W` from `weight`, 1 without). Only the lower triangle of `jtj` is written. The
/// Levenberg-Marquardt step, the verdict's information matrix and the structural test all use it.
pub(crate) fn normal_equations(
    x: &Deviation,
    poses: &[NormPose],
    weight: Option<PoseWeight<'_>>,
    jtj: &mut Matrix<PARAM_COUNT>,
    jte: &mut Deviation,
) {
    // Flat: one `memset` call, not one per row.
    jtj.as_flattened_mut().fill(0.0);
    jte.fill(0.0);
    for (i, pose) in poses.iter().enumerate() {
        let w = match weight {
            None => 1.0,
            Some(weight) => match weight(i) {
                Some(w) => w,
                None => continue,
            },
        };
        // Read in place (destructured, the gradient was copied).
        let error_gradient = modulus_error_gradient(x, pose);
        add_normal_row(jtj, jte, &error_gradient.1, w, error_gradient.0);
    }
}

fn symmetrize(m: &mut Matrix<PARAM_COUNT>) {
    for i in 0..PARAM_COUNT {
        for j in 0..i {
            m[j][i] = m[i][j];
        }
    }
}

fn max_abs(v: &Deviation) -> f32 {
    v.iter().fold(0.0f32, |m, x| if x.abs() > m { x.abs() } else { m })
}

fn add(x: &Deviation, step: &Deviation) -> Deviation {
    let mut out = *x;
    for (o, s) in out.iter_mut().zip(step) {
        *o += s;
    }
    out
}

/// `step` becomes `x - step`; returns the largest `|step|` ([`max_abs`]), in one loop (in place: no
/// candidate vector beside the step).
fn subtract_from(x: &Deviation, step: &mut Deviation) -> f32 {
    let mut largest = 0.0f32;
    for (s, &xi) in step.iter_mut().zip(x) {
        largest = if s.abs() > largest { s.abs() } else { largest };
        *s = xi - *s;
    }
    largest
}

/// Levenberg-Marquardt on the per-pose modulus errors, from `x0`.
///
/// Damped Gauss-Newton with Marquardt's diagonal scaling; the 9x9 system is solved by the library's
/// factorisation, unscaled (`L D L^T`, no square roots), on the stack. Stops on a small step, on no further decrease, or at `max_iterations`.
pub fn levenberg_marquardt(x0: Deviation, poses: &[NormPose], config: &LmConfig) -> Result<SolveReport, SolveError> {
    levenberg_marquardt_holding(x0, poses, config, Held::NONE)
}

/// Holds the parameters flagged in `held` at their start values (Newton): their rows and columns of the
/// Hessian become the identity and their right-hand side 0, so their step is 0.
fn hold(jtj: &mut Matrix<PARAM_COUNT>, rhs: &mut Deviation, held: Held) {
    if held.is_empty() {
        return;
    }
    for i in 0..PARAM_COUNT {
        for j in 0..PARAM_COUNT {
            if held.contains(i) || held.contains(j) {
                jtj[i][j] = if i == j { 1.0 } else { 0.0 };
            }
        }
        if held.contains(i) {
            rhs[i] = 0.0;
        }
    }
}

/// [`levenberg_marquardt`] with the parameters flagged in `held` fixed at their values in `x0`.
pub fn levenberg_marquardt_holding(
    x0: Deviation,
    poses: &[NormPose],
    config: &LmConfig,
    held: Held,
) -> Result<SolveReport, SolveError> {
    check_input(&x0, poses, held)?;
    let mut x = x0;
    let end = levenberg_marquardt_in_place(&mut x, poses, config, held)?;
    Ok(SolveReport { x, cost: end.cost, iterations: end.iterations, termination: end.termination })
}

/// How [`levenberg_marquardt_in_place`] ended: a [`SolveReport`] but for the deviation vector.
pub(crate) struct LmEnd {
    /// Normalised objective at the result.
    pub cost: f32,
    /// Iterations run.
    pub iterations: u32,
    /// Why it stopped.
    pub termination: SolveTermination,
}

/// [`levenberg_marquardt_holding`] from `x`, into `x` (no copy of the vector in and out), on poses
/// whose number the caller has checked (a calibration checks it when it prepares the problem: not
/// twice). On an error `x` is unspecified.
#[inline(never)] // its frame need not merge with the caller's (peak stack on the device)
pub(crate) fn levenberg_marquardt_in_place(
    x: &mut Deviation,
    poses: &[NormPose],
    config: &LmConfig,
    held: Held,
) -> Result<LmEnd, SolveError> {
    // A NaN or an infinity in `x` or in a pose makes the objective non-finite (no operation of a modulus
    // error turns one finite): the inputs need no check of their own here (the public wrapper names them).
    let mut cost = objective(x, poses);
    if !cost.is_finite() {
        return Err(SolveError::Diverged);
    }
    let mut lambda = config.initial_damping;
    // Zeroed from a constant (one `memset` call each; `[[0.0; 9]; 9]` in place was one per row).
    let (mut jtj, mut jte, mut damped) = (zero_matrix(), [0.0; PARAM_COUNT], zero_matrix());
    // The normal equations are built (in place) at the start and after each accepted step.
    let mut rebuild = true;
    let mut iterations = 0;
    // One exit (one report written): about 100 bytes fewer on a Cortex-M4F than a return per reason.
    let termination = loop {
        if iterations == config.max_iterations {
            break SolveTermination::MaxIterations;
        }
        iterations += 1;
        if rebuild {
            normal_equations(x, poses, None, &mut jtj, &mut jte);
            rebuild = false;
        }
        // The damped matrix is `jtj` below the diagonal (read from there: no copy) and this diagonal.
        for i in 0..PARAM_COUNT {
            damped[i][i] = jtj[i][i] + lambda * larger(jtj[i][i], 1e-12);
        }
        // Solved for `J^T e`, the step is its negative (exactly: rounding is symmetric).
        let mut candidate = jte;
        if ldlt_solve_holding_split(&jtj, &mut damped, &mut candidate, held).is_err() {
            if lambda < 1e10 {
                lambda *= 10.0;
                continue;
            }
            return Err(SolveError::Singular);
        }
        let largest_step = subtract_from(x, &mut candidate);
        let candidate_cost = objective(&candidate, poses);
        // (`cost` is finite: not above it means finite, NaN excluded.)
        if candidate_cost <= cost {
            (*x, cost) = (candidate, candidate_cost);
            lambda = larger(lambda * 0.3, 1e-9);
            if largest_step < config.step_tolerance {
                break SolveTermination::Converged;
            }
            rebuild = true;
        } else {
            lambda *= 10.0;
            if lambda > 1e10 {
                break SolveTermination::NoFurtherDecrease;
            }
        }
    };
    Ok(LmEnd { cost, iterations, termination })
}

/// The classical Newton iteration on `fE` (the paper's baseline): full Hessian
/// `H = (2/N) sum(grad E grad E^T + 2 E Jr^T Jr)`, undamped step `H d = -grad fE`, no line search.
pub fn newton(x0: Deviation, poses: &[NormPose], config: &NewtonConfig) -> Result<SolveReport, SolveError> {
    newton_holding(x0, poses, config, Held::NONE)
}

/// [`newton`] with the parameters flagged in `held` fixed at their values in `x0`.
pub fn newton_holding(
    x0: Deviation,
    poses: &[NormPose],
    config: &NewtonConfig,
    held: Held,
) -> Result<SolveReport, SolveError> {
    check_input(&x0, poses, held)?;
    let mut x = x0;
    for iteration in 1..=config.max_iterations {
        let mut hessian = [[0.0; PARAM_COUNT]; PARAM_COUNT];
        let mut gradient = [0.0; PARAM_COUNT];
        for pose in poses {
            let (e, g) = modulus_error_gradient(&x, pose);
            let jr = residual_jacobian(pose.u);
            for i in 0..PARAM_COUNT {
                gradient[i] += e * g[i];
                for j in 0..i + 1 {
                    let second: f32 = (0..3).map(|r| jr[r][i] * jr[r][j]).sum();
                    hessian[i][j] += g[i] * g[j] + 2.0 * e * second;
                }
            }
        }
        symmetrize(&mut hessian);
        hold(&mut hessian, &mut gradient, held);
        // The common factor 2/N cancels in H d = -g.
        let step = solve_lu(hessian, gradient.map(|v| -v)).map_err(|_| SolveError::Singular)?;
        x = add(&x, &step);
        if x.iter().any(|v| !v.is_finite()) {
            return Err(SolveError::Diverged);
        }
        if max_abs(&step) < config.step_tolerance {
            let cost = objective(&x, poses);
            return Ok(SolveReport { x, cost, iterations: iteration, termination: SolveTermination::Converged });
        }
    }
    let cost = objective(&x, poses);
    if !cost.is_finite() {
        return Err(SolveError::Diverged);
    }
    Ok(SolveReport { x, cost, iterations: config.max_iterations, termination: SolveTermination::MaxIterations })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Twelve unit directions (the six faces and six diagonals), exact: `q = 0`.
    fn poses() -> [NormPose; 12] {
        let s = core::f32::consts::FRAC_1_SQRT_2;
        let dirs = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [s, s, 0.0],
            [0.0, s, -s],
            [-s, 0.0, s],
            [s, -s, 0.0],
            [0.0, -s, -s],
            [s, 0.0, s],
        ];
        dirs.map(|u| NormPose { u, q: 0.0 })
    }

    #[test]
    fn a_non_finite_value_anywhere_in_the_input_is_refused_without_an_input_check() {
        // The in-place LM relies on the objective at the start: every NaN or infinity in a pose (its
        // direction, where a zero component meets a zero coefficient too, or its `q`) or in `x` must
        // make it non-finite. The public LM names the cause.
        let config = LmConfig::DEFAULT;
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            for pose in 0..12 {
                for field in 0..4 {
                    let mut set = poses();
                    match field {
                        3 => set[pose].q = bad,
                        a => set[pose].u[a] = bad,
                    }
                    let mut x = [0.0; PARAM_COUNT];
                    let in_place = levenberg_marquardt_in_place(&mut x, &set, &config, Held::NONE);
                    assert!(matches!(in_place, Err(SolveError::Diverged)), "{bad} in pose {pose} field {field}");
                    let public = levenberg_marquardt([0.0; PARAM_COUNT], &set, &config);
                    assert!(matches!(public, Err(SolveError::NonFiniteInput)), "{bad} in pose {pose} field {field}");
                }
            }
            for i in 0..PARAM_COUNT {
                let mut x = [0.0; PARAM_COUNT];
                x[i] = bad;
                let mut moved = x;
                let in_place = levenberg_marquardt_in_place(&mut moved, &poses(), &config, Held::NONE);
                assert!(matches!(in_place, Err(SolveError::Diverged)), "{bad} in x[{i}]");
                let public = levenberg_marquardt(x, &poses(), &config);
                assert!(matches!(public, Err(SolveError::NonFiniteInput)), "{bad} in x[{i}]");
            }
        }
        // Finite input still converges (the check is not refusing everything).
        let mut x = [0.01; PARAM_COUNT];
        assert!(levenberg_marquardt_in_place(&mut x, &poses(), &config, Held::NONE).is_ok());
        assert!(x.iter().all(|v| v.abs() < 1e-4), "{x:?}");
    }
}
