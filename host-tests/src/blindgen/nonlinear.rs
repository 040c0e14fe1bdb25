//! Scale non-linearity: each axis reads `a + k2 a^2 + k3 a^3` of its linear input `a` (in g), with
//! random signs. Shapes: square, cube, both.

use serde_json::{Value, json};

use super::noise::Rng;
use super::session::Ctx;
use super::vec3::V3;
use super::{Effect, EffectModel, Injector, LogSpec, Magnitude};

/// Per-axis square and cube terms.
#[derive(Debug, Clone, PartialEq)]
pub struct Nonlinear {
    /// Square coefficients (1/g).
    pub k2_per_g: V3,
    /// Cube coefficients (1/g^2).
    pub k3_per_g2: V3,
    /// Largest error at 1 g over the axes (mg), as drawn.
    pub at_1g_mg: f64,
}

/// Sets a random non-linearity on `spec`.
pub fn randomise(rng: &mut Rng, spec: &mut LogSpec) {
    let at_1g_mg = rng.log_uniform(0.3, 30.0);
    let (square, cube) = match rng.index(3) {
        0 => (true, false),
        1 => (false, true),
        _ => (true, true),
    };
    let mut draw = |on: bool| -> V3 {
        core::array::from_fn(|_| if on { rng.sign() * rng.range(0.3, 1.0) * at_1g_mg * 1e-3 } else { 0.0 })
    };
    let k2_per_g = draw(square);
    let k3_per_g2 = draw(cube);
    spec.set_effect(Effect::Nonlinear(Nonlinear { k2_per_g, k3_per_g2, at_1g_mg }));
}

impl EffectModel for Nonlinear {
    fn shape(&self) -> String {
        match (self.k2_per_g != [0.0; 3], self.k3_per_g2 != [0.0; 3]) {
            (true, false) => "square",
            (false, true) => "cube",
            _ => "square_and_cube",
        }
        .into()
    }

    fn params(&self) -> Value {
        json!({"k2_per_g": self.k2_per_g, "k3_per_g2": self.k3_per_g2})
    }

    fn magnitude(&self) -> Magnitude {
        Magnitude { value: self.at_1g_mg, unit: "mg", what: "largest error at 1 g" }
    }

    fn injector(&self, _rng: Rng) -> Box<dyn Injector + '_> {
        Box::new(self)
    }
}

impl Injector for &Nonlinear {
    fn response_g(&mut self, _ctx: &Ctx, a: V3) -> V3 {
        core::array::from_fn(|k| a[k] + self.k2_per_g[k] * a[k] * a[k] + self.k3_per_g2[k] * a[k] * a[k] * a[k])
    }
}
