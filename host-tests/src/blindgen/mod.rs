//! An independent generator of accelerometer calibration logs with physical effects beyond the
//! 9-parameter linear model, for blind tests of the diagnosis tool.
//!
//! A log is a session of static poses in random orientations joined by hand rotations
//! ([`session`]), read by a sensor with a random linear truth ([`sensor::Truth`]), white noise, one
//! output unit, and at most one effect from a [`Family`]. Every log has a *twin*: the same spec and
//! the same noise with the effect switched off ([`LogSpec::twin`]).
//!
//! Why a second generator beside [`crate::sim`] (the host's simulator): this one is the blind test's
//! data source, written from the physics by someone who never saw the diagnosis's detectors, with its
//! own rotations, noise and effect models. Sharing code with `sim` (whose scenarios the detectors were
//! developed on) would let one modelling choice, or one bug, shape both the test data and what the
//! detectors expect, and the blind score would no longer measure anything. Keep it separate and do not
//! tune it to the detectors.
//!
//! ```
//! use accelcal_host::blindgen::{Family, generate, random_small_spec};
//! let spec = random_small_spec(Family::Drift, 7);
//! let log = generate(&spec);
//! let twin = generate(&spec.twin());
//! assert_eq!(log.samples.len(), twin.samples.len());
//! assert!(log.to_csv_string().starts_with("t,ax"));
//! ```

pub mod colored;
pub mod drift;
pub mod motion;
pub mod noise;
pub mod nonlinear;
pub mod orientation;
pub mod outlier;
pub mod output;
pub mod sensor;
pub mod session;
pub mod settling;
pub mod temperature;
pub use crate::vec3;

use serde_json::Value;

use noise::{Rng, STREAM_EFFECT, STREAM_NOISE, STREAM_SPEC};
use orientation::Quat;
use sensor::{Truth, Units};
use session::{Ctx, G_MPS2, HoldWindow, SessionSpec, Timeline};
use vec3::{V3, add, scale};

/// Seeds from this one on are held out: kept aside and looked at only at the end.
pub const HELD_OUT_SEED: u64 = 1_000_000;

/// Sample rates a random log is drawn from (Hz).
pub const RATES_HZ: [f64; 7] = [50.0, 100.0, 200.0, 250.0, 400.0, 500.0, 1000.0];

/// The families of effects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Family {
    /// No effect (plain, coarsely quantised, or with a varying temperature column).
    Clean,
    /// Bias changing with time.
    Drift,
    /// Bias and/or scale depending on temperature.
    Temperature,
    /// Per-axis square and cube terms of the scale.
    Nonlinearity,
    /// Transients after each rotation: exponential and/or mount ringing.
    Settling,
    /// Motion within holds: taps, sway, a bump.
    Motion,
    /// Coloured noise: random walk, Gauss-Markov, flicker.
    ColoredNoise,
    /// Outside the catalogue: one bad pose, mains pickup, hysteresis, cross-axis products.
    OutOfCatalogue,
}

impl Family {
    /// Every family.
    pub const ALL: [Self; 8] = [
        Self::Clean,
        Self::Drift,
        Self::Temperature,
        Self::Nonlinearity,
        Self::Settling,
        Self::Motion,
        Self::ColoredNoise,
        Self::OutOfCatalogue,
    ];

    /// The name used in the manifest and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Self::Clean => "clean",
            Self::Drift => "drift",
            Self::Temperature => "temperature",
            Self::Nonlinearity => "nonlinearity",
            Self::Settling => "settling",
            Self::Motion => "motion",
            Self::ColoredNoise => "colored_noise",
            Self::OutOfCatalogue => "out_of_catalogue",
        }
    }

    /// The family called `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.name() == name)
    }
}

/// How strong an effect is, in a unit natural to it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Magnitude {
    /// The value.
    pub value: f64,
    /// Its unit (e.g. `mg`).
    pub unit: &'static str,
    /// What it measures.
    pub what: &'static str,
}

/// The per-sample hooks of an effect, called in this order for every sample: `advance`, `motion`,
/// `body_force_mps2`, `response_g`, `bias_mps2`.
pub trait Injector {
    /// Updates internal state (filters, processes) to the sample at `ctx`.
    fn advance(&mut self, _ctx: &Ctx) {}
    /// Extra motion: a small rotation of the attitude (world rotation vector, rad) and a linear
    /// acceleration (world, m/s^2).
    fn motion(&mut self, _ctx: &Ctx) -> (V3, V3) {
        ([0.0; 3], [0.0; 3])
    }
    /// Extra specific force in the body frame (m/s^2), e.g. the mount ringing.
    fn body_force_mps2(&mut self, _ctx: &Ctx) -> V3 {
        [0.0; 3]
    }
    /// The axes' response to their linear input `a_g` (g): non-linearity, temperature scale.
    fn response_g(&mut self, _ctx: &Ctx, a_g: V3) -> V3 {
        a_g
    }
    /// Extra bias added to `B` (m/s^2, before `Ka^-1`).
    fn bias_mps2(&mut self, _ctx: &Ctx) -> V3 {
        [0.0; 3]
    }
}

/// What every effect tells the manifest and how it builds its injector.
pub trait EffectModel {
    /// The shape's name.
    fn shape(&self) -> String;
    /// The effect's parameters, as JSON.
    fn params(&self) -> Value;
    /// How strong it is.
    fn magnitude(&self) -> Magnitude;
    /// The per-sample injector; `rng` is the effect's own stream (for random processes).
    fn injector(&self, rng: Rng) -> Box<dyn Injector + '_>;
}

/// One effect of any family.
#[derive(Debug, Clone, PartialEq)]
pub enum Effect {
    /// See [`drift`].
    Drift(drift::Drift),
    /// See [`temperature`].
    Temperature(temperature::TempEffect),
    /// See [`nonlinear`].
    Nonlinear(nonlinear::Nonlinear),
    /// See [`settling`].
    Settling(settling::Settling),
    /// See [`motion`].
    Motion(motion::Motion),
    /// See [`colored`].
    Colored(colored::Colored),
    /// See [`outlier`].
    Outlier(outlier::Outlier),
}

impl Effect {
    /// The effect as its model.
    pub fn model(&self) -> &dyn EffectModel {
        match self {
            Self::Drift(e) => e,
            Self::Temperature(e) => e,
            Self::Nonlinear(e) => e,
            Self::Settling(e) => e,
            Self::Motion(e) => e,
            Self::Colored(e) => e,
            Self::Outlier(e) => e,
        }
    }
}

/// Everything that defines a log.
#[derive(Debug, Clone, PartialEq)]
pub struct LogSpec {
    /// The seed it was drawn from (also seeds the noise and the effect's processes).
    pub seed: u64,
    /// The family it illustrates.
    pub family: Family,
    /// The shape within the family.
    pub shape: String,
    /// The session (poses, rate, thermometer).
    pub session: SessionSpec,
    /// The linear truth.
    pub truth: Truth,
    /// Output unit.
    pub units: Units,
    /// White noise per sample and axis (mg, 1 sigma).
    pub noise_mg: f64,
    /// The effect, if any.
    pub effect: Option<Effect>,
}

impl LogSpec {
    /// The same log with the effect switched off (same session, truth and noise).
    pub fn twin(&self) -> Self {
        Self { effect: None, ..self.clone() }
    }

    /// `true` for a seed of the held-out range.
    pub fn held_out(&self) -> bool {
        self.seed >= HELD_OUT_SEED
    }

    /// Sets the effect and the shape name from it.
    pub fn set_effect(&mut self, effect: Effect) {
        self.shape = effect.model().shape();
        self.effect = Some(effect);
    }
}

/// One sample of a log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Time (s).
    pub t_s: f64,
    /// Reading in the log's unit (integer-valued for counts).
    pub accel: V3,
    /// Thermometer (deg C), if the log has one.
    pub temp_c: Option<f64>,
}

/// A generated log.
#[derive(Debug, Clone, PartialEq)]
pub struct Log {
    /// The samples.
    pub samples: Vec<Sample>,
    /// The hold windows (the first includes the rest).
    pub holds: Vec<HoldWindow>,
    /// Output unit.
    pub units: Units,
}

/// A random spec of `family` from `seed` (deterministic).
pub fn random_spec(family: Family, seed: u64) -> LogSpec {
    build_spec(family, seed, false)
}

/// Like [`random_spec`], but small for tests: 12 poses at 100 Hz (the effect is drawn for this
/// session, so its strength is as drawn).
pub fn random_small_spec(family: Family, seed: u64) -> LogSpec {
    build_spec(family, seed, true)
}

/// A random spec, optionally shrunk before the effect is drawn.
fn build_spec(family: Family, seed: u64, small: bool) -> LogSpec {
    let mut rng = Rng::new(seed, STREAM_SPEC);
    let rate_hz = RATES_HZ[rng.index(RATES_HZ.len())];
    let mut session = SessionSpec::random(&mut rng, rate_hz);
    if small {
        session.poses.truncate(12);
        session.rate_hz = 100.0;
    }
    if rng.chance(0.5) {
        session.temperature = Some(temperature::TempProfile::random_ambient(&mut rng));
    }
    let truth = Truth::random(&mut rng);
    let units = Units::random(&mut rng);
    let noise_mg = rng.log_uniform(0.2, 5.0);
    let mut spec = LogSpec { seed, family, shape: "plain".into(), session, truth, units, noise_mg, effect: None };
    randomise_effect(&mut rng, &mut spec);
    spec
}

/// Draws the family's effect (and any session change it needs) into `spec`.
fn randomise_effect(rng: &mut Rng, spec: &mut LogSpec) {
    match spec.family {
        Family::Clean => clean_shape(rng, spec),
        Family::Drift => drift::randomise(rng, spec),
        Family::Temperature => temperature::randomise(rng, spec),
        Family::Nonlinearity => nonlinear::randomise(rng, spec),
        Family::Settling => settling::randomise(rng, spec),
        Family::Motion => motion::randomise(rng, spec),
        Family::ColoredNoise => colored::randomise(rng, spec),
        Family::OutOfCatalogue => outlier::randomise(rng, spec),
    }
}

/// Clean logs: plain, coarsely quantised (noise below one LSB), with a varying thermometer, or
/// deliberately face-aligned.
fn clean_shape(rng: &mut Rng, spec: &mut LogSpec) {
    match rng.index(4) {
        0 => spec.shape = "plain".into(),
        1 => {
            spec.shape = "quantised".into();
            spec.units = Units::COARSE;
            spec.noise_mg = rng.log_uniform(0.2, 3.0);
        }
        2 => {
            spec.shape = "face_aligned".into();
            spec.session.align_to_faces(rng);
        }
        _ => {
            spec.shape = "temperature_column".into();
            let total_s = spec.session.total_s();
            spec.session.temperature = Some(temperature::TempProfile::random_varying(rng, total_s));
        }
    }
}

/// Generates the log of `spec` (deterministic).
pub fn generate(spec: &LogSpec) -> Log {
    let timeline = Timeline::new(&spec.session);
    let mut noise = Rng::new(spec.seed, STREAM_NOISE);
    let effect_rng = Rng::new(spec.seed, STREAM_EFFECT);
    let mut none = NoEffect;
    let mut boxed = spec.effect.as_ref().map(|e| e.model().injector(effect_rng));
    let injector: &mut dyn Injector = match boxed.as_mut() {
        Some(b) => b.as_mut(),
        None => &mut none,
    };
    let count = spec.session.sample_count();
    let samples = (0..count).map(|i| sample(spec, &timeline, i, injector, &mut noise)).collect();
    Log { samples, holds: timeline.holds().to_vec(), units: spec.units }
}

/// The injector of a log without effect.
struct NoEffect;

impl Injector for NoEffect {}

/// Sample `i`: kinematics, effect hooks, linear model, white noise, output unit.
fn sample(spec: &LogSpec, timeline: &Timeline, i: usize, inj: &mut dyn Injector, noise: &mut Rng) -> Sample {
    let ctx = timeline.ctx(i as f64 / spec.session.rate_hz);
    inj.advance(&ctx);
    let (attitude, accel_world) = timeline.kinematics(&ctx);
    let (extra_rot, extra_accel) = inj.motion(&ctx);
    let attitude = Quat::from_rotvec(extra_rot).then_after(attitude);
    let specific_world = add(add(accel_world, extra_accel), [0.0, 0.0, G_MPS2]);
    let f_b = add(attitude.rotate_inv(specific_world), inj.body_force_mps2(&ctx));
    let a_g = inj.response_g(&ctx, scale(spec.truth.ka_inv(f_b), 1.0 / G_MPS2));
    let bias = spec.truth.ka_inv(add(spec.truth.bias_mps2, inj.bias_mps2(&ctx)));
    let white = scale(noise.normal3(), spec.noise_mg * 1e-3 * G_MPS2);
    let f_s = add(add(scale(a_g, G_MPS2), bias), white);
    let temp_c = ctx.thermometer_c.map(|c| c + temperature::THERMOMETER_NOISE_C * noise.normal());
    Sample { t_s: ctx.t_s, accel: f_s.map(|v| spec.units.convert(v)), temp_c }
}
