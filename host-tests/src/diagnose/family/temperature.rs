//! Temperature: bias, relative scale, or both, linear or quadratic (a second-order temperature
//! coefficient) in the temperature the sensor sees: the thermometer's reading, or that reading
//! through a first-order lag (the sensor warms later than the thermometer), with the lag's time
//! constant from a grid, or as a smooth course in time (a coarse thermometer's staircase) run ahead
//! by a few lags (the thermometer lags the sensor); linear in a fine course and its rate of change
//! (a board thermometer lagging the die by any time, under a temperature that cycles in minutes);
//! and a bias moving smoothly in that temperature (a penalised spline, `smooth.rs`, along the
//! thermometer instead of time): a coefficient that is no polynomial, such as a package stress
//! relaxing over a few kelvin.

use super::{Context, Evaluation, Family, Variant, bias_scale_effect, evaluation_of, smooth};
use crate::diagnose::MIN_GAIN;
use crate::diagnose::gap::row_time;
use crate::diagnose::math::{V3, dot, lstsq, lstsq_with_covariance, mean, median};
use crate::diagnose::within::{Within, WithinVariant};

/// Lag time constants tried, s (0 = no lag).
const LAGS_S: [f64; 5] = [0.0, 30.0, 100.0, 300.0, 1000.0];

/// Time constants by which the thermometer may lag the sensor, s: a thermometer on the board beside
/// the part (not the die's own) sees the die's temperature through the board's thermal lag, tens of
/// seconds, so the die runs ahead of it by about `tau` times its rate of change. Read on the smooth
/// course ([`SMOOTH_S`]).
const LEADS_S: [f64; 2] = [10.0, 30.0];

/// Knot spacing of the fine course, s: a room's air conditioning cycling every few minutes, or a
/// hand's warmth, changes the die's temperature faster than the smooth course ([`SMOOTH_S`])
/// follows, and a board thermometer lagging the die by a minute reads a 4-minute cycle a sixth of
/// a period late. Through a first-order lag of `tau` the die reads the thermometer plus `tau` times
/// its rate of change: a bias linear in the die's temperature is linear in the fine course and in
/// its rate ([`rate_variants`]), whatever the lag.
const FINE_SMOOTH_S: f64 = 30.0;

/// Knot spacing of the smooth course through which the thermometer is also read, s: a coarse
/// thermometer (1 degC steps) is a staircase whose steps misplace a pose's temperature by up to half
/// a step; the die's own temperature moves smoothly (its thermal time constants are minutes).
pub(crate) const SMOOTH_S: f64 = 200.0;

/// Largest local temperature coefficient of a MEMS accelerometer's bias (per axis) a temperature
/// fit may claim, mg/K: six times the largest datasheet figure of current parts (0 g offset vs
/// temperature 0.1-0.5 mg/K). A time drift in a warmed-up part whose thermometer wanders by a few
/// tenths of a kelvin is fitted by such a thermometer at 3-10 mg/K.
const MAX_BIAS_MG_PER_K: f64 = 3.0;

/// Largest local relative scale coefficient a temperature fit may claim, per K: ten times the
/// datasheet range (sensitivity change 0.01-0.05 %/K).
const MAX_SCALE_PER_K: f64 = 5e-3;

/// Least deviation from their mean some pose's (or segment's) temperature must reach, K, for the
/// thermometer to be a cause: one that stays within a quarter of a kelvin stands in for time, not
/// temperature. MEMS coefficients (bias 0.1-0.5 mg/K, scale 0.01-0.05 %/K) move the reading by a
/// few tenths of a milli-g at most over such a span, while any drift of the part is fitted through
/// a thermometer that creeps along with the room. On the development and seen Python sets (2 880
/// logs) the 8 visible drifts named temperature had thermometers spanning 0.05-0.41 K; the 188
/// visible temperature logs, 1.99 K or more (the least of all 360, 0.26 K, left no visible gap).
const MIN_DEVIATION_K: f64 = 0.25;

/// `temps` reach [`MIN_DEVIATION_K`] from their mean `t0`.
fn spans_enough(temps: &[f64], t0: f64) -> bool {
    temps.iter().map(|t| (t - t0).abs()).fold(0.0, f64::max) >= MIN_DEVIATION_K
}

/// The thermometer as read: through a first-order lag of so many seconds (0: as it reads), as a
/// smooth course in time (knots [`SMOOTH_S`] apart, no lag), or that course run ahead by so many
/// seconds (the thermometer lags the sensor: its course plus `tau` times its rate of change, the
/// first-order lag undone).
#[derive(Clone, Copy)]
enum Source {
    Lagged(f64),
    Smoothed,
    Leading(f64),
}

impl Source {
    fn all() -> impl Iterator<Item = Source> {
        std::iter::once(Source::Smoothed)
            .chain(LAGS_S.iter().map(|&lag| Source::Lagged(lag)))
            .chain(LEADS_S.iter().map(|&lead| Source::Leading(lead)))
    }

    /// The extra parameter a lag or a smoothing costs.
    fn params(&self) -> usize {
        match self {
            Source::Smoothed => 1,
            Source::Lagged(lag) => usize::from(*lag > 0.0),
            Source::Leading(_) => 2,
        }
    }

    fn detail(&self) -> String {
        match self {
            Source::Smoothed => format!(" (thermometer smoothed, knots {SMOOTH_S:.0} s apart)"),
            Source::Lagged(lag) if *lag > 0.0 => format!(" (thermometer lagged {lag:.0} s)"),
            Source::Lagged(_) => String::new(),
            Source::Leading(lead) => format!(" (thermometer smoothed, lagging the sensor by {lead:.0} s)"),
        }
    }

    /// The temperature per row, `course` the thermometer's smooth course
    /// ([`Context::thermometer_course`]).
    fn temps(&self, ctx: &Context<'_>, course: Option<&Course>) -> Option<Vec<f64>> {
        match self {
            Source::Smoothed => Some(course?.temps.clone()),
            Source::Lagged(lag) => lagged_temps(ctx, *lag),
            Source::Leading(lead) => {
                let course = course?;
                Some(course.temps.iter().zip(&course.rate).map(|(t, r)| t + lead * r).collect())
            }
        }
    }
}

/// Seconds over which the smooth course's rate of change is taken ([`Course::fit`]).
const RATE_WINDOW_S: f64 = 2.0;

/// The thermometer's course ([`smoothed_temps`], knots [`SMOOTH_S`] apart, or [`FINE_SMOOTH_S`] for
/// the fine one) and its rate of change over [`RATE_WINDOW_S`], per row, K/s: a thermometer lagging
/// the sensor by `tau` reads the course the sensor was at about `tau` times the rate earlier.
pub(crate) struct Course {
    temps: Vec<f64>,
    rate: Vec<f64>,
}

impl Course {
    pub(crate) fn fit(ctx: &Context<'_>, spacing: f64) -> Option<Self> {
        let temps = smoothed_temps(ctx, spacing)?;
        let times: Vec<f64> = (0..temps.len()).map(|i| row_time(ctx.table, i, ctx.m.rate)).collect();
        let (mut lo, mut hi) = (0, 0);
        let mut rate = Vec::with_capacity(temps.len());
        for t in &times {
            while times[lo] < t - RATE_WINDOW_S / 2.0 {
                lo += 1;
            }
            while hi + 1 < times.len() && times[hi + 1] <= t + RATE_WINDOW_S / 2.0 {
                hi += 1;
            }
            let span = times[hi] - times[lo];
            rate.push(if span > 0.0 { (temps[hi] - temps[lo]) / span } else { 0.0 });
        }
        Some(Self { temps, rate })
    }
}

/// The temperature column smoothed in time, per row: a least-squares cubic spline with knots
/// `spacing` seconds apart through its one-second means. A thermometer's steps (1 degC on some
/// boards) are a staircase around the die's smooth course; the spline follows the course.
fn smoothed_temps(ctx: &Context<'_>, spacing: f64) -> Option<Vec<f64>> {
    let temps = ctx.table.temps_c.as_ref()?;
    let times: Vec<f64> = (0..temps.len()).map(|i| row_time(ctx.table, i, ctx.m.rate)).collect();
    let (t0, t_end) = (*times.first()?, *times.last()?);
    let span = (t_end - t0).max(1e-9);
    let count = ((span / spacing).ceil() as usize).max(1) + 3;
    // One-second block means as the data the spline is fitted to.
    let mut blocks: Vec<(f64, f64, f64)> = Vec::new();
    for (t, temp) in times.iter().zip(temps) {
        match blocks.last_mut() {
            Some((start, sum, n)) if t - *start < 1.0 => (*sum, *n) = (*sum + temp, *n + 1.0),
            _ => blocks.push((*t, *temp, 1.0)),
        }
    }
    let basis = |t: f64| -> Vec<f64> { (0..count).map(|j| smooth::bspline(j, count, span, t - t0)).collect() };
    let rows: Vec<Vec<f64>> = blocks.iter().map(|(t, _, _)| basis(*t)).collect();
    let target: Vec<f64> = blocks.iter().map(|(_, sum, n)| -sum / n).collect();
    let train: Vec<usize> = (0..rows.len()).collect();
    let c = lstsq(&rows, &target, &train)?;
    Some(times.iter().map(|t| basis(*t).iter().zip(&c).map(|(b, x)| b * x).sum()).collect())
}

pub(crate) struct Temperature;

/// What a temperature variant moves: the bias per axis, the relative scale per axis, or both. (One
/// relative scale common to every axis, as drift has, was tried: development sets -2, a flicker
/// named temperature and a non-linearity then named colored-noise.)
#[derive(Clone, Copy)]
enum Terms {
    Bias,
    Scale,
    BiasAndScale,
}

impl Terms {
    const ALL: [Terms; 3] = [Terms::Bias, Terms::Scale, Terms::BiasAndScale];

    fn what(self) -> &'static str {
        match self {
            Terms::Bias => "bias",
            Terms::Scale => "scale",
            Terms::BiasAndScale => "bias and scale",
        }
    }

    /// The calibrated-reading change per parameter at the reading `f`, the temperature `dt` from
    /// the mean, up to the power `power`.
    fn effect(self, f: V3, dt: f64, power: usize) -> Vec<V3> {
        match self {
            Terms::Bias => bias_scale_effect(f, dt, power, true, false),
            Terms::Scale => bias_scale_effect(f, dt, power, false, true),
            Terms::BiasAndScale => bias_scale_effect(f, dt, power, true, true),
        }
    }

    /// Parameters per power of the temperature.
    fn per_power(self) -> usize {
        match self {
            Terms::Bias | Terms::Scale => 3,
            Terms::BiasAndScale => 6,
        }
    }

    /// Where each kind of coefficient lies within a power's columns ([`Terms::effect`]'s order), the
    /// columns it has, and its largest plausible local slope (input unit or relative, per K).
    fn limits(self, ctx: &Context<'_>) -> Vec<(usize, usize, f64)> {
        let bias = (0, 3, MAX_BIAS_MG_PER_K / ctx.m.to_mg(1.0));
        match self {
            Terms::Bias => vec![bias],
            Terms::Scale => vec![(0, 3, MAX_SCALE_PER_K)],
            Terms::BiasAndScale => vec![bias, (3, 3, MAX_SCALE_PER_K)],
        }
    }
}

/// The temperature as read through `source`, averaged over each pose.
fn pose_temps(ctx: &Context<'_>, source: Source, course: Option<&Course>) -> Option<Vec<f64>> {
    Some(pose_means(ctx, &source.temps(ctx, course)?))
}

/// The per-row temperatures `temps` averaged over each pose.
fn pose_means(ctx: &Context<'_>, temps: &[f64]) -> Vec<f64> {
    ctx.poses.iter().map(|p| mean(&temps[p.rows.clone()])).collect()
}

/// Seconds of readings whose median starts a lagged thermometer ([`lagged_temps`]): a coarse
/// thermometer's first reading may lie a whole step from the temperature it flickers about (a 1 K
/// step read 22 and then mostly 23), and a lag started there rises over its time constant as a
/// warm-up the sensor never had (a two-time-constant drift under a thermometer spanning 0.11 K was
/// named temperature, "lagged 100 s"). Short beside the lags: a thermometer falling by 1 K a
/// minute at the start moves 0.08 K in 5 s (a temperature log then named `unexplained`).
const LAG_START_S: f64 = 1.0;

/// The temperature column through a first-order lag of `tau` seconds, per row, started at the
/// median of the first [`LAG_START_S`] of readings.
fn lagged_temps(ctx: &Context<'_>, tau: f64) -> Option<Vec<f64>> {
    let temps = ctx.table.temps_c.as_ref()?;
    let mut lagged = Vec::with_capacity(temps.len());
    // Row times count from the first row.
    let first_second: Vec<f64> = temps
        .iter()
        .enumerate()
        .take_while(|(i, _)| row_time(ctx.table, *i, ctx.m.rate) < LAG_START_S)
        .map(|(_, t)| *t)
        .collect();
    let mut state = Some(median(&first_second)).filter(|m| m.is_finite()).or(temps.first().copied())?;
    let mut last_t = 0.0;
    for (i, t_c) in temps.iter().enumerate() {
        let t = row_time(ctx.table, i, ctx.m.rate);
        let alpha = if tau > 0.0 { 1.0 - (-(t - last_t).max(0.0) / tau).exp() } else { 1.0 };
        state += alpha * (t_c - state);
        last_t = t;
        lagged.push(state);
    }
    Some(lagged)
}

/// Temperature parametrisations of the within-pose channel: bias, scale or both, linear or
/// quadratic in the (lagged) temperature of each segment.
fn within_variants(ctx: &Context<'_>, w: &Within) -> Vec<WithinVariant> {
    let mut out = Vec::new();
    let course = ctx.thermometer_course();
    for source in Source::all() {
        let Some(lagged) = source.temps(ctx, course) else { continue };
        let temps: Vec<f64> = w.rows.iter().map(|r| mean(&lagged[r.clone()])).collect();
        let t0 = mean(&temps);
        let lagged = &lagged;
        if !spans_enough(&temps, t0) {
            continue;
        }
        let (through, lag_params) = (source.detail(), source.params());
        for power in 1..=2 {
            let shape = if power == 1 { "linear" } else { "quadratic" };
            for terms in Terms::ALL {
                let detail = format!("{} {shape} in temperature{through}", terms.what());
                out.push(w.variant(ctx.m, terms.per_power() * power, detail, &|p, _, rows| {
                    terms.effect(ctx.calibrated()[p], mean(&lagged[rows]) - t0, power)
                }));
                out.last_mut().expect("just pushed").params += lag_params;
            }
        }
    }
    out
}

/// The columns of `terms` in the pose temperatures `temps`, up to the power `power` of the
/// temperature change (a second-order temperature coefficient for `power` 2).
fn design(ctx: &Context<'_>, temps: &[f64], power: usize, terms: Terms) -> Vec<Vec<f64>> {
    let t0 = mean(temps);
    temps
        .iter()
        .zip(ctx.directions())
        .zip(ctx.calibrated())
        .map(|((t, u), f)| terms.effect(*f, t - t0, power).iter().map(|e| dot(*u, *e)).collect())
        .collect()
}

/// Standard errors by which a fitted temperature coefficient must exceed the physical limits to be
/// refused: a coefficient the poses barely determine (few poses along an axis) may be large by
/// chance.
const BEYOND_LIMIT_SIGMAS: f64 = 2.0;

/// How a temperature fit's coefficients stand against a MEMS part's limits.
#[derive(Clone, Copy, PartialEq)]
enum Grade {
    /// Within the limits themselves: the thermometer is a credible cause.
    Credible,
    /// Beyond them by at most [`BEYOND_LIMIT_SIGMAS`] standard errors: the held-out test decides.
    Plausible,
    /// Further beyond: the thermometer only stands in for something else.
    Implausible,
}

/// The temperature columns `extra` (from [`design`]), fitted with the calibration to every pose,
/// graded by the local coefficients they claim over the poses' temperatures against a MEMS part's:
/// the bias's at most [`MAX_BIAS_MG_PER_K`], the relative scale's at most [`MAX_SCALE_PER_K`]
/// (`None` fit: credible, the held-out test decides).
fn grade(ctx: &Context<'_>, extra: &[Vec<f64>], temps: &[f64], power: usize, terms: Terms) -> Grade {
    let Some((x, cov, ms)) = lstsq_with_covariance(&ctx.rows_with(extra), &ctx.m.r) else { return Grade::Credible };
    let base = ctx.base_rows[0].len();
    let t0 = mean(temps);
    let per_power = terms.per_power();
    let (x, cov) = (&x, &cov);
    // The local slope d(effect)/dT at `dt` as a combination of the coefficients, its size, standard
    // error and limit.
    let slope = |dt: f64, column: usize, limit: f64| {
        let slope_terms: Vec<(usize, f64)> =
            (1..=power).map(|k| (base + (k - 1) * per_power + column, k as f64 * dt.powi(k as i32 - 1))).collect();
        let slope: f64 = slope_terms.iter().map(|&(j, w)| w * x[j]).sum();
        let var: f64 =
            slope_terms.iter().flat_map(|&(j, w)| slope_terms.iter().map(move |&(l, v)| w * v * cov[j][l])).sum();
        (slope.abs(), (var * ms).max(0.0).sqrt(), limit)
    };
    let limits = terms.limits(ctx);
    let slopes: Vec<(f64, f64, f64)> = temps
        .iter()
        .flat_map(|t| {
            let dt = t - t0;
            limits.iter().flat_map(move |&(offset, columns, limit)| (0..columns).map(move |a| (dt, offset + a, limit)))
        })
        .map(|(dt, column, limit)| slope(dt, column, limit))
        .collect();
    let within = |sigmas: f64| slopes.iter().all(|&(size, se, limit)| size - sigmas * se <= limit);
    if within(0.0) {
        Grade::Credible
    } else if within(BEYOND_LIMIT_SIGMAS) {
        Grade::Plausible
    } else {
        Grade::Implausible
    }
}

impl Family for Temperature {
    fn name(&self) -> &'static str {
        "temperature"
    }

    fn within_variants(&self, ctx: &Context<'_>, within: &Within) -> Vec<WithinVariant> {
        within_variants(ctx, within)
    }

    /// The thermometer, measured on its own, shapes the effect in the holds and in the pose means
    /// alike: holds that move too little to be significant still pin its coefficients with the
    /// pose means, which then judge them on the withheld poses. A temperature effect of 12 poses
    /// (3 degrees of freedom beside the calibration) is tested no other way.
    fn joint_needs_moving_holds(&self) -> bool {
        false
    }

    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        graded_variants(ctx).into_iter().map(|(v, _)| v).collect()
    }

    /// The standard evaluation, the thermometer marked a credible cause when the parametrisation
    /// the candidate names has its fitted coefficients within the physical limits themselves,
    /// without [`BEYOND_LIMIT_SIGMAS`]' allowance.
    fn evaluate(&self, ctx: &Context<'_>) -> Evaluation {
        let (variants, grades): (Vec<Variant>, Vec<Grade>) = graded_variants(ctx).into_iter().unzip();
        let credible: Vec<String> = variants
            .iter()
            .zip(&grades)
            .filter(|(_, g)| **g == Grade::Credible)
            .map(|(v, _)| v.detail.clone())
            .collect();
        let (mut e, named) = evaluation_of(self, ctx, ctx.best_of(variants));
        e.credible_cause = e.candidate.applicable && named.is_some_and(|n| credible.contains(&n));
        add_wander(ctx, &mut e);
        e
    }
}

/// Puts the smooth course in temperature ([`wander_in_temperature`]) in the candidate when it
/// predicts the withheld pose means better than the polynomials and is as rigid as a line
/// ([`RIGID_EDF`]), or they do not explain them, or it beats them by [`WANDER_AHEAD`]. Its slopes
/// are within a MEMS part's, so the thermometer is then a credible cause; a course that bends
/// more than a line is a wander (as a drift's is).
fn add_wander(ctx: &Context<'_>, e: &mut Evaluation) {
    let gain = if e.candidate.applicable { e.candidate.heldout_gain } else { f64::NEG_INFINITY };
    let taken = |f: &smooth::SmoothFit| {
        f.edf() <= RIGID_EDF || gain < MIN_GAIN || ctx.value_gain(f.ratio()) >= gain + WANDER_AHEAD
    };
    let Some(fit) = wander_in_temperature(ctx).filter(taken) else { return };
    let (before, rigid) = (e.candidate.detail.clone(), fit.edf() <= RIGID_EDF);
    smooth::add(ctx, e, fit);
    if e.candidate.detail != before {
        (e.credible_cause, e.wander) = (true, !rigid);
    }
}

/// Effective parameters up to which the smooth course in temperature bends no more than one
/// coefficient per axis does: a shape as rigid as the linear fit, not a wander.
const RIGID_EDF: f64 = 3.5;

/// Held-out gain by which a smooth course in temperature that bends more than a line must beat
/// the family's polynomials when they explain the withheld poses: it follows the thermometer's path
/// as a drift's wander follows time's (on the fresh sets of stops 83-97 one room cycle, its
/// quadratic gaining 0.74 and the course 0.81, was then named colored noise by the holds' walk).
const WANDER_AHEAD: f64 = 0.2;

/// Share of the poses' temperature span the smooth course extends beyond it at each end: a hold's
/// segments read a little past the extreme pose means.
const COURSE_MARGIN: f64 = 0.1;

/// Thermometer readings the smooth wander in temperature is tried along.
const WANDER_SOURCES: [Source; 4] =
    [Source::Lagged(0.0), Source::Leading(5.0), Source::Leading(10.0), Source::Leading(30.0)];

/// The bias wandering smoothly in the temperature the sensor sees ([`smooth::best_along`]): a
/// temperature coefficient that is not a polynomial, with as few effective parameters as the data
/// ask, read through each of [`WANDER_SOURCES`]; the best of those whose local slope stays within
/// [`MAX_BIAS_MG_PER_K`] at every pose (two blindgen2 wanders in time under room thermometers
/// were courses of 5-15 mg/K through each reading tried).
fn wander_in_temperature(ctx: &Context<'_>) -> Option<smooth::SmoothFit> {
    let course = ctx.thermometer_course();
    let limit = MAX_BIAS_MG_PER_K / ctx.m.to_mg(1.0);
    let mut best: Option<smooth::SmoothFit> = None;
    for source in WANDER_SOURCES {
        let Some(temps) = source.temps(ctx, course) else { continue };
        let pose_temps = pose_means(ctx, &temps);
        if !spans_enough(&pose_temps, mean(&pose_temps)) {
            continue;
        }
        let lo = pose_temps.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = pose_temps.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let (lo, span) = (lo - COURSE_MARGIN * (hi - lo), (1.0 + 2.0 * COURSE_MARGIN) * (hi - lo));
        let temps = &temps;
        let at = move |_: f64, rows: std::ops::Range<usize>| mean(&temps[rows]) - lo;
        let along = format!("in temperature{}", source.detail());
        let c = smooth::Course { span, at: &at, along, unit: "K", digits: 1 };
        let xs: Vec<f64> = pose_temps.iter().map(|t| t - lo).collect();
        if let Some(fit) = smooth::best_along(ctx, &c).filter(|f| f.steepest(&xs) <= limit)
            && best.as_ref().is_none_or(|b| fit.ratio() < b.ratio())
        {
            best = Some(fit);
        }
    }
    best
}

/// The parametrisations whose fitted coefficients are not [`Grade::Implausible`], with their grade.
fn graded_variants(ctx: &Context<'_>) -> Vec<(Variant, Grade)> {
    let mut out = Vec::new();
    let course = ctx.thermometer_course();
    for source in Source::all() {
        let Some(temps) = pose_temps(ctx, source, course) else { continue };
        let t0 = mean(&temps);
        if !spans_enough(&temps, t0) {
            continue;
        }
        let (through, lag_params) = (source.detail(), source.params());
        for terms in Terms::ALL {
            for (power, shape) in [(1, "linear"), (2, "quadratic")] {
                let params = terms.per_power() * power + lag_params;
                let extra = design(ctx, &temps, power, terms);
                let grade = grade(ctx, &extra, &temps, power, terms);
                if grade == Grade::Implausible {
                    continue;
                }
                let detail = format!("{} {shape} in temperature{through}", terms.what());
                out.push((Variant { extra, params, detail }, grade));
            }
        }
    }
    out.extend(rate_variants(ctx));
    out
}

/// Bias, scale or both linear in the thermometer's fine course ([`FINE_SMOOTH_S`]) and in its
/// rate of change: the die's temperature seen through the thermometer's first-order lag, with a
/// coefficient per axis for each (the lag's, `tau` times the temperature's, fitted with them on
/// every fold's training poses). Graded by the temperature's coefficients; charged the smoothing too.
fn rate_variants(ctx: &Context<'_>) -> Vec<(Variant, Grade)> {
    let Some(fine) = Course::fit(ctx, FINE_SMOOTH_S) else { return Vec::new() };
    let (temps, rates) = (pose_means(ctx, &fine.temps), pose_means(ctx, &fine.rate));
    if !spans_enough(&temps, mean(&temps)) {
        return Vec::new();
    }
    let mut out = Vec::new();
    for terms in Terms::ALL {
        let mut extra = design(ctx, &temps, 1, terms);
        for (row, rate_row) in extra.iter_mut().zip(design(ctx, &rates, 1, terms)) {
            row.extend(rate_row);
        }
        let grade = grade(ctx, &extra, &temps, 1, terms);
        if grade == Grade::Implausible {
            continue;
        }
        let detail = format!(
            "{} linear in temperature and its rate of change (thermometer smoothed over {FINE_SMOOTH_S:.0} s, \
             lagging the sensor)",
            terms.what()
        );
        out.push((Variant { extra, params: 2 * terms.per_power() + 1, detail }, grade));
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::csvio::Table;
    use crate::diagnose::{DiagnoseOptions, Diagnosis, diagnose, gap};
    use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};

    /// A clean simulated log of the own simulator and the times of its rows, s.
    fn clean_log(seed: u64) -> (Table, Vec<f64>) {
        let table = to_table(&generate(&random_scenario(EffectClass::None, seed)), "sim").unwrap();
        let times = (0..table.samples.len()).map(|i| gap::row_time(&table, i, 100.0)).collect();
        (table, times)
    }

    /// Adds a bias of `bias_mg(t)` mg along one sensor direction to every row (`times` its times, s).
    fn add_bias_mg(table: &mut Table, times: &[f64], bias_mg: impl Fn(f64) -> f64) {
        let mg = table.median_magnitude * 1e-3;
        let direction = [0.48, -0.6, 0.64];
        for (sample, t) in table.samples.iter_mut().zip(times) {
            let bias = bias_mg(*t) * mg;
            *sample = std::array::from_fn(|a| sample[a] + direction[a] * bias);
        }
    }

    /// The diagnosis of a clean log with a bias ramping by `drift_mg` along one sensor direction over
    /// the log, under a die thermometer (1/16 K steps) creeping by `creep_k` from 27.8 degC.
    fn drift_under_creeping_thermometer(seed: u64, drift_mg: f64, creep_k: f64) -> Diagnosis {
        let (mut table, times) = clean_log(seed);
        let end = times[times.len() - 1];
        add_bias_mg(&mut table, &times, |t| drift_mg * t / end);
        table.temps_c = Some(times.iter().map(|t| ((27.8 + creep_k * t / end) * 16.0).round() / 16.0).collect());
        diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap()
    }

    #[test]
    fn a_drift_under_a_thermometer_creeping_a_fifth_of_a_kelvin_is_not_temperature() {
        // A warmed-up part: its bias ramps by 1.5 mg along one sensor direction over the log while
        // its die thermometer (1/16 K steps) creeps by 0.2 K with the room. As a temperature effect
        // that is 7.5 mg/K, beyond any MEMS part's offset coefficient: the thermometer only stands
        // in for time.
        for seed in [3, 4] {
            let d = drift_under_creeping_thermometer(seed, 1.5, 0.2);
            assert_eq!(d.verdict, "drift", "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_small_drift_under_a_thermometer_creeping_a_third_of_a_kelvin_is_not_temperature() {
        // As above with a drift of 0.6 mg under a thermometer creeping by 0.3 K: through it 2 mg/K,
        // within a MEMS part's limits, but a thermometer moving so little stands in for time.
        for seed in [3, 4] {
            let d = drift_under_creeping_thermometer(seed, 0.6, 0.3);
            let temperature = d.candidates.iter().find(|c| c.effect == "temperature").unwrap();
            assert!(!temperature.applicable, "seed {seed}: {}", d.to_text());
            assert_ne!(d.verdict, "temperature", "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_coarse_thermometers_first_reading_a_step_low_starts_no_warm_up() {
        // A part settling by 0.8 mg along one sensor direction (time constant 100 s) under a
        // thermometer of 1 K steps that reads 22 for its first fifth of a second, then flickers
        // about 22.9 (every tenth reading 22). A lag started at the first reading rises from 22 to
        // 22.9 over 100 s: the part's settling, as a warm-up it never had.
        for seed in [3, 4] {
            let (mut table, times) = clean_log(seed);
            add_bias_mg(&mut table, &times, |t| 0.8 * (1.0 - (-t / 100.0).exp()));
            let reading = |(i, t): (usize, &f64)| if *t < 0.2 || i % 10 == 0 { 22.0 } else { 23.0 };
            table.temps_c = Some(times.iter().enumerate().map(reading).collect());
            let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
            assert_ne!(d.verdict, "temperature", "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_warm_up_read_by_a_board_thermometer_lagging_the_die_is_temperature() {
        // A part taken from the cold warms by 10 K (time constant 200 s); its bias follows the die
        // at 0.4 mg/K along one sensor direction. The thermometer on the board sees the die through
        // a 25 s lag (1/16 K steps): the die runs ahead of it.
        for seed in [5, 8] {
            let (mut table, times) = clean_log(seed);
            let die = |t: f64| 20.0 - 10.0 * (-t / 200.0).exp();
            add_bias_mg(&mut table, &times, |t| 0.4 * (die(t) - 10.0));
            table.temps_c = Some(board_thermometer(&times, die, 25.0));
            let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
            let temperature = d.candidates.iter().find(|c| c.effect == "temperature").unwrap();
            assert_eq!(d.verdict, "temperature", "seed {seed}: {}", d.to_text());
            assert!(temperature.detail.contains("lagging the sensor"), "seed {seed}: {}", temperature.detail);
        }
    }

    /// `die` (degC at a time, s) as a board thermometer reads it: through a first-order lag of
    /// `lag_s`, in 1/16 K steps.
    fn board_thermometer(times: &[f64], die: impl Fn(f64) -> f64, lag_s: f64) -> Vec<f64> {
        let (mut board, mut last_t) = (die(0.0), 0.0);
        let mut readings = Vec::with_capacity(times.len());
        for t in times {
            board += (1.0 - (-(t - last_t) / lag_s).exp()) * (die(*t) - board);
            last_t = *t;
            readings.push((board * 16.0).round() / 16.0);
        }
        readings
    }

    #[test]
    fn an_air_conditioning_cycle_read_by_a_board_thermometer_a_minute_late_is_temperature() {
        // The room's air conditioning cycles the die by 1.5 K every 4 minutes; the part's bias
        // follows it at 0.4 mg/K along one sensor direction. The thermometer on the board sees the
        // die through a 60 s lag (1/16 K steps): it reads the cycle a sixth of a period late and at
        // 0.54 of its swing. The smooth course (knots 200 s apart) cannot follow a 4-minute cycle,
        // and its leads of 10 and 30 s miss the lag: the temperature family trailed the drift's
        // wander on seeds 3-6 (held-out ratios 2.2-5.5 against 1.8-2.9; seed 6 `unexplained`).
        // The fine course and its rate of change leave 1.1-2.0, ahead of time on every seed.
        for seed in 3..=10 {
            let (mut table, times) = clean_log(seed);
            let die = |t: f64| 25.0 + 1.5 * (2.0 * std::f64::consts::PI * t / 240.0).sin();
            add_bias_mg(&mut table, &times, |t| 0.4 * (die(t) - 25.0));
            table.temps_c = Some(board_thermometer(&times, die, 60.0));
            let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
            let gain = |effect: &str| d.candidates.iter().find(|c| c.effect == effect).unwrap().heldout_gain;
            assert_eq!(d.verdict, "temperature", "seed {seed}: {}", d.to_text());
            assert!(gain("temperature") > gain("drift"), "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_bias_curved_in_temperature_under_a_room_cycle_is_a_smooth_course_in_temperature() {
        // The room's heating cycles the board by 5 K (two cycles over the log); the part's bias
        // follows the die through a package stress that relaxes over a few kelvin, 2 tanh((T - 25)
        // / 1 K) mg along one sensor direction (2 mg/K at the steepest): no line or square in
        // temperature, and a course in time that turns four times. The thermometer reads 1/16 K
        // steps. Without the smooth course the temperature family named a line in temperature.
        for seed in [3, 4] {
            let (mut table, times) = clean_log(seed);
            let end = times[times.len() - 1];
            let die = |t: f64| 25.0 + 5.0 * (4.0 * std::f64::consts::PI * t / end).sin();
            add_bias_mg(&mut table, &times, |t| 2.0 * ((die(t) - 25.0) / 1.0).tanh());
            table.temps_c = Some(times.iter().map(|t| (die(*t) * 16.0).round() / 16.0).collect());
            let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
            let temperature = d.candidates.iter().find(|c| c.effect == "temperature").unwrap();
            assert_eq!(d.verdict, "temperature", "seed {seed}: {}", d.to_text());
            assert!(temperature.detail.contains("smoothly in temperature"), "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_warm_up_read_by_a_one_degree_thermometer_is_temperature() {
        // A board warming by 12 degC (time constant 300 s); its bias follows the die temperature at
        // 0.4 mg/K along one sensor direction; the thermometer reads whole degrees.
        let (mut table, times) = clean_log(8);
        let die = |t: f64| 20.0 + 12.0 * (1.0 - (-t / 300.0).exp());
        add_bias_mg(&mut table, &times, |t| 0.4 * (die(t) - 20.0));
        table.temps_c = Some(times.iter().map(|t| die(*t).round()).collect());
        let d = diagnose(&table, &DiagnoseOptions::DEFAULT).unwrap();
        let temperature = d.candidates.iter().find(|c| c.effect == "temperature").unwrap();
        assert_eq!(d.verdict, "temperature", "{:?}", d.candidates);
        assert!(temperature.detail.contains("smoothed"), "{}", temperature.detail);
    }
}
