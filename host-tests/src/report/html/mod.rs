//! One self-contained HTML page per run (`calibrate`, `diagnose` and `paper --report DIR` write
//! `DIR/index.html`): inline SVG figures, inline CSS, no script to run and nothing fetched from the
//! network.
//!
//! The page is drawn from the run's JSON document alone (the one `--json` prints), and carries that
//! document in a `<script type="application/json" id="data">` block. Every number shown sits in an
//! element whose `data-key` is the JSON pointer of the value it shows, so a reader (or a test) can
//! check the page against the data. Every drawn data mark (a stem, a dot) has the class `datum`.
//!
//! ```
//! let doc = serde_json::json!({"a": 0.123456789});
//! let cell = accelcal_host::report::html::number_cell("/a", &doc);
//! assert_eq!(cell, r#"<td data-key="/a">0.123457</td>"#);
//! ```

mod calibrate;
pub mod data;
mod diagnosis;
mod paper;
mod svg;

use std::path::{Path, PathBuf};

pub use data::{PoseResidual, calibrated_direction, pose_residuals_mg, pose_temperatures_c};

/// Significant digits of the numbers shown.
pub const SIGNIFICANT_DIGITS: usize = 6;

/// Writes `dir/index.html` for a `calibrate --json` document; returns the page's path.
///
/// # Errors
/// A message naming the directory or file that could not be written.
pub fn write_calibrate_report(dir: &Path, document: &serde_json::Value) -> Result<PathBuf, String> {
    let html = page("accelcal calibration report", &calibrate::body(document), document);
    write_page(dir, &html)
}

/// Writes `dir/index.html` for a `diagnose --json` document; returns the page's path.
///
/// # Errors
/// A message naming the directory or file that could not be written.
pub fn write_diagnose_report(dir: &Path, document: &serde_json::Value) -> Result<PathBuf, String> {
    let html = page("accelcal diagnosis report", &diagnosis::body(document), document);
    write_page(dir, &html)
}

/// Writes `dir/index.html` for a `paper --json` document (Table 2, Fig. 3, Fig. 6); returns the
/// page's path.
///
/// # Errors
/// A message naming the directory or file that could not be written.
pub fn write_paper_report(dir: &Path, document: &serde_json::Value) -> Result<PathBuf, String> {
    let html = page("accelcal paper reproduction", &paper::body(document), document);
    write_page(dir, &html)
}

fn write_page(dir: &Path, html: &str) -> Result<PathBuf, String> {
    std::fs::create_dir_all(dir)
        .map_err(|e| format!("--report {}: cannot create the directory: {e}", dir.display()))?;
    let path = dir.join("index.html");
    std::fs::write(&path, html).map_err(|e| format!("{}: cannot write the report: {e}", path.display()))?;
    Ok(path)
}

const STYLE: &str = "body{font-family:system-ui,sans-serif;max-width:760px;margin:24px auto;color:#222}\
table{border-collapse:collapse;margin:8px 0;font-size:90%}td.text{text-align:left}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}\
th{background:#f2f2f2}.pass{color:#1b7f2a}.fail{color:#c62828}svg{display:block;margin:12px 0}\
svg text{font-size:12px;fill:#222}svg .title{font-size:14px;font-weight:bold}svg .tick{font-size:11px}\
.note{color:#555;font-size:90%}";

/// The whole page: head with inline style, `body`, and the JSON document.
fn page(title: &str, body: &str, document: &serde_json::Value) -> String {
    format!(
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n<title>{t}</title>\n<style>{STYLE}</style>\n\
         </head>\n<body>\n<h1>{t}</h1>\n{body}\n<script type=\"application/json\" id=\"data\">{json}</script>\n</body>\n</html>\n",
        t = escape(title),
        json = json_for_script(document),
    )
}

/// The document as JSON that cannot end its `<script>` element early (`<`, `>` and `&` escaped as
/// `\u003c`... inside strings, the only place they can occur).
pub fn json_for_script(document: &serde_json::Value) -> String {
    document.to_string().replace('<', "\\u003c").replace('>', "\\u003e").replace('&', "\\u0026")
}

/// `s` with the HTML special characters escaped (text and attribute values).
pub fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            c => out.push(c),
        }
    }
    out
}

/// `v` with [`SIGNIFICANT_DIGITS`] significant digits (`-` for a non-finite value).
pub fn sig(v: f64) -> String {
    if !v.is_finite() {
        return "-".into();
    }
    if v.fract() == 0.0 && v.abs() < 1e6 {
        return format!("{v:.0}");
    }
    let magnitude = v.abs().log10().floor() as i32;
    if (-3..6).contains(&magnitude) {
        let decimals = (SIGNIFICANT_DIGITS as i32 - 1 - magnitude).max(0) as usize;
        format!("{v:.decimals$}")
    } else {
        format!("{v:.prec$e}", prec = SIGNIFICANT_DIGITS - 1)
    }
}

/// The number at JSON pointer `key` of `document`, shown with [`sig`] in an element tagged with
/// `data-key` (`-` when absent or null).
pub fn number_span(key: &str, document: &serde_json::Value) -> String {
    tagged("span", key, document)
}

/// [`number_span`] as a table cell.
pub fn number_cell(key: &str, document: &serde_json::Value) -> String {
    tagged("td", key, document)
}

fn tagged(element: &str, key: &str, document: &serde_json::Value) -> String {
    match document.pointer(key).and_then(serde_json::Value::as_f64) {
        Some(v) => format!(r#"<{element} data-key="{}">{}</{element}>"#, escape(key), sig(v)),
        None => format!("<{element}>-</{element}>"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sig_keeps_six_significant_digits() {
        assert_eq!(sig(0.123456789), "0.123457");
        assert_eq!(sig(-1.5), "-1.50000");
        assert_eq!(sig(6.0), "6");
        assert_eq!(sig(0.0), "0");
        assert_eq!(sig(123456.7), "123457");
        assert_eq!(sig(1234567.8), "1.23457e6");
        assert_eq!(sig(2.5e-5), "2.50000e-5");
        assert_eq!(sig(f64::NAN), "-");
        assert_eq!("1.23457e5".parse::<f64>(), Ok(123457.0));
    }

    #[test]
    fn escaping_covers_markup_and_script_end() {
        assert_eq!(escape(r#"<a href="x">&'"#), "&lt;a href=&quot;x&quot;&gt;&amp;&#39;");
        let doc = serde_json::json!({"file": "</script><b>"});
        let json = json_for_script(&doc);
        assert!(!json.contains("</script>"), "{json}");
        assert_eq!(serde_json::from_str::<serde_json::Value>(&json).unwrap(), doc);
    }

    #[test]
    fn missing_or_null_numbers_show_a_dash_without_a_key() {
        let doc = serde_json::json!({"a": null});
        assert_eq!(number_cell("/a", &doc), "<td>-</td>");
        assert_eq!(number_span("/b", &doc), "<span>-</span>");
    }
}
