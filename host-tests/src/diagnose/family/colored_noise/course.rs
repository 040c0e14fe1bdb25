//! The pose means' course in time: a random walk's, or a course that is no walk's. A bias or scale
//! that walks (integrated white noise) moves the pose means with steps at every time scale, down to
//! the time between two poses, and neighbouring poses share its path. Four other courses move
//! them too: a smooth one (a creep, a wander low-passed by the part's thermal mass) along
//! a curve neighbouring poses share even more closely; one step (a knock, a register reload), a
//! single jump in a quiet path; a scatter of each pose on its own (a hysteresis of the previous
//! pose, a bad pose), shared by no neighbour; and a drift's rigid shape (a line, a parabola, a
//! warm-up), one curve whose size alone is free. Each is a Gaussian process in time, seen
//! through the poses' directions as the calibration's bias and scale columns see them, and scored
//! by its restricted likelihood (the calibration's nine columns integrated out) at the levels that
//! fit the pose means best.

use super::Context;
use crate::diagnose::family::drift::{TAU_FACTORS, warm_up};
use crate::diagnose::math::{ScaledFactor, median};

/// Levels tried for a process, in the pose means' median noise standard deviations (0: absent).
const LEVELS: [f64; 13] = [0.0, 0.01, 0.023, 0.053, 0.12, 0.28, 0.65, 1.5, 3.4, 7.9, 18.0, 42.0, 100.0];

/// Correlation lengths of the smooth course, as shares of the log's span (a Gaussian kernel).
const SMOOTH_LENGTHS: [f64; 5] = [0.08, 0.12, 0.18, 0.27, 0.4];

/// Time constants of a warm-up's rigid course ([`warm_up`]), as shares of the log's span: the drift
/// family's ([`TAU_FACTORS`]) but its fastest and its slowest (0.1-0.8).
const WARM_UP_SHARES: [f64; 4] = [TAU_FACTORS[1], TAU_FACTORS[2], TAU_FACTORS[3], TAU_FACTORS[4]];

/// Most poses whose course is read. Each likelihood costs the cube of the poses, for every level
/// and step tried (a log of 181 poses took 11 s with it, 1.0 s without: stop 104); a log of more poses
/// has holds enough to read a walk from. Of the 15 936 blind logs scored at stop 103 every answer
/// the course changed was on a log of 24-40 poses; 455 have more than this.
const MAX_POSES: usize = 48;

/// A kernel between poses (time or orientation), pose by pose.
type Kernel = Vec<Vec<f64>>;

/// The pose means' noise variance (output unit): white noise over the pose and the rounding's floor,
/// along the pose's direction.
fn pose_variance(ctx: &Context<'_>, p: usize) -> f64 {
    let m = ctx.m;
    let kt = m.model.kt_times(m.directions[p]);
    let n = ctx.poses[p].n as f64;
    (0..3).map(|a| kt[a] * kt[a] * (m.white[a] / n + m.quantisation[a])).sum()
}

/// How the calibration's columns `cols` see a process of the same level on each axis: the pose
/// pairs' dot products of those columns, scaled to a mean diagonal of 1.
fn spatial(ctx: &Context<'_>, cols: std::ops::Range<usize>) -> Kernel {
    let rows = &ctx.base_rows;
    let k: Kernel =
        rows.iter().map(|ri| rows.iter().map(|rj| cols.clone().map(|c| ri[c] * rj[c]).sum()).collect()).collect();
    let mean_diagonal = (0..k.len()).map(|i| k[i][i]).sum::<f64>() / k.len().max(1) as f64;
    let scale = if mean_diagonal > 0.0 { 1.0 / mean_diagonal } else { 0.0 };
    k.into_iter().map(|row| row.into_iter().map(|v| v * scale).collect()).collect()
}

fn dot_n(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The restricted negative log-likelihood of the pose residuals `r` under covariance `c`, the
/// calibration's columns `rows` integrated out (constants dropped); `None` when `c` is singular.
fn restricted_nll(c: Kernel, rows: &[Vec<f64>], r: &[f64]) -> Option<f64> {
    let factor = ScaledFactor::new(c, 0.0)?;
    let wr = factor.whiten(r);
    let columns = rows.first().map_or(0, Vec::len);
    let wx: Vec<Vec<f64>> =
        (0..columns).map(|j| factor.whiten(&rows.iter().map(|row| row[j]).collect::<Vec<_>>())).collect();
    let xtx: Kernel = wx.iter().map(|a| wx.iter().map(|b| dot_n(a, b)).collect()).collect();
    let xtr: Vec<f64> = wx.iter().map(|a| dot_n(a, &wr)).collect();
    let inner = ScaledFactor::new(xtx, 1e-12)?;
    let fitted = dot_n(&xtr, &inner.solve(&xtr)?);
    Some(0.5 * (factor.log_det() + inner.log_det() + dot_n(&wr, &wr) - fitted))
}

/// The pose means' noise and the two ways the calibration's columns see a process (its bias's and
/// its scale's).
struct PoseMeans<'c, 'a> {
    ctx: &'c Context<'a>,
    noise: Vec<f64>,
    sigma: f64,
    spatial: [Kernel; 2],
}

impl PoseMeans<'_, '_> {
    /// The best restricted negative log-likelihood over `levels` of a bias and a scale process
    /// of time kernel `time`.
    fn best_nll(&self, time: &Kernel, levels: &[f64]) -> f64 {
        let n = self.noise.len();
        let mut best = f64::INFINITY;
        for bias in levels {
            for scale in levels {
                let (vb, vs) = ((bias * self.sigma).powi(2), (scale * self.sigma).powi(2));
                let c: Kernel = (0..n)
                    .map(|i| {
                        (0..n)
                            .map(|j| {
                                let own = if i == j { self.noise[i] } else { 0.0 };
                                own + time[i][j] * (vb * self.spatial[0][i][j] + vs * self.spatial[1][i][j])
                            })
                            .collect()
                    })
                    .collect();
                if let Some(nll) = restricted_nll(c, &self.ctx.base_rows, &self.ctx.m.r) {
                    best = best.min(nll);
                }
            }
        }
        best
    }
}

/// Time kernel `f(t_i, t_j)` between the poses' mid times (seconds from the first pose's start).
fn time_kernel(ctx: &Context<'_>, f: &dyn Fn(f64, f64) -> f64) -> Kernel {
    let start = ctx.poses.first().map_or(0.0, |p| p.t_start);
    let t: Vec<f64> = ctx.poses.iter().map(|p| p.t_mid() - start).collect();
    t.iter().map(|&a| t.iter().map(|&b| f(a, b)).collect()).collect()
}

/// The time kernel of a scatter of each pose on its own: no two poses share it.
fn own_kernel(n: usize) -> Kernel {
    (0..n).map(|i| (0..n).map(|j| f64::from(u8::from(i == j))).collect()).collect()
}

/// Time kernels of one step: between pose `k - 1` and pose `k`, or during pose `k`'s hold at an
/// unknown time (a uniform share of the hold after it: mean 1/2, variance 1/12).
fn step_kernels(n: usize, k: usize) -> [Kernel; 2] {
    let between: Vec<f64> = (0..n).map(|i| f64::from(u8::from(i >= k))).collect();
    let during: Vec<f64> = (0..n).map(|i| if i == k { 0.5 } else { between[i] }).collect();
    let outer = |h: &[f64], own: f64| -> Kernel {
        (0..n).map(|i| (0..n).map(|j| h[i] * h[j] + if i == j && i == k { own } else { 0.0 }).collect()).collect()
    };
    [outer(&between, 0.0), outer(&during, 1.0 / 12.0)]
}

/// The best of a drift's rigid courses: a line, a parabola and warm-ups from the log's start
/// ([`WARM_UP_SHARES`]), each one curve `f` in time whose size on each axis is free (kernel
/// `f(t_i) f(t_j)`). A walk starts from nothing at the log's start and its variance grows with time,
/// as a warm-up's course does: a warm-up's pose means, which no stationary smooth course follows
/// as closely, otherwise read as a walk's.
fn rigid_nll(ctx: &Context<'_>, poses: &PoseMeans<'_, '_>, span: f64) -> f64 {
    let along = |f: &dyn Fn(f64) -> f64| poses.best_nll(&time_kernel(ctx, &|a, b| f(a / span) * f(b / span)), &LEVELS);
    let warm_ups = WARM_UP_SHARES.iter().map(|&share| along(&|x| warm_up(x, share)));
    warm_ups.fold(along(&|x| x).min(along(&|x| x * x)), f64::min)
}

/// A course the pose means may follow instead of a walk's.
#[derive(Clone, Copy)]
pub(crate) enum Course {
    /// A smooth course (Gaussian in the time between two poses, its correlation length among
    /// [`SMOOTH_LENGTHS`]).
    Smooth,
    /// A scatter of each pose on its own.
    Own,
    /// A drift's rigid shape ([`rigid_nll`]).
    Rigid,
    /// One step at any time ([`step_nll`]).
    Step,
}

/// Every course a walk's is told from, cheapest first (the step is searched over the poses).
pub(crate) const OTHER_COURSES: [Course; 4] = [Course::Smooth, Course::Own, Course::Rigid, Course::Step];

/// The best of one step at any time (coarser levels: it is searched over the poses).
fn step_nll(poses: &PoseMeans<'_, '_>) -> f64 {
    let n = poses.noise.len();
    let levels: Vec<f64> = LEVELS.iter().step_by(2).copied().collect();
    (0..n)
        .flat_map(|k| {
            let [between, during] = step_kernels(n, k);
            // A step before the first pose is the calibration's constant.
            if k == 0 { vec![during] } else { vec![between, during] }
        })
        .map(|time| poses.best_nll(&time, &levels))
        .fold(f64::INFINITY, f64::min)
}

/// A random walk in time explains the pose means better than every other course
/// ([`OTHER_COURSES`]) by `margin` in restricted log-likelihood.
pub(crate) fn walk_beats_others(ctx: &Context<'_>, margin: f64) -> bool {
    walk_beats(ctx, margin, &OTHER_COURSES)
}

/// A random walk in time (kernel `min(t_i, t_j)`) explains the pose means better than each of
/// `others` by `margin` in restricted log-likelihood, asked in their order. Not asked beyond
/// [`MAX_POSES`].
pub(crate) fn walk_beats(ctx: &Context<'_>, margin: f64, others: &[Course]) -> bool {
    if ctx.poses.len() > MAX_POSES {
        return false;
    }
    let noise: Vec<f64> = (0..ctx.poses.len()).map(|p| pose_variance(ctx, p)).collect();
    let sigma = median(&noise.iter().map(|v| v.sqrt()).collect::<Vec<_>>());
    let poses = PoseMeans { ctx, noise, sigma, spatial: [spatial(ctx, 0..3), spatial(ctx, 3..6)] };
    let span = ctx.poses.last().map_or(0.0, |p| p.t_end) - ctx.poses.first().map_or(0.0, |p| p.t_start);
    let span = span.max(f64::MIN_POSITIVE);
    let walk = poses.best_nll(&time_kernel(ctx, &|a, b| a.min(b) / span), &LEVELS);
    let beaten = |other: f64| other - walk >= margin;
    let smooth = |share: f64| time_kernel(ctx, &|a, b| (-0.5 * ((a - b) / (share * span)).powi(2)).exp());
    others.iter().all(|course| match course {
        Course::Smooth => SMOOTH_LENGTHS.iter().all(|&share| beaten(poses.best_nll(&smooth(share), &LEVELS))),
        Course::Own => beaten(poses.best_nll(&own_kernel(ctx.poses.len()), &LEVELS)),
        Course::Rigid => beaten(rigid_nll(ctx, &poses, span)),
        Course::Step => beaten(step_nll(&poses)),
    })
}
