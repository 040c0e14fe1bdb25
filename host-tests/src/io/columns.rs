//! Which columns to read: chosen by the user (`--columns`, names or 0-based indices) or found by
//! name, case-insensitively, after dropping unit decorations (`_raw`, `_g`, `(g)`, `[m/s^2]`, ...)
//! and qualifiers such as `mean`.
//!
//! ```
//! use accelcal_host::io::{ColumnRef, ColumnSpec};
//! let spec: ColumnSpec = "t,ax,ay,az".parse().unwrap();
//! assert_eq!(spec.time, Some(ColumnRef::Name("t".into())));
//! ```

use std::fmt;
use std::str::FromStr;

use super::{CsvError, ReadOptions, clip};

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

/// What a header cell names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Field {
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

pub(crate) fn tokens(name: &str) -> Vec<String> {
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
pub(crate) fn classify(name: &str) -> Option<Field> {
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
pub(crate) fn time_scale(toks: &[String]) -> f64 {
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
    pub(crate) accel: [usize; 3],
    pub(crate) temp: Option<usize>,
    pub(crate) count: Option<usize>,
    pub(crate) stale: Option<usize>,
    pub(crate) std: Option<[usize; 3]>,
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

/// The columns found by name in `header` (file line `line`).
pub(crate) fn detect(file: &str, header: &[String], line: usize) -> Result<Columns, CsvError> {
    let file = &file.to_string();
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
    let missing: Vec<&'static str> = (0..3).filter(|&a| accel[a].is_none()).map(|a| ["ax", "ay", "az"][a]).collect();
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

/// The columns of `spec` in `header` (file line `line`); the stale flag is still found by name.
pub(crate) fn from_spec(file: &str, spec: &ColumnSpec, header: &[String], line: usize) -> Result<Columns, CsvError> {
    let resolve = |c: &ColumnRef| -> Result<usize, CsvError> {
        let found = match c {
            ColumnRef::Index(i) => Some(*i),
            ColumnRef::Name(n) => header.iter().position(|h| h.trim().eq_ignore_ascii_case(n.trim())),
        };
        found.ok_or_else(|| CsvError::UnknownColumn {
            file: file.to_string(),
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
