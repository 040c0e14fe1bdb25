//! Where the header is: the first line that is not blank or a comment, unless a preamble (a
//! logger's title, metadata such as `Fs,100`) comes first; the data starts on the line after it.

use super::text::{Delimiter, Lines, is_blank_or_comment, parse_number, split_cells};
use super::{CsvError, PREAMBLE_SEARCH_LINES};

/// The header line of a text and where the data after it starts.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct HeaderAt {
    /// 1-based line of the first line that is not blank or a comment.
    pub(crate) first_line: usize,
    /// 1-based line of the header.
    pub(crate) line: usize,
    /// The header's text.
    pub(crate) text: String,
    /// Byte offset of the line after the header.
    pub(crate) data_offset: usize,
    /// `true` when the header's line ends with a lone CR (an LF after it ends no line).
    pub(crate) ends_with_cr: bool,
}

/// Finds the header of `text`. The header is the last all-text line (no numeric cell) before the
/// first all-numeric line among the first [`PREAMBLE_SEARCH_LINES`]; without such a pair (e.g. a
/// text label column in every row) it is the first line.
///
/// # Errors
/// [`CsvError::Empty`] for a text of blank lines and comments, [`CsvError::NoHeader`] when the
/// first line is numbers.
pub(crate) fn find_header(file: &str, text: &str, delimiter: Option<Delimiter>) -> Result<HeaderAt, CsvError> {
    // (0-based index, text, offset after the line end) of the lines searched.
    let mut searched: Vec<(usize, &str, usize)> = Vec::new();
    let (mut non_blank, mut numeric) = (0, None);
    for (i, (line, end)) in Lines::new(text).enumerate() {
        searched.push((i, line, end));
        if !is_blank_or_comment(line) {
            non_blank += 1;
            if is_numeric_line(line, delimiter) {
                numeric = Some(i);
                break;
            }
            if non_blank >= PREAMBLE_SEARCH_LINES {
                break;
            }
        }
    }
    let Some(first) = searched.iter().position(|(_, l, _)| !is_blank_or_comment(l)) else {
        return Err(CsvError::Empty { file: file.to_string() });
    };
    let (first_index, first_text, _) = searched[first];
    if numeric == Some(first) {
        return Err(CsvError::NoHeader {
            file: file.to_string(),
            line: first_index + 1,
            text: first_text.trim().into(),
        });
    }
    let header =
        numeric.and_then(|k| (first..k).rev().find(|&i| is_text_line(searched[i].1, delimiter))).unwrap_or(first);
    let (index, header_text, data_offset) = searched[header];
    let ends_with_cr = text.as_bytes().get(data_offset.wrapping_sub(1)) == Some(&b'\r');
    Ok(HeaderAt {
        first_line: first_index + 1,
        line: index + 1,
        text: header_text.to_string(),
        data_offset,
        ends_with_cr,
    })
}

/// `true` for a line whose cells are all numbers (or empty), at least one of them a number.
fn is_numeric_line(line: &str, delimiter: Option<Delimiter>) -> bool {
    let delimiter = delimiter.unwrap_or_else(|| Delimiter::detect(line));
    let mut any = false;
    for c in &split_cells(line, delimiter) {
        match parse_number(c, delimiter) {
            Ok(v) => any |= v.is_some(),
            Err(()) => return false,
        }
    }
    any
}

/// `true` for a non-blank line none of whose cells is a number.
fn is_text_line(line: &str, delimiter: Option<Delimiter>) -> bool {
    if is_blank_or_comment(line) {
        return false;
    }
    let delimiter = delimiter.unwrap_or_else(|| Delimiter::detect(line));
    split_cells(line, delimiter).iter().all(|c| !matches!(parse_number(c, delimiter), Ok(Some(_))))
}
