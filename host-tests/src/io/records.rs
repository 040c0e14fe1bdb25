//! CSV records through the `csv` crate, each with its 1-based file line; blank lines and `#`
//! comments are skipped, cells are unquoted (and trimmed by [`super::text::cell`]).

use std::io::Read;

use csv::ByteRecord;

use super::CsvError;
use super::text::{Delimiter, LineEnds, csv_reader, squeeze_whitespace};

/// The data records of a file (or of its part after the header).
pub(crate) struct Records<R: Read> {
    file: String,
    reader: csv::Reader<LineEnds<R>>,
    delimiter: Delimiter,
    /// File line of the reader's line 0 (the reader counts from 1).
    line_offset: usize,
    scratch: ByteRecord,
}

impl<R: Read> Records<R> {
    /// Records of `source`, whose first line is file line `line_offset + 1`; `after_cr` as in
    /// [`LineEnds::new`].
    pub(crate) fn new(file: &str, source: R, delimiter: Delimiter, line_offset: usize, after_cr: bool) -> Self {
        let reader = csv_reader(LineEnds::new(source, delimiter, after_cr), delimiter, true);
        Self { file: file.to_string(), reader, delimiter, line_offset, scratch: ByteRecord::new() }
    }

    /// Reads the next data record into `record`: its file line, or `None` at the end.
    ///
    /// # Errors
    /// [`CsvError::Io`] when the file cannot be read; [`CsvError::Binary`] for a NUL byte.
    pub(crate) fn next_into(&mut self, record: &mut ByteRecord) -> Result<Option<usize>, CsvError> {
        loop {
            let more = self
                .reader
                .read_byte_record(record)
                .map_err(|e| CsvError::Io { file: self.file.clone(), message: e.to_string() })?;
            if !more {
                return Ok(None);
            }
            let line = self.line_offset + record.position().map_or(0, |p| p.line() as usize);
            if record.as_slice().contains(&0) {
                return Err(CsvError::Binary { file: self.file.clone(), line, what: "NUL bytes" });
            }
            if self.delimiter == Delimiter::Whitespace {
                squeeze_whitespace(record, &mut self.scratch);
            }
            if !self.is_blank_or_comment(record) {
                return Ok(Some(line));
            }
        }
    }

    /// A record of nothing but blanks (one empty cell, or empty cells between tabs), or a comment
    /// whose `#` follows blanks.
    fn is_blank_or_comment(&self, record: &ByteRecord) -> bool {
        let all_empty = record.iter().all(|c| c.trim_ascii().is_empty());
        let blank = all_empty && (record.len() <= 1 || self.delimiter == Delimiter::Tab);
        blank || record.get(0).is_some_and(|c| c.trim_ascii_start().starts_with(b"#"))
    }
}
