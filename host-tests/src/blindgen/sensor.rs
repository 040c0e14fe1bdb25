//! The simulated sensor's linear model (the truth to recover) and its output units.
//!
//! The sensor reads `f_s = Ka^-1 (f_b + B)` with `Ka = [[Sx,0,0],[Mx,Sy,0],[My,Mz,Sz]]`, the
//! convention of `accelcal::model`.

use serde_json::{Value, json};

use super::noise::Rng;
use super::session::G_MPS2;
use super::vec3::V3;

/// The 9-parameter truth of one log, in m/s^2 for the bias.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Truth {
    /// `B` (m/s^2).
    pub bias_mps2: V3,
    /// Diagonal of `Ka`: `[Sx, Sy, Sz]`.
    pub scale: V3,
    /// Lower off-diagonal of `Ka`: `[Mx, My, Mz]` at (1,0), (2,0), (2,1).
    pub nonorth: V3,
}

impl Truth {
    /// A random truth: `S` in 0.95-1.05, `M` within +-0.02, `B` within +-0.3 m/s^2.
    pub fn random(rng: &mut Rng) -> Self {
        Self {
            bias_mps2: core::array::from_fn(|_| rng.range(-0.3, 0.3)),
            scale: core::array::from_fn(|_| rng.range(0.95, 1.05)),
            nonorth: core::array::from_fn(|_| rng.range(-0.02, 0.02)),
        }
    }

    /// `Ka^-1 y` (forward substitution).
    pub fn ka_inv(&self, y: V3) -> V3 {
        let (s, m) = (self.scale, self.nonorth);
        let x0 = y[0] / s[0];
        let x1 = (y[1] - m[0] * x0) / s[1];
        let x2 = (y[2] - m[1] * x0 - m[2] * x1) / s[2];
        [x0, x1, x2]
    }

    /// The calibration: `Ka f_s - B` (`f_s` in m/s^2).
    pub fn apply(&self, f_s: V3) -> V3 {
        let (s, m, b) = (self.scale, self.nonorth, self.bias_mps2);
        [
            s[0] * f_s[0] - b[0],
            m[0] * f_s[0] + s[1] * f_s[1] - b[1],
            m[1] * f_s[0] + m[2] * f_s[1] + s[2] * f_s[2] - b[2],
        ]
    }

    /// The truth in `units` (bias in the output unit, `S` and `M` unitless) as JSON.
    pub fn to_json(&self, units: Units) -> Value {
        let k = units.per_mps2();
        json!({
            "B": self.bias_mps2.map(|b| b * k),
            "B_mps2": self.bias_mps2,
            "S": self.scale,
            "M": self.nonorth,
        })
    }
}

/// Output unit of a log.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Units {
    /// Metres per second squared.
    Mps2,
    /// Standard gravities.
    G,
    /// Signed integer counts of a `bits`-bit converter at `lsb_per_g` counts per g.
    Counts {
        /// Counts per g.
        lsb_per_g: f64,
        /// Converter width (saturates at `+-(2^(bits-1) - 1)`).
        bits: u32,
    },
}

impl Units {
    /// A random unit: m/s^2, g, 16384 or 4096 counts/g (16 bits), or a coarse 12-bit 8 mg/LSB.
    pub fn random(rng: &mut Rng) -> Self {
        match rng.index(5) {
            0 => Self::Mps2,
            1 => Self::G,
            2 => Self::Counts { lsb_per_g: 16384.0, bits: 16 },
            3 => Self::Counts { lsb_per_g: 4096.0, bits: 16 },
            _ => Self::COARSE,
        }
    }

    /// A coarse 12-bit sensor, 1 LSB = 8 mg.
    pub const COARSE: Self = Self::Counts { lsb_per_g: 125.0, bits: 12 };

    /// Output units per m/s^2.
    pub fn per_mps2(self) -> f64 {
        match self {
            Self::Mps2 => 1.0,
            Self::G => 1.0 / G_MPS2,
            Self::Counts { lsb_per_g, .. } => lsb_per_g / G_MPS2,
        }
    }

    /// A reading in m/s^2 expressed in this unit (rounded and saturated for counts).
    pub fn convert(self, value_mps2: f64) -> f64 {
        let v = value_mps2 * self.per_mps2();
        match self {
            Self::Counts { bits, .. } => {
                let full = f64::from((1u32 << (bits - 1)) - 1);
                v.round().clamp(-full, full)
            }
            _ => v,
        }
    }

    /// The name used in the manifest.
    pub fn name(self) -> &'static str {
        match self {
            Self::Mps2 => "m/s^2",
            Self::G => "g",
            Self::Counts { .. } => "counts",
        }
    }

    /// The column suffix the CSV reader recognises.
    pub fn column_suffix(self) -> &'static str {
        match self {
            Self::Mps2 => "_mps2",
            Self::G => "_g",
            Self::Counts { .. } => "_raw",
        }
    }

    /// Counts per g, for count units.
    pub fn lsb_per_g(self) -> Option<f64> {
        match self {
            Self::Counts { lsb_per_g, .. } => Some(lsb_per_g),
            _ => None,
        }
    }

    /// Formats one reading.
    pub fn format(self, value: f64) -> String {
        match self {
            Self::Mps2 => format!("{value:.6}"),
            Self::G => format!("{value:.7}"),
            // `+ 0.0` turns a negative zero into zero.
            Self::Counts { .. } => format!("{:.0}", value + 0.0),
        }
    }
}
