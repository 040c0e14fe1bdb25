//! Seeding without importing `rand_core`: [`seeded_rng`] gives the [`DefaultRng`] for a `u64` seed.
//!
//! ```
//! let mut rng = accelcal::seeded_rng(42); // print the seed with the results
//! use accelcal::rand_core::Rng;
//! assert_eq!(rng.next_u32(), accelcal::seeded_rng(42).next_u32());
//! ```

use rand_core::SeedableRng;

use crate::calibrate::DefaultRng;

/// The [`DefaultRng`] seeded from `seed` (`SeedableRng::seed_from_u64`): the same seed gives the same
/// calibration.
pub fn seeded_rng(seed: u64) -> DefaultRng {
    DefaultRng::seed_from_u64(seed)
}
