//! Text before it is CSV: the encoding (UTF-8, or Latin-1 with a warning; binary refused), the
//! line ends (LF, CR LF or a lone CR, each one line), the delimiter, and single lines split into
//! cells by the `csv` crate (for the header and the preamble before it).
//!
//! ```
//! use accelcal_host::io::{Delimiter, split_cells, split_lines};
//! assert_eq!(split_lines("a\rb\r\nc"), vec!["a", "b", "c"]);
//! assert_eq!(split_cells("\"t, s\" ; 1,5", Delimiter::Semicolon), vec!["t, s", "1,5"]);
//! ```

use std::borrow::Cow;
use std::io::{self, Read};

use super::CsvError;

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

    fn byte(self) -> u8 {
        match self {
            Self::Comma => b',',
            Self::Semicolon => b';',
            Self::Tab => b'\t',
            Self::Whitespace => b' ',
        }
    }
}

/// The text of `bytes`: UTF-8 (a byte-order mark dropped), or Latin-1 with a warning in `notes`
/// when a few bytes are not UTF-8; NUL bytes, UTF-16 and binary data are refused.
pub(crate) fn decode<'a>(file: &str, bytes: &'a [u8], notes: &mut Vec<String>) -> Result<Cow<'a, str>, CsvError> {
    if let Some(pos) = bytes.iter().position(|&b| b == 0) {
        let utf16 = bytes.starts_with(&[0xFF, 0xFE]) || bytes.starts_with(&[0xFE, 0xFF]);
        let what = if utf16 { "UTF-16 text; save it as UTF-8" } else { "NUL bytes" };
        return Err(CsvError::Binary { file: file.to_string(), line: line_at(bytes, pos), what });
    }
    let text = match std::str::from_utf8(bytes) {
        Ok(t) => Cow::Borrowed(t),
        Err(e) => {
            let line = line_at(bytes, e.valid_up_to());
            if looks_binary(bytes) {
                return Err(CsvError::Binary { file: file.to_string(), line, what: "invalid UTF-8" });
            }
            // Text with a few non-UTF-8 bytes, e.g. a Latin-1 degree sign from a serial monitor.
            notes.push(format!("{file}:{line}: not UTF-8; read as Latin-1 (ISO 8859-1)"));
            Cow::Owned(latin1(bytes))
        }
    };
    // Latin-1 text has no byte-order mark (U+FEFF is not one of its characters).
    Ok(match text {
        Cow::Borrowed(t) => Cow::Borrowed(t.strip_prefix('\u{feff}').unwrap_or(t)),
        owned => owned,
    })
}

/// Bytes as Latin-1 (ISO 8859-1) characters.
pub(crate) fn latin1(bytes: &[u8]) -> String {
    bytes.iter().map(|&b| char::from(b)).collect()
}

/// 1-based line of byte `offset` (LF counted).
fn line_at(bytes: &[u8], offset: usize) -> usize {
    1 + bytes[..offset.min(bytes.len())].iter().filter(|&&b| b == b'\n').count()
}

/// `true` for bytes that are not text in any 8-bit encoding: control characters other than tab,
/// CR, LF and form feed, or more bytes above 0x7F than a few accented letters or unit signs
/// (over 16 and over 1 % of the file).
fn looks_binary(bytes: &[u8]) -> bool {
    let control = bytes.iter().any(|&b| (b < 0x20 && !matches!(b, b'\t' | b'\n' | b'\r' | 0x0c)) || b == 0x7f);
    let high = bytes.iter().filter(|&&b| b >= 0x80).count();
    control || (high > 16 && high * 100 > bytes.len())
}

/// A reader that ends every line with LF: a CR LF pair and a lone CR (old Mac OS) both become one
/// LF, so that the `csv` crate's line numbers count each line once. In whitespace-delimited text
/// tabs become spaces.
pub(crate) struct LineEnds<R> {
    inner: R,
    last_was_cr: bool,
    tabs_to_spaces: bool,
}

impl<R: Read> LineEnds<R> {
    /// `after_cr`: the text before `inner` ended with a CR (an LF first in `inner` ends no line).
    pub(crate) fn new(inner: R, delimiter: Delimiter, after_cr: bool) -> Self {
        Self { inner, last_was_cr: after_cr, tabs_to_spaces: delimiter == Delimiter::Whitespace }
    }
}

impl<R: Read> Read for LineEnds<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        loop {
            let n = self.inner.read(buf)?;
            if n == 0 {
                return Ok(0);
            }
            let mut kept = 0;
            for i in 0..n {
                let b = buf[i];
                let after_cr = std::mem::replace(&mut self.last_was_cr, b == b'\r');
                if b == b'\n' && after_cr {
                    continue;
                }
                buf[kept] = match b {
                    b'\r' => b'\n',
                    b'\t' if self.tabs_to_spaces => b' ',
                    _ => b,
                };
                kept += 1;
            }
            if kept > 0 {
                return Ok(kept);
            }
        }
    }
}

/// The `csv` crate's reader as every table is read: no header record (the header is found first),
/// rows of any length (checked against the header with their line), `#` comments. Cells are trimmed
/// as they are read ([`cell`]): the crate's own trimming copies every record.
pub(crate) fn csv_reader<R: Read>(source: R, delimiter: Delimiter, comments: bool) -> csv::Reader<R> {
    csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .comment(comments.then_some(b'#'))
        .delimiter(delimiter.byte())
        .from_reader(source)
}

/// Drops the empty cells a run of spaces leaves between whitespace-delimited cells.
pub(crate) fn squeeze_whitespace(record: &mut csv::ByteRecord, scratch: &mut csv::ByteRecord) {
    if record.iter().all(|c| !c.trim_ascii().is_empty()) {
        return;
    }
    scratch.clear();
    for cell in record.iter().filter(|c| !c.trim_ascii().is_empty()) {
        scratch.push_field(cell);
    }
    std::mem::swap(record, scratch);
}

/// Cell `i` of a record as trimmed text (Latin-1 when not UTF-8); empty past the last cell.
pub(crate) fn cell(record: &csv::ByteRecord, i: usize) -> Cow<'_, str> {
    let bytes = record.get(i).unwrap_or_default();
    match std::str::from_utf8(bytes) {
        Ok(text) => Cow::Borrowed(text.trim()),
        Err(_) => Cow::Owned(latin1(bytes).trim().to_string()),
    }
}

/// Splits one line into trimmed, unquoted cells (`"a,b"` is one cell, `""` in quotes a quote).
pub fn split_cells(line: &str, delimiter: Delimiter) -> Vec<String> {
    let source = LineEnds::new(line.as_bytes(), delimiter, false);
    let mut reader = csv_reader(source, delimiter, false);
    let (mut record, mut scratch) = (csv::ByteRecord::new(), csv::ByteRecord::new());
    // Reading a slice cannot fail; a line without cells gives none.
    if !reader.read_byte_record(&mut record).unwrap_or(false) {
        return Vec::new();
    }
    if delimiter == Delimiter::Whitespace {
        squeeze_whitespace(&mut record, &mut scratch);
    }
    (0..record.len()).map(|i| cell(&record, i).into_owned()).collect()
}

/// Lines ended by LF, CR LF or a lone CR (old Mac OS); a line number counts each of them once.
pub fn split_lines(text: &str) -> Vec<&str> {
    let mut lines: Vec<&str> = Lines::new(text).map(|(line, _)| line).collect();
    if text.ends_with(['\n', '\r']) || text.is_empty() {
        lines.push("");
    }
    lines
}

/// The lines of a text and, with each, the byte offset just past its line end.
pub(crate) struct Lines<'a> {
    text: &'a str,
    offset: usize,
}

impl<'a> Lines<'a> {
    pub(crate) fn new(text: &'a str) -> Self {
        Self { text, offset: 0 }
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (&'a str, usize);
    fn next(&mut self) -> Option<Self::Item> {
        let rest = self.text.get(self.offset..).filter(|r| !r.is_empty())?;
        let (end, width) = match rest.find(['\n', '\r']) {
            Some(end) => (end, if rest[end..].starts_with("\r\n") { 2 } else { 1 }),
            None => (rest.len(), 0),
        };
        self.offset += end + width;
        Some((&rest[..end], self.offset))
    }
}

/// `true` for a line that is empty, blanks only, or a `#` comment.
pub(crate) fn is_blank_or_comment(line: &str) -> bool {
    let t = line.trim();
    t.is_empty() || t.starts_with('#')
}

/// A cell as a number: `Ok(Some(v))`, `Ok(None)` for missing (empty, NaN, inf), `Err` for text.
/// With `;` as the delimiter a decimal comma (`1,5`) is accepted.
pub(crate) fn parse_number(cell: &str, delimiter: Delimiter) -> Result<Option<f64>, ()> {
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
