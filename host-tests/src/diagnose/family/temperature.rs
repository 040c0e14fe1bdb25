//! Temperature: bias, relative scale, or both, linear or quadratic (a second-order temperature
//! coefficient) in the temperature the sensor sees: the thermometer's reading, or that reading
//! through a first-order lag (the sensor warms later than the thermometer), with the lag's time
//! constant from a grid.

use super::{Context, Family, Variant};
use crate::diagnose::gap::row_time;
use crate::diagnose::math::{V3, mean};
use crate::diagnose::within::{Within, WithinVariant};

/// Lag time constants tried, s (0 = no lag).
const LAGS_S: [f64; 5] = [0.0, 30.0, 100.0, 300.0, 1000.0];

pub(crate) struct Temperature;

/// The temperature column through a first-order lag of `tau` seconds, averaged over each pose.
fn lagged_pose_temps(ctx: &Context<'_>, tau: f64) -> Option<Vec<f64>> {
    let lagged = lagged_temps(ctx, tau)?;
    Some(ctx.poses.iter().map(|p| mean(&lagged[p.rows.clone()])).collect())
}

/// The temperature column through a first-order lag of `tau` seconds, per row.
fn lagged_temps(ctx: &Context<'_>, tau: f64) -> Option<Vec<f64>> {
    let temps = ctx.table.temps_c.as_ref()?;
    let mut lagged = Vec::with_capacity(temps.len());
    let mut state = *temps.first()?;
    let mut last_t = row_time(ctx.table, 0, ctx.m.rate);
    for (i, t_c) in temps.iter().enumerate() {
        let t = row_time(ctx.table, i, ctx.m.rate);
        let alpha = if tau > 0.0 { 1.0 - (-(t - last_t).max(0.0) / tau).exp() } else { 1.0 };
        state += alpha * (t_c - state);
        last_t = t;
        lagged.push(state);
    }
    Some(lagged)
}

/// Temperature parametrisations of the within-pose channel: bias, scale or both, linear or
/// quadratic in the (lagged) temperature of each segment.
fn within_variants(ctx: &Context<'_>, w: &Within) -> Vec<WithinVariant> {
    let mut out = Vec::new();
    for lag in LAGS_S {
        let Some(lagged) = lagged_temps(ctx, lag) else { return out };
        let temps: Vec<f64> = w.rows.iter().map(|r| mean(&lagged[r.clone()])).collect();
        let t0 = mean(&temps);
        let lagged = &lagged;
        if temps.iter().map(|t| (t - t0).abs()).fold(0.0, f64::max) < 0.05 {
            continue;
        }
        let through = if lag > 0.0 { format!(" (thermometer lagged {lag:.0} s)") } else { String::new() };
        let lag_params = usize::from(lag > 0.0);
        for power in 1..=2 {
            let shape = if power == 1 { "linear" } else { "quadratic" };
            for (bias, scale, what) in [(true, false, "bias"), (false, true, "scale"), (true, true, "bias and scale")] {
                let params = 3 * power * (usize::from(bias) + usize::from(scale));
                let detail = format!("{what} {shape} in temperature{through}");
                out.push(w.variant(ctx.m, params, detail, &|p, _, rows| {
                    let dt = mean(&lagged[rows]) - t0;
                    temperature_effect(ctx.calibrated()[p], dt, power, bias, scale)
                }));
                out.last_mut().expect("just pushed").params += lag_params;
            }
        }
    }
    out
}

/// The calibrated-reading change per parameter: bias per axis, then relative scale per axis, for
/// each power of the temperature change `dt`.
fn temperature_effect(f: V3, dt: f64, power: usize, bias: bool, scale: bool) -> Vec<V3> {
    let axis = |a: usize, v: f64| -> V3 { std::array::from_fn(|i| if i == a { v } else { 0.0 }) };
    let mut out = Vec::new();
    for k in 1..=power {
        let x = dt.powi(k as i32);
        if bias {
            out.extend((0..3).map(|a| axis(a, x)));
        }
        if scale {
            out.extend((0..3).map(|a| axis(a, f[a] * x)));
        }
    }
    out
}

/// Bias and/or scale columns in the pose temperatures `temps`, up to the power `power` of the
/// temperature change (a second-order temperature coefficient for `power` 2).
fn design(ctx: &Context<'_>, temps: &[f64], power: usize, bias: bool, scale: bool) -> Vec<Vec<f64>> {
    let t0 = mean(temps);
    temps
        .iter()
        .zip(ctx.directions())
        .zip(ctx.calibrated())
        .map(|((t, u), f)| {
            let effect = temperature_effect(*f, t - t0, power, bias, scale);
            effect.iter().map(|e| u.iter().zip(e).map(|(a, b)| a * b).sum()).collect()
        })
        .collect()
}

impl Family for Temperature {
    fn name(&self) -> &'static str {
        "temperature"
    }

    fn within_variants(&self, ctx: &Context<'_>, within: &Within) -> Vec<WithinVariant> {
        within_variants(ctx, within)
    }

    fn variants(&self, ctx: &Context<'_>) -> Vec<Variant> {
        let mut out = Vec::new();
        for lag in LAGS_S {
            let Some(temps) = lagged_pose_temps(ctx, lag) else { return out };
            let t0 = mean(&temps);
            if temps.iter().map(|t| (t - t0).abs()).fold(0.0, f64::max) < 0.05 {
                continue;
            }
            let lag_params = usize::from(lag > 0.0);
            let through = if lag > 0.0 { format!(" (thermometer lagged {lag:.0} s)") } else { String::new() };
            for (bias, scale, what) in [(true, false, "bias"), (false, true, "scale"), (true, true, "bias and scale")] {
                for (power, shape) in [(1, "linear"), (2, "quadratic")] {
                    let params = 3 * power * (usize::from(bias) + usize::from(scale)) + lag_params;
                    let extra = design(ctx, &temps, power, bias, scale);
                    out.push(Variant { extra, params, detail: format!("{what} {shape} in temperature{through}") });
                }
            }
        }
        out
    }
}
