//! Reading a CSV file and calibrating its poses: the options shared by `calibrate` and `diagnose`,
//! and the whole `calibrate` pipeline (read, find poses or take the means, calibrate, leave-one-out).

use std::path::{Path, PathBuf};

use accelcal::accumulator::Pose;
use accelcal::calibrate::{CalibrationConfig, Init, Method};
use accelcal::model::{PARAM_COUNT, Params};
use accelcal_host::calib;
use accelcal_host::csvio::{self, AccumulateOptions, ColumnSpec, ReadOptions, Units};
use accelcal_host::io::stream as csvstream;

use super::Failure;

/// How to read a CSV file (shared by the commands that read one).
#[derive(clap::Args)]
pub(super) struct InputArgs {
    /// The CSV file (header row required).
    pub(super) file: PathBuf,
    /// Columns to use: t,ax,ay,az or t,ax,ay,az,temp, as header names or 0-based indices.
    #[arg(long)]
    pub(super) columns: Option<ColumnSpec>,
    /// Units of the acceleration columns (auto: from the header's unit label or the readings' size).
    #[arg(long, value_enum, ignore_case = true, default_value_t = UnitsArg::Auto)]
    pub(super) units: UnitsArg,
    /// Rows are per-pose means (optional `n` column), not raw samples.
    #[arg(long)]
    pub(super) means: bool,
    /// Local gravity, m/s^2.
    #[arg(long, default_value_t = 9.80665)]
    pub(super) gravity: f64,
    /// Initial estimate: auto (ellipsoid fit of the pose means, any orientations; the six faces when no
    /// ellipsoid fits), ellipsoid, or six-position (the paper's: each axis pointed up and down).
    #[arg(long, value_enum, default_value_t = InitArg::Auto)]
    pub(super) init: InitArg,
    /// Read a raw log as a stream (constant memory; automatic from 64 MB): units, rate and noise floor
    /// from its first 4 MB.
    #[arg(long)]
    pub(super) stream: bool,
    /// Segment the raw log by this label column (one pose per contiguous run of a label) instead of
    /// detecting still intervals.
    #[arg(long, value_name = "NAME", conflicts_with = "means")]
    pub(super) pose_column: Option<String>,
}

impl InputArgs {
    /// The reading options these arguments give.
    pub(super) fn read_options(&self, means: bool) -> ReadOptions {
        ReadOptions { columns: self.columns.clone(), units: self.units.into(), means, delimiter: None }
    }
}

/// `--units`: [`Units`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum UnitsArg {
    Auto,
    #[value(alias = "count", alias = "raw", alias = "lsb")]
    Counts,
    G,
    #[value(alias = "m/s^2", alias = "m/s2", alias = "ms2", alias = "m/s/s")]
    Mps2,
}

impl From<UnitsArg> for Units {
    fn from(a: UnitsArg) -> Self {
        match a {
            UnitsArg::Auto => Self::Auto,
            UnitsArg::Counts => Self::Counts,
            UnitsArg::G => Self::G,
            UnitsArg::Mps2 => Self::Mps2,
        }
    }
}

/// `--init`: the library's [`Init`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum InitArg {
    Auto,
    Ellipsoid,
    SixPosition,
}

impl From<InitArg> for Init {
    fn from(a: InitArg) -> Self {
        match a {
            InitArg::Auto => Self::Auto,
            InitArg::Ellipsoid => Self::Ellipsoid,
            InitArg::SixPosition => Self::SixPosition,
        }
    }
}

/// `--method`: the library's [`Method`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub(super) enum MethodArg {
    #[value(name = "taga+lm")]
    TagaLm,
    Taga,
    Lm,
    Newton,
}

impl From<MethodArg> for Method {
    fn from(a: MethodArg) -> Self {
        match a {
            MethodArg::TagaLm => Self::TagaLm,
            MethodArg::Taga => Self::Taga,
            MethodArg::Lm => Self::Lm,
            MethodArg::Newton => Self::Newton,
        }
    }
}

/// A file read, its poses found and calibrated.
pub(super) struct Loaded {
    pub(super) table: csvio::Table,
    pub(super) poses: Vec<Pose>,
    pub(super) spans: Option<Vec<csvio::PoseSpan>>,
    pub(super) host: calib::HostCalibration,
    /// The configuration calibrated with.
    pub(super) config: CalibrationConfig,
    /// Rows the pose detection skipped as stale repeats.
    pub(super) stale_repeats: usize,
    /// Still intervals of a raw log left out of the poses.
    pub(super) left_out: Option<StillLeftOut>,
    /// Data rows read (a large file's `table` holds only its first rows).
    pub(super) rows: usize,
}

/// A file read: the table (a large raw log's first rows only), its data rows, and for a large raw log
/// the poses found while streaming it (constant memory).
fn read_input(input: &InputArgs) -> Result<(csvio::Table, usize, Option<csvio::Accumulation>), Failure> {
    let opts = input.read_options(input.means);
    let large = input.stream || csvstream::is_large(&input.file);
    if input.means || input.pose_column.is_some() || !large {
        let table = csvio::read_csv(&input.file, &opts).map_err(|e| e.to_string())?;
        let rows = table.samples.len();
        return Ok((table, rows, None));
    }
    let acc_opts = AccumulateOptions::default();
    let enough = enough_to_calibrate(input);
    let streamed = csvstream::stream_holds(&input.file, &opts, &acc_opts, csvstream::PREFIX_BYTES, enough)
        .map_err(|e| e.to_string())?;
    Ok((streamed.table, streamed.rows, Some(streamed.accumulation)))
}

/// Poses found: the poses, their spans in a raw log, the stale repeats skipped.
type FoundPoses = (Vec<Pose>, Option<Vec<csvio::PoseSpan>>, usize, Option<StillLeftOut>);

/// Still intervals the pose finder left out of a raw log, and the shortest pose it kept.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(super) struct StillLeftOut {
    /// Shorter than the shortest pose.
    pub(super) too_short: u32,
    /// Moving more than noise allows.
    pub(super) moving: u32,
    /// A reading at the sensor's full scale.
    pub(super) saturated: u32,
    /// The shortest pose kept, seconds (with a known sample rate).
    pub(super) shortest_pose_s: Option<f64>,
    /// The shortest pose kept, readings.
    pub(super) shortest_pose_samples: u32,
    /// The factor the still test's limit on a block's mean change was widened by for correlated
    /// (low-passed) readings, when fewer than six poses were found without it.
    pub(super) mean_change_widened: Option<f64>,
}

impl StillLeftOut {
    fn of(acc: &csvio::Accumulation) -> Self {
        let r = acc.rejections;
        let shortest_pose_s = acc.sample_rate_hz.map(|rate| f64::from(acc.min_pose_samples) / rate);
        let widened = acc.mean_change_widened;
        Self {
            too_short: r.too_short,
            moving: r.moving,
            saturated: r.saturated,
            shortest_pose_s,
            shortest_pose_samples: acc.min_pose_samples,
            mean_change_widened: widened,
        }
    }

    /// The text line, when any interval was left out.
    pub(super) fn line(&self) -> Option<String> {
        let shortest = match self.shortest_pose_s {
            Some(s) => format!(" (shorter than {s:.2} s)"),
            None => format!(" (shorter than {} readings)", self.shortest_pose_samples),
        };
        let widened = self.mean_change_widened.map_or(String::new(), |c| {
            format!(
                "; readings correlated (a low-pass filter): the limit on a block's mean change widened {c:.1}x, as too few \
                 poses were found without it"
            )
        });
        (self.too_short + self.moving + self.saturated > 0 || !widened.is_empty()).then(|| {
            format!(
                "still intervals left out: {} too short{shortest}, {} moving, {} saturated{widened}",
                self.too_short, self.moving, self.saturated
            )
        })
    }
}

/// The poses of the table: the means, the label runs, or the still intervals found (streamed or
/// not), with their spans and the stale repeats skipped.
fn find_poses(
    input: &InputArgs,
    table: &csvio::Table,
    streamed: Option<csvio::Accumulation>,
) -> Result<FoundPoses, Failure> {
    if input.means {
        return Ok((csvio::to_poses_from_means(table), None, 0, None));
    }
    if let Some(column) = &input.pose_column {
        return Ok((accelcal_host::labelled::poses_by_label(table, &input.file, column)?, None, 0, None));
    }
    let acc = match streamed {
        Some(acc) => check_accumulation(acc, &input.file)?,
        None => accumulate_all(table, input)?,
    };
    let left_out = StillLeftOut::of(&acc);
    Ok((acc.poses, Some(acc.spans), acc.skipped_repeats, Some(left_out)))
}

/// The whole `calibrate` pipeline: read, find poses (or take the means), calibrate, leave-one-out.
pub(super) fn load_and_calibrate(input: &InputArgs, method: Method, seed: u64, warn: bool) -> Result<Loaded, Failure> {
    calib::check_gravity_positive(input.gravity)?;
    let (table, rows, streamed) = read_input(input)?;
    calib::check_gravity(input.gravity, table.units, table.median_magnitude)
        .map_err(|e| format!("{}: {e}", input.file.display()))?;
    if warn {
        for w in &table.warnings {
            eprintln!("accelcal: warning: {w}");
        }
    }
    let (poses, spans, stale_repeats, left_out) = find_poses(input, &table, streamed)?;
    check_pose_count(&input.file, poses.len(), None)?;
    // Six faces fit biases and scales (the non-orthogonality held); nine directions or more fit all nine.
    if poses.len() < calib::MIN_POSES {
        return Err(format!(
            "{}: {} static poses found, at least {} are needed ({PARAM_COUNT} or more in different directions fit \
             all {PARAM_COUNT} parameters; hold the sensor still in more orientations)",
            input.file.display(),
            poses.len(),
            calib::MIN_POSES
        )
        .into());
    }
    let config = calibration_config(input, table.units, method);
    let host = calib::run_with_loo(&poses, &config, seed).map_err(|e| format!("{}: {e}", input.file.display()))?;
    Ok(Loaded { table, poses, spans, host, config, stale_repeats, left_out, rows })
}

/// The configuration for the file's units: "before" is the readings taken at face value in their
/// unit (counts: the coarse six-position model).
fn calibration_config(input: &InputArgs, units: Units, method: Method) -> CalibrationConfig {
    let config = input_config(input);
    let before = match units {
        Units::G => Some(Params { scale: [config.gravity; 3], ..Params::IDENTITY }),
        Units::Mps2 => Some(Params::IDENTITY),
        _ => None,
    };
    CalibrationConfig { method, before, ..config }
}

/// What the command line sets of the calibration whatever the units: gravity and initial estimate.
fn input_config(input: &InputArgs) -> CalibrationConfig {
    CalibrationConfig { gravity: input.gravity as f32, init: input.init.into(), ..CalibrationConfig::DEFAULT }
}

/// Refuses more poses than one calibration takes ([`calib::MAX_POSES`], the library's buffer),
/// naming the count and, when known, the line where the last pose that fits ends.
fn check_pose_count(file: &Path, found: usize, last_fitting_line: Option<usize>) -> Result<(), Failure> {
    let limit = calib::MAX_POSES;
    if found <= limit {
        return Ok(());
    }
    let cut = last_fitting_line.map_or(String::new(), |l| format!("; pose {limit} ends at line {l}"));
    Err(format!(
        "{}: {found} poses found, one calibration takes at most {limit}: split the log (or the means file) into \
         parts of at most {limit} poses{cut}",
        file.display()
    )
    .into())
}

/// The pose finder's test of the poses it found ([`calib::enough_poses`] with the input's initial
/// estimate and gravity): while they are not enough it tries its later settings.
fn enough_to_calibrate(input: &InputArgs) -> impl Fn(&[Pose]) -> bool {
    let config = input_config(input);
    move |poses: &[Pose]| calib::enough_poses(poses, &config)
}

/// The poses of a raw log; more than one calibration takes is an error (never a silent drop).
pub(super) fn accumulate_all(table: &csvio::Table, input: &InputArgs) -> Result<csvio::Accumulation, Failure> {
    let file = &input.file;
    let acc = csvio::accumulate_until(table, &AccumulateOptions::default(), enough_to_calibrate(input))
        .map_err(|e| format!("{}: {e}", file.display()))?;
    check_accumulation(acc, file)
}

/// The accumulation, unless it found more poses than one calibration takes.
fn check_accumulation(acc: csvio::Accumulation, file: &Path) -> Result<csvio::Accumulation, Failure> {
    let found = acc.poses.len() + acc.dropped_full as usize;
    check_pose_count(file, found, acc.spans.get(calib::MAX_POSES - 1).map(|s| s.last_line))?;
    Ok(acc)
}
