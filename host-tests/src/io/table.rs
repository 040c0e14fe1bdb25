//! A file read into columns, the rows dropped by reason, and one data row as read.

use super::columns::ColumnsUsed;
use super::{Delimiter, HeaderUnit, Units, clip};

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

/// Data rows [`read_csv`](super::read_csv) dropped, by reason (each row counted once).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DroppedRows {
    /// A needed cell empty, NaN or infinite.
    pub non_finite: usize,
    /// Marked stale by a stale-flag column (`stale`, `is_stale`, ...: non-zero).
    pub stale_flag: usize,
    /// A truncated last line (a power cut while logging).
    pub truncated: usize,
}

impl Table {
    /// Appends one row read from file line `line`.
    pub(crate) fn push_row(&mut self, row: Row, line: usize) {
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

    /// Every per-row column has one value per row of [`Table::samples`] (a table read by
    /// [`read_csv`](super::read_csv) always has; one built or cut by hand may not).
    pub fn columns_agree(&self) -> bool {
        let rows = self.samples.len();
        let agrees = |len: Option<usize>| len.is_none_or(|len| len == rows);
        self.line_of_row.len() == rows
            && agrees(self.times_s.as_ref().map(Vec::len))
            && agrees(self.temps_c.as_ref().map(Vec::len))
            && agrees(self.counts_n.as_ref().map(Vec::len))
            && agrees(self.std_devs.as_ref().map(Vec::len))
    }

    /// Keeps the first `rows` rows of every per-row column.
    pub fn truncate(&mut self, rows: usize) {
        self.samples.truncate(rows);
        self.line_of_row.truncate(rows);
        self.times_s.iter_mut().for_each(|c| c.truncate(rows));
        self.temps_c.iter_mut().for_each(|c| c.truncate(rows));
        self.counts_n.iter_mut().for_each(|c| c.truncate(rows));
        self.std_devs.iter_mut().for_each(|c| c.truncate(rows));
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

/// One data row as read, in the file's units (before any header unit's scaling).
pub(crate) struct Row {
    pub(crate) time: Option<f64>,
    pub(crate) accel: [f64; 3],
    pub(crate) temp: Option<f64>,
    pub(crate) count: Option<u32>,
    pub(crate) std: [f64; 3],
}
