//! The unit of the simulated readings ([`OutputUnits`]): m/s^2, g, or counts of a 16-bit converter.

use std::fmt;
use std::str::FromStr;

/// The unit of the simulated readings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum OutputUnits {
    /// Raw ADC counts of a 16-bit converter: `reading = round(f_s_in_g * lsb_per_g + offset)`,
    /// clamped into `[offset - 32768, offset + 32767]`: the `i16` range for `offset = 0` (e.g. an
    /// MPU-6050 at ±2 g: 16384 LSB/g), the `u16` range for `offset = 32768` (offset-binary output).
    Counts {
        /// Counts per g (`1 g = SimConfig::gravity`).
        lsb_per_g: f64,
        /// Reading at zero specific force, counts.
        offset: f64,
    },
    /// Units of g (`1 g = SimConfig::gravity`).
    G,
    /// m/s^2.
    Mps2,
}

impl OutputUnits {
    /// An MPU-6050 at ±2 g: 16384 LSB/g, signed.
    pub const MPU6050_2G: Self = Self::Counts { lsb_per_g: 16384.0, offset: 0.0 };

    /// Converts a reading in m/s^2 to this unit, unrounded and unclamped.
    pub fn from_mps2(&self, value_mps2: f64, gravity_mps2: f64) -> f64 {
        match *self {
            Self::Counts { lsb_per_g, offset } => value_mps2 / gravity_mps2 * lsb_per_g + offset,
            Self::G => value_mps2 / gravity_mps2,
            Self::Mps2 => value_mps2,
        }
    }

    /// What the converter outputs for `value` (this unit): rounded and clamped for counts,
    /// unchanged otherwise.
    pub fn quantize(&self, value: f64) -> f64 {
        match self.count_range() {
            Some((low, high)) => value.round().clamp(low, high),
            None => value,
        }
    }

    /// The `[lowest, highest]` output for counts, `None` for the other units.
    pub fn count_range(&self) -> Option<(f64, f64)> {
        match *self {
            Self::Counts { offset, .. } => {
                let offset = offset.round();
                Some((offset - 32768.0, offset + 32767.0))
            }
            Self::G | Self::Mps2 => None,
        }
    }

    /// A white-noise standard deviation of `noise_mg` milli-g in this unit.
    pub fn noise_std(&self, noise_mg: f64, gravity_mps2: f64) -> f64 {
        let noise_g = noise_mg * 1e-3;
        match *self {
            Self::Counts { lsb_per_g, .. } => noise_g * lsb_per_g,
            Self::G => noise_g,
            Self::Mps2 => noise_g * gravity_mps2,
        }
    }

    /// `true` for [`OutputUnits::Counts`].
    pub fn is_counts(&self) -> bool {
        matches!(self, Self::Counts { .. })
    }

    /// `true` when the unit is usable: counts need a finite, non-zero `lsb_per_g` and a finite offset.
    pub fn is_valid(&self) -> bool {
        match *self {
            Self::Counts { lsb_per_g, offset } => lsb_per_g.is_finite() && lsb_per_g > 0.0 && offset.is_finite(),
            Self::G | Self::Mps2 => true,
        }
    }
}

impl fmt::Display for OutputUnits {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Counts { lsb_per_g, offset } => write!(f, "counts:{lsb_per_g}:{offset}"),
            Self::G => f.write_str("g"),
            Self::Mps2 => f.write_str("mps2"),
        }
    }
}

/// Why an output unit did not parse.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ParseUnitsError(pub String);

impl fmt::Display for ParseUnitsError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "invalid output unit `{}` (expected mps2, g, counts, counts:LSB_PER_G or counts:LSB_PER_G:OFFSET)",
            self.0
        )
    }
}

impl std::error::Error for ParseUnitsError {}

impl FromStr for OutputUnits {
    type Err = ParseUnitsError;

    /// Parses `mps2` (also `m/s2`, `m/s^2`), `g`, `counts` (16384 LSB/g, offset 0),
    /// `counts:LSB_PER_G` or `counts:LSB_PER_G:OFFSET`; case-insensitive.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let error = || ParseUnitsError(s.to_string());
        let text = s.trim().to_ascii_lowercase();
        let units = match text.as_str() {
            "mps2" | "m/s2" | "m/s^2" => Self::Mps2,
            "g" => Self::G,
            "counts" => Self::MPU6050_2G,
            _ => {
                let rest = text.strip_prefix("counts:").ok_or_else(error)?;
                let mut parts = rest.split(':');
                let lsb_per_g = parts.next().and_then(|p| p.trim().parse::<f64>().ok()).ok_or_else(error)?;
                let offset = match parts.next() {
                    Some(p) => p.trim().parse::<f64>().map_err(|_| error())?,
                    None => 0.0,
                };
                if parts.next().is_some() {
                    return Err(error());
                }
                Self::Counts { lsb_per_g, offset }
            }
        };
        if units.is_valid() { Ok(units) } else { Err(error()) }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn units_parse_and_display() {
        for units in [
            OutputUnits::Mps2,
            OutputUnits::G,
            OutputUnits::MPU6050_2G,
            OutputUnits::Counts { lsb_per_g: 1024.0, offset: 32768.0 },
        ] {
            assert_eq!(units.to_string().parse::<OutputUnits>(), Ok(units));
        }
        assert_eq!("counts".parse::<OutputUnits>(), Ok(OutputUnits::MPU6050_2G));
        assert_eq!("m/s^2".parse::<OutputUnits>(), Ok(OutputUnits::Mps2));
        assert!("counts:0".parse::<OutputUnits>().is_err());
        assert!("counts:16384:1:2".parse::<OutputUnits>().is_err());
        assert!("furlongs".parse::<OutputUnits>().is_err());
    }
}
