//! Test logs: a clean simulated log whose holds are knocked (for the shortest-pose rule).

use core::f64::consts::PI;

use crate::csvio::{self, AccumulateOptions, Table};
use crate::sim::scenario::{EffectClass, generate, random_scenario, to_table};

/// A clean simulated log read at 800 Hz (the library keeps still intervals of 100 samples, 0.125 s),
/// with knocks in every `every`-th hold: from `at` of the hold's length on, `times` times: 0.1 s of
/// shaking (0.3 g at 37 Hz), then `rest_s` resting pressed (a finger's force, 3 % along the
/// reading), then the hold goes on.
pub(crate) fn knocked_log(every: usize, at: f64, rest_s: f64, times: usize) -> Table {
    let mut scenario = random_scenario(EffectClass::None, 7);
    scenario.sim.rate_hz = 800.0;
    let mut table = to_table(&generate(&scenario), "knocked").unwrap();
    let library = AccumulateOptions { min_pose_s: 0.0, ..AccumulateOptions::default() };
    let acc = csvio::accumulate(&table, &library).unwrap();
    let rate = acc.sample_rate_hz.unwrap();
    let amplitude = 0.3 * table.median_magnitude;
    for span in acc.spans.iter().step_by(every) {
        let len = span.last_row + 1 - span.first_row;
        let start = span.first_row + (at * len as f64) as usize;
        let period = 0.1 + rest_s;
        let rows = start..(start + (period * times as f64 * rate) as usize).min(span.last_row + 1);
        for row in rows {
            let t = (row - start) as f64 / rate % period;
            let sample = &mut table.samples[row];
            *sample = if t < 0.1 {
                std::array::from_fn(|a| sample[a] + amplitude * (2.0 * PI * 37.0 * t + a as f64).sin())
            } else {
                sample.map(|v| v * 1.03)
            };
        }
    }
    table
}
