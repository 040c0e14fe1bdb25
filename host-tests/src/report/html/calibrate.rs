//! The body of the `calibrate` report: summary, verdict, parameter table, per-pose residual stems,
//! pose directions on the sphere, residual against time and temperature, per-pose table. Drawn from
//! the `calibrate --json` document only.

use std::fmt::Write as _;

use serde_json::Value;

use super::svg::{AFTER, Axes, BEFORE, Direction, LEFT_OUT, hemispheres, legend};
use super::{escape, number_cell, number_span, sig};

/// One pose as the page draws it.
pub(super) struct PosePoint {
    /// Pose number from 1.
    pub(super) number: usize,
    pub(super) left_out: bool,
    /// Unit vector of the calibrated reading.
    pub(super) direction: Option<[f64; 3]>,
    /// Middle of the pose, s (with a time column).
    pub(super) t_mid_s: Option<f64>,
    pub(super) temp_c: Option<f64>,
    pub(super) before_mg: Option<f64>,
    pub(super) after_mg: Option<f64>,
}

/// The page body for a `calibrate --json` document.
pub fn body(doc: &Value) -> String {
    let points = pose_points(doc);
    let mut out = String::new();
    summary(&mut out, doc);
    verdict(&mut out, doc);
    params_table(&mut out, doc);
    out.push_str(
        "<h2>Residual per pose</h2>\n<p class=\"note\">Before: the readings at face value (g, m/s<sup>2</sup>) or \
         the initial estimate (counts, whose scale is unknown).</p>\n",
    );
    stems_figure(&mut out, &points, true, "before and after calibration");
    stems_figure(&mut out, &points, false, "after calibration (zoomed)");
    sphere_figure(&mut out, &points);
    against_figure(&mut out, &points, "time", "pose middle time (s)", |p| p.t_mid_s);
    against_figure(&mut out, &points, "temperature", "pose mean temperature (deg C)", |p| p.temp_c);
    pose_table(&mut out, doc, &points);
    out
}

fn pose_points(doc: &Value) -> Vec<PosePoint> {
    let left_out: Vec<u64> = doc["verdict"]["poses_left_out"]
        .as_array()
        .map_or(Vec::new(), |a| a.iter().filter_map(Value::as_u64).collect());
    let f = |v: &Value| v.as_f64();
    let poses = doc["poses"].as_array().map_or(&[][..], Vec::as_slice);
    poses
        .iter()
        .enumerate()
        .map(|(i, p)| PosePoint {
            number: i + 1,
            left_out: left_out.contains(&(i as u64)),
            direction: p["direction"]
                .as_array()
                .filter(|d| d.len() == 3)
                .map(|d| [0, 1, 2].map(|k| d[k].as_f64().unwrap_or(f64::NAN))),
            t_mid_s: f(&p["t_start"]).zip(f(&p["t_end"])).map(|(a, b)| 0.5 * (a + b)),
            temp_c: f(&p["temp_c"]),
            before_mg: f(&p["residual_before_mg"]),
            after_mg: f(&p["residual_after_mg"]),
        })
        .collect()
}

fn summary(out: &mut String, doc: &Value) {
    let text = |k: &str| escape(doc[k].as_str().unwrap_or("?"));
    let poses = doc["poses"].as_array().map_or(0, Vec::len);
    let _ = write!(
        out,
        "<p>File <code>{}</code>, units {}, {poses} poses, method {}, gravity {} m/s<sup>2</sup>.</p>\n\
         <table><tr><th>modulus RMSE (mg)</th><th>before</th><th>after</th><th>leave-one-pose-out</th><th>noise floor</th></tr>\
         <tr><th></th>{}{}{}{}</tr></table>\n",
        text("file"),
        text("units"),
        text("method"),
        number_span("/gravity", doc),
        number_cell("/rmse_mg/before", doc),
        number_cell("/rmse_mg/after", doc),
        number_cell("/rmse_mg/loo", doc),
        number_cell("/noise_floor_mg", doc),
    );
}

/// The verdict's reasons to fail, in words.
fn fail_reasons(v: &Value) -> Vec<String> {
    let mut reasons: Vec<String> = [
        ("rmse_over_limit", "the modulus RMSE after calibration is over the limit"),
        ("model_misfit", "the model does not fit: the RMSE is well above the noise floor"),
        ("implausible", "the parameters are implausible for an accelerometer"),
        ("not_converged", "the optimiser did not converge"),
    ]
    .into_iter()
    .filter(|(k, _)| v[*k].as_bool() == Some(true))
    .map(|(_, text)| text.to_string())
    .collect();
    let undetermined = names(&v["undetermined"]);
    if !undetermined.is_empty() {
        reasons.push(format!("poorly determined by the poses: {undetermined}"));
    }
    reasons
}

fn names(list: &Value) -> String {
    list.as_array().map_or(Vec::new(), |a| a.iter().filter_map(Value::as_str).collect::<Vec<_>>()).join(" ")
}

fn verdict(out: &mut String, doc: &Value) {
    let v = &doc["verdict"];
    let pass = v["pass"].as_bool() == Some(true);
    let (class, word) = if pass { ("pass", "PASS") } else { ("fail", "FAIL") };
    let _ = writeln!(out, r#"<h2>Verdict: <span class="{class}" id="verdict">{word}</span></h2><ul>"#);
    for reason in fail_reasons(v) {
        let _ = writeln!(out, "<li>{}</li>", escape(&reason));
    }
    let held = names(&v["held_at_nominal"]);
    if !held.is_empty() {
        let _ = writeln!(out, "<li>held at nominal (the orientations do not determine them): {}</li>", escape(&held));
    }
    let left: Vec<String> = v["poses_left_out"]
        .as_array()
        .map_or(Vec::new(), |a| a.iter().filter_map(Value::as_u64).map(|i| format!("#{}", i + 1)).collect());
    if !left.is_empty() {
        let _ = writeln!(out, "<li>poses left out (far off the fitted ellipsoid): {}</li>", left.join(", "));
    }
    out.push_str("</ul>\n");
}

pub(super) fn params_table(out: &mut String, doc: &Value) {
    let std_note = if doc.get("param_std").is_some() {
        "; value &plusmn; standard deviation (from the fit's information matrix)"
    } else {
        ""
    };
    let _ = writeln!(
        out,
        "<h2>Parameters</h2><p class=\"note\">f<sub>b</sub> = K<sub>a</sub> f<sub>s</sub> - B{std_note}.</p>\n\
         <table id=\"params\"><tr><th></th><th>x</th><th>y</th><th>z</th></tr>"
    );
    for (row, (key, label)) in
        [("bias", "bias B"), ("scale", "scale S"), ("nonorth", "non-orthogonality M")].iter().enumerate()
    {
        let _ = write!(out, "<tr><th>{label}</th>");
        for axis in 0..3 {
            let value = number_span(&format!("/params/{key}/{axis}"), doc);
            let std = doc.get("param_std").map(|_| format!(" &plusmn; {}", std_span(doc, 3 * row + axis)));
            let _ = write!(out, "<td>{value}{}</td>", std.unwrap_or_default());
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
}

/// The standard deviation of parameter `index`, or "held" for a parameter held at nominal.
fn std_span(doc: &Value, index: usize) -> String {
    let key = format!("/param_std/{index}");
    let name = accelcal::model::PARAM_NAMES.get(index).copied().unwrap_or("?");
    let held = doc["verdict"]["held_at_nominal"].as_array().is_some_and(|a| a.iter().any(|n| n.as_str() == Some(name)));
    if held && doc.pointer(&key).is_none_or(Value::is_null) { "held".into() } else { number_span(&key, doc) }
}

pub(super) fn stems_figure(out: &mut String, points: &[PosePoint], with_before: bool, title: &str) {
    let xs: Vec<f64> = points.iter().map(|p| p.number as f64).collect();
    let ys: Vec<f64> =
        points.iter().flat_map(|p| [p.before_mg.filter(|_| with_before), p.after_mg]).flatten().collect();
    let axes = Axes::fit(&xs, &ys);
    axes.open(out, &format!("modulus residual (|f| - g) / g per pose, {title}"), "pose", "residual (mg)");
    for p in points {
        let x = p.number as f64;
        if let Some(b) = p.before_mg.filter(|_| with_before) {
            axes.stem(out, x - 0.18, b, BEFORE, &format!("pose #{} before: {} mg", p.number, sig(b)));
        }
        if let Some(a) = p.after_mg {
            let colour = if p.left_out { LEFT_OUT } else { AFTER };
            axes.stem(out, x + 0.18, a, colour, &format!("pose #{} after: {} mg", p.number, sig(a)));
        }
    }
    if with_before {
        legend(out, 0, BEFORE, "before calibration");
    }
    legend(out, 1, AFTER, "after calibration");
    legend(out, 2, LEFT_OUT, "after, pose left out");
    out.push_str("</svg>\n");
}

pub(super) fn sphere_figure(out: &mut String, points: &[PosePoint]) {
    let directions: Vec<Direction> = points
        .iter()
        .filter_map(|p| {
            p.direction.map(|unit| Direction {
                unit,
                colour: if p.left_out { LEFT_OUT } else { AFTER },
                tip: format!("pose #{}: ({:.3}, {:.3}, {:.3})", p.number, unit[0], unit[1], unit[2]),
            })
        })
        .collect();
    out.push_str("<h2>Pose directions (coverage)</h2>\n");
    hemispheres(out, "direction of each pose's calibrated reading", &directions);
}

pub(super) fn against_figure(
    out: &mut String,
    points: &[PosePoint],
    what: &str,
    x_label: &str,
    x_of: fn(&PosePoint) -> Option<f64>,
) {
    let _ = writeln!(out, "<h2>Residual against {what}</h2>");
    let drawn: Vec<(f64, &PosePoint)> = points.iter().filter_map(|p| x_of(p).map(|x| (x, p))).collect();
    if drawn.is_empty() {
        let _ = writeln!(out, r#"<p class="note">No {what} column in the recording: nothing to draw.</p>"#);
        return;
    }
    let xs: Vec<f64> = drawn.iter().map(|d| d.0).collect();
    let ys: Vec<f64> = drawn.iter().flat_map(|(_, p)| [p.before_mg, p.after_mg]).flatten().collect();
    let axes = Axes::fit(&xs, &ys);
    axes.open(out, &format!("modulus residual against {what}"), x_label, "residual (mg)");
    for (x, p) in &drawn {
        if let Some(b) = p.before_mg {
            axes.dot(out, *x, b, BEFORE, &format!("pose #{} before: {} mg", p.number, sig(b)));
        }
        if let Some(a) = p.after_mg {
            let colour = if p.left_out { LEFT_OUT } else { AFTER };
            axes.dot(out, *x, a, colour, &format!("pose #{} after: {} mg", p.number, sig(a)));
        }
    }
    legend(out, 0, BEFORE, "before calibration");
    legend(out, 1, AFTER, "after calibration");
    out.push_str("</svg>\n");
}

fn pose_table(out: &mut String, doc: &Value, points: &[PosePoint]) {
    out.push_str(
        "<h2>Poses</h2>\n<table id=\"poses\"><tr><th>#</th><th>mean x</th><th>mean y</th><th>mean z</th>\
         <th>temperature (deg C)</th><th>residual before (mg)</th><th>after (mg)</th></tr>\n",
    );
    for p in points {
        let i = p.number - 1;
        let flag = if p.left_out { " (left out)" } else { "" };
        let _ = write!(out, "<tr><th>{}{flag}</th>", p.number);
        for axis in 0..3 {
            out.push_str(&number_cell(&format!("/poses/{i}/mean/{axis}"), doc));
        }
        for key in ["temp_c", "residual_before_mg", "residual_after_mg"] {
            out.push_str(&number_cell(&format!("/poses/{i}/{key}"), doc));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
}
