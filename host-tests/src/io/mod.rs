//! Reading for the host tools, through the `csv` crate: reads accelerometer recordings (raw samples or per-pose means) from
//! delimited text, finds the columns by name, resolves the units, and turns the rows into
//! [`Pose`](accelcal::accumulator::Pose)s, either directly (means files) or through the library's static detector
//! ([`Accumulator`](accelcal::accumulator::Accumulator)).
//!
//! Every error names the file, the line where one applies, and what is wrong, quoting at most
//! [`MAX_QUOTED_CHARS`] characters of input; nothing here panics on input. Tolerated defects get a
//! warning in [`Table::warnings`]: a truncated last line (e.g. a power cut while logging), isolated
//! NaN/inf/empty cells (those rows are skipped), a temperature column empty or NaN throughout (read
//! without it). Rows dropped are counted by reason in [`Table::dropped`] (a non-zero stale-flag
//! column, `stale`/`is_stale`, drops its row). Lines may end in LF, CR LF or a lone CR.
//!
//! ```
//! use accelcal_host::io::{read_csv_str, ReadOptions, Units};
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
//!
//! # Stages
//! [`text`] (encoding, line ends, delimiter) -> `header` (where the header is) -> [`columns`] (which
//! cells) -> `records` (the `csv` crate's records with their lines) -> `rows` (a record to a row) ->
//! `read` (a whole text into a [`Table`]) -> [`units`]; [`stream`] reads large files the same way
//! without keeping their rows.

use std::path::Path;

pub mod columns;
mod error;
mod header;
mod read;
mod records;
mod rows;
pub mod stream;
mod table;
pub mod text;
pub mod units;

pub use columns::{ColumnRef, ColumnSpec, ColumnSpecError, ColumnsUsed};
pub(crate) use columns::{Columns, all_by_index};
pub use error::{CsvError, MAX_QUOTED_CHARS};
pub(crate) use error::{clip, list};
pub(crate) use read::Parser;
pub use table::{DroppedRows, Table};
pub use text::{Delimiter, split_cells, split_lines};
pub use units::{HeaderUnit, Units, UnitsParseError};

/// Median time step (s) of raw samples above which [`read_csv`] warns that the time column is
/// probably not in seconds.
pub const MAX_PLAUSIBLE_STEP_S: f64 = 1.0;

/// Lines searched for the first all-numeric line when looking for the header below a preamble.
pub const PREAMBLE_SEARCH_LINES: usize = 1000;

/// Largest fraction of data rows that may be skipped for NaN/inf/empty cells before the file is
/// rejected instead of warned about.
pub const MAX_SKIPPED_FRACTION: f64 = 0.1;

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
    let mut notes = Vec::new();
    let text = text::decode(name, bytes, &mut notes)?;
    Parser { file: name.to_string(), opts, notes }.parse_with_columns(&text)
}
