//! One CSV record to one [`Row`]: the cell count checked against the header, the stale flag, the
//! numbers parsed (a missing one skips the row), a cut-off last line recognised.

use csv::ByteRecord;

use super::CsvError;
use super::columns::Columns;
use super::table::Row;
use super::text::{Delimiter, cell, parse_number};

/// What became of one data record.
pub(crate) enum Outcome {
    /// Read.
    Row(Row),
    /// Marked stale by the stale-flag column.
    Stale,
    /// A needed cell empty, NaN or infinite: skipped.
    NonFinite,
    /// The last line, cut off (a power cut while logging); why, for the warning.
    Truncated(String),
}

/// How records are turned into rows.
pub(crate) struct RowReader<'a> {
    pub(crate) file: &'a str,
    pub(crate) columns: &'a Columns,
    pub(crate) header: &'a [String],
    pub(crate) delimiter: Delimiter,
    /// The cell count every row must have.
    pub(crate) expected_cells: usize,
    /// `true`: rows need at least `expected_cells` cells, not exactly as many.
    pub(crate) at_least: bool,
}

impl RowReader<'_> {
    /// The record of file line `line`; `last` is `Some(ends_with_newline)` for the file's last record.
    ///
    /// # Errors
    /// [`CsvError::RaggedRow`], [`CsvError::NonNumeric`] or [`CsvError::BadCount`] with the line.
    pub(crate) fn read(&self, record: &ByteRecord, line: usize, last: Option<bool>) -> Result<Outcome, CsvError> {
        let cells = record.len();
        let ragged = if self.at_least { cells < self.expected_cells } else { cells != self.expected_cells };
        if ragged {
            if last.is_some() && cells < self.expected_cells {
                return Ok(Outcome::Truncated(format!("{cells} of {} cells", self.expected_cells)));
            }
            let file = self.file.to_string();
            return Err(CsvError::RaggedRow { file, line, cells, expected: self.expected_cells });
        }
        if self.is_stale(record, line)? {
            return Ok(Outcome::Stale);
        }
        match self.parse_row(record, line) {
            Ok(Some(row)) => Ok(Outcome::Row(row)),
            Ok(None) => Ok(Outcome::NonFinite),
            // A cut-off last line (no line end) may end in half a number.
            Err(e) if last == Some(false) => Ok(Outcome::Truncated(e.to_string())),
            Err(e) => Err(e),
        }
    }

    fn column(&self, i: usize) -> String {
        self.header.get(i).cloned().unwrap_or_else(|| format!("#{i}"))
    }

    fn non_numeric(&self, record: &ByteRecord, line: usize, i: usize) -> CsvError {
        let (file, column, text) = (self.file.to_string(), self.column(i), cell(record, i).into_owned());
        CsvError::NonNumeric { file, line, column, text }
    }

    /// Cell `i` as a number, `None` when missing.
    fn number(&self, record: &ByteRecord, line: usize, i: usize) -> Result<Option<f64>, CsvError> {
        parse_number(&cell(record, i), self.delimiter).map_err(|()| self.non_numeric(record, line, i))
    }

    /// Three values, or none when one is missing.
    fn triple(&self, record: &ByteRecord, line: usize, indices: [usize; 3]) -> Result<Option<[f64; 3]>, CsvError> {
        let mut out = [0.0; 3];
        for (o, i) in out.iter_mut().zip(indices) {
            match self.number(record, line, i)? {
                Some(v) => *o = v,
                None => return Ok(None),
            }
        }
        Ok(Some(out))
    }

    /// An optional column's value: `Ok(None)` without the column, `Err(None)` when the cell is missing.
    fn optional(&self, record: &ByteRecord, line: usize, i: Option<usize>) -> Result<Option<f64>, Option<CsvError>> {
        let Some(i) = i else { return Ok(None) };
        match self.number(record, line, i) {
            Ok(Some(v)) => Ok(Some(v)),
            Ok(None) => Err(None),
            Err(e) => Err(Some(e)),
        }
    }

    /// One data row: `Ok(None)` when a needed cell is NaN, infinite or empty (the row is skipped).
    fn parse_row(&self, record: &ByteRecord, line: usize) -> Result<Option<Row>, CsvError> {
        let Some(accel) = self.triple(record, line, self.columns.accel)? else { return Ok(None) };
        let columns = self.columns;
        let time = match self.optional(record, line, columns.time.map(|t| t.0)) {
            Ok(v) => v.map(|v| v * columns.time.map_or(1.0, |t| t.1)),
            Err(e) => return e.map_or(Ok(None), Err),
        };
        let temp = match self.optional(record, line, columns.temp) {
            Ok(v) => v,
            Err(e) => return e.map_or(Ok(None), Err),
        };
        let count = match columns.count {
            Some(i) => Some(self.count(record, line, i)?),
            None => None,
        };
        let std = match columns.std {
            Some(indices) => match self.triple(record, line, indices)? {
                Some(s) => s,
                None => return Ok(None),
            },
            None => [0.0; 3],
        };
        Ok(Some(Row { time, accel, temp, count, std }))
    }

    /// A sample-count cell: a non-negative integer.
    fn count(&self, record: &ByteRecord, line: usize, i: usize) -> Result<u32, CsvError> {
        match parse_number(&cell(record, i), self.delimiter) {
            Ok(Some(v)) if v >= 0.0 && v.fract() == 0.0 && v <= f64::from(u32::MAX) => Ok(v as u32),
            _ => {
                let (file, column, text) = (self.file.to_string(), self.column(i), cell(record, i).into_owned());
                Err(CsvError::BadCount { file, line, column, text })
            }
        }
    }

    /// `true` when the row's stale flag (if the file has one) is a non-zero number; empty is not stale.
    fn is_stale(&self, record: &ByteRecord, line: usize) -> Result<bool, CsvError> {
        let Some(i) = self.columns.stale else { return Ok(false) };
        Ok(self.number(record, line, i)?.is_some_and(|v| v != 0.0))
    }
}
