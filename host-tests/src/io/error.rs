//! Why a file could not be read: every message names the file and, where one applies, the line,
//! and quotes at most [`MAX_QUOTED_CHARS`] characters of input.

use std::fmt;

use super::Units;

/// Most characters of input text (a cell, a line, a header) an error message quotes.
pub const MAX_QUOTED_CHARS: usize = 80;

/// At most [`MAX_QUOTED_CHARS`] characters of `text` for a message, with `...` when cut.
pub(crate) fn clip(text: &str) -> String {
    match text.char_indices().nth(MAX_QUOTED_CHARS) {
        Some((cut, _)) => format!("{}...", &text[..cut]),
        None => text.to_string(),
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
                write_wrong_units(f, file, *declared, *median_magnitude, *looks_like, header.as_deref())
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

/// The message of [`CsvError::WrongUnits`].
fn write_wrong_units(
    f: &mut fmt::Formatter<'_>,
    file: &str,
    declared: Units,
    median_magnitude: f64,
    looks_like: Option<Units>,
    header: Option<&str>,
) -> fmt::Result {
    let typical = match declared {
        Units::G => "about 1",
        Units::Mps2 => "about 9.8",
        _ => "hundreds to tens of thousands",
    };
    let by = header.map_or(String::new(), |h| format!(" (as the header `{}` says)", clip(h)));
    write!(
        f,
        "{file}: values no accelerometer reads in {declared}{by}: the median |a| is {median_magnitude:.4}, a \
         static accelerometer reads {typical}"
    )?;
    match (looks_like, header) {
        (Some(u), Some(_)) => write!(f, "; the values look like {u}: use --units {u}"),
        (Some(u), None) => write!(f, "; the values look like {u}: use --units {u} (or --units auto)"),
        (None, _) => f.write_str("; check the columns"),
    }
}

impl std::error::Error for CsvError {}
