//! The diagnosis's result types and its JSON document (`diagnose --json`: every candidate with its
//! held-out evidence, ranked), a `#[derive(Serialize)]` view of the result. The text and the figure
//! files are presentation: `crate::report::diagnosis`.
//!
//! Non-finite numbers serialise as `null` (serde_json's rule for `f64`); the keys come out sorted
//! because the CLI prints through [`serde_json::Value`].

use accelcal::model::Params;
use serde::{Serialize, Serializer};

use super::locate::orientation_label;

/// Step 1 and 4: the gap before and after the winning effect.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gap {
    /// Real modulus RMSE of the nominal fit, mg.
    pub real_rmse_mg: f64,
    /// Mean simulated RMSE, mg.
    pub sim_rmse_mg: f64,
    /// Standard deviation of the simulated RMSE over the repeats, mg.
    pub sim_spread_mg: f64,
    /// `(real - sim) / spread`.
    pub z: f64,
    /// See [`SIGNIFICANT_Z`](super::SIGNIFICANT_Z).
    pub significant: bool,
    /// `real / sim` with the nominal model.
    pub ratio_before: f64,
    /// Real RMSE after adding the winning effect, mg.
    pub real_rmse_after_mg: f64,
    /// Simulated RMSE after adding the winning effect, mg.
    pub sim_rmse_after_mg: f64,
    /// `real / sim` after adding the winning effect (= before for `none`).
    pub ratio_after: f64,
}

impl Gap {
    /// `significant`, or why not: too few simulated standard deviations, or a ratio below
    /// [`SIGNIFICANT_RATIO`](super::SIGNIFICANT_RATIO) (the noise model's own error).
    pub fn significance(&self) -> String {
        if self.significant {
            "significant".to_string()
        } else if self.z >= super::SIGNIFICANT_Z {
            format!(
                "not significant (ratio below {}: the noise model's own error on logs from other generators)",
                super::SIGNIFICANT_RATIO
            )
        } else {
            "not significant".to_string()
        }
    }

    /// No gap measured (no calibration could be made): every figure NaN, not significant.
    pub const UNMEASURED: Self = Self {
        real_rmse_mg: f64::NAN,
        sim_rmse_mg: f64::NAN,
        sim_spread_mg: f64::NAN,
        z: f64::NAN,
        significant: false,
        ratio_before: f64::NAN,
        real_rmse_after_mg: f64::NAN,
        sim_rmse_after_mg: f64::NAN,
        ratio_after: f64::NAN,
    };
}

/// One pose in the report.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseReport {
    /// Mid time, s.
    pub t_mid_s: f64,
    /// Static duration, s.
    pub duration_s: f64,
    /// Mean temperature, deg C.
    pub temp_c: Option<f64>,
    /// Calibrated unit direction (sensor axes).
    pub direction: [f64; 3],
    /// Modulus residual of the nominal fit, mg.
    pub residual_mg: f64,
    /// Its white-noise standard deviation, mg.
    pub expected_mg: f64,
    /// Modulus residual after the winning effect, mg (`None` for a pose it drops).
    pub residual_after_mg: Option<f64>,
    /// Modulus of the last-third mean minus that of the first third, mg.
    pub early_late_mg: f64,
    /// Chi-square of the within-pose segment means (white noise: about 12).
    pub within_chi2: f64,
}

/// Allan deviation of the longest rest.
#[derive(Debug, Clone, PartialEq)]
pub struct Allan {
    /// Duration of the longest rest, s.
    pub rest_s: f64,
    /// Cluster times, s.
    pub tau_s: Vec<f64>,
    /// Allan deviation (RMS over the axes), mg.
    pub adev_mg: Vec<f64>,
    /// White-noise prediction, mg.
    pub white_mg: Vec<f64>,
}

/// One candidate's result.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Candidate {
    /// Effect name (see [`EFFECT_NAMES`](super::EFFECT_NAMES)).
    pub effect: &'static str,
    /// `false` when the data cannot test it (e.g. no temperature column).
    pub applicable: bool,
    /// Withheld-pose ratio (penalised), 1 = fully explained.
    pub heldout_ratio: f64,
    /// `1 - ln(heldout_ratio) / ln(nominal heldout ratio)` (a ratio below 1 weighted by
    /// [`OVERSHOOT_WEIGHT`](super::OVERSHOOT_WEIGHT) for a noise model,
    /// [`VALUE_OVERSHOOT_WEIGHT`](super::VALUE_OVERSHOOT_WEIGHT) for a fit of the values).
    pub heldout_gain: f64,
    /// The gap ratio with this effect added.
    pub ratio_after: f64,
    /// Extra parameters.
    pub extra_params: usize,
    /// The chosen variant (time constant, bias/scale, dropped poses, walk).
    pub detail: String,
    /// Gain on the within-pose channel (withheld poses' movement during their holds), as for
    /// `heldout_gain`; NaN when the channel is not significant or the family does not move there.
    pub within_gain: f64,
    /// The variant chosen on the within-pose channel (empty when none).
    pub within_detail: String,
    /// Chi-square per coefficient between that variant fitted on the holds alone and on the pose
    /// means alone (a time-varying effect moves both alike); NaN when not measured.
    pub within_disagreement: f64,
    /// Every pose-level parametrisation tried, with its penalised held-out ratio (smaller is
    /// better; the chosen one is the smallest).
    #[serde(serialize_with = "variants_json")]
    pub variants: Vec<(String, f64)>,
    /// The pose-level parametrisation that fits the poses it is fitted on best (with enough residual
    /// degrees of freedom), for a gap the withheld poses cannot test; `None` when none was fitted.
    pub in_sample: Option<InSampleFit>,
}

/// A parametrisation fitted to every pose and judged on those poses alone (no pose withheld).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InSampleFit {
    /// The parametrisation.
    pub detail: String,
    /// The gap ratio it leaves on the poses it was fitted on (1 = white noise).
    pub ratio: f64,
    /// Poses beyond the design's columns.
    pub residual_dof: usize,
    /// The drop in the poses' chi-square per extra column, over the chi-square left per residual
    /// degree of freedom (an F statistic).
    pub explained_per_param: f64,
    /// The pose residuals with it (`None`: dropped).
    #[serde(skip)]
    pub after: Vec<Option<f64>>,
}

impl Candidate {
    /// The evidence for the family: the larger of its pose-level and within-pose gains.
    pub fn evidence(&self) -> f64 {
        if self.within_gain.is_finite() { self.heldout_gain.max(self.within_gain) } else { self.heldout_gain }
    }
}

/// An out-of-catalogue probe (never a verdict; see `unexplained`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Probe {
    /// The shape probed.
    pub shape: &'static str,
    /// Held-out gain, as for a candidate.
    pub heldout_gain: f64,
    /// The best parametrisation.
    pub detail: String,
    /// The smallest gap ratio a parametrisation leaves on the poses it was fitted on (NaN: none had
    /// enough residual degrees of freedom), as [`Candidate::in_sample`].
    pub in_sample_ratio: f64,
    /// Evidence by which it must exceed a family's to veto it (`unexplained`): 0, or more for a shape
    /// a catalogue family can take (a bias step is a fast drift).
    #[serde(skip)]
    pub veto_margin: f64,
    /// A bias step that a hold beside it shows as a jump: a slow change (drift, temperature) that
    /// imitates it on the pose means would move that hold as a line, so it vetoes those with no margin.
    #[serde(skip)]
    pub jump_in_hold: bool,
    /// The columns of its best parametrisation (its coefficients, without the charge of its search;
    /// one per pose left out).
    #[serde(skip)]
    pub columns: usize,
    /// For a bias step, the first pose it shifts: the step lies before that pose's hold or inside it.
    #[serde(skip)]
    pub step_before: Option<usize>,
}

/// The whole diagnosis.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    /// The file (as named in the table).
    pub file: String,
    /// Rows read.
    pub samples: usize,
    /// Units of the readings.
    pub units: String,
    /// Calibration gravity, m/s^2.
    pub gravity: f64,
    /// Seed used.
    pub seed: u64,
    /// Simulated repeats of the experiment.
    pub repeats: usize,
    /// The library's nominal parameters.
    pub params: Params,
    /// White noise per axis, mg (median within-pose standard deviation).
    pub white_mg: [f64; 3],
    /// Step 1 / 4.
    pub gap: Gap,
    /// Step 2: per pose.
    pub poses: Vec<PoseReport>,
    /// Still intervals shorter than [`MIN_POSE_S`](super::MIN_POSE_S) left out.
    pub short_poses: usize,
    /// Poses whose start or end moved with the tail of a move (a sixth and a guard sixth trimmed).
    pub tails_trimmed: usize,
    /// Short poses that moved within themselves, left out as fragments of moves.
    pub moving_fragments: usize,
    /// The factor the pose finder widened its test of a block's mean change by for correlated
    /// (low-passed) readings, when too few poses were found without it or the holds were found cut in
    /// pieces.
    pub mean_change_widened: Option<f64>,
    /// Step 2: noise.
    pub allan: Allan,
    /// Step 3.
    pub candidates: Vec<Candidate>,
    /// Out-of-catalogue probes.
    pub probes: Vec<Probe>,
    /// Held-out ratio of the nominal model.
    pub heldout_ratio_nominal: f64,
    /// Step 3 verdict: an [`EFFECT_NAMES`](super::EFFECT_NAMES) entry, `none`, or `unexplained` (a significant gap no
    /// family explains on withheld poses).
    pub verdict: &'static str,
    /// For `unexplained`: where the gap lies; for a verdict the withheld poses do not test (drift
    /// seen only within the holds): what supports it.
    pub located: Option<String>,
    /// `true` when the gap is significant and a candidate explains it (gain >= [`MIN_GAIN`](super::MIN_GAIN),
    /// or its fit to every pose alone leaves white noise: see `located`).
    pub explained: bool,
    /// Step 4.
    pub shrink: f64,
    /// Why no calibration (and so no gap) was made, when the verdict rests on the holds alone (a log
    /// whose holds move too much to keep enough still poses).
    pub not_calibrated: Option<String>,
    /// The poses left out as moving within their holds, when the verdict comes from the others
    /// (and the gap and verdict with them).
    pub disturbed_left_out: Option<String>,
}

impl Diagnosis {
    /// The applicable candidates, best held-out gain first.
    pub fn ranked(&self) -> Vec<&Candidate> {
        let mut v: Vec<&Candidate> = self.candidates.iter().filter(|c| c.applicable).collect();
        v.sort_by(|a, b| b.evidence().total_cmp(&a.evidence()));
        v
    }
}

/// `variants` as `[{"detail", "heldout_ratio"}]`.
fn variants_json<S: Serializer>(variants: &[(String, f64)], s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct Variant<'a> {
        detail: &'a str,
        heldout_ratio: f64,
    }
    s.collect_seq(variants.iter().map(|(detail, heldout_ratio)| Variant { detail, heldout_ratio: *heldout_ratio }))
}

/// The `diagnose --json` document (see the module doc for numbers and key order).
#[derive(Debug, Serialize)]
pub struct DiagnosisDocument<'a> {
    file: &'a str,
    samples: usize,
    units: &'a str,
    gravity: f64,
    seed: u64,
    repeats: usize,
    /// The number of poses (their details are under `where.per_pose`).
    poses: usize,
    /// Still intervals shorter than the least pose duration, left out.
    short_poses_left_out: usize,
    /// Poses whose start or end was trimmed as the tail of a move.
    tails_trimmed: usize,
    /// Short poses that moved within themselves, left out as fragments of moves.
    moving_fragments_left_out: usize,
    /// The pose finder's widening of its test of a block's mean change (correlated readings).
    mean_change_widened: Option<f64>,
    params: &'a Params,
    noise: NoiseSummary,
    gap: &'a Gap,
    #[serde(rename = "where")]
    located: Where<'a>,
    heldout_ratio_nominal: f64,
    candidates: &'a [Candidate],
    candidates_ranked: Vec<RankedCandidate<'a>>,
    probes: &'a [Probe],
    verdict: VerdictSummary<'a>,
    not_calibrated: Option<&'a str>,
    disturbed_left_out: Option<&'a str>,
}

/// `noise`: white noise per axis and the longest rest.
#[derive(Debug, Serialize)]
struct NoiseSummary {
    white_mg: [f64; 3],
    longest_rest_s: f64,
}

/// `where`: step 2, where the gap lies.
#[derive(Debug, Serialize)]
struct Where<'a> {
    per_pose: Vec<PoseRow<'a>>,
    by_orientation: Vec<OrientationRow>,
    time: TimeSummary,
    temperature: Option<TemperatureSummary>,
    within_pose: WithinPose,
    noise: AllanSummary<'a>,
}

/// One pose of `where.per_pose`.
#[derive(Debug, Serialize)]
struct PoseRow<'a> {
    index: usize,
    orientation: String,
    #[serde(flatten)]
    pose: &'a PoseReport,
}

/// One row of `where.by_orientation`.
#[derive(Debug, Serialize)]
struct OrientationRow {
    orientation: String,
    poses: usize,
    rms_mg: f64,
}

/// `where.time`.
#[derive(Debug, Serialize)]
struct TimeSummary {
    correlation: Option<f64>,
    rms_first_half_mg: f64,
    rms_second_half_mg: f64,
}

/// `where.temperature` (absent without a temperature column).
#[derive(Debug, Serialize)]
struct TemperatureSummary {
    correlation: Option<f64>,
    min_c: f64,
    max_c: f64,
}

/// `where.within_pose`.
#[derive(Debug, Serialize)]
struct WithinPose {
    early_late_rms_mg: f64,
    white_expected_mg: f64,
    ratio: f64,
}

/// `where.noise`: the Allan deviation of the longest rest.
#[derive(Debug, Serialize)]
struct AllanSummary<'a> {
    allan_tau_s: &'a [f64],
    allan_adev_mg: &'a [f64],
    allan_white_mg: &'a [f64],
    ratio_at_longest_tau: Option<f64>,
}

/// One entry of `candidates_ranked`.
#[derive(Debug, Serialize)]
struct RankedCandidate<'a> {
    effect: &'a str,
    heldout_gain: f64,
    within_gain: f64,
    evidence: f64,
}

/// `verdict`: step 3 and 4.
#[derive(Debug, Serialize)]
struct VerdictSummary<'a> {
    effect: &'a str,
    #[serde(rename = "where")]
    located: Option<&'a str>,
    explained: bool,
    heldout_gain: Option<f64>,
    shrink: f64,
}

impl Diagnosis {
    /// The JSON document (`diagnose --json`).
    pub fn document(&self) -> DiagnosisDocument<'_> {
        DiagnosisDocument {
            file: &self.file,
            samples: self.samples,
            units: &self.units,
            gravity: self.gravity,
            seed: self.seed,
            repeats: self.repeats,
            poses: self.poses.len(),
            short_poses_left_out: self.short_poses,
            tails_trimmed: self.tails_trimmed,
            moving_fragments_left_out: self.moving_fragments,
            mean_change_widened: self.mean_change_widened,
            params: &self.params,
            noise: NoiseSummary { white_mg: self.white_mg, longest_rest_s: self.allan.rest_s },
            gap: &self.gap,
            located: self.where_document(),
            heldout_ratio_nominal: self.heldout_ratio_nominal,
            candidates: &self.candidates,
            candidates_ranked: self.ranked().into_iter().map(RankedCandidate::from).collect(),
            probes: &self.probes,
            verdict: self.verdict_document(),
            not_calibrated: self.not_calibrated.as_deref(),
            disturbed_left_out: self.disturbed_left_out.as_deref(),
        }
    }

    /// The JSON document as a [`serde_json::Value`] (keys sorted).
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::to_value(self.document()).unwrap_or_default()
    }

    fn where_document(&self) -> Where<'_> {
        let (correlation, rms_first_half_mg, rms_second_half_mg) = self.time_stats();
        let (early_late_rms_mg, white_expected_mg) = self.within_stats();
        let by_orientation = self.by_orientation().into_iter();
        Where {
            per_pose: (self.poses.iter().enumerate())
                .map(|(index, pose)| PoseRow { index, orientation: orientation_label(pose.direction), pose })
                .collect(),
            by_orientation: by_orientation
                .map(|(orientation, poses, rms_mg)| OrientationRow { orientation, poses, rms_mg })
                .collect(),
            time: TimeSummary { correlation, rms_first_half_mg, rms_second_half_mg },
            temperature: self.temperature_stats().map(|(correlation, min_c, max_c)| TemperatureSummary {
                correlation,
                min_c,
                max_c,
            }),
            within_pose: WithinPose {
                early_late_rms_mg,
                white_expected_mg,
                ratio: early_late_rms_mg / white_expected_mg,
            },
            noise: AllanSummary {
                allan_tau_s: &self.allan.tau_s,
                allan_adev_mg: &self.allan.adev_mg,
                allan_white_mg: &self.allan.white_mg,
                ratio_at_longest_tau: self.allan.adev_mg.last().zip(self.allan.white_mg.last()).map(|(a, w)| a / w),
            },
        }
    }

    fn verdict_document(&self) -> VerdictSummary<'_> {
        let best = self.candidates.iter().find(|c| c.effect == self.verdict);
        VerdictSummary {
            effect: self.verdict,
            located: self.located.as_deref(),
            explained: self.explained,
            heldout_gain: best.map(|c| c.heldout_gain),
            shrink: self.shrink,
        }
    }
}

impl<'a> From<&'a Candidate> for RankedCandidate<'a> {
    fn from(c: &'a Candidate) -> Self {
        Self { effect: c.effect, heldout_gain: c.heldout_gain, within_gain: c.within_gain, evidence: c.evidence() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pose(t_mid_s: f64, direction: [f64; 3]) -> PoseReport {
        PoseReport {
            t_mid_s,
            duration_s: 5.0,
            temp_c: None,
            direction,
            residual_mg: 0.5,
            expected_mg: 0.1,
            residual_after_mg: None,
            early_late_mg: 0.0,
            within_chi2: 12.0,
        }
    }

    fn diagnosis() -> Diagnosis {
        let gap = Gap {
            real_rmse_mg: 2.0,
            sim_rmse_mg: 1.0,
            sim_spread_mg: 0.1,
            z: 10.0,
            significant: true,
            ratio_before: 2.0,
            real_rmse_after_mg: f64::NAN,
            sim_rmse_after_mg: 1.0,
            ratio_after: 2.0,
        };
        let candidate = Candidate {
            effect: "drift",
            applicable: true,
            heldout_ratio: 1.5,
            heldout_gain: 0.25,
            ratio_after: 1.2,
            extra_params: 3,
            detail: "tau 5 s".into(),
            within_gain: f64::NAN,
            within_detail: String::new(),
            within_disagreement: f64::NAN,
            variants: vec![("tau 5 s".into(), 1.5)],
            in_sample: None,
        };
        Diagnosis {
            file: "f.csv".into(),
            samples: 10,
            units: "g".into(),
            gravity: 9.81,
            seed: 1,
            repeats: 2,
            params: Params::default(),
            white_mg: [0.1; 3],
            gap,
            poses: vec![pose(1.0, [0.0, 0.0, 1.0]), pose(9.0, [1.0, 0.0, 0.0])],
            short_poses: 3,
            tails_trimmed: 0,
            moving_fragments: 1,
            mean_change_widened: None,
            allan: Allan { rest_s: 5.0, tau_s: vec![0.1], adev_mg: vec![0.2], white_mg: vec![0.1] },
            candidates: vec![candidate],
            probes: vec![],
            heldout_ratio_nominal: 3.0,
            verdict: "unexplained",
            located: Some("one orientation: +z".into()),
            explained: false,
            shrink: 0.0,
            not_calibrated: None,
            disturbed_left_out: None,
        }
    }

    #[test]
    fn movement_within_the_holds_that_one_pose_carries_is_placed_there() {
        // Eight poses alike but for their change within the hold: white noise gives 0.245 mg (the
        // thirds' difference of a pose mean of 0.1 mg); holds moving 0.6 mg each, or one 1.5 mg.
        let directions = [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0]];
        let moved = |changes: &dyn Fn(usize) -> f64| {
            let mut d = diagnosis();
            d.poses =
                (0..8).map(|i| PoseReport { early_late_mg: changes(i), ..pose(i as f64, directions[i % 4]) }).collect();
            crate::diagnose::locate::unexplained_location(&d)
        };
        assert_eq!(moved(&|_| 0.6), "within poses: 2.4x white noise");
        let one = moved(&|i| if i == 3 { 1.5 } else { 0.05 });
        assert_eq!(one, "within poses: 2.2x white noise, 99 % of it in pose #3");
    }

    #[test]
    fn the_document_has_the_documented_shape_and_non_finite_numbers_are_null() {
        let json = diagnosis().to_json();
        let text = json.to_string();
        assert!(text.contains(r#""variants":[{"detail":"tau 5 s","heldout_ratio":1.5}]"#), "{text}");
        assert!(json["candidates"][0]["within_gain"].is_null());
        assert!(json["gap"]["real_rmse_after_mg"].is_null());
        assert_eq!(json["candidates_ranked"][0]["evidence"], 0.25);
        let row = json["where"]["per_pose"][1].as_object().unwrap();
        let keys: Vec<&str> = row.keys().map(String::as_str).collect();
        let expected = [
            "direction",
            "duration_s",
            "early_late_mg",
            "expected_mg",
            "index",
            "orientation",
            "residual_after_mg",
            "residual_mg",
            "t_mid_s",
            "temp_c",
            "within_chi2",
        ];
        assert_eq!(keys, expected);
        assert_eq!(row["index"], 1);
        assert!(json["where"]["temperature"].is_null());
        assert_eq!(json["where"]["noise"]["ratio_at_longest_tau"], 2.0);
        assert_eq!(json["verdict"]["where"], "one orientation: +z");
        assert!(json["verdict"]["heldout_gain"].is_null());
        assert_eq!(json["poses"], 2);
        assert_eq!(json["short_poses_left_out"], 3);
        assert_eq!(json["moving_fragments_left_out"], 1);
    }
}
