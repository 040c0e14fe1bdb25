//! The body of the `paper` report: Table 2 (our Monte Carlo and the Cramer-Rao bound beside the
//! paper's printed values), Fig. 3 (AGA, LAGA and TAGA on Rastrigin) and Fig. 6 (the calibration's
//! convergence), drawn from the `paper --json` document only.

use std::fmt::Write as _;

use serde_json::Value;

use super::svg::{AFTER, Axes, BEFORE, LEFT_OUT, legend};
use super::{escape, number_cell, number_span};

/// Colours of the series beyond "before" (grey), "after" (blue) and "left out" (red).
const GREEN: &str = "#2e7d32";
const ORANGE: &str = "#ef6c00";

/// Our methods in Table 2, with their colours in its figure.
const OUR_METHODS: [(&str, &str); 3] = [("newton", AFTER), ("taga", GREEN), ("taga+lm", ORANGE)];

/// The paper's columns of Table 2 (keys of `paper_table2_pct`), with their colours.
const PAPER_COLUMNS: [(&str, &str, &str); 2] =
    [("newton", "paper Newton", "#7b1fa2"), ("taga", "paper TAGA", LEFT_OUT)];

/// The page body for a `paper --json` document.
pub fn body(doc: &Value) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "<p>{} simulated experiments, plan <code>{}</code>, {} mg white noise per sample and axis, first seed {}.</p>",
        number_span("/runs", doc),
        escape(doc["plan"].as_str().unwrap_or("?")),
        number_span("/noise_mg", doc),
        number_span("/seed", doc),
    );
    table2(&mut out, doc);
    table2_figure(&mut out, doc);
    fig3(&mut out, doc);
    fig6(&mut out, doc);
    out
}

fn names(doc: &Value) -> Vec<String> {
    let names = doc["params"].as_array().map_or(&[][..], Vec::as_slice);
    names.iter().map(|n| n.as_str().unwrap_or("?").to_string()).collect()
}

fn table2(out: &mut String, doc: &Value) {
    out.push_str(
        "<h2>Table 2: relative error of the parameters (%)</h2>\n<p class=\"note\">Ours: the RMS over the runs \
         (Cramer-Rao bound: the smallest RMS any unbiased method can reach). The paper's: one run, signed; only \
         its order of magnitude can be compared.</p>\n<table><tr><th>parameter</th><th>Cramer-Rao bound</th>",
    );
    for (method, _) in OUR_METHODS {
        let _ = write!(out, "<th>{}</th>", escape(method));
    }
    for (_, label, _) in PAPER_COLUMNS {
        let _ = write!(out, "<th>{label}</th>");
    }
    out.push_str("</tr>\n");
    for (i, name) in names(doc).iter().enumerate() {
        let _ = write!(out, "<tr><th>{}</th>{}", escape(name), number_cell(&format!("/crlb_rel_pct/{i}"), doc));
        for (method, _) in OUR_METHODS {
            out.push_str(&number_cell(&format!("/rel_err_pct/{method}/{i}"), doc));
        }
        for (key, _, _) in PAPER_COLUMNS {
            out.push_str(&number_cell(&format!("/paper_table2_pct/{key}/{i}"), doc));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
}

/// Table 2 as dots on a log scale: the bound, our RMS errors, the magnitude of the paper's errors.
fn table2_figure(out: &mut String, doc: &Value) {
    let names = names(doc);
    let mut series: Vec<(&str, &str, Vec<f64>)> = vec![("Cramer-Rao bound", BEFORE, values(&doc["crlb_rel_pct"]))];
    for (method, colour) in OUR_METHODS {
        series.push((method, colour, values(&doc["rel_err_pct"][method])));
    }
    for (key, label, colour) in PAPER_COLUMNS {
        series.push((label, colour, values(&doc["paper_table2_pct"][key]).iter().map(|v| v.abs()).collect()));
    }
    let xs: Vec<f64> = (0..=names.len() + 1).map(|i| i as f64).collect();
    let ys: Vec<f64> = series.iter().flat_map(|s| s.2.iter().copied()).collect();
    let axes = Axes::fit_log_y(&xs, &with_headroom(ys, 100.0)).categorical_x();
    axes.open(out, "Table 2: |relative error| per parameter (log scale)", "parameter", "relative error (%)");
    for (i, name) in names.iter().enumerate() {
        axes.x_label(out, i as f64 + 1.0, name);
    }
    for (k, (label, colour, ys)) in series.iter().enumerate() {
        // Side by side within a parameter's slot.
        let offset = (k as f64 - (series.len() - 1) as f64 / 2.0) * 0.1;
        for (i, y) in ys.iter().enumerate() {
            let x = i as f64 + 1.0 + offset;
            if axes.shows(x, *y) {
                axes.dot(out, x, *y, colour, &format!("{}: {label} {y}", names.get(i).map_or("?", String::as_str)));
            }
        }
        legend(out, k, colour, label);
    }
    out.push_str("</svg>\n");
}

/// `ys` and a value `factor` times their largest: headroom above the data for the legend.
fn with_headroom(mut ys: Vec<f64>, factor: f64) -> Vec<f64> {
    let highest = ys.iter().copied().filter(|y| y.is_finite()).fold(f64::MIN_POSITIVE, f64::max);
    ys.push(highest * factor);
    ys
}

/// The numbers of a JSON array (NaN for a non-number).
fn values(v: &Value) -> Vec<f64> {
    v.as_array().map_or(Vec::new(), |a| a.iter().map(|x| x.as_f64().unwrap_or(f64::NAN)).collect())
}

/// A named curve: name, colour, points.
type Curve<'a> = (&'a str, &'a str, Vec<(f64, f64)>);

/// A curve per generation (index = generation).
fn per_generation(values: &[f64]) -> Vec<(f64, f64)> {
    values.iter().enumerate().map(|(g, v)| (g as f64, *v)).collect()
}

fn fig3(out: &mut String, doc: &Value) {
    out.push_str(
        "<h2>Fig. 3: the operators on 2-D Rastrigin</h2>\n<p class=\"note\">Mean best cost over the seeds per \
         generation (population 40, the same seeds for each). The paper's Fig. 3 shows TAGA converging fastest; \
         it prints no values. A cost of exactly 0 cannot be drawn on the log scale.</p>\n\
         <table><tr><th>operator</th><th>successes (best &lt; 1e-3)</th><th>seeds</th></tr>\n",
    );
    let operators = [("aga", BEFORE), ("laga", AFTER), ("taga", LEFT_OUT)];
    for (name, _) in operators {
        let key = |k: &str| format!("/operators/{name}/{k}");
        let _ = writeln!(
            out,
            "<tr><th>{name}</th>{}{}</tr>",
            number_cell(&key("successes"), doc),
            number_cell(&key("seeds"), doc)
        );
    }
    out.push_str("</table>\n");
    let curves: Vec<Curve> = operators
        .iter()
        .map(|(name, colour)| (*name, *colour, per_generation(&values(&doc["operators"][*name]["mean_best"]))))
        .collect();
    let xs: Vec<f64> = curves.iter().flat_map(|c| c.2.iter().map(|p| p.0)).collect();
    let ys: Vec<f64> = curves.iter().flat_map(|c| c.2.iter().map(|p| p.1)).collect();
    let axes = Axes::fit_log_y(&xs, &with_headroom(ys, 10.0));
    axes.open(out, "Fig. 3: mean best Rastrigin cost per generation", "generation", "cost");
    for (k, (name, colour, points)) in curves.iter().enumerate() {
        axes.polyline(out, points, colour, false);
        legend(out, k, colour, name);
    }
    out.push_str("</svg>\n");
}

fn fig6(out: &mut String, doc: &Value) {
    out.push_str(
        "<h2>Fig. 6: convergence of the calibration</h2>\n<p class=\"note\">One TAGA run on one simulated \
         experiment (the paper's set-up through the calibration pipeline): the objective fE of the best individual \
         and the population mean per generation. The paper reports convergence in about 40 generations (dashed \
         line).</p>\n",
    );
    let trace = doc["trace"].as_array().map_or(&[][..], Vec::as_slice);
    let curve = |k: &str| -> Vec<(f64, f64)> {
        trace.iter().enumerate().map(|(g, t)| (g as f64, t[k].as_f64().unwrap_or(f64::NAN))).collect()
    };
    let (best, mean) = (curve("best"), curve("mean"));
    let xs: Vec<f64> = best.iter().map(|p| p.0).collect();
    let ys: Vec<f64> = best.iter().chain(&mean).map(|p| p.1).collect();
    let axes = Axes::fit_log_y(&xs, &ys);
    axes.open(out, "Fig. 6: TAGA objective per generation", "generation", "fE ((m/s^2)^4)");
    axes.polyline(out, &best, AFTER, false);
    axes.polyline(out, &mean, BEFORE, true);
    axes.reference_x(out, 40.0, "paper: ~40");
    legend(out, 0, AFTER, "best");
    legend(out, 1, BEFORE, "population mean");
    out.push_str("</svg>\n");
    generations_table(out, doc);
}

/// Generations for TAGA to come within 1 % of the least-squares optimum, per set-up.
fn generations_table(out: &mut String, doc: &Value) {
    out.push_str(
        "<table><tr><th>TAGA set-up</th><th>median generations to 1 %</th><th>95th percentile</th>\
         <th>share within 1 % by generation 40</th><th>runs</th></tr>\n",
    );
    let setups = doc["generations_to_1pct"].as_array().map_or(0, Vec::len);
    for i in 0..setups {
        let key = |k: &str| format!("/generations_to_1pct/{i}/{k}");
        let init = doc["generations_to_1pct"][i]["init"].as_str().unwrap_or("?");
        let _ = write!(out, "<tr><td class=\"text\">{}</td>", escape(init));
        for k in ["median", "p95", "share_by_40", "runs"] {
            out.push_str(&number_cell(&key(k), doc));
        }
        out.push_str("</tr>\n");
    }
    out.push_str("</table>\n");
}
