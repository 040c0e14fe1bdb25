//! Streaming pose detection for large raw logs: memory stays constant whatever the file's size.
//!
//! The first [`PREFIX_BYTES`] are read as a [`Table`] (header, columns, units, and the detector's
//! settings: sample rate, block, stale repeats, noise floor, time-gap threshold); then every row of the
//! file (the prefix's, then the rest, line by line) is fed to the library's accumulator without being
//! kept. A second pass finds the lines and times of the poses' first and last samples. The checks of
//! [`super::read_csv`] apply to every row (cells, numbers, time order, physical range, NaN
//! share); the units and the detector's settings come from the prefix.

use std::fmt;
use std::io::{BufReader, Read};
use std::path::Path;

use accelcal::accumulator::{Accumulator, AccumulatorError, Pose};
use csv::ByteRecord;

use super::records::Records;
use super::rows::{Outcome, RowReader};
use super::{Columns, CsvError, MAX_SKIPPED_FRACTION, ReadOptions, Table, all_by_index};
use crate::poses::{self, AccumulateOptions, Accumulation, Detector, MAX_POSES, PoseSpan};

/// Files at least this large are read by [`stream_poses`] in `calibrate` (smaller ones in memory).
pub const STREAM_MIN_BYTES: u64 = 64 << 20;

/// Bytes read into memory first to find the header, the units and the detector's settings.
pub const PREFIX_BYTES: usize = 4 << 20;

/// Why a streamed file could not be read or its poses found.
#[derive(Debug, Clone, PartialEq)]
pub enum StreamError {
    /// The file (or a row of it).
    Csv(CsvError),
    /// The detector.
    Accumulator(String, AccumulatorError),
}

impl fmt::Display for StreamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Csv(e) => e.fmt(f),
            Self::Accumulator(file, e) => write!(f, "{file}: {e}"),
        }
    }
}

impl std::error::Error for StreamError {}

impl From<CsvError> for StreamError {
    fn from(e: CsvError) -> Self {
        Self::Csv(e)
    }
}

/// A streamed file: its prefix as a table (header, units, warnings and the rows dropped in the
/// whole file), the number of rows read and the poses found.
#[derive(Debug, Clone)]
pub struct Streamed {
    /// The prefix's table; [`Table::dropped`] and [`Table::warnings`] cover the whole file.
    pub table: Table,
    /// Data rows read in the whole file.
    pub rows: usize,
    /// The poses found; span rows count data rows read.
    pub accumulation: Accumulation,
}

/// `true` when `path` is large enough for [`stream_poses`].
pub fn is_large(path: &Path) -> bool {
    std::fs::metadata(path).is_ok_and(|m| m.len() >= STREAM_MIN_BYTES)
}

/// [`stream_poses`] with each of `poses::attempts` until the poses found are `enough`
/// (`poses::until_enough`), as [`poses::accumulate_until`] does in memory.
///
/// # Errors
/// As [`stream_poses`].
pub fn stream_holds(
    path: &Path,
    opts: &ReadOptions,
    acc_opts: &AccumulateOptions,
    prefix_bytes: usize,
    enough: impl Fn(&[Pose]) -> bool,
) -> Result<Streamed, StreamError> {
    poses::until_enough(
        acc_opts,
        |s: &Streamed| enough(&s.accumulation.poses),
        |s: &Streamed| !poses::fragmented(&s.accumulation),
        |s: &Streamed| s.accumulation.poses.len(),
        |o| stream_poses(path, opts, o, prefix_bytes),
    )
}

/// Finds the poses of a raw log without holding its rows (see the [module docs](self)), reading the
/// first `prefix_bytes` (normally [`PREFIX_BYTES`]) into memory.
///
/// # Errors
/// The [`CsvError`] of the first bad row (as [`super::read_csv`]), or the accumulator's error.
pub fn stream_poses(
    path: &Path,
    opts: &ReadOptions,
    acc_opts: &AccumulateOptions,
    prefix_bytes: usize,
) -> Result<Streamed, StreamError> {
    let file = path.display().to_string();
    if !path.exists() {
        return Err(CsvError::Missing { file }.into());
    }
    let prefix = read_prefix(path, &file, prefix_bytes)?;
    let (mut table, columns) = super::read_csv_bytes_with_columns(&file, &prefix.bytes, opts)?;
    let (prefix_len, first_line, after_cr) = (prefix.bytes.len(), prefix.lines + 1, prefix.bytes.ends_with(b"\r"));
    drop(prefix);
    let settings = Detector::derive(&table, acc_opts);
    let source = Source { path, file: &file, opts, columns: &columns, prefix_len, first_line, after_cr };
    let run = match settings.block {
        8 => source.detect::<8>(&table, &settings)?,
        16 => source.detect::<16>(&table, &settings)?,
        32 => source.detect::<32>(&table, &settings)?,
        64 => source.detect::<64>(&table, &settings)?,
        128 => source.detect::<128>(&table, &settings)?,
        _ => return Err(StreamError::Accumulator(file, AccumulatorError::InvalidConfig)),
    };
    let spans = source.spans(&table, &settings, &run.poses)?;
    let prefix_rows = table.samples.len();
    add_stream_drops(&mut table, &run.totals, prefix_rows)?;
    table.warnings.push(format!(
        "{file}: large file read as a stream: units, sample rate and noise floor from its first {prefix_rows} rows"
    ));
    let mut accumulation = Accumulation {
        poses: run.poses,
        spans,
        rejections: run.rejections,
        dropped_full: run.dropped_full,
        interruptions: run.totals.interruptions,
        block_samples: settings.block,
        sample_rate_hz: settings.sample_rate_hz,
        skipped_repeats: run.totals.skipped_repeats,
        min_noise_variance: settings.config.min_noise_variance,
        noise_variance: run.noise_variance,
        min_pose_samples: settings.config.min_pose_samples,
        mean_change_widened: settings.mean_change_widened,
    };
    settings.drop_scattered(&mut accumulation, table.median_magnitude);
    Ok(Streamed { table, rows: run.totals.rows, accumulation })
}

/// The first bytes of a file, cut after a line end, and the lines they hold.
struct Prefix {
    bytes: Vec<u8>,
    lines: usize,
}

/// The first `prefix_bytes` of the file cut after its last line end (LF, CR LF or a lone CR).
fn read_prefix(path: &Path, file: &str, prefix_bytes: usize) -> Result<Prefix, CsvError> {
    let io = |e: std::io::Error| CsvError::Io { file: file.to_string(), message: e.to_string() };
    let f = std::fs::File::open(path).map_err(io)?;
    let mut bytes = Vec::with_capacity(prefix_bytes.min(PREFIX_BYTES));
    f.take(prefix_bytes as u64).read_to_end(&mut bytes).map_err(io)?;
    let cut = bytes.iter().rposition(|&b| b == b'\n' || b == b'\r').map_or(bytes.len(), |i| i + 1);
    bytes.truncate(cut);
    let lone_cr = bytes.windows(2).filter(|w| w[0] == b'\r' && w[1] != b'\n').count();
    let lines = bytes.iter().filter(|&&b| b == b'\n').count() + lone_cr + usize::from(bytes.ends_with(b"\r"));
    Ok(Prefix { bytes, lines })
}

/// Counts over the whole file.
#[derive(Debug, Clone, Copy, Default)]
struct Totals {
    rows: usize,
    pushed: usize,
    skipped_repeats: usize,
    interruptions: u32,
    non_finite: usize,
    first_non_finite_line: usize,
    stale_flag: usize,
    truncated: usize,
}

/// What one pass over the rows does with each sample: interrupt the stream first when `gap` (a gap
/// in the time stamps, even before a skipped row), then feed it when `push` (not a stale repeat).
struct Feed {
    gap: bool,
    push: bool,
}

/// The state deciding what to do with each row, as `Run::go` in `poses` does.
struct Feeder<'a> {
    settings: &'a Detector,
    previous: Option<(Option<f64>, [f64; 3])>,
}

impl Feeder<'_> {
    fn feed(&mut self, time: Option<f64>, sample: [f64; 3], totals: &mut Totals) -> Feed {
        let previous = self.previous.replace((time, sample));
        totals.rows += 1;
        let gap = match (previous.and_then(|p| p.0), time, self.settings.gap_s) {
            (Some(t0), Some(t1), Some(gap_s)) => t1 - t0 > gap_s,
            _ => false,
        };
        if gap {
            totals.interruptions += 1;
        }
        if self.settings.skip_repeats && previous.is_some_and(|p| p.1 == sample) {
            totals.skipped_repeats += 1;
            return Feed { gap, push: false };
        }
        totals.pushed += 1;
        Feed { gap, push: true }
    }
}

/// The result of the detection pass.
struct DetectRun {
    poses: Vec<Pose>,
    rejections: accelcal::accumulator::Rejections,
    dropped_full: u32,
    noise_variance: f32,
    totals: Totals,
}

/// The file and how to read its rows.
struct Source<'a> {
    path: &'a Path,
    file: &'a str,
    opts: &'a ReadOptions,
    columns: &'a Columns,
    prefix_len: usize,
    /// File line of the first line after the prefix.
    first_line: usize,
    /// The prefix ends with a CR (an LF first after it ends no line).
    after_cr: bool,
}

impl Source<'_> {
    /// Pass 1: every row into the accumulator.
    fn detect<const BLOCK: usize>(&self, table: &Table, settings: &Detector) -> Result<DetectRun, StreamError> {
        let file = self.file.to_string();
        let mut acc = Accumulator::<f32, MAX_POSES, BLOCK>::new(settings.config)
            .map_err(|e| StreamError::Accumulator(file.clone(), e))?;
        let mut dropped_full = 0u32;
        let mut failure = None;
        let mut handle = |r: Result<_, AccumulatorError>| match r {
            Ok(_) | Err(AccumulatorError::NonFiniteSample) => {}
            Err(AccumulatorError::Full) => dropped_full += 1,
            Err(e) => failure = failure.or(Some(e)),
        };
        let mut feeder = Feeder { settings, previous: None };
        let mut totals = Totals::default();
        self.for_each_row(table, &mut totals, |_, time, sample, totals| {
            let feed = feeder.feed(time, sample, totals);
            if feed.gap {
                handle(acc.interrupt());
            }
            if feed.push {
                handle(acc.push(sample.map(|v| v as f32)));
            }
        })?;
        handle(acc.finish());
        if let Some(e) = failure {
            return Err(StreamError::Accumulator(file, e));
        }
        let (rejections, noise_variance) = (acc.rejections(), acc.noise_variance());
        Ok(DetectRun { poses: acc.poses().to_vec(), rejections, dropped_full, noise_variance, totals })
    }

    /// Pass 2: the line, time and row of each pose's first and last sample.
    fn spans(&self, table: &Table, settings: &Detector, poses: &[Pose]) -> Result<Vec<PoseSpan>, StreamError> {
        let mut wanted: Vec<usize> = poses
            .iter()
            .flat_map(|p| {
                [p.start_index as usize, (p.end_index as usize).saturating_sub(1).max(p.start_index as usize)]
            })
            .collect();
        wanted.sort_unstable();
        wanted.dedup();
        let mut found: Vec<(usize, usize, usize, Option<f64>)> = Vec::with_capacity(wanted.len());
        let mut feeder = Feeder { settings, previous: None };
        let mut totals = Totals::default();
        self.for_each_row(table, &mut totals, |line, time, sample, totals| {
            let row = totals.rows;
            if feeder.feed(time, sample, totals).push && wanted.get(found.len()) == Some(&(totals.pushed - 1)) {
                found.push((totals.pushed - 1, row, line, time));
            }
        })?;
        let at = |index: usize| found.iter().rev().find(|f| f.0 <= index).or(found.first()).copied();
        Ok(poses
            .iter()
            .filter_map(|p| {
                let first = at(p.start_index as usize)?;
                let last = at((p.end_index as usize).saturating_sub(1).max(p.start_index as usize))?;
                Some(PoseSpan {
                    first_row: first.1,
                    last_row: last.1,
                    first_line: first.2,
                    last_line: last.2,
                    start_s: first.3,
                    end_s: last.3,
                })
            })
            .collect())
    }

    /// Calls `f(line, time, sample, totals)` for every data row: the prefix table's rows, then the
    /// rest of the file's records, checked as [`super::read_csv`] checks rows.
    fn for_each_row(
        &self,
        table: &Table,
        totals: &mut Totals,
        mut f: impl FnMut(usize, Option<f64>, [f64; 3], &mut Totals),
    ) -> Result<(), StreamError> {
        for (i, sample) in table.samples.iter().enumerate() {
            f(table.line_of_row[i], table.times_s.as_ref().map(|t| t[i]), *sample, totals);
        }
        let (mut records, ends_with_newline) = self.open_rest(table)?;
        let mut check = RowCheck::new(self, table);
        let (mut record, mut next) = (ByteRecord::new(), ByteRecord::new());
        let mut current = records.next_into(&mut record)?;
        while let Some(line) = current {
            let following = records.next_into(&mut next)?;
            let last = following.is_none().then_some(ends_with_newline);
            if let Some((time, sample)) = check.row(line, &record, last, totals)? {
                f(line, time, sample, totals);
            }
            std::mem::swap(&mut record, &mut next);
            current = following;
        }
        Ok(())
    }

    /// The records after the prefix, and whether the file ends with a line end.
    fn open_rest(&self, table: &Table) -> Result<(Records<BufReader<std::fs::File>>, bool), CsvError> {
        use std::io::{Seek, SeekFrom};
        let io = |e: std::io::Error| CsvError::Io { file: self.file.to_string(), message: e.to_string() };
        let mut f = std::fs::File::open(self.path).map_err(io)?;
        let mut last = [0u8];
        let ends_with_newline = match f.seek(SeekFrom::End(-1)) {
            Ok(_) => f.read_exact(&mut last).map(|()| matches!(last[0], b'\n' | b'\r')).map_err(io)?,
            Err(_) => true,
        };
        f.seek(SeekFrom::Start(self.prefix_len as u64)).map_err(io)?;
        let reader = BufReader::with_capacity(1 << 16, f);
        let records = Records::new(self.file, reader, table.delimiter, self.first_line - 1, self.after_cr);
        Ok((records, ends_with_newline))
    }
}

/// A row's time (with a time column), seconds, and its sample in the working unit.
type TimedSample = (Option<f64>, [f64; 3]);

/// The checks of one streamed row, with the state they need (previous time and line).
struct RowCheck<'a> {
    rows: RowReader<'a>,
    source: &'a Source<'a>,
    factor: f64,
    limit: f64,
    units: super::Units,
    accel_names: &'a [String; 3],
    previous: Option<(usize, f64)>,
}

impl<'a> RowCheck<'a> {
    fn new(source: &'a Source<'a>, table: &'a Table) -> Self {
        let previous = table.times_s.as_ref().and_then(|t| Some((*table.line_of_row.last()?, *t.last()?)));
        // With every column by index any row holding them is read (the prefix checked the count).
        let by_index = all_by_index(source.opts);
        let rows = RowReader {
            file: source.file,
            columns: source.columns,
            header: &table.header,
            delimiter: table.delimiter,
            expected_cells: if by_index { source.columns.max_index() + 1 } else { table.header.len() },
            at_least: by_index,
        };
        Self {
            rows,
            source,
            factor: table.units_header.as_ref().map_or(1.0, |h| h.factor),
            limit: table.units.non_physical_limit(),
            units: table.units,
            accel_names: &table.columns.accel,
            previous,
        }
    }

    /// One record: `Ok(Some((time, sample)))` for a row read, `Ok(None)` for a row dropped (counted
    /// in `totals`), or the row's error. `last` as in [`RowReader::read`].
    fn row(
        &mut self,
        line: usize,
        record: &ByteRecord,
        last: Option<bool>,
        totals: &mut Totals,
    ) -> Result<Option<TimedSample>, CsvError> {
        let row = match self.rows.read(record, line, last)? {
            Outcome::Row(row) => row,
            Outcome::Stale => {
                totals.stale_flag += 1;
                return Ok(None);
            }
            Outcome::NonFinite => {
                totals.non_finite += 1;
                if totals.first_non_finite_line == 0 {
                    totals.first_non_finite_line = line;
                }
                return Ok(None);
            }
            Outcome::Truncated(_) => {
                totals.truncated += 1;
                return Ok(None);
            }
        };
        let sample = row.accel.map(|v| v * self.factor);
        self.check_range(line, sample)?;
        self.check_time(line, row.time)?;
        Ok(Some((row.time, sample)))
    }

    fn check_range(&self, line: usize, sample: [f64; 3]) -> Result<(), CsvError> {
        match sample.iter().position(|v| v.abs() > self.limit) {
            None => Ok(()),
            Some(axis) => Err(CsvError::Gigantic {
                file: self.source.file.to_string(),
                line,
                column: self.accel_names[axis].clone(),
                value: sample[axis],
                units: self.units,
            }),
        }
    }

    fn check_time(&mut self, line: usize, time: Option<f64>) -> Result<(), CsvError> {
        let Some(time_s) = time else { return Ok(()) };
        let previous = self.previous.replace((line, time_s));
        let Some((previous_line, previous_s)) = previous else { return Ok(()) };
        let file = self.source.file.to_string();
        if time_s == previous_s {
            return Err(CsvError::DuplicateTime { file, line, previous_line, time_s });
        }
        if time_s < previous_s {
            return Err(CsvError::NonMonotonicTime { file, line, previous_line, previous_s, time_s });
        }
        Ok(())
    }
}

/// Adds the rows dropped after the prefix to the table's counts and warnings; too many NaN rows in
/// the whole file is the same error as in memory.
fn add_stream_drops(table: &mut Table, totals: &Totals, prefix_rows: usize) -> Result<(), CsvError> {
    let file = table.file.clone();
    let all_non_finite = table.dropped.non_finite + totals.non_finite;
    let rows = totals.rows + all_non_finite;
    if all_non_finite > 1 && all_non_finite as f64 > MAX_SKIPPED_FRACTION * rows as f64 {
        let first_line = totals.first_non_finite_line;
        return Err(CsvError::TooManyNonFinite { file, skipped: all_non_finite, rows, first_line });
    }
    if totals.non_finite > 0 {
        table.warnings.push(format!(
            "{file}: {} more rows after the first {prefix_rows} skipped for NaN, infinite or empty values (first at \
             line {})",
            totals.non_finite, totals.first_non_finite_line
        ));
    }
    if totals.truncated > 0 {
        table.warnings.push(format!("{file}: last line truncated (power cut?): ignored"));
    }
    table.dropped.non_finite = all_non_finite;
    table.dropped.stale_flag += totals.stale_flag;
    table.dropped.truncated += totals.truncated;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn temp_file(name: &str, text: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("accelcal-csvstream-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        path
    }

    /// Twelve still directions of 300 rows at 100 Hz with noise and 80-row moves, a NaN row, a
    /// blank line and a comment in the middle.
    fn log() -> String {
        let s = 1.0 / 3f64.sqrt();
        let dirs = [
            [1.0, 0.0, 0.0],
            [-1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, -1.0, 0.0],
            [0.0, 0.0, 1.0],
            [0.0, 0.0, -1.0],
            [s, s, s],
            [-s, s, -s],
            [s, -s, -s],
            [-s, -s, s],
            [s, s, -s],
            [-s, s, s],
        ];
        let mut text = String::from("t,ax,ay,az\n");
        let (mut t, mut lcg) = (0.0, 9u32);
        for (k, d) in dirs.iter().enumerate() {
            for i in 0..380 {
                lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let n = (f64::from(lcg >> 16) / 65536.0 - 0.5) * 0.004;
                let w = if i < 300 { 0.0 } else { (f64::from(i - 300) * 0.3).sin() };
                text.push_str(&format!("{t:.2},{:.5},{:.5},{:.5}\n", d[0] + n + w, d[1] - n + 0.5 * w, d[2] + n - w));
                t += 0.01;
            }
            if k == 7 {
                text.push_str(&format!("{t:.2},nan,0,1\n\n# operator turned the cube\n"));
                t += 0.01;
            }
        }
        text
    }

    #[test]
    fn a_streamed_log_of_short_holds_only_falls_back_as_in_memory() {
        // Every hold knocked from its start: still intervals of 0.4 s only at 800 Hz.
        let knocked = crate::sim::knocked::knocked_log(1, 0.0, 0.4, 1000);
        let times = knocked.times_s.as_ref().unwrap();
        let mut text = String::from("t,ax,ay,az\n");
        for (t, s) in times.iter().zip(&knocked.samples) {
            text += &format!("{t:.6},{:.7},{:.7},{:.7}\n", s[0], s[1], s[2]);
        }
        let path = temp_file("short-holds.csv", &text);
        let opts = ReadOptions::default();
        let table = super::super::read_csv(&path, &opts).unwrap();
        let min_poses = crate::calib::MIN_POSES;
        let in_memory = poses::accumulate_holds(&table, &AccumulateOptions::default(), min_poses).unwrap();
        let held = stream_poses(&path, &opts, &AccumulateOptions::default(), 20_000).unwrap();
        assert!(held.accumulation.poses.len() < min_poses, "{} poses of 0.5 s", held.accumulation.poses.len());
        let enough = |p: &[Pose]| p.len() >= min_poses;
        let streamed = stream_holds(&path, &opts, &AccumulateOptions::default(), 20_000, enough).unwrap();
        assert!(in_memory.poses.len() >= min_poses, "{} poses", in_memory.poses.len());
        assert_eq!(streamed.accumulation.poses, in_memory.poses);
        assert_eq!(streamed.accumulation.min_pose_samples, in_memory.min_pose_samples);
    }

    #[test]
    fn streaming_finds_the_poses_and_spans_reading_in_memory_finds() {
        let text = log();
        let path = temp_file("log.csv", &text);
        let opts = ReadOptions::default();
        let table = super::super::read_csv(&path, &opts).unwrap();
        let in_memory = poses::accumulate(&table, &AccumulateOptions::default()).unwrap();
        let streamed = stream_poses(&path, &opts, &AccumulateOptions::default(), 2000).unwrap();
        assert!(streamed.table.samples.len() < 100, "the prefix must be a small part of the file");
        assert_eq!(in_memory.poses.len(), 12);
        assert_eq!(streamed.accumulation.poses, in_memory.poses);
        assert_eq!(streamed.accumulation.spans, in_memory.spans);
        assert_eq!(streamed.rows, table.samples.len());
        assert_eq!(streamed.table.dropped, table.dropped);
        assert_eq!(streamed.table.dropped.non_finite, 1);
    }

    #[test]
    fn streaming_skips_stale_repeats_and_breaks_at_time_gaps_as_in_memory() {
        // Every reading of `log` four times (a sensor polled at 4x its rate), and a 5 s gap in a hold.
        let mut text = String::from("t,ax,ay,az\n");
        let mut t = 0.0;
        for (k, line) in log().lines().skip(1).filter(|l| l.contains(',') && !l.contains("nan")).enumerate() {
            let values = line.split_once(',').unwrap().1;
            for copy in 0..4 {
                // The gap falls before a repeated copy: the stream is interrupted all the same.
                if k == 2000 && copy == 2 {
                    t += 5.0;
                }
                text.push_str(&format!("{t:.4},{values}\n"));
                t += 0.0025;
            }
        }
        let path = temp_file("stale_gap.csv", &text);
        let opts = ReadOptions::default();
        let table = super::super::read_csv(&path, &opts).unwrap();
        let in_memory = poses::accumulate(&table, &AccumulateOptions::default()).unwrap();
        let streamed = stream_poses(&path, &opts, &AccumulateOptions::default(), 4000).unwrap().accumulation;
        assert!(in_memory.skipped_repeats > 10_000 && in_memory.interruptions == 1, "{in_memory:?}");
        assert_eq!((streamed.skipped_repeats, streamed.interruptions), (in_memory.skipped_repeats, 1));
        assert_eq!(streamed.poses, in_memory.poses);
        assert_eq!(streamed.spans, in_memory.spans);
    }

    #[test]
    fn streamed_rows_are_checked_with_their_line() {
        let text = log();
        let lines: Vec<&str> = text.lines().collect();
        let mut bad = lines.clone();
        bad[3000] = "29.99,0,zero,1";
        let path = temp_file("bad_cell.csv", &(bad.join("\n") + "\n"));
        let e = stream_poses(&path, &ReadOptions::default(), &AccumulateOptions::default(), 2000).unwrap_err();
        assert!(e.to_string().contains("bad_cell.csv:3001: column `ay`: `zero` is not a number"), "{e}");
        let mut backwards = lines.clone();
        backwards[4000] = "1.00,0,0,1";
        let path = temp_file("backwards.csv", &(backwards.join("\n") + "\n"));
        let e = stream_poses(&path, &ReadOptions::default(), &AccumulateOptions::default(), 2000).unwrap_err();
        assert!(e.to_string().contains("backwards.csv:4001: time goes backwards"), "{e}");
        let path = temp_file("truncated.csv", &(text.clone() + "99.99,0.1"));
        let streamed = stream_poses(&path, &ReadOptions::default(), &AccumulateOptions::default(), 2000).unwrap();
        assert_eq!(streamed.table.dropped.truncated, 1);
        assert!(streamed.table.warnings.iter().any(|w| w.contains("truncated")), "{:?}", streamed.table.warnings);
    }

    #[test]
    fn lone_cr_and_cr_lf_files_stream_as_lf_with_the_same_lines() {
        let text = log();
        let lf = temp_file("lines_lf.csv", &text);
        let opts = (ReadOptions::default(), AccumulateOptions::default());
        let expected = stream_poses(&lf, &opts.0, &opts.1, 2000).unwrap().accumulation;
        for (name, end) in [("lines_cr.csv", "\r"), ("lines_crlf.csv", "\r\n")] {
            let body = text.replace('\n', end);
            // The prefix ends on a CR: in the CR LF file the LF after it must not count as a line.
            let prefix = body[2000..].find('\r').unwrap() + 2001;
            let path = temp_file(name, &body);
            let streamed = stream_poses(&path, &opts.0, &opts.1, prefix).unwrap().accumulation;
            assert_eq!(streamed.poses, expected.poses, "{name}");
            assert_eq!(streamed.spans, expected.spans, "{name}");
        }
        let bad = text.replacen("29.99,", "29.99,x", 1).replace('\n', "\r");
        let e = stream_poses(&temp_file("bad_cr.csv", &bad), &opts.0, &opts.1, 2000).unwrap_err();
        assert!(e.to_string().contains("bad_cr.csv:3001: column `ax`"), "{e}");
    }

    #[test]
    fn quoted_cells_and_whitespace_delimited_rows_stream_as_in_memory() {
        let text = log();
        let quoted: String = text.lines().map(|l| format!("\"{}\"\n", l.replacen(',', "\",\"", 3))).collect();
        let spaced: String = text.lines().map(|l| format!("  {}\n", l.replace(',', "   "))).collect();
        let tabbed: String = text.lines().map(|l| format!("{}\n", l.replace(',', " \t "))).collect();
        for (name, body) in [("quoted.csv", quoted), ("spaced.csv", spaced), ("tabbed.csv", tabbed)] {
            let path = temp_file(name, &body);
            let table = super::super::read_csv(&path, &ReadOptions::default()).unwrap();
            let in_memory = poses::accumulate(&table, &AccumulateOptions::default()).unwrap();
            let streamed = stream_poses(&path, &ReadOptions::default(), &AccumulateOptions::default(), 2000).unwrap();
            assert_eq!(in_memory.poses.len(), 12, "{name}");
            assert_eq!(streamed.accumulation.poses, in_memory.poses, "{name}");
            assert_eq!(streamed.accumulation.spans, in_memory.spans, "{name}");
        }
    }
}
