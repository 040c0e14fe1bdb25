//! Drift: a bias that moves with time. Parametrisations: one exponential warm-up
//! `c (1 - exp(-t / tau))` per axis (`tau` from a grid), two exponentials (a fast and a slow
//! time constant), polynomials in time of degree 1 to 3, and, on the within-pose channel (where
//! every hold shows the drift's course), a smooth wander: piecewise-linear in time with knots
//! evenly spaced over the log. The scale factors can drift too (a ratiometric front end on a
//! discharging supply, a reference that ages or warms with no thermometer): a relative scale per
//! axis linear in time, alone or with the bias, or settling exponentially; one relative scale common
//! to every axis (linear or quadratic in time: a ratiometric supply moves all three at once), alone
//! or with the bias on the same course (linear or exponential), unless a thermometer moves
//! by [`THERMAL_SPAN_K`] or more (a scale that changes as the log goes on is then the temperature
//! family's: time is the temperature's proxy, and on a steady warm-up the two cannot be told
//! apart).

use super::context::CHANNELS_DISAGREE;
use super::{
    Context, Evaluation, Family, Variant, bias_scale_effect, common_scale_effect, periodic, smooth, standard_evaluation,
};
use crate::diagnose::gap::PoseData;
use crate::diagnose::math::{V3, axis, dot};
use crate::diagnose::within::{Effect, Within, WithinVariant};

/// Knot counts of the piecewise-linear wander (within-pose channel).
const KNOTS: [usize; 3] = [3, 5, 9];

/// Harmonics of the smooth wander (sines and cosines of periods `2 T / j`, `T` the log's length).
const HARMONICS: [usize; 5] = [1, 2, 3, 4, 6];

/// Time constants tried, as fractions of the log's duration.
pub(crate) const TAU_FACTORS: [f64; 6] = [0.05, 0.1, 0.2, 0.4, 0.8, 1.6];

/// Least share of the holds' movement beyond white noise a line per hold must explain for
/// [`drifting_holds`] (a random walk's path: about 0.7; see [`Within::line_share`]).
const HOLD_LINES_EXPLAIN: f64 = 0.9;

/// Held-out ratio, relative to the drift's best, at which one sinusoid over the log predicts the
/// withheld poses so much better that the bias oscillates ([`oscillates`]). On the development
/// sets (1584 logs; 576 drifts, temperatures and out-of-catalogue effects scanned) the sinusoid
/// reached 0.66 times the drift's ratio at best on drifts (a wander of 1.5 cycles; the next 0.77),
/// at least 0.74 on every out-of-catalogue shape but an aliased motor's beat and one cross-axis
/// product (0.48), 0.13-0.31 on four of ten motor beats (2.3-5.8 cycles; the others 0.88 and
/// more) and 0.45 on a bias cycling with the room's heating: the threshold lies between, near
/// their geometric middle.
const PERIODIC_OVER_DRIFT: f64 = 0.5;

pub(crate) struct Drift;

/// A drift has no period: when one sinusoid over the log ([`Context::periodic`]) predicts the withheld
/// poses [`PERIODIC_OVER_DRIFT`] times better than every drift shape, the bias oscillates (an
/// aliased vibration, a pickup), and the drift is refuted. Why, or `None`.
fn oscillates(ctx: &Context<'_>, e: &Evaluation) -> Option<String> {
    let drift = e.candidate.heldout_ratio;
    let fit = ctx.periodic().filter(|p| e.candidate.applicable && p.ratio <= PERIODIC_OVER_DRIFT * drift)?;
    Some(format!(
        "the bias oscillates: one sinusoid of period {:.0} s ({:.1} cycles over the log) predicts the withheld poses \
         better than any drift shape (held-out ratio {:.2} against {drift:.2}): a periodic bias, not a drift",
        fit.period_s, fit.cycles, fit.ratio
    ))
}

/// A drift moves the holds as it moves the pose means: when the named pose-level shape's coefficients
/// from the holds alone and from the pose means (with the calibration) disagree beyond
/// [`CHANNELS_DISAGREE`] ([`Context::channel_disagreement`]), the pose means' fit is not a drift of
/// the part (on a log of 13 poses, a bias warming up over 127 s fitted a cross-axis product of gap
/// ratio 69 to 1.9, and was 266 chi-square per coefficient from the still holds). Holds that move
/// beyond white noise have already set aside the shapes they contradict
/// ([`moving_holds_contradict`]); this refutes the family when the holds are still. Why, or `None`.
fn holds_disagree(ctx: &Context<'_>, e: &Evaluation) -> Option<String> {
    let detail = &e.candidate.detail;
    let shape = pose_shapes(ctx).into_iter().find(|s| s.detail == *detail)?;
    let disagreement = holds_disagreement(ctx, &shape, &shape.variant(ctx)).filter(|d| *d > CHANNELS_DISAGREE)?;
    Some(format!(
        "the holds do not move as the pose means' drift ({detail}) would move them ({disagreement:.0} chi-square per coefficient apart)"
    ))
}

/// [`Context::channel_disagreement`] of the pose-level `shape` (its columns at the pose means
/// `variant`; `None`: no within-pose channel).
fn holds_disagreement(ctx: &Context<'_>, shape: &Shape<'_>, variant: &Variant) -> Option<f64> {
    let w = ctx.within.as_ref()?;
    let columns = variant.extra.first().map_or(0, Vec::len);
    ctx.channel_disagreement(w, &w.variant(ctx.m, columns, shape.detail.clone(), &*shape.effect))
}

/// The holds move beyond white noise and their coefficients of `shape` disagree with the pose
/// means' beyond [`CHANNELS_DISAGREE`]: the holds show the drift, but not along this course, and
/// the shape is set aside for the others (a warm-up with two directions and time constants, 10 s
/// and 97 s, on 13 poses of 5-7 s: its best shape, a scale common to every axis in time, was 84
/// chi-square per coefficient from the moving holds, and the whole family was refuted; a bias
/// warming up over the holds' course gains 0.56 on withheld poses).
fn moving_holds_contradict(ctx: &Context<'_>, shape: &Shape<'_>, variant: &Variant) -> bool {
    ctx.holds_move() && holds_disagreement(ctx, shape, variant).is_some_and(|d| d > CHANNELS_DISAGREE)
}

/// The holds drift smoothly: their movement is significant and a line in time through each hold
/// explains nearly all of it, more than a random walk's path by two standard errors (a random walk
/// moving the holds 1.3 times white noise reached a share of 0.9 in a quarter of the paths; ask
/// [`super::settling::settling_holds`] first: a transient as slow as the hold is nearly a line too).
/// A drift faster than the poses are spaced (a wander with a fresh rate in each hold) shows so even
/// when the pose means cannot follow its course. The description, or `None`.
pub(crate) fn drifting_holds(ctx: &Context<'_>) -> Option<String> {
    let within = ctx.within.as_ref().filter(|w| w.significant && !periodic::predicts_poses(ctx))?;
    let share = within.line_share();
    (share >= HOLD_LINES_EXPLAIN && within.smoother_than_a_walk()).then(|| {
        format!(
            "the holds drift smoothly: a line per hold explains {:.0} % of their movement beyond white noise ({:.1}x white), too fast for the pose means to follow",
            100.0 * share.min(1.0),
            within.nominal_ratio
        )
    })
}

/// A warm-up's course at `t`: `1 - exp(-t / tau)` (`t`, `tau` in one unit).
pub(crate) fn warm_up(t: f64, tau: f64) -> f64 {
    1.0 - (-t / tau).exp()
}

/// The time constants (s) the pose level tries, [`TAU_FACTORS`] of the log ending at `t_end`. None
/// faster than the first hold: a warm-up over within it is seen by the pose means in the first pose
/// alone (a one-pose offset); that hold's course is the settling family's evidence.
fn pose_level_taus(ctx: &Context<'_>, t_end: f64) -> Vec<f64> {
    let first_hold_s = ctx.poses.first().map_or(0.0, |p| p.t_end - p.t_start);
    TAU_FACTORS.iter().map(|f| f * t_end).filter(|tau| *tau >= first_hold_s).collect()
}

/// A function of time, s.
type Basis = Box<dyn Fn(f64) -> f64>;

/// Named time bases `phi_k(t)` (each costs 3 parameters, one per axis) over a log ending at `t_end`.
fn time_bases(t_end: f64) -> Vec<(String, Vec<Basis>)> {
    let warm = |tau: f64| Box::new(move |t: f64| warm_up(t, tau)) as Box<dyn Fn(f64) -> f64>;
    let mut out: Vec<(String, Vec<Basis>)> = Vec::new();
    for f in TAU_FACTORS {
        out.push((format!("bias (1 - exp(-t / {:.0} s))", f * t_end), vec![warm(f * t_end)]));
    }
    for (i, f1) in TAU_FACTORS.iter().enumerate() {
        for f2 in TAU_FACTORS.iter().skip(i + 2) {
            let detail = format!("bias with two time constants, {:.0} s and {:.0} s", f1 * t_end, f2 * t_end);
            out.push((detail, vec![warm(f1 * t_end), warm(f2 * t_end)]));
        }
    }
    for degree in 1..=3i32 {
        let bases = (1..=degree).map(|k| Box::new(move |t: f64| (t / t_end).powi(k)) as Box<dyn Fn(f64) -> f64>);
        out.push((format!("bias polynomial in time, degree {degree}"), bases.collect()));
    }
    for harmonics in HARMONICS {
        let mut bases: Vec<Box<dyn Fn(f64) -> f64>> = Vec::new();
        for j in 1..=harmonics {
            let w = std::f64::consts::PI * j as f64 / t_end;
            bases.push(Box::new(move |t: f64| (w * t).sin()));
            bases.push(Box::new(move |t: f64| (w * t).cos()));
        }
        let shortest = 2.0 * t_end / harmonics as f64;
        out.push((format!("bias wandering smoothly in time (periods down to {shortest:.0} s)"), bases));
    }
    for knots in KNOTS {
        let h = t_end / (knots - 1) as f64;
        let hats = (0..knots).map(|j| {
            Box::new(move |t: f64| (1.0 - ((t - j as f64 * h) / h).abs()).max(0.0)) as Box<dyn Fn(f64) -> f64>
        });
        out.push((format!("bias piecewise linear in time ({knots} knots, {h:.0} s apart)"), hats.collect()));
    }
    out
}

/// Scale (with or without the bias) linear in time: whether with the bias, and the description.
const SCALE_SHAPES: [(bool, &str); 2] = [(false, "scale linear in time"), (true, "bias and scale linear in time")];

/// Span of the pose temperatures, K, from which a scale changing with time may be thermal and is
/// left to the temperature family. Below it a thermal cause would need a temperature coefficient of
/// the scale beyond datasheet limits (0.01-0.05 %/K): 0.05 %/K over 1 K moves a 1 g reading by
/// 0.5 mg. On the development sets, scales sagging with the supply of a warmed-up part had
/// thermometers moving 0.07-0.46 K; warm-ups and chamber ramps move several kelvin.
const THERMAL_SPAN_K: f64 = 1.0;

/// A scale changing with time is tested: the thermometer moves by less than [`THERMAL_SPAN_K`].
fn scale_may_drift(ctx: &Context<'_>) -> bool {
    let temps = || ctx.poses.iter().filter_map(|p| p.temp);
    temps().fold(f64::NEG_INFINITY, f64::max) - temps().fold(f64::INFINITY, f64::min) < THERMAL_SPAN_K
}

/// The scale shapes the log tests ([`scale_may_drift`]).
fn scale_shapes(ctx: &Context<'_>) -> &'static [(bool, &'static str)] {
    if scale_may_drift(ctx) { &SCALE_SHAPES } else { &[] }
}

/// Degrees in time of a relative scale common to every axis: a ratiometric front end follows its
/// supply, and a shared reference its own drift, on all three axes at once. One or two parameters
/// where the per-axis scale takes three or six: a log of 12 poses, whose calibration leaves 3
/// degrees of freedom, can test it.
const COMMON_SCALE_DEGREES: [usize; 2] = [1, 2];

/// The common scale's shapes the log tests ([`scale_may_drift`]): degree and description.
fn common_scale_shapes(ctx: &Context<'_>) -> Vec<(usize, String)> {
    if !scale_may_drift(ctx) {
        return Vec::new();
    }
    COMMON_SCALE_DEGREES
        .iter()
        .map(|&d| {
            let shape = if d == 1 { "linear".to_string() } else { format!("polynomial of degree {d}") };
            (d, format!("scale common to every axis, {shape} in time"))
        })
        .collect()
}

impl Family for Drift {
    fn name(&self) -> &'static str {
        "drift"
    }

    fn within_variants(&self, ctx: &Context<'_>, within: &Within) -> Vec<WithinVariant> {
        let t_end = ctx.poses.last().map_or(1.0, |p| p.t_end).max(1e-9);
        let mut out: Vec<WithinVariant> = time_bases(t_end)
            .into_iter()
            .map(|(detail, bases)| {
                let params = 3 * bases.len();
                within.variant(ctx.m, params, detail, &|_, t, _| {
                    bases.iter().flat_map(|phi| (0..3).map(move |a| axis(a, phi(t)))).collect()
                })
            })
            .collect();
        for &(bias, detail) in scale_shapes(ctx) {
            let params = 3 + 3 * usize::from(bias);
            out.push(within.variant(ctx.m, params, detail.into(), &|p, t, _| {
                bias_scale_effect(ctx.calibrated()[p], t / t_end, 1, bias, true)
            }));
        }
        for (degree, detail) in common_scale_shapes(ctx) {
            out.push(within.variant(ctx.m, degree, detail, &|p, t, _| {
                common_scale_effect(ctx.calibrated()[p], t / t_end, degree)
            }));
        }
        out
    }

    fn evaluate(&self, ctx: &Context<'_>) -> Evaluation {
        let mut e = standard_evaluation(self, ctx);
        if let Some(fit) = smooth::best(ctx) {
            smooth::add(ctx, &mut e, fit);
        }
        match oscillates(ctx, &e).or_else(|| holds_disagree(ctx, &e)) {
            Some(why) => {
                let mut refuted = ctx.not_testable(self.name());
                refuted.candidate.detail = why;
                refuted
            }
            None => e,
        }
    }

    /// The pose-level shapes the poses can test, less those the moving holds contradict
    /// ([`moving_holds_contradict`]).
    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        let shapes = pose_shapes(ctx);
        shapes
            .iter()
            .map(|s| (s, s.variant(ctx)))
            .filter(|(s, v)| s.min_dof.is_none_or(|dof| ctx.trains_beyond(&v.extra, dof)))
            .filter(|(s, v)| !moving_holds_contradict(ctx, s, v))
            .map(|(_, v)| v)
            .collect()
    }
}

/// A pose-level shape of the drift: its charged parameters, description and the change of pose
/// `p`'s calibrated reading at time `t` (s) per coefficient; `min_dof`, the fewest training poses
/// beyond its columns in every fold for it to be tried (`None`: no such condition).
struct Shape<'a> {
    params: usize,
    detail: String,
    effect: Box<Effect<'a>>,
    min_dof: Option<usize>,
}

impl Shape<'_> {
    fn new<'a>(params: usize, detail: String, effect: impl Fn(usize, f64) -> Vec<V3> + 'a) -> Shape<'a> {
        Shape { params, detail, effect: Box::new(move |p, t, _| effect(p, t)), min_dof: None }
    }

    /// Its columns at the pose means (each pose at its hold's middle time).
    fn variant(&self, ctx: &Context<'_>) -> Variant {
        let extra = (ctx.poses.iter().zip(ctx.directions()).enumerate())
            .map(|(p, (pose, u))| {
                (self.effect)(p, pose.t_mid(), pose.rows.clone()).iter().map(|e| dot(*u, *e)).collect()
            })
            .collect();
        Variant { extra, params: self.params, detail: self.detail.clone() }
    }
}

/// A bias per axis following each of `courses` (functions of time, s).
fn bias_courses<'a>(courses: impl Fn(f64) -> Vec<f64> + 'a) -> impl Fn(usize, f64) -> Vec<V3> + 'a {
    move |_, t| courses(t).into_iter().flat_map(|c| (0..3).map(move |a| axis(a, c))).collect()
}

/// The pose-level shapes: a bias warming up with one or two time constants, polynomial in time,
/// and the scale's shapes ([`scale_shapes_in_time`]); the log ending at its last pose's middle.
fn pose_shapes<'a>(ctx: &'a Context<'_>) -> Vec<Shape<'a>> {
    let t_end = ctx.poses.last().map_or(1.0, PoseData::t_mid).max(1e-9);
    let taus = pose_level_taus(ctx, t_end);
    let mut out = Vec::new();
    for &tau in &taus {
        let detail = format!("bias (1 - exp(-t / {tau:.0} s))");
        out.push(Shape::new(4, detail, bias_courses(move |t| vec![warm_up(t, tau)])));
    }
    for (i, &t1) in taus.iter().enumerate() {
        for &t2 in taus.iter().skip(i + 2) {
            let detail = format!("bias with two time constants, {t1:.0} s and {t2:.0} s");
            out.push(Shape::new(8, detail, bias_courses(move |t| vec![warm_up(t, t1), warm_up(t, t2)])));
        }
    }
    for degree in 1..=3usize {
        let detail = if degree == 1 {
            "bias linear in time".into()
        } else {
            format!("bias polynomial in time, degree {degree}")
        };
        let powers = move |t: f64| (1..=degree).map(|k| (t / t_end).powi(k as i32)).collect();
        out.push(Shape::new(3 * degree, detail, bias_courses(powers)));
    }
    out.extend(scale_shapes_in_time(ctx, t_end));
    out
}

/// The change in the calibrated reading `f` of a bias (3 parameters) and one relative scale common
/// to every axis (1), both following the same course `c` (a ratiometric part on a sagging supply).
fn bias_and_common_scale(f: V3, c: f64) -> Vec<V3> {
    let mut e = bias_scale_effect(f, c, 1, true, false);
    e.extend(common_scale_effect(f, c, 1));
    e
}

/// Fewest training poses beyond the columns of a per-axis scale settling exponentially in every
/// fold ([`course_variants`]): its time constant is chosen among several on the same withheld poses,
/// and exactly determined (12 columns on 12 training poses) one of them predicted the withheld poses
/// of a hysteresis (the Rust generator's, a bias set by each turn; gap ratio 1006) to 0.83 of white
/// noise.
const TAU_CHOICE_MIN_DOF: usize = 1;

/// Scales that follow one course in time with more than one coefficient: per axis, settling
/// exponentially (a reference warming after power-on, each axis by its own amount; the time
/// constant a parameter too), and together with the bias, the common scale and the bias following
/// the same course (a supply's voltage, linear or settling: one cause moves both).
fn course_shapes<'a>(ctx: &'a Context<'_>, t_end: f64) -> Vec<Shape<'a>> {
    let cal = ctx.calibrated();
    let mut out = Vec::new();
    for tau in pose_level_taus(ctx, t_end) {
        let detail = format!("scale (1 - exp(-t / {tau:.0} s)) per axis");
        let per_axis = move |p: usize, t: f64| bias_scale_effect(cal[p], warm_up(t, tau), 1, false, true);
        out.push(Shape { min_dof: Some(TAU_CHOICE_MIN_DOF), ..Shape::new(4, detail, per_axis) });
        let detail = format!("bias and common scale (1 - exp(-t / {tau:.0} s))");
        out.push(Shape::new(5, detail, move |p, t| bias_and_common_scale(cal[p], warm_up(t, tau))));
    }
    let linear = move |p: usize, t: f64| bias_and_common_scale(cal[p], t / t_end);
    out.push(Shape::new(4, "bias and common scale linear in time".into(), linear));
    out
}

/// The scale shapes (per axis, and common to every axis) at the pose level, the log ending at
/// `t_end`.
fn scale_shapes_in_time<'a>(ctx: &'a Context<'_>, t_end: f64) -> Vec<Shape<'a>> {
    let cal = ctx.calibrated();
    let mut out: Vec<Shape<'a>> = scale_shapes(ctx)
        .iter()
        .map(|&(bias, detail)| {
            let effect = move |p: usize, t: f64| bias_scale_effect(cal[p], t / t_end, 1, bias, true);
            Shape::new(3 + 3 * usize::from(bias), detail.into(), effect)
        })
        .collect();
    for (degree, detail) in common_scale_shapes(ctx) {
        out.push(Shape::new(degree, detail, move |p, t| common_scale_effect(cal[p], t / t_end, degree)));
    }
    if scale_may_drift(ctx) {
        out.extend(course_shapes(ctx, t_end));
    }
    out
}

#[cfg(test)]
mod tests {
    use crate::csvio::Table;
    use crate::diagnose::math::norm;
    use crate::diagnose::{DiagnoseOptions, diagnose};
    use crate::sim::scenario::{EffectClass, SimLog, covers_every_axis, random_scenario, to_table};
    use crate::sim::{Plan, SimConfig, plan_directions, simulate_with};

    #[test]
    fn a_scale_sagging_on_every_axis_at_once_is_drift_on_twelve_poses() {
        // A ratiometric front end on a discharging supply: every axis's scale falls by 0.3 % over
        // the log, the thermometer flat. Twelve hand-placed poses leave the calibration 3 degrees of
        // freedom: the per-axis scale in time (3 parameters) cannot be tested, the common one can.
        for seed in [21, 22, 23] {
            let d = diagnose_disturbed(seed, 12, &|t, end_s, r| {
                let scale = 1.0 - 3.0e-3 * t / end_s;
                r.iter_mut().for_each(|v| *v *= scale);
            });
            assert_eq!(d.verdict, "drift", "seed {seed}: {}", d.to_text());
            let named = d.candidates.iter().find(|c| c.effect == "drift").unwrap();
            assert!(named.detail.starts_with("scale common to every axis"), "seed {seed}: {:?}", named.variants);
        }
    }

    /// A log of `poses` random poses covering every axis whose readings `disturb` changes with the
    /// time `t` (s) of a log lasting `end_s`, the thermometer flat: the diagnosis.
    fn diagnose_disturbed(
        seed: u64,
        poses: usize,
        disturb: &dyn Fn(f64, f64, &mut [f64; 3]),
    ) -> crate::diagnose::Diagnosis {
        diagnose(&disturbed_log(seed, poses, disturb), &DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT }).unwrap()
    }

    /// The log of [`diagnose_disturbed`].
    fn disturbed_log(seed: u64, poses: usize, disturb: &dyn Fn(f64, f64, &mut [f64; 3])) -> Table {
        log_of(seed, poses, &|_| {}, disturb)
    }

    /// [`disturbed_log`] with holds of 15 s and 0.3 mg of noise.
    fn quiet_log(seed: u64, poses: usize, disturb: &dyn Fn(f64, f64, &mut [f64; 3])) -> Table {
        log_of(seed, poses, &|sim| (sim.seconds_per_pose, sim.noise_mg) = (15.0, 0.3), disturb)
    }

    /// [`disturbed_log`] of a simulation `adjust` changes.
    fn log_of(
        seed: u64,
        poses: usize,
        adjust: &dyn Fn(&mut SimConfig),
        disturb: &dyn Fn(f64, f64, &mut [f64; 3]),
    ) -> Table {
        let mut scenario = random_scenario(EffectClass::None, seed);
        let mut geometry = seed;
        while !covers_every_axis(&plan_directions(&Plan::Random(poses), geometry)) {
            geometry = geometry.wrapping_add(0x1_0000_0000);
        }
        scenario.sim.plan = Plan::Random(poses);
        scenario.sim.seed = geometry;
        adjust(&mut scenario.sim);
        let sim = &scenario.sim;
        let end_s = sim.initial_rest_s + poses as f64 * (sim.seconds_per_pose + sim.move_seconds);
        let recording =
            simulate_with(sim, &mut [&mut |t: f64, _p: Option<usize>, r: &mut [f64; 3]| disturb(t, end_s, r)]);
        let temps_c = vec![25.0; recording.samples.len()];
        to_table(&SimLog { recording, temps_c }, "disturbed").unwrap()
    }

    #[test]
    fn a_drift_the_still_holds_refute_is_not_named_and_one_they_show_is() {
        // y reads 6 mg y z more (at 1 g) on 13 poses held 15 s (0.3 mg noise): the pose means move
        // with the orientation, the holds stay still. A bias warming up over hundreds of seconds
        // fits the pose means and predicts the withheld ones (held-out gains 0.81 and 0.59), but its
        // course is not in the holds (276 and 410 chi-square per coefficient apart).
        let opts = |seed| DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
        for seed in [31, 36] {
            let coupled = quiet_log(seed, 13, &|_, _, r| r[1] += 6.0e-3 * r[1] * r[2] / norm(*r));
            let d = diagnose(&coupled, &opts(seed)).unwrap();
            assert_ne!(d.verdict, "drift", "seed {seed}: {}", d.to_text());
            let (detail, _) = drift_fit(&d);
            assert!(detail.starts_with("the holds do not move"), "seed {seed}: {detail}");
            // x's bias rising by 1 mg over the same log: the holds move as the pose means do.
            let drifting = quiet_log(seed, 13, &|t, end_s, r| r[0] += 1.0e-3 * norm(*r) * t / end_s);
            let d = diagnose(&drifting, &opts(seed)).unwrap();
            assert_eq!(d.verdict, "drift", "seed {seed}: {}", d.to_text());
        }
    }

    #[test]
    fn a_shape_the_moving_holds_contradict_leaves_the_drift_to_the_shapes_they_allow() {
        // A bias warming up along two directions with time constants of 10 s and 100 s (8 and 4 mg)
        // on 13 poses held 6 s after the initial rest (1 mg noise): the holds move. The best shape
        // on the pose means, a scale common to every axis in time, is 38-107 chi-square per
        // coefficient from the holds; until stop 90 that refuted the whole family.
        let opts = |seed| DiagnoseOptions { seed, ..DiagnoseOptions::DEFAULT };
        for seed in [6, 17, 38] {
            let log = log_of(seed, 13, &|sim| (sim.seconds_per_pose, sim.noise_mg) = (6.0, 1.0), &|t, _, r| {
                let (fast, slow) = (8.0e-3 * super::warm_up(t, 10.0), 4.0e-3 * super::warm_up(t, 100.0));
                let (g, along_fast, along_slow) = (norm(*r), [0.0, 0.79, -0.61], [-0.08, 0.59, 0.56]);
                (0..3).for_each(|a| r[a] += g * (fast * along_fast[a] + slow * along_slow[a]));
            });
            let d = diagnose(&log, &opts(seed)).unwrap();
            // Each pose's segment means: chi-square about 12 under white noise.
            let chi2 = d.poses.iter().map(|p| p.within_chi2).sum::<f64>() / d.poses.len() as f64;
            assert!(chi2 > 60.0, "seed {seed}: the holds move: chi-square {chi2} per pose");
            let (detail, gain) = drift_fit(&d);
            assert!(!detail.starts_with("the holds do not move"), "seed {seed}: {detail}");
            assert!(gain >= 0.1, "seed {seed}: {detail} gains {gain}");
        }
    }

    /// The drift family's best shape and held-out gain.
    fn drift_fit(d: &crate::diagnose::Diagnosis) -> (String, f64) {
        let c = d.candidates.iter().find(|c| c.effect == "drift").unwrap();
        (c.detail.clone(), c.heldout_gain)
    }

    #[test]
    fn scale_factors_creeping_each_by_its_own_amount_on_one_time_course_are_drift() {
        // Per-axis scale factors settling exponentially after power-on (a reference warming with no
        // thermometer), each axis by its own amount, tau 0.3 of the log, 20 poses: no bias moves.
        // Without the exponential scale shapes the best (a scale linear in time) gained 0.47, 0.89
        // and 0.93 on withheld poses.
        for seed in [51, 52, 53] {
            let d = diagnose_disturbed(seed, 20, &|t, end_s, r| {
                let course = 1.0 - (-t / (0.3 * end_s)).exp();
                let creep = [2.0e-3, -1.5e-3, 1.2e-3];
                r.iter_mut().zip(creep).for_each(|(v, k)| *v *= 1.0 + k * course);
            });
            let (detail, gain) = drift_fit(&d);
            assert_eq!(d.verdict, "drift", "seed {seed}: {}", d.to_text());
            assert!(detail.ends_with("per axis") && gain >= 0.8, "seed {seed}: {detail} {gain}");
        }
    }

    #[test]
    fn a_bias_and_a_common_scale_moving_together_are_drift() {
        // A ratiometric part on a sagging supply: the bias (its own direction) and every axis's
        // scale follow the supply's voltage, here a decay of time constant 0.4 of the log. Without
        // the shapes moving both together the best (a common scale, quadratic in time) gained 0.61
        // on withheld poses on seed 52.
        for seed in [51, 52, 53, 54] {
            let d = diagnose_disturbed(seed, 20, &|t, end_s, r| {
                let course = 1.0 - (-t / (0.4 * end_s)).exp();
                let bias_g = [3.0e-3, -2.5e-3, 2.0e-3];
                r.iter_mut().zip(bias_g).for_each(|(v, b)| *v = *v * (1.0 - 2.5e-3 * course) + b * course);
            });
            let (detail, gain) = drift_fit(&d);
            assert_eq!(d.verdict, "drift", "seed {seed}: {}", d.to_text());
            assert!(gain >= 0.85, "seed {seed}: {detail} {gain}");
        }
    }
}
