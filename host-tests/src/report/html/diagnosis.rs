//! The body of the `diagnose` report: the verdict (which unmodelled effect, if any, explains the
//! gap), the gap between the real residual and a simulation of the same poses, the candidates with
//! their held-out evidence and the ratio after, the probes, Allan deviation on log-log axes, and the
//! per-pose residual (stems, sphere, against time and temperature). Drawn from the
//! `diagnose --json` document only.

use std::fmt::Write as _;

use serde_json::Value;

use super::calibrate::{PosePoint, against_figure, params_table, sphere_figure, stems_figure};
use super::svg::{AFTER, Axes, BEFORE, legend};
use super::{escape, number_cell, sig};

/// The page body for a `diagnose --json` document.
pub fn body(doc: &Value) -> String {
    let mut out = String::new();
    summary(&mut out, doc);
    table(&mut out, doc, "Gap: real residual against the simulated one", "/gap", 1, GAP_COLUMNS);
    let candidates = doc["candidates"].as_array().map_or(0, Vec::len);
    table(&mut out, doc, "Candidates (held-out evidence)", "/candidates", candidates, CANDIDATE_COLUMNS);
    gains_figure(&mut out, doc, candidates);
    let ranked = doc["candidates_ranked"].as_array().map_or(0, Vec::len);
    table(&mut out, doc, "Candidates ranked", "/candidates_ranked", ranked, RANKED_COLUMNS);
    let probes = doc["probes"].as_array().map_or(0, Vec::len);
    table(&mut out, doc, "Probes", "/probes", probes, PROBE_COLUMNS);
    allan_figure(&mut out, doc);
    params_table(&mut out, doc);
    let points = pose_points(doc);
    out.push_str("<h2>Residual per pose</h2>\n");
    stems_figure(&mut out, &points, false, "after calibration");
    sphere_figure(&mut out, &points);
    against_figure(&mut out, &points, "time", "pose middle time (s)", |p| p.t_mid_s);
    against_figure(&mut out, &points, "temperature", "pose mean temperature (deg C)", |p| p.temp_c);
    out
}

/// Columns of a table: (JSON key in each row, header).
type Columns = &'static [(&'static str, &'static str)];

const GAP_COLUMNS: Columns = &[
    ("real_rmse_after_mg", "real RMSE after (mg)"),
    ("sim_rmse_after_mg", "simulated RMSE after (mg)"),
    ("sim_spread_mg", "simulated spread (mg)"),
    ("ratio_before", "ratio before"),
    ("ratio_after", "ratio after"),
    ("z", "z"),
    ("significant", "significant"),
];
const CANDIDATE_COLUMNS: Columns = &[
    ("effect", "effect"),
    ("detail", "model"),
    ("applicable", "applicable"),
    ("extra_params", "extra parameters"),
    ("heldout_gain", "held-out gain"),
    ("heldout_ratio", "held-out ratio"),
    ("ratio_after", "ratio after"),
    ("within_gain", "within-pose gain"),
    ("within_disagreement", "holds vs pose means (chi2/coef)"),
];
const RANKED_COLUMNS: Columns = &[
    ("effect", "effect"),
    ("evidence", "evidence"),
    ("heldout_gain", "held-out gain"),
    ("within_gain", "within-pose gain"),
];
const PROBE_COLUMNS: Columns = &[("shape", "shape"), ("detail", "detail"), ("heldout_gain", "held-out gain")];

fn summary(out: &mut String, doc: &Value) {
    let text = |k: &str| escape(&plain(&doc[k]));
    let v = &doc["verdict"];
    let explained = v["explained"].as_bool() == Some(true);
    let _ = write!(
        out,
        "<p>File <code>{}</code>, units {}, {} samples, {} poses, {} simulated repeats, seed {}.</p>\n\
         <h2>Verdict: <span id=\"verdict\" class=\"{}\">{}</span></h2>\n",
        text("file"),
        text("units"),
        text("samples"),
        text("poses"),
        text("repeats"),
        text("seed"),
        if explained { "pass" } else { "fail" },
        escape(&verdict_line(v)),
    );
    table(
        out,
        doc,
        "",
        "/verdict",
        1,
        &[("effect", "effect"), ("where", "where"), ("heldout_gain", "held-out gain"), ("shrink", "shrink")],
    );
}

fn verdict_line(v: &Value) -> String {
    match (v["explained"].as_bool(), v["effect"].as_str()) {
        (Some(true), Some(effect)) => format!("the gap is explained by {effect}"),
        (_, Some(effect)) => format!("not explained (best candidate: {effect})"),
        _ => "not explained".into(),
    }
}

/// A JSON scalar as text (strings without quotes, null as `-`).
fn plain(v: &Value) -> String {
    match v {
        Value::String(s) => s.clone(),
        Value::Null => "-".into(),
        other => other.to_string(),
    }
}

/// A table of `rows` objects under `base` (an object itself when `rows` is 1 and `base` is not an
/// array); numbers are tagged cells, other values text.
fn table(out: &mut String, doc: &Value, title: &str, base: &str, rows: usize, columns: Columns) {
    if !title.is_empty() {
        let _ = writeln!(out, "<h2>{}</h2>", escape(title));
    }
    out.push_str("<table><tr>");
    for (_, header) in columns {
        let _ = write!(out, "<th>{}</th>", escape(header));
    }
    out.push_str("</tr>\n");
    let is_array = doc.pointer(base).is_some_and(Value::is_array);
    for row in 0..rows {
        let prefix = if is_array { format!("{base}/{row}") } else { base.to_string() };
        out.push_str("<tr>");
        for (key, _) in columns {
            let pointer = format!("{prefix}/{key}");
            match doc.pointer(&pointer) {
                Some(v) if v.is_number() => out.push_str(&number_cell(&pointer, doc)),
                Some(v) => {
                    let _ = write!(out, r#"<td class="text">{}</td>"#, escape(&plain(v)));
                }
                None => out.push_str("<td>-</td>"),
            }
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
}

fn gains_figure(out: &mut String, doc: &Value, count: usize) {
    let gains: Vec<(f64, f64, String)> = (0..count)
        .filter_map(|i| {
            let c = &doc["candidates"][i];
            c["heldout_gain"].as_f64().map(|g| ((i + 1) as f64, g, plain(&c["detail"])))
        })
        .collect();
    if gains.is_empty() {
        return;
    }
    let xs: Vec<f64> = gains.iter().map(|g| g.0).collect();
    let ys: Vec<f64> = gains.iter().map(|g| g.1).collect();
    let axes = Axes::fit(&xs, &ys);
    axes.open(out, "held-out gain of each candidate (row of the table above)", "candidate", "held-out gain");
    for (x, gain, detail) in &gains {
        axes.stem(out, *x, *gain, AFTER, &format!("#{x}: {detail}: {}", sig(*gain)));
    }
    out.push_str("</svg>\n");
}

fn allan_figure(out: &mut String, doc: &Value) {
    let noise = &doc["where"]["noise"];
    let series = |key: &str| -> Vec<(f64, f64)> {
        let taus = noise["allan_tau_s"].as_array().map_or(&[][..], Vec::as_slice);
        taus.iter()
            .zip(noise[key].as_array().map_or(&[][..], Vec::as_slice))
            .filter_map(|(t, a)| t.as_f64().zip(a.as_f64()))
            .collect()
    };
    let (measured, white) = (series("allan_adev_mg"), series("allan_white_mg"));
    out.push_str("<h2>Allan deviation</h2>\n");
    if measured.is_empty() {
        out.push_str("<p class=\"note\">No long enough rest in the recording: no Allan deviation.</p>\n");
        return;
    }
    let xs: Vec<f64> = measured.iter().chain(&white).map(|p| p.0).collect();
    let ys: Vec<f64> = measured.iter().chain(&white).map(|p| p.1).collect();
    let axes = Axes::fit_log_log(&xs, &ys);
    axes.open(out, "Allan deviation of the longest rest (log-log)", "averaging time tau (s)", "Allan deviation (mg)");
    axes.polyline(out, &measured, AFTER, false);
    axes.polyline(out, &white, BEFORE, true);
    legend(out, 0, AFTER, "measured");
    legend(out, 1, BEFORE, "white noise alone");
    out.push_str("</svg>\n");
}

fn pose_points(doc: &Value) -> Vec<PosePoint> {
    let poses = doc["where"]["per_pose"].as_array().map_or(&[][..], Vec::as_slice);
    poses
        .iter()
        .enumerate()
        .map(|(i, p)| PosePoint {
            number: i + 1,
            left_out: false,
            direction: p["direction"]
                .as_array()
                .filter(|d| d.len() == 3)
                .map(|d| [0, 1, 2].map(|k| d[k].as_f64().unwrap_or(f64::NAN))),
            t_mid_s: p["t_mid_s"].as_f64(),
            temp_c: p["temp_c"].as_f64(),
            before_mg: None,
            after_mg: p["residual_after_mg"].as_f64(),
        })
        .collect()
}
