//! CSV input for the host tools: reads accelerometer recordings (raw samples or per-pose means) from
//! delimited text, finds the columns by name, resolves the units, and turns the rows into
//! [`Pose`]s, either directly (means files) or through the library's static detector
//! ([`Accumulator`]).
//!
//! Every error names the file, the line where one applies, and what is wrong, quoting at most
//! [`MAX_QUOTED_CHARS`] characters of input; nothing here panics on input. Tolerated defects get a
//! warning in [`Table::warnings`]: a truncated last line (e.g. a power cut while logging), isolated
//! NaN/inf/empty cells (those rows are skipped), a temperature column empty or NaN throughout (read
//! without it). Rows dropped are counted by reason in [`Table::dropped`] (a non-zero stale-flag
//! column, `stale`/`is_stale`, drops its row). Lines may end in LF, CR LF or a lone CR.
//!
//! ```
//! use accelcal_host::csvio::{read_csv_str, ReadOptions, Units};
//! let text = "time_s,ax,ay,az\n0.00,0.01,0.02,0.99\n0.01,0.01,0.03,1.01\n";
//! let table = read_csv_str("demo.csv", text, &ReadOptions::default()).unwrap();
//! assert_eq!(table.units, Units::G);
//! assert_eq!(table.samples.len(), 2);
//! assert_eq!(table.line_of_row, vec![2, 3]);
//! ```
//!
//! # Format
//! - A header row is required (blank lines and lines starting with `#` before it are skipped).
//! - The delimiter is detected from the header: comma, semicolon, tab, or runs of whitespace.
//!   Double-quoted cells are unquoted. With `;` as the delimiter a decimal comma (`1,5`) is accepted.
//! - Columns are found by name, case-insensitively, after dropping unit decorations (`_raw`, `_g`,
//!   `_mps2`, `(g)`, `[m/s^2]`, ...) and qualifiers such as `mean`: time `t`/`time`/`timestamp`
//!   (a `ms`/`us`/`ns` unit in the name is converted to seconds), acceleration `ax`/`acc_x`/`accx`/
//!   `accel_x`/`x`/`mean_x`/`x_mean` (and y, z), optional `temp`/`temperature` (deg C), optional
//!   `n`/`n_samples`/`count` (samples per mean), and in means files optional `std_x`/`x_std` (the
//!   per-pose standard deviation). [`ColumnSpec`] overrides the detection.
//! - A unit in the acceleration columns' names (`ax_mg`, `ax_g`, `acc_x_mps2`, `ax[m/s^2]`, `ax (g)`,
//!   `ax_lsb`) sets the units (mg is scaled to g); [`ReadOptions::units`] other than auto wins.

use std::borrow::Cow;
use std::fmt;
use std::path::Path;
use std::str::FromStr;

use accelcal::accumulator::{Accumulator, AccumulatorConfig, AccumulatorError, Pose, Rejections};
use accelcal::model::{Params, STANDARD_GRAVITY_MPS2};

use crate::stats::median;

/// Pose capacity of the accumulator used by [`accumulate`].
pub const MAX_POSES: usize = crate::calib::MAX_POSES;

/// Block lengths (samples) [`accumulate`] can use; the block length is a const generic of the
/// library's accumulator, so only these are compiled in.
pub const BLOCK_SIZES: [usize; 5] = [8, 16, 32, 64, 128];

/// Block duration [`accumulate`] aims at when the sample rate is known, seconds.
pub const TARGET_BLOCK_S: f64 = 0.16;

/// Block length used when the sample rate is unknown (no time column), samples.
pub const DEFAULT_BLOCK_SAMPLES: usize = 16;

/// Median time step (s) of raw samples above which [`read_csv`] warns that the time column is
/// probably not in seconds.
pub const MAX_PLAUSIBLE_STEP_S: f64 = 1.0;

/// Lines searched for the first all-numeric line when looking for the header below a preamble.
pub const PREAMBLE_SEARCH_LINES: usize = 1000;

/// Largest fraction of data rows that may be skipped for NaN/inf/empty cells before the file is
/// rejected instead of warned about.
pub const MAX_SKIPPED_FRACTION: f64 = 0.1;

/// Most characters of input text (a cell, a line, a header) an error message quotes.
pub const MAX_QUOTED_CHARS: usize = 80;

/// Units of the acceleration columns.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Units {
    /// Decide from the magnitudes: median |a| near 1 means g, near 9.8 means m/s^2, large values
    /// mean raw counts.
    #[default]
    Auto,
    /// Raw ADC counts (LSB), any offset and scale.
    Counts,
    /// Standard gravities.
    G,
    /// Metres per second squared.
    Mps2,
}

impl Units {
    /// Lower-case name as used on the command line (`auto`, `counts`, `g`, `mps2`).
    pub const fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Counts => "counts",
            Self::G => "g",
            Self::Mps2 => "mps2",
        }
    }

    /// One standard gravity expressed in this unit; `None` for counts and auto.
    pub const fn one_g(self) -> Option<f64> {
        match self {
            Self::G => Some(1.0),
            Self::Mps2 => Some(STANDARD_GRAVITY_MPS2 as f64),
            Self::Counts | Self::Auto => None,
        }
    }

    /// The gravity to calibrate against so that the calibrated output keeps a physical unit:
    /// 1.0 for g data (output in g), 9.80665 for m/s^2 data and for counts (output in m/s^2).
    pub const fn calibration_gravity(self) -> f32 {
        match self {
            Self::G => 1.0,
            Self::Mps2 | Self::Counts | Self::Auto => STANDARD_GRAVITY_MPS2,
        }
    }

    /// The model the "before" RMSE is judged with: no correction for data already in a physical unit
    /// (`Some(Params::IDENTITY)`), the coarse calibration (`None`) for counts.
    pub const fn before_model(self) -> Option<Params> {
        match self {
            Self::G | Self::Mps2 => Some(Params::IDENTITY),
            Self::Counts | Self::Auto => None,
        }
    }

    /// Full scale beyond which a single reading is taken as non-physical (corrupt), in this unit:
    /// 1000 g, 9806.65 m/s^2, 2^31 counts.
    pub const fn non_physical_limit(self) -> f64 {
        match self {
            Self::G => 1000.0,
            Self::Mps2 => 1000.0 * STANDARD_GRAVITY_MPS2 as f64,
            Self::Counts | Self::Auto => 2_147_483_648.0,
        }
    }
}

impl fmt::Display for Units {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A units name that is not `auto`, `counts`, `g` or `mps2`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnitsParseError(pub String);

impl fmt::Display for UnitsParseError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "unknown units `{}`: expected auto, counts, g or mps2", self.0)
    }
}

impl std::error::Error for UnitsParseError {}

impl FromStr for Units {
    type Err = UnitsParseError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s.trim().to_ascii_lowercase().as_str() {
            "auto" => Ok(Self::Auto),
            "counts" | "count" | "raw" | "lsb" => Ok(Self::Counts),
            "g" => Ok(Self::G),
            "mps2" | "m/s^2" | "m/s2" | "ms2" | "m/s/s" => Ok(Self::Mps2),
            _ => Err(UnitsParseError(s.to_string())),
        }
    }
}

/// A column chosen by header name (case-insensitive, exact after trimming) or by 0-based index.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ColumnRef {
    /// Header name.
    Name(String),
    /// 0-based position.
    Index(usize),
}

impl fmt::Display for ColumnRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Name(n) => write!(f, "`{n}`"),
            Self::Index(i) => write!(f, "column index {i}"),
        }
    }
}

/// Explicit columns, overriding the detection by name (`--columns`).
///
/// Parsed from comma-separated entries, each a header name or a 0-based index, `-` (or nothing) for
/// an absent optional column:
/// - 3 entries: `ax,ay,az` (no time);
/// - 4: `t,ax,ay,az`; 5: `t,ax,ay,az,temp`; 6: `t,ax,ay,az,temp,n`.
///
/// With a spec only the listed columns are read (no per-pose standard deviations).
///
/// ```
/// use accelcal_host::csvio::{ColumnRef, ColumnSpec};
/// let spec: ColumnSpec = "-,1,2,3,temp_C".parse().unwrap();
/// assert_eq!(spec.time, None);
/// assert_eq!(spec.accel[0], ColumnRef::Index(1));
/// assert_eq!(spec.temp, Some(ColumnRef::Name("temp_C".into())));
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnSpec {
    /// Time column (seconds, or the unit in its header name).
    pub time: Option<ColumnRef>,
    /// x, y, z acceleration columns.
    pub accel: [ColumnRef; 3],
    /// Temperature column, deg C.
    pub temp: Option<ColumnRef>,
    /// Sample-count column (means files).
    pub count: Option<ColumnRef>,
}

/// A `--columns` value that cannot be parsed.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ColumnSpecError {
    /// The spec as given.
    pub spec: String,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for ColumnSpecError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "bad column spec `{}`: {} (expected `ax,ay,az`, `t,ax,ay,az`, `t,ax,ay,az,temp` or \
             `t,ax,ay,az,temp,n`; names or 0-based indices; `-` for none)",
            clip(&self.spec),
            self.reason
        )
    }
}

impl std::error::Error for ColumnSpecError {}

impl FromStr for ColumnSpec {
    type Err = ColumnSpecError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let err = |reason: String| ColumnSpecError { spec: s.to_string(), reason };
        let entries: Vec<Option<ColumnRef>> = s
            .split(',')
            .map(|e| {
                let e = e.trim();
                if e.is_empty() || e == "-" {
                    None
                } else if let Ok(i) = e.parse::<usize>() {
                    Some(ColumnRef::Index(i))
                } else {
                    Some(ColumnRef::Name(e.to_string()))
                }
            })
            .collect();
        let (time, rest) = match entries.len() {
            3 => (None, &entries[..]),
            4..=6 => (entries[0].clone(), &entries[1..]),
            n => return Err(err(format!("{n} entries"))),
        };
        let axis =
            |i: usize| rest[i].clone().ok_or_else(|| err(format!("the {} column is required", ["x", "y", "z"][i])));
        Ok(Self {
            time,
            accel: [axis(0)?, axis(1)?, axis(2)?],
            temp: rest.get(3).cloned().flatten(),
            count: rest.get(4).cloned().flatten(),
        })
    }
}

/// Cell delimiter.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Delimiter {
    /// `,`
    Comma,
    /// `;` (a decimal comma in the cells is then accepted)
    Semicolon,
    /// tab
    Tab,
    /// runs of spaces and tabs
    Whitespace,
}

impl Delimiter {
    /// Detected from the header line: the most frequent of `,` `\t` `;` (ties in that order), or
    /// whitespace when none occurs.
    pub fn detect(header: &str) -> Self {
        let count = |c: char| header.chars().filter(|&h| h == c).count();
        let candidates = [(Self::Comma, count(',')), (Self::Tab, count('\t')), (Self::Semicolon, count(';'))];
        let mut best = (Self::Whitespace, 0);
        for (d, n) in candidates {
            if n > best.1 {
                best = (d, n);
            }
        }
        best.0
    }

    fn char(self) -> Option<char> {
        match self {
            Self::Comma => Some(','),
            Self::Semicolon => Some(';'),
            Self::Tab => Some('\t'),
            Self::Whitespace => None,
        }
    }
}

/// How to read a file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ReadOptions {
    /// Explicit columns; `None` detects them by name.
    pub columns: Option<ColumnSpec>,
    /// Units of the acceleration columns. [`Units::Auto`] by default.
    pub units: Units,
    /// Each row is one pose mean (e.g. a static-interval summary), not a raw sample.
    pub means: bool,
    /// Cell delimiter; `None` (default) detects it from the header.
    pub delimiter: Option<Delimiter>,
}

/// The columns a table was read from (header names as written).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ColumnsUsed {
    /// Time column and its factor to seconds.
    pub time: Option<(String, f64)>,
    /// x, y, z acceleration columns.
    pub accel: [String; 3],
    /// Temperature column.
    pub temp: Option<String>,
    /// Sample-count column.
    pub count: Option<String>,
    /// Per-axis standard-deviation columns (means files).
    pub std: Option<[String; 3]>,
}

/// A file read into columns. Row `i` of every column comes from file line `line_of_row[i]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// The file name as given (used in messages).
    pub file: String,
    /// Time of each row, seconds (from the time column), strictly increasing.
    pub times_s: Option<Vec<f64>>,
    /// x, y, z acceleration per row, in [`Table::units`] (raw counts are kept as given).
    pub samples: Vec<[f64; 3]>,
    /// Temperature per row, deg C.
    pub temps_c: Option<Vec<f64>>,
    /// Samples averaged per row (means files with an `n` column).
    pub counts_n: Option<Vec<u32>>,
    /// Per-axis standard deviation per row (means files with `std_x`... columns), in [`Table::units`].
    pub std_devs: Option<Vec<[f64; 3]>>,
    /// The resolved units (never [`Units::Auto`]).
    pub units: Units,
    /// `true` when the units were detected, not declared.
    pub units_detected: bool,
    /// The unit the column names declare (`ax_mg`, `ax (g)`, ...), when they did and `--units` did
    /// not override it; the values were scaled by its factor.
    pub units_header: Option<HeaderUnit>,
    /// Median of |a| over the rows, in [`Table::units`].
    pub median_magnitude: f64,
    /// 1-based file line of each row.
    pub line_of_row: Vec<usize>,
    /// Tolerated defects, one message each (how many and where).
    pub warnings: Vec<String>,
    /// The delimiter used.
    pub delimiter: Delimiter,
    /// The header cells as read.
    pub header: Vec<String>,
    /// The columns the values came from.
    pub columns: ColumnsUsed,
    /// Data rows not read into the table, by reason.
    pub dropped: DroppedRows,
}

/// Data rows [`read_csv`] dropped, by reason (each row counted once).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DroppedRows {
    /// A needed cell empty, NaN or infinite.
    pub non_finite: usize,
    /// Marked stale by a stale-flag column (`stale`, `is_stale`, ...: non-zero).
    pub stale_flag: usize,
    /// A truncated last line (a power cut while logging).
    pub truncated: usize,
}

/// A unit named in an acceleration column's header, e.g. `mg` in `ax_mg`.
#[derive(Debug, Clone, PartialEq)]
pub struct HeaderUnit {
    /// The column whose name says it.
    pub column: String,
    /// The unit as named (`g`, `mg`, `m/s^2`, `counts`).
    pub label: &'static str,
    /// The working unit the values are read in.
    pub units: Units,
    /// Factor from the named unit to the working unit (`mg` to `g`: 0.001).
    pub factor: f64,
}

/// The unit a column name declares: its last unit token (`ax_mg`, `acc_x_mps2`, `ax[m/s^2]`, `ax (g)`).
fn header_unit(name: &str) -> Option<HeaderUnit> {
    let (label, units, factor) = tokens(name).iter().rev().find_map(|t| match t.as_str() {
        "g" => Some(("g", Units::G, 1.0)),
        "mg" => Some(("mg", Units::G, 1e-3)),
        "mps2" | "ms2" | "si" => Some(("m/s^2", Units::Mps2, 1.0)),
        // `raw` often means uncalibrated (in g or m/s^2), not counts: it declares nothing.
        "lsb" | "counts" | "cnt" => Some(("counts", Units::Counts, 1.0)),
        _ => None,
    })?;
    Some(HeaderUnit { column: name.to_string(), label, units, factor })
}

impl Table {
    /// Appends one row read from file line `line`.
    fn push_row(&mut self, row: Row, line: usize) {
        self.samples.push(row.accel);
        self.line_of_row.push(line);
        if let (Some(t), Some(v)) = (self.times_s.as_mut(), row.time) {
            t.push(v);
        }
        if let (Some(t), Some(v)) = (self.temps_c.as_mut(), row.temp) {
            t.push(v);
        }
        if let (Some(n), Some(v)) = (self.counts_n.as_mut(), row.count) {
            n.push(v);
        }
        if let Some(s) = self.std_devs.as_mut() {
            s.push(row.std);
        }
    }

    /// What the units are and why, e.g. `g (detected: median |a| = 0.998)`.
    pub fn units_summary(&self) -> String {
        let how = match &self.units_header {
            Some(h) if h.factor != 1.0 => format!("header `{}`: {}, scaled by {}", clip(&h.column), h.label, h.factor),
            Some(h) => format!("header `{}`", clip(&h.column)),
            None if self.units_detected => "detected".to_string(),
            None => "declared".to_string(),
        };
        format!("{} ({how}: median |a| = {:.4} {})", self.units, self.median_magnitude, self.units)
    }

    /// Mean sample rate from the time column, `(rows - 1) / (t_last - t_first)`, Hz; `None` without
    /// times or with fewer than two rows.
    pub fn sample_rate_hz(&self) -> Option<f64> {
        let t = self.times_s.as_ref()?;
        let span_s = t.last()? - t.first()?;
        (t.len() >= 2 && span_s > 0.0).then(|| (t.len() - 1) as f64 / span_s)
    }
}

/// Why a file could not be read. Display always names the file and, where one applies, the line.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum CsvError {
    /// The file does not exist.
    Missing {
        /// File.
        file: String,
    },
    /// Another I/O error.
    Io {
        /// File.
        file: String,
        /// The system's message.
        message: String,
    },
    /// The file is empty (or only blank lines and comments).
    Empty {
        /// File.
        file: String,
    },
    /// Not text: NUL bytes or invalid UTF-8.
    Binary {
        /// File.
        file: String,
        /// Line of the first offending byte.
        line: usize,
        /// What was found.
        what: &'static str,
    },
    /// The first line is numbers, not a header.
    NoHeader {
        /// File.
        file: String,
        /// Line.
        line: usize,
        /// The line's text.
        text: String,
    },
    /// A header and no data rows.
    HeaderOnly {
        /// File.
        file: String,
        /// Line of the header.
        line: usize,
    },
    /// Required columns not found by name.
    MissingColumns {
        /// File.
        file: String,
        /// Line of the header.
        line: usize,
        /// Which columns are missing (`ax`, `ay`, `az`).
        missing: Vec<&'static str>,
        /// The header cells seen.
        header: Vec<String>,
    },
    /// A column of the `--columns` spec is not in the header.
    UnknownColumn {
        /// File.
        file: String,
        /// Line of the header.
        line: usize,
        /// The column asked for.
        requested: String,
        /// The header cells seen.
        header: Vec<String>,
    },
    /// Several columns match one role.
    AmbiguousColumn {
        /// File.
        file: String,
        /// Line of the header.
        line: usize,
        /// The role (`ax`, `time`, ...).
        role: &'static str,
        /// The matching header cells.
        candidates: Vec<String>,
    },
    /// A row has the wrong number of cells.
    RaggedRow {
        /// File.
        file: String,
        /// Line.
        line: usize,
        /// Cells found.
        cells: usize,
        /// Cells expected (from the header).
        expected: usize,
    },
    /// `--columns` names a column index past the last column.
    ColumnIndexOutOfRange {
        /// File.
        file: String,
        /// Line that sets the column count (the header, or the first data row when every column is
        /// given by index).
        line: usize,
        /// The largest index asked for (0-based).
        index: usize,
        /// Columns that line has.
        columns: usize,
        /// `true` when `line` is the header.
        from_header: bool,
    },
    /// A cell that should be a number is not.
    NonNumeric {
        /// File.
        file: String,
        /// Line.
        line: usize,
        /// Column name.
        column: String,
        /// The cell text.
        text: String,
    },
    /// A sample-count cell that is not a non-negative integer.
    BadCount {
        /// File.
        file: String,
        /// Line.
        line: usize,
        /// Column name.
        column: String,
        /// The cell text.
        text: String,
    },
    /// A time stamp equal to the previous one.
    DuplicateTime {
        /// File.
        file: String,
        /// Line.
        line: usize,
        /// Line of the previous row.
        previous_line: usize,
        /// The repeated time, seconds.
        time_s: f64,
    },
    /// A time stamp earlier than the previous one.
    NonMonotonicTime {
        /// File.
        file: String,
        /// Line.
        line: usize,
        /// Line of the previous row.
        previous_line: usize,
        /// Previous time, seconds.
        previous_s: f64,
        /// This time, seconds.
        time_s: f64,
    },
    /// The declared units do not fit the values.
    WrongUnits {
        /// File.
        file: String,
        /// Declared units.
        declared: Units,
        /// Median |a| in the file.
        median_magnitude: f64,
        /// What the values look like (`None` when nothing fits).
        looks_like: Option<Units>,
        /// The column whose name declared the units (`None`: `--units` declared them).
        header: Option<String>,
    },
    /// The units cannot be told from the values.
    UnknownUnits {
        /// File.
        file: String,
        /// Median |a| in the file.
        median_magnitude: f64,
    },
    /// A value no accelerometer produces (corrupt cell).
    Gigantic {
        /// File.
        file: String,
        /// Line.
        line: usize,
        /// Column name.
        column: String,
        /// The value.
        value: f64,
        /// The units it was judged in.
        units: Units,
    },
    /// Too many rows with NaN/inf/empty cells to skip them silently.
    TooManyNonFinite {
        /// File.
        file: String,
        /// Rows with such cells.
        skipped: usize,
        /// Data rows in all.
        rows: usize,
        /// Line of the first one.
        first_line: usize,
    },
}

/// The cells quoted and joined, clipped to about [`MAX_QUOTED_CHARS`] characters.
pub(crate) fn list(cells: &[String]) -> String {
    let quoted: Vec<String> = cells.iter().map(|c| format!("`{c}`")).collect();
    let joined = quoted.join(", ");
    if joined.chars().count() > MAX_QUOTED_CHARS {
        format!("{} ({} cells)", clip(&joined), cells.len())
    } else {
        joined
    }
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Missing { file } => write!(f, "{file}: no such file"),
            Self::Io { file, message } => write!(f, "{file}: cannot read: {message}"),
            Self::Empty { file } => write!(f, "{file}: the file is empty (no header, no data)"),
            Self::Binary { file, line, what } => {
                write!(f, "{file}:{line}: not a text CSV file ({what}); is it a binary (e.g. MATLAB .mat) file?")
            }
            Self::NoHeader { file, line, text } => write!(
                f,
                "{file}:{line}: expected a header row naming the columns (e.g. `t,ax,ay,az`), found data: `{}`",
                clip(text)
            ),
            Self::HeaderOnly { file, line } => write!(f, "{file}:{line}: the header is the only row; there is no data"),
            Self::MissingColumns { file, line, missing, header } => write!(
                f,
                "{file}:{line}: no column for {} in the header [{}]; name them ax/ay/az (or acc_x, x, ...) or \
                 choose them with --columns",
                missing.join(", "),
                list(header)
            ),
            Self::UnknownColumn { file, line, requested, header } => {
                write!(f, "{file}:{line}: column {} is not in the header [{}]", clip(requested), list(header))
            }
            Self::AmbiguousColumn { file, line, role, candidates } => write!(
                f,
                "{file}:{line}: several columns could be {role}: [{}]; choose with --columns",
                list(candidates)
            ),
            Self::RaggedRow { file, line, cells, expected } => {
                write!(f, "{file}:{line}: {cells} cells, the header has {expected}")
            }
            Self::ColumnIndexOutOfRange { file, line, index, columns, from_header } => write!(
                f,
                "{file}:{line}: --columns asks for column index {index}, but the {} has {columns} columns (indices \
                 0-{}); indices count from 0",
                if *from_header { "header" } else { "first data row" },
                columns.saturating_sub(1)
            ),
            Self::NonNumeric { file, line, column, text } => {
                write!(f, "{file}:{line}: column `{}`: `{}` is not a number", clip(column), clip(text))
            }
            Self::BadCount { file, line, column, text } => write!(
                f,
                "{file}:{line}: column `{}`: `{}` is not a sample count (a non-negative integer)",
                clip(column),
                clip(text)
            ),
            Self::DuplicateTime { file, line, previous_line, time_s } => write!(
                f,
                "{file}:{line}: time {time_s} s repeats line {previous_line}: time stamps must increase \
                 (drop the time column with --columns if it is not a clock)"
            ),
            Self::NonMonotonicTime { file, line, previous_line, previous_s, time_s } => write!(
                f,
                "{file}:{line}: time goes backwards, {time_s} s after {previous_s} s at line {previous_line} \
                 (concatenated captures? drop the time column with --columns)"
            ),
            Self::WrongUnits { file, declared, median_magnitude, looks_like, header } => {
                let typical = match declared {
                    Units::G => "about 1",
                    Units::Mps2 => "about 9.8",
                    _ => "hundreds to tens of thousands",
                };
                let by = header.as_ref().map_or(String::new(), |h| format!(" (as the header `{}` says)", clip(h)));
                write!(
                    f,
                    "{file}: values no accelerometer reads in {declared}{by}: the median |a| is \
                     {median_magnitude:.4}, a static accelerometer reads {typical}"
                )?;
                match (looks_like, header) {
                    (Some(u), Some(_)) => write!(f, "; the values look like {u}: use --units {u}"),
                    (Some(u), None) => write!(f, "; the values look like {u}: use --units {u} (or --units auto)"),
                    (None, _) => f.write_str("; check the columns"),
                }
            }
            Self::UnknownUnits { file, median_magnitude } => write!(
                f,
                "{file}: cannot tell the units from the values (median |a| = {median_magnitude:.4} fits neither \
                 g (~1), m/s^2 (~9.8) nor raw counts); declare them with --units"
            ),
            Self::Gigantic { file, line, column, value, units } => write!(
                f,
                "{file}:{line}: column `{}`: {value:e} {units} is not a physical accelerometer reading \
                 (limit {:e} {units}); corrupt line?",
                clip(column),
                units.non_physical_limit()
            ),
            Self::TooManyNonFinite { file, skipped, rows, first_line } => write!(
                f,
                "{file}:{first_line}: {skipped} of {rows} rows have NaN, infinite or empty values (first at line \
                 {first_line}); too many to skip"
            ),
        }
    }
}

impl std::error::Error for CsvError {}

/// Reads `path` (see the [module docs](self) for the format).
///
/// # Errors
/// A [`CsvError`] naming the file, the line where one applies and the problem; see its variants.
pub fn read_csv(path: &Path, opts: &ReadOptions) -> Result<Table, CsvError> {
    let file = path.display().to_string();
    let bytes = match std::fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Err(CsvError::Missing { file }),
        Err(e) => return Err(CsvError::Io { file, message: e.to_string() }),
    };
    read_csv_bytes(&file, &bytes, opts)
}

/// Reads CSV text held in memory; `name` stands for the file name in messages.
///
/// # Errors
/// As [`read_csv`], except the file-system errors.
pub fn read_csv_str(name: &str, text: &str, opts: &ReadOptions) -> Result<Table, CsvError> {
    read_csv_bytes(name, text.as_bytes(), opts)
}

fn line_at(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())].iter().filter(|&&b| b == b'\n').count()
}

/// Reads CSV bytes (checked for NUL bytes and UTF-8 first); `name` stands for the file name.
///
/// # Errors
/// As [`read_csv`], except the file-system errors.
pub fn read_csv_bytes(name: &str, bytes: &[u8], opts: &ReadOptions) -> Result<Table, CsvError> {
    read_csv_bytes_with_columns(name, bytes, opts).map(|(table, _)| table)
}

/// [`read_csv_bytes`], also returning the column indices read (to read more rows the same way).
pub(crate) fn read_csv_bytes_with_columns(
    name: &str,
    bytes: &[u8],
    opts: &ReadOptions,
) -> Result<(Table, Columns), CsvError> {
    let file = name.to_string();
    if let Some(pos) = bytes.iter().position(|&b| b == 0) {
        let utf16 = bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]);
        let what = if utf16 { "UTF-16 text; save it as UTF-8" } else { "NUL bytes" };
        return Err(CsvError::Binary { file, line: line_at(bytes, pos), what });
    }
    let mut notes = Vec::new();
    let text: Cow<'_, str> = match std::str::from_utf8(bytes) {
        Ok(t) => Cow::Borrowed(t),
        Err(e) => {
            let line = line_at(bytes, e.valid_up_to());
            if looks_binary(bytes) {
                return Err(CsvError::Binary { file, line, what: "invalid UTF-8" });
            }
            // Text with a few non-UTF-8 bytes, e.g. a Latin-1 degree sign from a serial monitor.
            notes.push(format!("{file}:{line}: not UTF-8; read as Latin-1 (ISO 8859-1)"));
            Cow::Owned(bytes.iter().map(|&b| char::from(b)).collect())
        }
    };
    let text = text.strip_prefix('\u{feff}').unwrap_or(&text);
    Parser { file, opts, notes }.parse_with_columns(text)
}

/// `true` for bytes that are not text in any 8-bit encoding: control characters other than tab,
/// CR, LF and form feed, or more bytes above 0x7F than a few accented letters or unit signs
/// (over 16 and over 1 % of the file).
fn looks_binary(bytes: &[u8]) -> bool {
    let control = bytes.iter().any(|&b| (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0c)) || b == 0x7f);
    let high = bytes.iter().filter(|&&b| b >= 0x80).count();
    control || (high > 16 && high * 100 > bytes.len())
}

/// What a header cell names.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Field {
    /// Time, with its factor to seconds.
    Time(f64),
    Accel(usize),
    Std(usize),
    Temp,
    Count,
    /// A flag marking stale (repeated, not new) readings: non-zero drops the row.
    Stale,
}

/// Unit and decoration tokens dropped from header names before matching.
const UNIT_TOKENS: &[&str] = &[
    "g", "mg", "mps2", "ms2", "raw", "lsb", "counts", "cnt", "adc", "si", "c", "degc", "celsius", "s", "sec", "secs",
    "seconds", "ms", "us", "ns",
];
/// Qualifier tokens dropped from header names.
const QUALIFIER_TOKENS: &[&str] =
    &["mean", "avg", "average", "1s", "value", "val", "reading", "linear", "sensor", "imu"];
/// Tokens that make a column something else than the quantity (a reference, a statistic, ...).
const EXCLUDING_TOKENS: &[&str] = &[
    "var",
    "variance",
    "min",
    "max",
    "median",
    "true",
    "ref",
    "reference",
    "expected",
    "norm",
    "magnitude",
    "bias",
    "err",
    "error",
    "offset",
    "cal",
    "calibrated",
    "first",
    "last",
    "start",
    "end",
    "index",
    "idx",
    "dropped",
];
const STD_TOKENS: &[&str] = &["std", "stdev", "stddev", "sd", "sigma"];

fn tokens(name: &str) -> Vec<String> {
    let lower = name.to_lowercase().replace("m/s^2", " mps2 ").replace("m/s²", " mps2 ").replace("m/s2", " mps2 ");
    lower.split(|c: char| !c.is_alphanumeric()).filter(|t| !t.is_empty()).map(str::to_string).collect()
}

fn axis_of(joined: &str) -> Option<usize> {
    for (axis, a) in ["x", "y", "z"].iter().enumerate() {
        let forms = [
            a.to_string(),
            format!("a{a}"),
            format!("a_{a}"),
            format!("acc{a}"),
            format!("acc_{a}"),
            format!("accel{a}"),
            format!("accel_{a}"),
            format!("acceleration{a}"),
            format!("acceleration_{a}"),
            format!("accelerometer_{a}"),
            format!("{a}_acc"),
            format!("{a}_accel"),
        ];
        if forms.iter().any(|f| f == joined) {
            return Some(axis);
        }
    }
    None
}

/// Classifies a header cell by name.
fn classify(name: &str) -> Option<Field> {
    let toks = tokens(name);
    if toks.iter().any(|t| EXCLUDING_TOKENS.contains(&t.as_str())) {
        return None;
    }
    let is_std = toks.iter().any(|t| STD_TOKENS.contains(&t.as_str()));
    let scale = time_scale(&toks);
    let kept: Vec<&str> = toks
        .iter()
        .map(String::as_str)
        .filter(|t| !UNIT_TOKENS.contains(t) && !QUALIFIER_TOKENS.contains(t) && !STD_TOKENS.contains(t))
        .collect();
    let joined = kept.join("_");
    if let Some(axis) = axis_of(&joined) {
        return Some(if is_std { Field::Std(axis) } else { Field::Accel(axis) });
    }
    if is_std {
        return None;
    }
    match joined.as_str() {
        "t" | "time" | "times" | "timestamp" | "time_stamp" | "t_center" | "elapsed" | "elapsed_time" => {
            Some(Field::Time(scale))
        }
        "temp" | "temperature" | "die_temp" | "temp_die" => Some(Field::Temp),
        "stale" | "is_stale" | "stale_flag" | "repeated" | "is_repeated" => Some(Field::Stale),
        "n" | "n_samples" | "nsamples" | "samples" | "count" | "n_kept" | "num_samples" | "sample_count" => {
            Some(Field::Count)
        }
        _ => None,
    }
}

/// Factor to seconds from the unit tokens of a time column's name.
fn time_scale(toks: &[String]) -> f64 {
    for t in toks {
        match t.as_str() {
            "ms" => return 1e-3,
            "us" => return 1e-6,
            "ns" => return 1e-9,
            _ => {}
        }
    }
    1.0
}

/// Indices of the columns to read.
#[derive(Debug, Clone, Default)]
pub(crate) struct Columns {
    pub(crate) time: Option<(usize, f64)>,
    accel: [usize; 3],
    temp: Option<usize>,
    count: Option<usize>,
    stale: Option<usize>,
    std: Option<[usize; 3]>,
}

impl Columns {
    pub(crate) fn max_index(&self) -> usize {
        let mut m = self.accel.iter().copied().max().unwrap_or(0);
        for i in [self.time.map(|t| t.0), self.temp, self.count, self.stale].into_iter().flatten() {
            m = m.max(i);
        }
        if let Some(s) = self.std {
            m = m.max(s.iter().copied().max().unwrap_or(0));
        }
        m
    }
}

pub(crate) struct Parser<'a> {
    pub(crate) file: String,
    pub(crate) opts: &'a ReadOptions,
    /// Warnings found before parsing (encoding).
    pub(crate) notes: Vec<String>,
}

/// Splits one line into trimmed, unquoted cells.
pub(crate) fn split_cells(line: &str, delimiter: Delimiter) -> Vec<Cow<'_, str>> {
    let Some(d) = delimiter.char() else {
        return line.split_whitespace().map(Cow::Borrowed).collect();
    };
    if !line.contains('"') {
        return line.split(d).map(|c| Cow::Borrowed(c.trim())).collect();
    }
    // Quote-aware split: "a,b" is one cell, "" inside quotes is a quote.
    let mut cells = Vec::new();
    let mut cell = String::new();
    let mut quoted = false;
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        if quoted {
            if c == '"' {
                if chars.peek() == Some(&'"') {
                    cell.push('"');
                    chars.next();
                } else {
                    quoted = false;
                }
            } else {
                cell.push(c);
            }
        } else if c == '"' {
            quoted = true;
        } else if c == d {
            cells.push(Cow::Owned(cell.trim().to_string()));
            cell.clear();
        } else {
            cell.push(c);
        }
    }
    cells.push(Cow::Owned(cell.trim().to_string()));
    cells
}

/// A cell as a number: `Ok(Some(v))`, `Ok(None)` for missing (empty, NaN, inf), `Err` for text.
fn parse_number(cell: &str, delimiter: Delimiter) -> Result<Option<f64>, ()> {
    if cell.is_empty() {
        return Ok(None);
    }
    let parsed = cell.parse::<f64>().or_else(|e| {
        if delimiter == Delimiter::Semicolon && cell.matches(',').count() == 1 && !cell.contains('.') {
            cell.replace(',', ".").parse::<f64>()
        } else {
            Err(e)
        }
    });
    match parsed {
        Ok(v) if v.is_finite() => Ok(Some(v)),
        Ok(_) => Ok(None),
        Err(_) => Err(()),
    }
}

/// `true` when `--columns` gives every column by index (then the first data row, not the header,
/// sets the cell count: a header may be malformed, e.g. two names run together).
pub(crate) fn all_by_index(opts: &ReadOptions) -> bool {
    opts.columns.as_ref().is_some_and(|s| {
        [Some(&s.accel[0]), Some(&s.accel[1]), Some(&s.accel[2]), s.time.as_ref(), s.temp.as_ref(), s.count.as_ref()]
            .into_iter()
            .flatten()
            .all(|c| matches!(c, ColumnRef::Index(_)))
    })
}

/// Lines ended by LF, CR LF or a lone CR (old Mac OS); a line number counts each of them once.
pub(crate) fn split_lines(text: &str) -> Vec<&str> {
    let mut lines = Vec::new();
    let mut rest = text;
    while let Some(end) = rest.find(['\n', '\r']) {
        lines.push(&rest[..end]);
        let width = if rest[end..].starts_with("\r\n") { 2 } else { 1 };
        rest = &rest[end + width..];
    }
    lines.push(rest);
    lines
}

/// At most [`MAX_QUOTED_CHARS`] characters of `text` for a message, with `...` when cut.
pub(crate) fn clip(text: &str) -> String {
    match text.char_indices().nth(MAX_QUOTED_CHARS) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text.to_string(),
    }
}

pub(crate) fn is_blank_or_comment(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

/// Units the median magnitude suggests, if any.
fn units_from_magnitude(median_magnitude: f64) -> Option<Units> {
    if (0.5..=2.0).contains(&median_magnitude) {
        Some(Units::G)
    } else if (4.9..=19.6).contains(&median_magnitude) {
        Some(Units::Mps2)
    } else if median_magnitude >= 25.0 && median_magnitude.is_finite() {
        Some(Units::Counts)
    } else {
        None
    }
}

/// `true` when declared units are plausible for the median magnitude (looser than detection).
fn units_plausible(units: Units, median_magnitude: f64) -> bool {
    match units {
        Units::G => (0.25..=4.0).contains(&median_magnitude),
        Units::Mps2 => (2.45..=39.3).contains(&median_magnitude),
        Units::Counts => median_magnitude >= 8.0,
        Units::Auto => true,
    }
}

impl Parser<'_> {
    /// The table, and the column indices it was read from.
    pub(crate) fn parse_with_columns(&self, text: &str) -> Result<(Table, Columns), CsvError> {
        let file = &self.file;
        let lines = split_lines(text);
        let (first_index, header_index) = self.find_header(&lines)?;
        let header_line = header_index + 1;
        let mut notes = self.notes.clone();
        if header_index > first_index {
            notes.push(format!(
                "{file}: lines {}-{} before the header (line {header_line}) skipped",
                first_index + 1,
                header_index
            ));
        }
        let header_text = lines[header_index];
        let delimiter = self.opts.delimiter.unwrap_or_else(|| Delimiter::detect(header_text));
        let header: Vec<String> = split_cells(header_text, delimiter).into_iter().map(|c| c.into_owned()).collect();
        let data_lines: Vec<(usize, &str)> = lines
            .iter()
            .enumerate()
            .skip(header_index + 1)
            .filter(|(_, l)| !is_blank_or_comment(l))
            .map(|(i, l)| (i + 1, *l))
            .collect();
        let mut columns = match &self.opts.columns {
            Some(spec) => self.columns_from_spec(spec, &header, header_line)?,
            None => self.detect_columns(&header, header_line)?,
        };
        self.drop_empty_temperature(&mut columns, &header, &data_lines, delimiter, &mut notes);
        if data_lines.is_empty() {
            return Err(CsvError::HeaderOnly { file: file.clone(), line: header_line });
        }
        let expected_cells = self.expected_cells(&columns, &header, header_line, data_lines[0], delimiter)?;
        let mut table = self.empty_table(&columns, header, delimiter, notes);
        let ends_with_newline = text.ends_with(['\n', '\r']);
        let skipped_lines = self.read_rows(&mut table, &data_lines, &columns, expected_cells, ends_with_newline)?;
        table.dropped.non_finite = skipped_lines.len();
        self.check_skipped(&mut table, &skipped_lines)?;
        if table.samples.is_empty() {
            return Err(CsvError::HeaderOnly { file: file.clone(), line: header_line });
        }
        self.check_times(&table)?;
        self.warn_slow_clock(&mut table);
        self.resolve_units(&mut table)?;
        Ok((table, columns))
    }

    /// The first non-blank line and the header's (0-based indices).
    fn find_header(&self, lines: &[&str]) -> Result<(usize, usize), CsvError> {
        let file = &self.file;
        let Some(first_index) = lines.iter().position(|l| !is_blank_or_comment(l)) else {
            return Err(CsvError::Empty { file: file.clone() });
        };
        if self.is_numeric_line(lines[first_index]) {
            return Err(CsvError::NoHeader {
                file: file.clone(),
                line: first_index + 1,
                text: lines[first_index].trim().to_string(),
            });
        }
        // The header is the last all-text line (no numeric cell) before the first all-numeric line;
        // lines before it (a logger's title or metadata such as `Fs,100`) are a preamble. Without
        // such a pair (e.g. a text label column in every row) the first line is the header.
        let header_index = lines
            .iter()
            .enumerate()
            .skip(first_index)
            .filter(|(_, l)| !is_blank_or_comment(l))
            .take(PREAMBLE_SEARCH_LINES)
            .find(|(_, l)| self.is_numeric_line(l))
            .and_then(|(k, _)| (first_index..k).rev().find(|&i| self.is_text_line(lines[i])))
            .unwrap_or(first_index);
        Ok((first_index, header_index))
    }

    /// The cell count every row must have, checked to hold every column read.
    fn expected_cells(
        &self,
        columns: &Columns,
        header: &[String],
        header_line: usize,
        first_data: (usize, &str),
        delimiter: Delimiter,
    ) -> Result<usize, CsvError> {
        // Rows must have the header's cell count; with all columns given by index the first data row
        // sets it (a header may be malformed, e.g. two names run together).
        let all_by_index = all_by_index(self.opts);
        let expected_cells = if all_by_index { split_cells(first_data.1, delimiter).len() } else { header.len() };
        if columns.max_index() >= expected_cells {
            return Err(CsvError::ColumnIndexOutOfRange {
                file: self.file.clone(),
                line: if all_by_index { first_data.0 } else { header_line },
                index: columns.max_index(),
                columns: expected_cells,
                from_header: !all_by_index,
            });
        }
        Ok(expected_cells)
    }

    /// A table with no rows yet, for `columns` of `header`.
    fn empty_table(&self, columns: &Columns, header: Vec<String>, delimiter: Delimiter, notes: Vec<String>) -> Table {
        let name_of = |i: usize| header.get(i).cloned().unwrap_or_else(|| format!("#{i}"));

        Table {
            file: self.file.clone(),
            times_s: columns.time.map(|_| Vec::new()),
            samples: Vec::new(),
            temps_c: columns.temp.map(|_| Vec::new()),
            counts_n: columns.count.map(|_| Vec::new()),
            std_devs: columns.std.map(|_| Vec::new()),
            units: self.opts.units,
            units_detected: false,
            units_header: None,
            dropped: DroppedRows::default(),
            median_magnitude: 0.0,
            line_of_row: Vec::new(),
            warnings: notes,
            delimiter,
            columns: ColumnsUsed {
                time: columns.time.map(|(i, s)| (name_of(i), s)),
                accel: columns.accel.map(name_of),
                temp: columns.temp.map(name_of),
                count: columns.count.map(name_of),
                std: columns.std.map(|s| s.map(name_of)),
            },
            header,
        }
    }

    /// Reads the data lines into `table`; returns the lines skipped for a missing value.
    fn read_rows(
        &self,
        table: &mut Table,
        data_lines: &[(usize, &str)],
        columns: &Columns,
        expected_cells: usize,
        ends_with_newline: bool,
    ) -> Result<Vec<usize>, CsvError> {
        let (file, delimiter) = (&self.file, table.delimiter);
        table.samples.reserve(data_lines.len());
        table.line_of_row.reserve(data_lines.len());
        let mut skipped_lines: Vec<usize> = Vec::new();
        let last = data_lines.len() - 1;
        for (k, &(line, row_text)) in data_lines.iter().enumerate() {
            let cells = split_cells(row_text, delimiter);
            let is_last = k == last;
            if cells.len() != expected_cells {
                if is_last && cells.len() < expected_cells {
                    table.dropped.truncated += 1;
                    table.warnings.push(format!(
                        "{file}:{line}: last line truncated ({} of {expected_cells} cells; power cut?): ignored",
                        cells.len()
                    ));
                    continue;
                }
                return Err(CsvError::RaggedRow {
                    file: file.clone(),
                    line,
                    cells: cells.len(),
                    expected: expected_cells,
                });
            }
            if self.is_stale(&cells, line, columns, &table.header, delimiter)? {
                table.dropped.stale_flag += 1;
                continue;
            }
            let row = self.parse_row(&cells, line, columns, &table.header, delimiter);
            let row = match row {
                Ok(r) => r,
                // A cut-off last line (no line end) may end in half a number.
                Err(e) if is_last && !ends_with_newline => {
                    table.dropped.truncated += 1;
                    table.warnings.push(format!("{file}:{line}: last line truncated ({e}; power cut?): ignored"));
                    continue;
                }
                Err(e) => return Err(e),
            };
            let Some(row) = row else {
                skipped_lines.push(line);
                continue;
            };
            table.push_row(row, line);
        }
        Ok(skipped_lines)
    }

    /// One data row: `Ok(None)` when a needed cell is NaN, infinite or empty (the row is skipped).
    pub(crate) fn parse_row(
        &self,
        cells: &[Cow<'_, str>],
        line: usize,
        columns: &Columns,
        header: &[String],
        delimiter: Delimiter,
    ) -> Result<Option<Row>, CsvError> {
        let column = |i: usize| header.get(i).cloned().unwrap_or_else(|| format!("#{i}"));
        let number = |i: usize| -> Result<Option<f64>, CsvError> {
            parse_number(&cells[i], delimiter).map_err(|()| CsvError::NonNumeric {
                file: self.file.clone(),
                line,
                column: column(i),
                text: cells[i].to_string(),
            })
        };
        // Three values or none (a missing one skips the row).
        let triple = |indices: [usize; 3]| -> Result<Option<[f64; 3]>, CsvError> {
            let mut out = [0.0; 3];
            for (o, i) in out.iter_mut().zip(indices) {
                match number(i)? {
                    Some(v) => *o = v,
                    None => return Ok(None),
                }
            }
            Ok(Some(out))
        };
        let Some(accel) = triple(columns.accel)? else { return Ok(None) };
        let time = match columns.time {
            Some((i, scale)) => match number(i)? {
                Some(v) => Some(v * scale),
                None => return Ok(None),
            },
            None => None,
        };
        let temp = match columns.temp {
            Some(i) => match number(i)? {
                Some(v) => Some(v),
                None => return Ok(None),
            },
            None => None,
        };
        let count = match columns.count {
            Some(i) => match parse_number(&cells[i], delimiter) {
                Ok(Some(v)) if v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) => Some(v as u32),
                _ => {
                    return Err(CsvError::BadCount {
                        file: self.file.clone(),
                        line,
                        column: column(i),
                        text: cells[i].to_string(),
                    });
                }
            },
            None => None,
        };
        let std = match columns.std {
            Some(indices) => match triple(indices)? {
                Some(s) => s,
                None => return Ok(None),
            },
            None => [0.0; 3],
        };
        Ok(Some(Row { time, accel, temp, count, std }))
    }

    /// `true` when the row's stale flag (if the file has one) is a non-zero number; empty is not stale.
    pub(crate) fn is_stale(
        &self,
        cells: &[Cow<'_, str>],
        line: usize,
        columns: &Columns,
        header: &[String],
        delimiter: Delimiter,
    ) -> Result<bool, CsvError> {
        let Some(i) = columns.stale else { return Ok(false) };
        match parse_number(&cells[i], delimiter) {
            Ok(v) => Ok(v.is_some_and(|v| v != 0.0)),
            Err(()) => Err(CsvError::NonNumeric {
                file: self.file.clone(),
                line,
                column: header.get(i).cloned().unwrap_or_else(|| format!("#{i}")),
                text: cells[i].to_string(),
            }),
        }
    }

    /// Warns about rows skipped for missing values, or fails when there are too many.
    fn check_skipped(&self, table: &mut Table, skipped_lines: &[usize]) -> Result<(), CsvError> {
        let file = &self.file;
        let rows = table.samples.len() + skipped_lines.len();
        if !skipped_lines.is_empty() {
            let too_many = table.samples.is_empty()
                || (skipped_lines.len() > 1 && skipped_lines.len() as f64 > MAX_SKIPPED_FRACTION * rows as f64);
            if too_many {
                return Err(CsvError::TooManyNonFinite {
                    file: file.clone(),
                    skipped: skipped_lines.len(),
                    rows,
                    first_line: skipped_lines[0],
                });
            }
            let shown: Vec<String> = skipped_lines.iter().take(5).map(usize::to_string).collect();
            let more = if skipped_lines.len() > 5 { ", ..." } else { "" };
            table.warnings.push(format!(
                "{file}: {} of {rows} rows skipped for NaN, infinite or empty values (lines {}{more})",
                skipped_lines.len(),
                shown.join(", ")
            ));
        }
        Ok(())
    }

    /// Drops the temperature column when it is empty, NaN or infinite in too many rows to skip them
    /// (a logger without a sensor writes `nan`): a warning names it and the data is read without it.
    fn drop_empty_temperature(
        &self,
        columns: &mut Columns,
        header: &[String],
        data_lines: &[(usize, &str)],
        delimiter: Delimiter,
        notes: &mut Vec<String>,
    ) {
        let Some(i) = columns.temp else { return };
        let missing = data_lines
            .iter()
            .filter(|(_, l)| split_cells(l, delimiter).get(i).is_some_and(|c| parse_number(c, delimiter) == Ok(None)))
            .count();
        if missing > 1 && missing as f64 > MAX_SKIPPED_FRACTION * data_lines.len() as f64 {
            let name = header.get(i).map_or_else(|| format!("#{i}"), |h| clip(h));
            notes.push(format!(
                "{}: temperature column `{name}` is empty or NaN in {missing} of {} rows: ignored (no temperature)",
                self.file,
                data_lines.len()
            ));
            columns.temp = None;
        }
    }

    /// `true` for a line whose cells are all numbers (or empty), at least one of them a number.
    fn is_numeric_line(&self, line: &str) -> bool {
        let delimiter = self.opts.delimiter.unwrap_or_else(|| Delimiter::detect(line));
        let cells = split_cells(line, delimiter);
        let mut any = false;
        for c in &cells {
            match parse_number(c, delimiter) {
                Ok(v) => any |= v.is_some(),
                Err(()) => return false,
            }
        }
        any
    }

    /// Raw samples a second or more apart usually mean a clock in milliseconds named without a unit.
    fn warn_slow_clock(&self, table: &mut Table) {
        let (Some(times), Some((name, scale))) = (&table.times_s, &table.columns.time) else { return };
        if self.opts.means || *scale != 1.0 || times.len() < 3 {
            return;
        }
        let steps: Vec<f64> = times.windows(2).map(|w| w[1] - w[0]).collect();
        let step_s = median(&steps);
        if step_s >= MAX_PLAUSIBLE_STEP_S {
            table.warnings.push(format!(
                "{}: time column `{}` steps by {step_s} per row, taken as seconds ({:.3} Hz); if it counts \
                 milliseconds, name it e.g. `time_ms`",
                self.file,
                clip(name),
                1.0 / step_s
            ));
        }
    }

    /// `true` for a non-blank line none of whose cells is a number.
    fn is_text_line(&self, line: &str) -> bool {
        if is_blank_or_comment(line) {
            return false;
        }
        let delimiter = self.opts.delimiter.unwrap_or_else(|| Delimiter::detect(line));
        split_cells(line, delimiter).iter().all(|c| !matches!(parse_number(c, delimiter), Ok(Some(_))))
    }

    fn check_times(&self, table: &Table) -> Result<(), CsvError> {
        let Some(times) = &table.times_s else { return Ok(()) };
        for i in 1..times.len() {
            let (previous_s, time_s) = (times[i - 1], times[i]);
            let (previous_line, line) = (table.line_of_row[i - 1], table.line_of_row[i]);
            let file = self.file.clone();
            if time_s == previous_s {
                return Err(CsvError::DuplicateTime { file, line, previous_line, time_s });
            }
            if time_s < previous_s {
                return Err(CsvError::NonMonotonicTime { file, line, previous_line, previous_s, time_s });
            }
        }
        Ok(())
    }

    /// The unit the acceleration column names agree on (`--units` other than auto overrides it, with
    /// a warning when they differ); names that disagree are warned about and ignored.
    fn header_units(&self, table: &mut Table) -> Option<HeaderUnit> {
        let named: Vec<HeaderUnit> = table.columns.accel.iter().filter_map(|c| header_unit(c)).collect();
        let first = named.first()?.clone();
        let file = &self.file;
        if named.iter().any(|h| h.label != first.label) {
            let labels: Vec<String> = named.iter().map(|h| format!("`{}`", clip(&h.column))).collect();
            table.warnings.push(format!("{file}: the columns {} name different units: ignored", labels.join(", ")));
            return None;
        }
        if self.opts.units != Units::Auto {
            if self.opts.units != first.units || first.factor != 1.0 {
                table.warnings.push(format!(
                    "{file}: --units {} overrides the unit {} in the header (`{}`)",
                    self.opts.units,
                    first.label,
                    clip(&first.column)
                ));
            }
            return None;
        }
        Some(first)
    }

    /// Scales the acceleration (and standard-deviation) values by a header unit's factor.
    fn scale_to_working_unit(table: &mut Table, factor: f64) {
        if factor == 1.0 {
            return;
        }
        for s in table.samples.iter_mut().chain(table.std_devs.iter_mut().flatten()) {
            *s = s.map(|v| v * factor);
        }
    }

    fn resolve_units(&self, table: &mut Table) -> Result<(), CsvError> {
        let file = &self.file;
        let header_unit = self.header_units(table);
        if let Some(h) = &header_unit {
            Self::scale_to_working_unit(table, h.factor);
        }
        let magnitudes: Vec<f64> = table.samples.iter().map(|s| s[0].hypot(s[1]).hypot(s[2])).collect();
        let median_magnitude = median(&magnitudes);
        let looks_like = units_from_magnitude(median_magnitude);
        let declared = header_unit.as_ref().map_or(self.opts.units, |h| h.units);
        let units = match declared {
            Units::Auto => match looks_like {
                Some(u) => u,
                None => return Err(CsvError::UnknownUnits { file: file.clone(), median_magnitude }),
            },
            declared if units_plausible(declared, median_magnitude) => declared,
            declared => {
                let header = header_unit.map(|h| h.column);
                return Err(CsvError::WrongUnits {
                    file: file.clone(),
                    declared,
                    median_magnitude,
                    looks_like,
                    header,
                });
            }
        };
        let limit = units.non_physical_limit();
        for (row, s) in table.samples.iter().enumerate() {
            if let Some(axis) = s.iter().position(|v| v.abs() > limit) {
                return Err(CsvError::Gigantic {
                    file: file.clone(),
                    line: table.line_of_row[row],
                    column: table.columns.accel[axis].clone(),
                    value: s[axis],
                    units,
                });
            }
        }
        table.units = units;
        table.units_detected = declared == Units::Auto;
        table.units_header = header_unit;
        table.median_magnitude = median_magnitude;
        Ok(())
    }

    fn detect_columns(&self, header: &[String], line: usize) -> Result<Columns, CsvError> {
        let file = &self.file;
        let fields: Vec<Option<Field>> = header.iter().map(|h| classify(h)).collect();
        let find = |role: &'static str, pred: &dyn Fn(Field) -> bool| -> Result<Option<usize>, CsvError> {
            let hits: Vec<usize> = (0..header.len()).filter(|&i| fields[i].is_some_and(pred)).collect();
            match hits.len() {
                0 => Ok(None),
                1 => Ok(Some(hits[0])),
                _ => Err(CsvError::AmbiguousColumn {
                    file: file.clone(),
                    line,
                    role,
                    candidates: hits.iter().map(|&i| header[i].clone()).collect(),
                }),
            }
        };
        let mut accel = [None; 3];
        let mut std = [None; 3];
        for a in 0..3 {
            accel[a] = find(["ax", "ay", "az"][a], &|f| f == Field::Accel(a))?;
            std[a] = find(["std_x", "std_y", "std_z"][a], &|f| f == Field::Std(a))?;
        }
        let missing: Vec<&'static str> =
            (0..3).filter(|&a| accel[a].is_none()).map(|a| ["ax", "ay", "az"][a]).collect();
        if !missing.is_empty() {
            return Err(CsvError::MissingColumns { file: file.clone(), line, missing, header: header.to_vec() });
        }
        let time = find("time", &|f| matches!(f, Field::Time(_)))?;
        let time = time.map(|i| match fields[i] {
            Some(Field::Time(scale)) => (i, scale),
            _ => (i, 1.0),
        });
        Ok(Columns {
            time,
            accel: accel.map(|a| a.unwrap_or(0)),
            temp: find("temperature", &|f| f == Field::Temp)?,
            stale: find("stale flag", &|f| f == Field::Stale)?,
            count: find("n (sample count)", &|f| f == Field::Count)?,
            std: match std {
                [Some(x), Some(y), Some(z)] => Some([x, y, z]),
                _ => None,
            },
        })
    }

    fn columns_from_spec(&self, spec: &ColumnSpec, header: &[String], line: usize) -> Result<Columns, CsvError> {
        let resolve = |c: &ColumnRef| -> Result<usize, CsvError> {
            let found = match c {
                ColumnRef::Index(i) => Some(*i),
                ColumnRef::Name(n) => header.iter().position(|h| h.trim().eq_ignore_ascii_case(n.trim())),
            };
            found.ok_or_else(|| CsvError::UnknownColumn {
                file: self.file.clone(),
                line,
                requested: c.to_string(),
                header: header.to_vec(),
            })
        };
        let time = match &spec.time {
            Some(c) => {
                let i = resolve(c)?;
                Some((i, header.get(i).map_or(1.0, |h| time_scale(&tokens(h)))))
            }
            None => None,
        };
        Ok(Columns {
            time,
            accel: [resolve(&spec.accel[0])?, resolve(&spec.accel[1])?, resolve(&spec.accel[2])?],
            temp: spec.temp.as_ref().map(&resolve).transpose()?,
            count: spec.count.as_ref().map(&resolve).transpose()?,
            // Not part of the spec: found by name.
            stale: header.iter().position(|h| classify(h) == Some(Field::Stale)),
            std: None,
        })
    }
}

pub(crate) struct Row {
    pub(crate) time: Option<f64>,
    pub(crate) accel: [f64; 3],
    temp: Option<f64>,
    count: Option<u32>,
    std: [f64; 3],
}

/// Each row of a means table as a pose: the mean, the variance from the `std_*` columns (0 without
/// them) and `n` from the count column (0 without it).
pub fn to_poses_from_means(table: &Table) -> Vec<Pose> {
    table
        .samples
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let n = table.counts_n.as_ref().map_or(0, |c| c[i]);
            let mut pose = Pose::from_mean(s.map(|v| v as f32), n);
            if let Some(std) = &table.std_devs {
                pose.variance = std[i].map(|d| (d * d) as f32);
            }
            pose
        })
        .collect()
}

/// Static-detection settings for [`accumulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccumulateOptions {
    /// The library's detector settings. Its `min_noise_variance` is raised to the quantisation floor
    /// measured in the data (`sum over axes of q^2 / 12`, `q` the smallest step between readings).
    pub config: AccumulatorConfig,
    /// Sample rate, Hz; `None` takes it from the time column (if any).
    pub sample_rate_hz: Option<f64>,
    /// Block length, samples (one of [`BLOCK_SIZES`]); `None` chooses about [`TARGET_BLOCK_S`] of
    /// samples from the sample rate, or [`DEFAULT_BLOCK_SAMPLES`] without one.
    pub block_samples: Option<usize>,
    /// A time step longer than this multiple of the mean step interrupts the stream (a pose never
    /// spans a gap in the recording). Defaults to 10.
    pub gap_factor: f64,
    /// Skip rows that repeat the previous row exactly (all three axes): stale reads of a sensor polled
    /// faster than its output data rate. `None` (default) decides from the data with
    /// [`repeats_look_stale`]: a coarsely quantised sensor repeats readings too, and those are kept.
    /// Stale readings are not independent samples, and the library's detector assumes independent
    /// noise.
    pub skip_repeats: Option<bool>,
}

/// Least fraction of rows repeating their predecessor (all three axes) for [`repeats_look_stale`].
pub const STALE_REPEAT_FRACTION: f64 = 0.2;

/// Least ratio of all-axes repeats to the count independent axes would give (per window of
/// [`STALE_WINDOW_ROWS`]) for [`repeats_look_stale`]. Quantisation measures about 1.05, stale reads
/// of a sensor polled 4x its data rate 1.6, 2x: 3.
pub const STALE_DEPENDENCE_RATIO: f64 = 1.3;

/// Rows per window in which [`repeats_look_stale`] compares the repeats of the axes.
pub const STALE_WINDOW_ROWS: usize = 64;

impl Default for AccumulateOptions {
    fn default() -> Self {
        Self {
            config: AccumulatorConfig::DEFAULT,
            sample_rate_hz: None,
            block_samples: None,
            gap_factor: 10.0,
            skip_repeats: None,
        }
    }
}

/// Fraction of rows that repeat the previous row exactly (all three axes).
pub fn repeat_fraction(samples: &[[f64; 3]]) -> f64 {
    if samples.len() < 2 {
        return 0.0;
    }
    samples.windows(2).filter(|w| w[0] == w[1]).count() as f64 / (samples.len() - 1) as f64
}

/// `true` when rows repeating their predecessor exactly look like stale reads, not quantisation: more
/// than [`STALE_REPEAT_FRACTION`] of the rows repeat on all three axes, and all three repeat together
/// more than [`STALE_DEPENDENCE_RATIO`] times as often as the per-axis repeats would by chance. A stale
/// read repeats the whole sample; a quantised sensor whose noise is below one step repeats each axis
/// on its own (counted per window, so that still and moving stretches are not mixed).
pub fn repeats_look_stale(samples: &[[f64; 3]]) -> bool {
    if repeat_fraction(samples) <= STALE_REPEAT_FRACTION {
        return false;
    }
    let (mut observed, mut expected) = (0.0, 0.0);
    for window in samples.windows(2).collect::<Vec<_>>().chunks(STALE_WINDOW_ROWS) {
        let per_axis = [0, 1, 2].map(|a| window.iter().filter(|w| w[0][a] == w[1][a]).count() as f64);
        let n = window.len() as f64;
        observed += window.iter().filter(|w| w[0] == w[1]).count() as f64;
        expected += per_axis[0] * per_axis[1] * per_axis[2] / (n * n);
    }
    observed > STALE_DEPENDENCE_RATIO * expected
}

/// Where a pose came from in the file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseSpan {
    /// First row averaged (index into the table).
    pub first_row: usize,
    /// Last row averaged.
    pub last_row: usize,
    /// File line of the first row.
    pub first_line: usize,
    /// File line of the last row.
    pub last_line: usize,
    /// Time of the first row, seconds (with a time column).
    pub start_s: Option<f64>,
    /// Time of the last row, seconds.
    pub end_s: Option<f64>,
}

/// The result of [`accumulate`].
#[derive(Debug, Clone, PartialEq)]
pub struct Accumulation {
    /// The poses found, in order.
    pub poses: Vec<Pose>,
    /// Where each pose came from.
    pub spans: Vec<PoseSpan>,
    /// Static intervals rejected, by reason.
    pub rejections: Rejections,
    /// Poses dropped because [`MAX_POSES`] were already stored.
    pub dropped_full: u32,
    /// Gaps in the time stamps that interrupted the stream.
    pub interruptions: u32,
    /// Block length used, samples.
    pub block_samples: usize,
    /// Sample rate used to choose it (of the rows fed, after skipping stale repeats), Hz.
    pub sample_rate_hz: Option<f64>,
    /// Rows skipped as stale repeats of the previous row.
    pub skipped_repeats: usize,
    /// The noise floor imposed (quantisation), input unit squared, summed over axes.
    pub min_noise_variance: f32,
    /// The detector's final noise variance estimate, input unit squared, summed over axes.
    pub noise_variance: f32,
}

/// The block length [`accumulate`] picks for a sample rate: the one of [`BLOCK_SIZES`] nearest (in
/// ratio) to [`TARGET_BLOCK_S`] of samples; [`DEFAULT_BLOCK_SAMPLES`] without a rate.
pub fn choose_block_samples(sample_rate_hz: Option<f64>) -> usize {
    let Some(rate) = sample_rate_hz.filter(|r| r.is_finite() && *r > 0.0) else {
        return DEFAULT_BLOCK_SAMPLES;
    };
    let target = (rate * TARGET_BLOCK_S).max(1.0).log2();
    BLOCK_SIZES
        .iter()
        .copied()
        .min_by(|a, b| ((*a as f64).log2() - target).abs().total_cmp(&((*b as f64).log2() - target).abs()))
        .unwrap_or(DEFAULT_BLOCK_SAMPLES)
}

/// The quantisation floor of the readings: `sum over axes of q^2 / 12` with `q` the smallest non-zero
/// step between consecutive readings of that axis (input unit squared).
pub fn quantisation_variance(samples: &[[f64; 3]]) -> f32 {
    let mut total = 0.0;
    for a in 0..3 {
        let step = samples
            .windows(2)
            .map(|w| (w[1][a] as f32 - w[0][a] as f32).abs())
            .filter(|d| *d > 0.0)
            .fold(f32::INFINITY, f32::min);
        if step.is_finite() {
            total += step * step / 12.0;
        }
    }
    total
}

/// Feeds every row of `table` (as `f32`, in the table's units) through the library's
/// `Accumulator::<f32, MAX_POSES, BLOCK>` and returns the poses it found, where they are in the file
/// and what was rejected. Time gaps (see [`AccumulateOptions::gap_factor`]) interrupt the stream.
///
/// # Errors
/// [`AccumulatorError::InvalidConfig`] for an invalid `opts.config` or a block length not in
/// [`BLOCK_SIZES`]. A full pose buffer is not an error: the poses beyond [`MAX_POSES`] are counted in
/// [`Accumulation::dropped_full`].
pub fn accumulate(table: &Table, opts: &AccumulateOptions) -> Result<Accumulation, AccumulatorError> {
    let repeats = repeat_fraction(&table.samples);
    let skip_repeats = opts.skip_repeats.unwrap_or_else(|| repeats_look_stale(&table.samples));
    let fed_fraction = if skip_repeats { 1.0 - repeats } else { 1.0 };
    let sample_rate_hz = opts.sample_rate_hz.or_else(|| table.sample_rate_hz()).map(|r| r * fed_fraction);
    let block = opts.block_samples.unwrap_or_else(|| choose_block_samples(sample_rate_hz));
    let mut config = opts.config;
    let floor = quantisation_variance(&table.samples);
    config.min_noise_variance = config.min_noise_variance.max(floor);
    let run = Run { table, config, gap_factor: opts.gap_factor, skip_repeats };
    let mut out = match block {
        8 => run.go::<8>()?,
        16 => run.go::<16>()?,
        32 => run.go::<32>()?,
        64 => run.go::<64>()?,
        128 => run.go::<128>()?,
        _ => return Err(AccumulatorError::InvalidConfig),
    };
    out.sample_rate_hz = sample_rate_hz;
    out.min_noise_variance = config.min_noise_variance;
    Ok(out)
}

struct Run<'a> {
    table: &'a Table,
    config: AccumulatorConfig,
    gap_factor: f64,
    skip_repeats: bool,
}

impl Run<'_> {
    fn go<const BLOCK: usize>(&self) -> Result<Accumulation, AccumulatorError> {
        let table = self.table;
        let mut acc = Accumulator::<f32, MAX_POSES, BLOCK>::new(self.config)?;
        let mut dropped_full = 0u32;
        let mut interruptions = 0u32;
        let mut handle = |r: Result<_, AccumulatorError>| match r {
            Ok(_) | Err(AccumulatorError::NonFiniteSample) => Ok(()),
            Err(AccumulatorError::Full) => {
                dropped_full += 1;
                Ok(())
            }
            Err(e) => Err(e),
        };
        let gap_s = table.times_s.as_ref().and_then(|t| {
            let span = t.last()? - t.first()?;
            (t.len() >= 2 && span > 0.0).then(|| self.gap_factor * span / (t.len() - 1) as f64)
        });
        // Table row of each sample pushed (pose indices count pushed samples).
        let mut row_of_pushed: Vec<usize> = Vec::with_capacity(table.samples.len());
        for (i, s) in table.samples.iter().enumerate() {
            if let (Some(t), Some(gap)) = (&table.times_s, gap_s)
                && i > 0
                && t[i] - t[i - 1] > gap
            {
                interruptions += 1;
                handle(acc.interrupt())?;
            }
            if self.skip_repeats && i > 0 && table.samples[i - 1] == *s {
                continue;
            }
            row_of_pushed.push(i);
            handle(acc.push(s.map(|v| v as f32)))?;
        }
        handle(acc.finish())?;
        let poses = acc.poses().to_vec();
        let last_pushed = row_of_pushed.len().saturating_sub(1);
        let spans = poses
            .iter()
            .map(|p| {
                let first = (p.start_index as usize).min(last_pushed);
                let last = (p.end_index as usize).saturating_sub(1).clamp(first, last_pushed);
                let (first_row, last_row) = (row_of_pushed[first], row_of_pushed[last]);
                PoseSpan {
                    first_row,
                    last_row,
                    first_line: table.line_of_row[first_row],
                    last_line: table.line_of_row[last_row],
                    start_s: table.times_s.as_ref().map(|t| t[first_row]),
                    end_s: table.times_s.as_ref().map(|t| t[last_row]),
                }
            })
            .collect();
        Ok(Accumulation {
            poses,
            spans,
            rejections: acc.rejections(),
            dropped_full,
            interruptions,
            block_samples: BLOCK,
            sample_rate_hz: None,
            skipped_repeats: table.samples.len() - row_of_pushed.len(),
            min_noise_variance: self.config.min_noise_variance,
            noise_variance: acc.noise_variance(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Table, CsvError> {
        read_csv_str("test.csv", text, &ReadOptions::default())
    }

    fn read_with(text: &str, opts: &ReadOptions) -> Result<Table, CsvError> {
        read_csv_str("test.csv", text, opts)
    }

    /// Display of an error, checked to name the file.
    fn message(e: &CsvError) -> String {
        let m = e.to_string();
        assert!(m.contains("test.csv"), "no file name in: {m}");
        m
    }

    #[test]
    fn reads_g_with_time_and_temperature() {
        let t = read("time_s,ax_g,ay_g,az_g,temp_C\n0.0,0.01,0.02,0.99,25.0\n0.01,0.02,0.01,1.01,25.1\n").unwrap();
        assert_eq!(t.units, Units::G);
        assert!(!t.units_detected);
        assert_eq!(t.units_header.as_ref().map(|h| (h.column.as_str(), h.label)), Some(("ax_g", "g")));
        assert_eq!(t.times_s, Some(vec![0.0, 0.01]));
        assert_eq!(t.temps_c, Some(vec![25.0, 25.1]));
        assert_eq!(t.samples[1], [0.02, 0.01, 1.01]);
        assert_eq!(t.line_of_row, vec![2, 3]);
        assert!(t.warnings.is_empty());
        assert!(t.units_summary().starts_with("g (header `ax_g`"), "{}", t.units_summary());
        assert!((t.sample_rate_hz().unwrap() - 100.0).abs() < 1e-9);
    }

    #[test]
    fn detects_units_from_magnitudes() {
        let t = read("ax,ay,az\n0.1,0.2,9.7\n0.1,0.3,9.8\n").unwrap();
        assert_eq!(t.units, Units::Mps2);
        let t = read("acc_x_raw,acc_y_raw,acc_z_raw\n33108,33329,36429\n33096,33336,36437\n").unwrap();
        assert_eq!(t.units, Units::Counts);
        assert_eq!(t.samples[0], [33108.0, 33329.0, 36429.0]);
        let e = read("x,y,z\n0.1,0.2,3.0\n").unwrap_err();
        assert!(matches!(e, CsvError::UnknownUnits { .. }));
        assert!(message(&e).contains("--units"));
    }

    #[test]
    fn wrong_declared_units_are_an_error() {
        let opts = ReadOptions { units: Units::G, ..ReadOptions::default() };
        let e = read_with("ax,ay,az\n100,200,16000\n110,190,16010\n", &opts).unwrap_err();
        let m = message(&e);
        assert!(m.contains("values no accelerometer reads in g"), "{m}");
        assert!(m.contains("--units counts"), "{m}");
        let opts = ReadOptions { units: Units::Counts, ..ReadOptions::default() };
        let e = read_with("ax,ay,az\n0.0,0.0,1.0\n", &opts).unwrap_err();
        assert!(matches!(e, CsvError::WrongUnits { looks_like: Some(Units::G), .. }), "{e}");
        let opts = ReadOptions { units: Units::Mps2, ..ReadOptions::default() };
        assert_eq!(read_with("ax,ay,az\n0.0,0.0,9.8\n", &opts).unwrap().units, Units::Mps2);
    }

    #[test]
    fn units_parse() {
        assert_eq!("auto".parse::<Units>(), Ok(Units::Auto));
        assert_eq!("COUNTS".parse::<Units>(), Ok(Units::Counts));
        assert_eq!("g".parse::<Units>(), Ok(Units::G));
        assert_eq!("mps2".parse::<Units>(), Ok(Units::Mps2));
        assert_eq!("m/s^2".parse::<Units>(), Ok(Units::Mps2));
        assert!("furlongs".parse::<Units>().unwrap_err().to_string().contains("furlongs"));
        assert_eq!(Units::G.calibration_gravity(), 1.0);
        assert_eq!(Units::Counts.before_model(), None);
    }

    #[test]
    fn missing_file_and_io() {
        let e = read_csv(Path::new("/nonexistent/dir/rec.csv"), &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Missing { .. }));
        assert!(e.to_string().contains("/nonexistent/dir/rec.csv"));
        let e = read_csv(Path::new("/"), &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Io { .. }), "{e:?}");
        assert!(e.to_string().starts_with("/:"));
    }

    #[test]
    fn empty_and_header_only() {
        assert!(matches!(read("").unwrap_err(), CsvError::Empty { .. }));
        assert!(matches!(read("\n\n# comment\n").unwrap_err(), CsvError::Empty { .. }));
        let e = read("ax,ay,az\n").unwrap_err();
        assert_eq!(e, CsvError::HeaderOnly { file: "test.csv".into(), line: 1 });
        assert!(message(&e).contains("test.csv:1:"));
        assert!(matches!(read("# made by logger\nax,ay,az\n\n").unwrap_err(), CsvError::HeaderOnly { line: 2, .. }));
    }

    #[test]
    fn headerless_file_is_an_error() {
        let e = read("0.01\t-0.05\t1.02\n0.06\t-0.05\t1.02\n").unwrap_err();
        assert!(matches!(e, CsvError::NoHeader { line: 1, .. }));
        assert!(message(&e).contains("header"));
    }

    #[test]
    fn missing_columns_list_the_header() {
        let e = read("time,gx,gy,gz\n0,1,2,3\n").unwrap_err();
        let m = message(&e);
        assert!(matches!(e, CsvError::MissingColumns { line: 1, .. }));
        assert!(m.contains("ax, ay, az") && m.contains("`gx`"), "{m}");
        let e = read("ax,ay,acc_x\n1,2,3\n").unwrap_err();
        assert!(matches!(e, CsvError::AmbiguousColumn { role: "ax", .. }), "{e:?}");
    }

    #[test]
    fn column_names_are_recognised() {
        let cases = [
            ("t,ax,ay,az", true),
            ("Time,AccX,AccY,AccZ", true),
            ("timestamp_ms,ax_raw,ay_raw,az_raw", true),
            ("time (s),x (g),y (g),z (g)", true),
            ("measurement,ax_g,ay_g,az_g,norm_g", false),
            (
                "interval,t_start_s,t_end_s,n_samples,mean_x_raw,mean_y_raw,mean_z_raw,std_x_raw,std_y_raw,std_z_raw",
                false,
            ),
            ("x_true (g),x_mean (g),x_std,y_true (g),y_mean (g),y_std,z_true (g),z_mean (g),z_std", false),
            ("t_center_s,ax_g_1s_mean,ay_g_1s_mean,az_g_1s_mean", true),
            ("acc_x [m/s^2];acc_y [m/s^2];acc_z [m/s^2]", false),
        ];
        for (header, has_time) in cases {
            let cells = split_cells(header, Delimiter::detect(header)).len();
            // A value the header's unit reads at rest (|a| = 1.73 g, or 9.87 m/s^2).
            let value = if header.contains("m/s^2") { "5.7" } else { "1" };
            let row = vec![value; cells].join(if header.contains(';') { ";" } else { "," });
            let t = read(&format!("{header}\n{row}\n")).unwrap_or_else(|e| panic!("{header}: {e}"));
            assert_eq!(t.times_s.is_some(), has_time, "{header}");
        }
        let t = read("interval,n_samples,mean_x_raw,mean_y_raw,mean_z_raw,std_x_raw,std_y_raw,std_z_raw\n1,100,3,4,33000,1,2,3\n")
            .unwrap();
        assert_eq!(t.counts_n, Some(vec![100]));
        assert_eq!(t.std_devs, Some(vec![[1.0, 2.0, 3.0]]));
        assert_eq!(t.columns.accel[2], "mean_z_raw");
        let t = read("timestamp_ms,ax,ay,az\n100,0,0,1\n110,0,0,1\n").unwrap();
        assert_eq!(t.times_s, Some(vec![0.1, 0.11]));
    }

    #[test]
    fn delimiters_and_quotes() {
        let t = read("ax;ay;az\n0,01;0,02;0,99\n").unwrap();
        assert_eq!(t.delimiter, Delimiter::Semicolon);
        assert_eq!(t.samples[0], [0.01, 0.02, 0.99]);
        let t = read("ax\tay\taz\n0.01\t0.02\t0.99\n").unwrap();
        assert_eq!(t.delimiter, Delimiter::Tab);
        let t = read("  ax   ay  az \n 0.01  0.02   0.99\r\n").unwrap();
        assert_eq!(t.delimiter, Delimiter::Whitespace);
        assert_eq!(t.samples[0], [0.01, 0.02, 0.99]);
        let t = read("\u{feff}\"ax\",\"ay\",\"az\"\r\n\"0.01\", 0.02 ,0.99\r\n").unwrap();
        assert_eq!(t.samples[0], [0.01, 0.02, 0.99]);
    }

    #[test]
    fn column_spec_parses_and_overrides() {
        let spec: ColumnSpec = "t,ax,ay,az".parse().unwrap();
        assert_eq!(spec.time, Some(ColumnRef::Name("t".into())));
        assert_eq!(spec.temp, None);
        let spec: ColumnSpec = "0,1,2".parse().unwrap();
        assert_eq!(spec.accel, [ColumnRef::Index(0), ColumnRef::Index(1), ColumnRef::Index(2)]);
        assert!("a,b".parse::<ColumnSpec>().is_err());
        assert!("t,-,ay,az".parse::<ColumnSpec>().unwrap_err().to_string().contains("x column"));
        assert!("1,2,3,4,5,6,7".parse::<ColumnSpec>().is_err());

        // Concatenated captures: the time column goes backwards, so leave it out.
        let text =
            "pos,timestamp_ms,ax_raw,ay_raw,az_raw,temp_C\nH1,171,17076,36,1216,24.1\nH2,100,16766,63,-1810,24.9\n";
        let e = read(text).unwrap_err();
        assert!(matches!(e, CsvError::NonMonotonicTime { line: 3, previous_line: 2, .. }), "{e:?}");
        assert!(message(&e).contains("test.csv:3:"));
        let opts =
            ReadOptions { columns: Some("-,ax_raw,ay_raw,az_raw,temp_c".parse().unwrap()), ..ReadOptions::default() };
        let t = read_with(text, &opts).unwrap();
        assert_eq!(t.times_s, None);
        assert_eq!(t.temps_c, Some(vec![24.1, 24.9]));
        assert_eq!(t.units, Units::Counts);

        let opts = ReadOptions { columns: Some("0,1,2,3".parse().unwrap()), ..ReadOptions::default() };
        let e =
            read_with("ax,ay,az\n1,2,3\n", &ReadOptions { columns: Some("ax,ay,bz".parse().unwrap()), ..opts.clone() })
                .unwrap_err();
        assert!(message(&e).contains("`bz`"));
        let e = read_with("ax,ay,az\n1,2,3\n", &ReadOptions { columns: Some("0,1,7".parse().unwrap()), ..opts })
            .unwrap_err();
        let expected = CsvError::ColumnIndexOutOfRange {
            file: "test.csv".into(),
            line: 2,
            index: 7,
            columns: 3,
            from_header: false,
        };
        assert_eq!(e, expected);
        assert!(message(&e).contains("column index 7, but the first data row has 3 columns (indices 0-2)"));
    }

    #[test]
    fn non_numeric_cell_names_line_column_and_text() {
        let e = read("t,ax,ay,az\n0,0,0,1\n0.01,0,zero,1\n").unwrap_err();
        assert_eq!(
            e,
            CsvError::NonNumeric { file: "test.csv".into(), line: 3, column: "ay".into(), text: "zero".into() }
        );
        let m = message(&e);
        assert!(m.contains("test.csv:3:") && m.contains("`ay`") && m.contains("`zero`"), "{m}");
        let e = read("ax,ay,az,n\n0,0,1,1.5\n").unwrap_err();
        assert!(matches!(e, CsvError::BadCount { line: 2, .. }));
    }

    #[test]
    fn time_must_increase() {
        let e = read("t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n0.01,0,0,1\n").unwrap_err();
        assert!(matches!(e, CsvError::DuplicateTime { line: 4, previous_line: 3, .. }), "{e:?}");
        assert!(message(&e).contains("repeats line 3"));
        let e = read("t,ax,ay,az\n0,0,0,1\n0.02,0,0,1\n0.01,0,0,1\n").unwrap_err();
        assert!(matches!(e, CsvError::NonMonotonicTime { line: 4, .. }));
    }

    #[test]
    fn binary_files_are_rejected() {
        let e = read_csv_bytes("test.csv", b"MATLAB 5.0 MAT-file\n\x00\x01\x02", &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Binary { line: 2, .. }), "{e:?}");
        message(&e);
        let e = read_csv_bytes("test.csv", b"ax,ay,az\n\xff\xfe\x01,1,2\n", &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Binary { line: 2, what: "invalid UTF-8", .. }), "{e:?}");
        let noise: Vec<u8> = (0..400u32).map(|i| 0x80 | (i.wrapping_mul(2_654_435_761) >> 25) as u8).collect();
        let e = read_csv_bytes("test.csv", &[b"ax,ay,az\n".as_slice(), &noise].concat(), &ReadOptions::default())
            .unwrap_err();
        assert!(matches!(e, CsvError::Binary { line: 2, .. }), "{e:?}");
        let e = read_csv_bytes("test.csv", b"\xff\xfea\x00x\x00", &ReadOptions::default()).unwrap_err();
        assert!(message(&e).contains("UTF-16"));
    }

    #[test]
    fn preamble_before_the_header_is_skipped() {
        let t = read(
            "Fs,100\nLogging Type,0\n\nax,ay,az,gx,gy,gz\n-12,-812,15032,-447,156,-86\n-208,-828,14796,-398,132,-63\n",
        )
        .unwrap();
        assert_eq!(t.line_of_row, vec![5, 6]);
        assert_eq!(t.units, Units::Counts);
        assert!(t.warnings[0].contains("lines 1-3 before the header (line 4) skipped"), "{:?}", t.warnings);
        // A title line, then a header with two names run together: columns by index.
        let text = "Data Collected on Level Surface. Z up.\ntime (s)x (g),y (g),z (g)\n0.005,0.099,0.064,0.774\n0.011,0.098,0.063,0.771\n";
        let e = read(text).unwrap_err();
        assert!(matches!(e, CsvError::MissingColumns { line: 2, .. }), "{e:?}");
        assert!(message(&e).contains("`time (s)x (g)`"));
        let opts = ReadOptions { columns: Some("0,1,2,3".parse().unwrap()), ..ReadOptions::default() };
        let t = read_with(text, &opts).unwrap();
        assert_eq!(t.times_s, Some(vec![0.005, 0.011]));
        assert_eq!(t.samples[1], [0.098, 0.063, 0.771]);
        // A corrupt first data line is data (and an error), not a header.
        let e = read("t,ax,ay,az\n0.1,0,0,103.79.00\n0.2,0,0,1\n").unwrap_err();
        assert!(matches!(e, CsvError::NonNumeric { line: 2, .. }), "{e:?}");
        // A text label column: no all-numeric line, the first line is the header.
        let t = read("pos,ax,ay,az\nH1,0,0,1\nH2,0,1,0\n").unwrap();
        assert_eq!(t.samples.len(), 2);
        assert!(t.warnings.is_empty());
    }

    #[test]
    fn latin1_text_is_read_with_a_warning() {
        let t = read_csv_bytes(
            "test.csv",
            b"Timestamp,aX (g),aY (g),aZ (g),gX (\xb0/s)\n0,0,0,1,0\n",
            &ReadOptions::default(),
        )
        .unwrap();
        assert_eq!(t.header[4], "gX (\u{b0}/s)");
        assert!(t.warnings[0].contains("test.csv:1: not UTF-8; read as Latin-1"), "{:?}", t.warnings);
    }

    #[test]
    fn a_clock_in_milliseconds_is_flagged() {
        let t = read("Timestamp,ax,ay,az\n410,0,0,9.8\n427,0,0,9.8\n442,0,0,9.8\n").unwrap();
        assert!(t.warnings.iter().any(|w| w.contains("`Timestamp` steps by 16 per row")), "{:?}", t.warnings);
        let t = read("time_ms,ax,ay,az\n410,0,0,9.8\n427,0,0,9.8\n442,0,0,9.8\n").unwrap();
        assert!(t.warnings.is_empty());
    }

    #[test]
    fn gigantic_values_are_rejected() {
        let mut text = String::from("ax,ay,az\n");
        for _ in 0..10 {
            text.push_str("0.0,0.0,1.0\n");
        }
        text.push_str("0.0,3e7,1.0\n");
        let e = read(&text).unwrap_err();
        assert!(matches!(e, CsvError::Gigantic { line: 12, units: Units::G, .. }), "{e:?}");
        assert!(message(&e).contains("`ay`"));
        let e = read("ax,ay,az\n1e300,0,0\n1e300,0,0\n").unwrap_err();
        assert!(matches!(e, CsvError::Gigantic { units: Units::Counts, .. }), "{e:?}");
    }

    #[test]
    fn truncated_last_line_is_tolerated() {
        let t = read("t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n0.02,0.1").unwrap();
        assert_eq!(t.samples.len(), 2);
        assert_eq!(t.warnings.len(), 1);
        assert!(t.warnings[0].contains("test.csv:4:") && t.warnings[0].contains("truncated"), "{:?}", t.warnings);
        // Cut inside a number, no line end.
        let t = read("t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n0.02,0.1,0,1.0e").unwrap();
        assert_eq!(t.samples.len(), 2);
        assert_eq!(t.warnings.len(), 1);
        // A short line in the middle is an error.
        let e = read("t,ax,ay,az\n0,0,0,1\n0.01,0\n0.02,0,0,1\n").unwrap_err();
        assert_eq!(e, CsvError::RaggedRow { file: "test.csv".into(), line: 3, cells: 2, expected: 4 });
        message(&e);
    }

    #[test]
    fn isolated_non_finite_rows_are_skipped() {
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..40 {
            let az = match i {
                7 => "NaN".to_string(),
                20 => "inf".to_string(),
                31 => String::new(),
                _ => "1.0".to_string(),
            };
            text.push_str(&format!("{},0.0,0.0,{az}\n", i as f64 * 0.01));
        }
        let t = read(&text).unwrap();
        assert_eq!(t.samples.len(), 37);
        assert_eq!(t.times_s.as_ref().unwrap().len(), 37);
        assert_eq!(t.warnings.len(), 1);
        assert!(
            t.warnings[0].contains("3 of 40 rows") && t.warnings[0].contains("lines 9, 22, 33"),
            "{:?}",
            t.warnings
        );
        assert_eq!(t.line_of_row[7], 10);

        let mut text = String::from("ax,ay,az\n");
        for i in 0..10 {
            text.push_str(if i % 2 == 0 { "0,0,nan\n" } else { "0,0,1\n" });
        }
        let e = read(&text).unwrap_err();
        assert!(matches!(e, CsvError::TooManyNonFinite { skipped: 5, rows: 10, first_line: 2, .. }), "{e:?}");
        message(&e);
    }

    #[test]
    fn means_rows_become_poses() {
        let opts = ReadOptions { means: true, ..ReadOptions::default() };
        let t = read_with(
            "position,mean_x_g,mean_y_g,mean_z_g,n,std_x,std_y,std_z\n1,0,0,1,200,0.001,0.002,0.003\n",
            &opts,
        )
        .unwrap();
        let poses = to_poses_from_means(&t);
        assert_eq!(poses.len(), 1);
        assert_eq!(poses[0].mean, [0.0, 0.0, 1.0]);
        assert_eq!(poses[0].n, 200);
        assert!((poses[0].variance[2] - 9e-6).abs() < 1e-9);
        let t = read_with("ax,ay,az\n0,0,1\n", &opts).unwrap();
        assert_eq!(to_poses_from_means(&t)[0].n, 0);
    }

    #[test]
    fn block_choice_follows_the_rate() {
        assert_eq!(choose_block_samples(None), DEFAULT_BLOCK_SAMPLES);
        assert_eq!(choose_block_samples(Some(100.0)), 16);
        assert_eq!(choose_block_samples(Some(400.0)), 64);
        assert_eq!(choose_block_samples(Some(180.0)), 32);
        assert_eq!(choose_block_samples(Some(9.5)), 8);
        assert_eq!(choose_block_samples(Some(f64::NAN)), DEFAULT_BLOCK_SAMPLES);
        assert!(
            (quantisation_variance(&[[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [1.0, 0.0, 3.0]]) - (1.0 + 4.0 + 9.0) / 12.0)
                .abs()
                < 1e-6
        );
    }

    #[test]
    fn accumulate_finds_static_poses_and_their_times() {
        // Three holds of 3 s at 100 Hz, counts with +-2 LSB noise, separated by 1 s turns.
        let holds = [[33000.0, 32800.0, 36900.0], [29000.0, 32800.0, 32700.0], [33000.0, 28700.0, 32700.0]];
        let mut text = String::from("time_s,ax_raw,ay_raw,az_raw\n");
        let mut i = 0u32;
        let mut lcg = 12345u32;
        let mut push = |text: &mut String, s: [f64; 3]| {
            lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let n = f64::from(lcg >> 29) - 3.5; // -3.5..3.5
            text.push_str(&format!("{:.2},{:.0},{:.0},{:.0}\n", f64::from(i) * 0.01, s[0] + n, s[1] - n, s[2] + n));
            i += 1;
        };
        for (h, hold) in holds.iter().enumerate() {
            for _ in 0..300 {
                push(&mut text, *hold);
            }
            if h + 1 < holds.len() {
                let next = holds[h + 1];
                for k in 0..100 {
                    let f = f64::from(k) / 100.0;
                    push(&mut text, [0, 1, 2].map(|a| hold[a] + f * (next[a] - hold[a]) + 900.0 * (f * 6.3).sin()));
                }
            }
        }
        let table = read(&text).unwrap();
        assert_eq!(table.units, Units::Counts);
        let acc = accumulate(&table, &AccumulateOptions::default()).unwrap();
        assert_eq!(acc.block_samples, 16);
        assert_eq!(acc.poses.len(), 3, "{acc:?}");
        for (pose, hold) in acc.poses.iter().zip(holds) {
            for (mean, expected) in pose.mean.iter().zip(hold) {
                assert!((f64::from(*mean) - expected).abs() < 1.0, "{pose:?}");
            }
        }
        let span = acc.spans[1];
        assert!(span.start_s.unwrap() >= 4.0 && span.end_s.unwrap() <= 7.0, "{span:?}");
        assert_eq!(span.first_line, table.line_of_row[span.first_row]);
        assert!((acc.min_noise_variance - 0.25).abs() < 1e-6);
    }

    #[test]
    fn stale_repeated_reads_are_skipped() {
        // A 100 Hz sensor polled at 400 Hz: every reading appears 4 times.
        let mut text = String::from("ax,ay,az\n");
        let mut lcg = 7u32;
        for _ in 0..500 {
            lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let n = f64::from(lcg >> 24) / 256.0 - 0.5;
            for _ in 0..4 {
                text.push_str(&format!("{:.4},{:.4},{:.4}\n", 0.01 * n, -0.01 * n, 1.0 + 0.01 * n));
            }
        }
        let table = read(&text).unwrap();
        assert!((repeat_fraction(&table.samples) - 0.75).abs() < 0.01);
        let acc = accumulate(&table, &AccumulateOptions::default()).unwrap();
        assert!(acc.skipped_repeats >= 1490, "{acc:?}");
        assert_eq!(acc.poses.len(), 1);
        assert_eq!(acc.spans[0].first_row % 4, 0, "spans refer to table rows");
        let kept = AccumulateOptions { skip_repeats: Some(false), ..AccumulateOptions::default() };
        assert_eq!(accumulate(&table, &kept).unwrap().skipped_repeats, 0);
    }

    #[test]
    fn time_gaps_interrupt_the_stream() {
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..400 {
            let t = f64::from(i) * 0.01 + if i >= 200 { 5.0 } else { 0.0 };
            text.push_str(&format!("{t:.2},0.0,0.0,{}\n", 1.0 + 0.001 * f64::from(i % 3)));
        }
        let table = read(&text).unwrap();
        let acc = accumulate(&table, &AccumulateOptions::default()).unwrap();
        assert_eq!(acc.interruptions, 1);
        assert_eq!(acc.poses.len(), 2, "{acc:?}");
        let bad = AccumulateOptions { block_samples: Some(12), ..AccumulateOptions::default() };
        assert_eq!(accumulate(&table, &bad).unwrap_err(), AccumulatorError::InvalidConfig);
    }
}
