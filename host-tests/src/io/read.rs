//! A whole text read into a [`Table`]: the header found, the columns chosen, every record read
//! through the `csv` crate into rows, then the checks over all rows (skipped share, time order,
//! units).

use csv::ByteRecord;

use super::columns::{self, Columns, ColumnsUsed, all_by_index};
use super::header::{HeaderAt, find_header};
use super::records::Records;
use super::rows::{Outcome, RowReader};
use super::table::{DroppedRows, Table};
use super::text::{Delimiter, cell, parse_number, split_cells};
use super::{CsvError, MAX_PLAUSIBLE_STEP_S, MAX_SKIPPED_FRACTION, ReadOptions, clip, units};
use crate::stats::median;

/// Reads one text (see [`Parser::parse_with_columns`]).
pub(crate) struct Parser<'a> {
    pub(crate) file: String,
    pub(crate) opts: &'a ReadOptions,
    /// Warnings found before parsing (encoding).
    pub(crate) notes: Vec<String>,
}

/// The first data record's line and cell count; with a temperature column also the records' count
/// and the temperature cells missing.
struct Survey {
    records: usize,
    first: Option<(usize, usize)>,
    temp_missing: usize,
}

impl Parser<'_> {
    /// The table, and the column indices it was read from.
    pub(crate) fn parse_with_columns(&self, text: &str) -> Result<(Table, Columns), CsvError> {
        let file = &self.file;
        let header_at = find_header(file, text, self.opts.delimiter)?;
        let mut notes = self.notes.clone();
        if header_at.line > header_at.first_line {
            let (first, last, line) = (header_at.first_line, header_at.line - 1, header_at.line);
            notes.push(format!("{file}: lines {first}-{last} before the header (line {line}) skipped"));
        }
        let delimiter = self.opts.delimiter.unwrap_or_else(|| Delimiter::detect(&header_at.text));
        let header = split_cells(&header_at.text, delimiter);
        let mut columns = match &self.opts.columns {
            Some(spec) => columns::from_spec(file, spec, &header, header_at.line)?,
            None => columns::detect(file, &header, header_at.line)?,
        };
        let survey = self.survey(text, &header_at, delimiter, columns.temp)?;
        self.drop_empty_temperature(&mut columns, &header, &survey, &mut notes);
        let Some(first) = survey.first else {
            return Err(CsvError::HeaderOnly { file: file.clone(), line: header_at.line });
        };
        let expected_cells = self.expected_cells(&columns, header.len(), header_at.line, first)?;
        let mut table = self.empty_table(&columns, header, delimiter, notes);
        let rows = RowReader {
            file,
            columns: &columns,
            header: &table.header.clone(),
            delimiter,
            expected_cells,
            at_least: false,
        };
        let skipped_lines = self.read_rows(&mut table, &rows, text, &header_at)?;
        table.dropped.non_finite = skipped_lines.len();
        self.check_skipped(&mut table, &skipped_lines)?;
        if table.samples.is_empty() {
            return Err(CsvError::HeaderOnly { file: file.clone(), line: header_at.line });
        }
        self.check_times(&table)?;
        self.warn_slow_clock(&mut table);
        units::resolve(file, self.opts.units, &mut table)?;
        Ok((table, columns))
    }

    /// The records after the header.
    fn records<'t>(&self, text: &'t str, at: &HeaderAt, delimiter: Delimiter) -> Records<&'t [u8]> {
        let data = text.as_bytes().get(at.data_offset..).unwrap_or_default();
        Records::new(&self.file, data, delimiter, at.line, at.ends_with_cr)
    }

    /// A first pass over the records (only to the first without a temperature column).
    fn survey(&self, text: &str, at: &HeaderAt, delimiter: Delimiter, temp: Option<usize>) -> Result<Survey, CsvError> {
        let mut records = self.records(text, at, delimiter);
        let mut record = ByteRecord::new();
        let mut survey = Survey { records: 0, first: None, temp_missing: 0 };
        while let Some(line) = records.next_into(&mut record)? {
            survey.records += 1;
            survey.first = survey.first.or(Some((line, record.len())));
            let missing = |i: usize| i < record.len() && parse_number(&cell(&record, i), delimiter) == Ok(None);
            survey.temp_missing += usize::from(temp.is_some_and(missing));
            if temp.is_none() {
                break; // Only the first record is needed.
            }
        }
        Ok(survey)
    }

    /// The cell count every row must have, checked to hold every column read: the header's, or with
    /// all columns given by index the first data row's (a header may be malformed, e.g. two names
    /// run together).
    fn expected_cells(
        &self,
        columns: &Columns,
        header_cells: usize,
        header_line: usize,
        (first_line, first_cells): (usize, usize),
    ) -> Result<usize, CsvError> {
        let all_by_index = all_by_index(self.opts);
        let expected_cells = if all_by_index { first_cells } else { header_cells };
        if columns.max_index() >= expected_cells {
            return Err(CsvError::ColumnIndexOutOfRange {
                file: self.file.clone(),
                line: if all_by_index { first_line } else { header_line },
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

    /// Reads the records into `table`; returns the lines skipped for a missing value.
    fn read_rows(
        &self,
        table: &mut Table,
        rows: &RowReader<'_>,
        text: &str,
        at: &HeaderAt,
    ) -> Result<Vec<usize>, CsvError> {
        let ends_with_newline = text.ends_with(['\n', '\r']);
        let mut records = self.records(text, at, rows.delimiter);
        let (mut record, mut next) = (ByteRecord::new(), ByteRecord::new());
        let mut skipped_lines = Vec::new();
        let mut current = records.next_into(&mut record)?;
        while let Some(line) = current {
            let following = records.next_into(&mut next)?;
            let last = following.is_none().then_some(ends_with_newline);
            match rows.read(&record, line, last)? {
                Outcome::Row(row) => table.push_row(row, line),
                Outcome::Stale => table.dropped.stale_flag += 1,
                Outcome::NonFinite => skipped_lines.push(line),
                Outcome::Truncated(why) => {
                    table.dropped.truncated += 1;
                    let file = &self.file;
                    table.warnings.push(format!("{file}:{line}: last line truncated ({why}; power cut?): ignored"));
                }
            }
            std::mem::swap(&mut record, &mut next);
            current = following;
        }
        Ok(skipped_lines)
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
        survey: &Survey,
        notes: &mut Vec<String>,
    ) {
        let Some(i) = columns.temp else { return };
        let (missing, rows) = (survey.temp_missing, survey.records);
        if missing > 1 && missing as f64 > MAX_SKIPPED_FRACTION * rows as f64 {
            let name = header.get(i).map_or_else(|| format!("#{i}"), |h| clip(h));
            notes.push(format!(
                "{}: temperature column `{name}` is empty or NaN in {missing} of {rows} rows: ignored (no temperature)",
                self.file
            ));
            columns.temp = None;
        }
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
}
