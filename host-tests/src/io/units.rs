//! Units of the acceleration columns: declared (`--units`), named in the headers (`ax_mg`) or told
//! from the magnitudes (median |a| near 1 is g, near 9.8 m/s^2, large raw counts).
//!
//! ```
//! use accelcal_host::io::Units;
//! assert_eq!("m/s^2".parse::<Units>(), Ok(Units::Mps2));
//! assert_eq!(Units::G.one_g(), Some(1.0));
//! ```

use std::fmt;
use std::str::FromStr;

use accelcal::model::{Params, STANDARD_GRAVITY_MPS2};

use super::columns::tokens;
use super::table::Table;
use super::{CsvError, clip};
use crate::stats::median;

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
pub(crate) fn header_unit(name: &str) -> Option<HeaderUnit> {
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

/// Units the median magnitude suggests, if any.
pub(crate) fn units_from_magnitude(median_magnitude: f64) -> Option<Units> {
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
pub(crate) fn units_plausible(units: Units, median_magnitude: f64) -> bool {
    match units {
        Units::G => (0.25..=4.0).contains(&median_magnitude),
        Units::Mps2 => (2.45..=39.3).contains(&median_magnitude),
        Units::Counts => median_magnitude >= 8.0,
        Units::Auto => true,
    }
}

/// The unit the acceleration column names agree on (`--units` other than auto overrides it, with
/// a warning when they differ); names that disagree are warned about and ignored.
fn header_units(file: &str, declared: Units, table: &mut Table) -> Option<HeaderUnit> {
    let named: Vec<HeaderUnit> = table.columns.accel.iter().filter_map(|c| header_unit(c)).collect();
    let first = named.first()?.clone();
    if named.iter().any(|h| h.label != first.label) {
        let labels: Vec<String> = named.iter().map(|h| format!("`{}`", clip(&h.column))).collect();
        table.warnings.push(format!("{file}: the columns {} name different units: ignored", labels.join(", ")));
        return None;
    }
    if declared != Units::Auto {
        if declared != first.units || first.factor != 1.0 {
            table.warnings.push(format!(
                "{file}: --units {} overrides the unit {} in the header (`{}`)",
                declared,
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

/// Resolves the table's units: from the header's unit label, `declared` (`--units`) or the magnitudes;
/// values scaled to the working unit and checked to be physical.
///
/// # Errors
/// [`CsvError::UnknownUnits`], [`CsvError::WrongUnits`] or [`CsvError::Gigantic`].
pub(crate) fn resolve(file: &str, declared: Units, table: &mut Table) -> Result<(), CsvError> {
    let header_unit = header_units(file, declared, table);
    if let Some(h) = &header_unit {
        scale_to_working_unit(table, h.factor);
    }
    let magnitudes: Vec<f64> = table.samples.iter().map(|s| s[0].hypot(s[1]).hypot(s[2])).collect();
    let median_magnitude = median(&magnitudes);
    let looks_like = units_from_magnitude(median_magnitude);
    let declared = header_unit.as_ref().map_or(declared, |h| h.units);
    let units = match declared {
        Units::Auto => match looks_like {
            Some(u) => u,
            None => return Err(CsvError::UnknownUnits { file: file.to_string(), median_magnitude }),
        },
        declared if units_plausible(declared, median_magnitude) => declared,
        declared => {
            let header = header_unit.map(|h| h.column);
            return Err(CsvError::WrongUnits {
                file: file.to_string(),
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
                file: file.to_string(),
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
