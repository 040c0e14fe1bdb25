//! `calibrate --report DIR` and `diagnose --report DIR` on a real recording, `paper --report DIR` on a
//! small run: the page exists, is self-contained (no script to run, nothing fetched), carries the same
//! JSON document as `--json` of the same run, every figure draws data, and every number shown equals
//! the JSON value it is tagged with (to the digits shown).
//!
//! Needs `../shared/data/real` beside the workspace: without it the tests fail, naming the folder.
//! The headless-browser test needs `chromium` (the OS package): it is `#[ignore]`d in a plain
//! `cargo test` and run by `.ci/run` with `--include-ignored`; run without chromium it fails, saying so.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// Significant digits the page shows (`accelcal_host::report::html::SIGNIFICANT_DIGITS`).
const DIGITS: i32 = accelcal_host::report::html::SIGNIFICANT_DIGITS as i32;

fn real_file(relative: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/real");
    let file = root.join(relative);
    assert!(
        file.is_file(),
        "{} is missing: the real recordings (../shared/data/real beside the workspace) are needed by this test",
        file.display()
    );
    file
}

/// Runs `calibrate FILE EXTRA --json --report DIR`; returns the stdout document and the page.
fn calibrate_with_report(name: &str, file: &Path, extra: &[&str]) -> (Value, String) {
    run_with_report("calibrate", name, file, extra)
}

/// Runs `COMMAND FILE EXTRA --json --report DIR`; returns the stdout document and the page.
fn run_with_report(command: &str, name: &str, file: &Path, extra: &[&str]) -> (Value, String) {
    let mut args = vec![command.as_ref(), file.as_os_str()];
    args.extend(extra.iter().map(std::ffi::OsStr::new));
    report_of(name, &args)
}

/// The page `report_of(name, ..)` wrote.
fn page_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("html_report").join(name).join("index.html")
}

/// Runs `paper` small (3 runs, 4 Rastrigin seeds) with `--json --report DIR`.
fn paper_with_report(name: &str) -> (Value, String) {
    let args = ["paper", "--runs", "3", "--operator-seeds", "4"];
    report_of(name, &args.map(std::ffi::OsStr::new))
}

/// Runs `ARGS --json --report DIR`; returns the stdout document and the page.
fn report_of(name: &str, args: &[&std::ffi::OsStr]) -> (Value, String) {
    let page_path = page_path(name);
    let dir = page_path.parent().unwrap();
    let _ = std::fs::remove_dir_all(dir);
    let out = Command::new(env!("CARGO_BIN_EXE_accelcal"))
        .args(args)
        .arg("--json")
        .arg("--report")
        .arg(dir)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(matches!(out.status.code(), Some(0 | 1)), "exit {:?}: {stderr}", out.status.code());
    assert!(page_path.is_file(), "{} not written: {stderr}", page_path.display());
    let document: Value = serde_json::from_slice(&out.stdout).expect("stdout is the JSON document");
    (document, std::fs::read_to_string(page_path).unwrap())
}

/// The text between `start` (after it) and the next `end`, for every occurrence.
fn between<'a>(text: &'a str, start: &str, end: &str) -> Vec<&'a str> {
    let mut found = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(start) {
        let after = &rest[i + start.len()..];
        let Some(j) = after.find(end) else { break };
        found.push(&after[..j]);
        rest = &after[j..];
    }
    found
}

/// The JSON embedded in the page.
fn embedded_json(page: &str) -> Value {
    let blocks = between(page, r#"<script type="application/json" id="data">"#, "</script>");
    assert_eq!(blocks.len(), 1, "one JSON block expected");
    serde_json::from_str(blocks[0]).expect("the embedded block is JSON")
}

/// Every `data-key="POINTER">TEXT<`: (pointer, shown text).
fn tagged_numbers(page: &str) -> Vec<(&str, &str)> {
    between(page, r#"data-key=""#, "<")
        .into_iter()
        .map(|s| s.split_once("\">").unwrap_or_else(|| panic!("malformed tagged element: {s}")))
        .collect()
}

/// `shown` is `value` rounded to [`DIGITS`] significant digits.
fn assert_shown_equals(key: &str, shown: &str, value: f64) {
    let parsed: f64 = shown.parse().unwrap_or_else(|_| panic!("{key}: '{shown}' is not a number"));
    if value == 0.0 {
        assert_eq!(parsed, 0.0, "{key}: the page shows {shown}, the JSON has 0");
        return;
    }
    let half_unit = 0.5 * 10f64.powi(value.abs().log10().floor() as i32 - (DIGITS - 1));
    assert!((parsed - value).abs() <= half_unit * (1.0 + 1e-9), "{key}: the page shows {shown}, the JSON has {value}");
}

fn check_numbers(page: &str, document: &Value) -> usize {
    let tagged = tagged_numbers(page);
    for (key, shown) in &tagged {
        let value = document.pointer(key).and_then(Value::as_f64);
        let value = value.unwrap_or_else(|| panic!("{key} is not a number in the JSON"));
        assert_shown_equals(key, shown, value);
    }
    tagged.len()
}

/// Every `<svg>` has at least one data mark; returns the count of marks per figure.
fn check_figures(page: &str) -> Vec<usize> {
    let figures = between(page, "<svg", "</svg>");
    assert!(figures.len() >= 3, "{} figures", figures.len());
    let marks: Vec<usize> = figures.iter().map(|f| f.matches("datum\"").count()).collect();
    for (i, (figure, count)) in figures.iter().zip(&marks).enumerate() {
        let label = between(figure, "aria-label=\"", "\"").first().copied().unwrap_or("?");
        assert!(*count > 0, "figure {i} ({label}) draws nothing");
    }
    marks
}

fn check_self_contained(page: &str) {
    assert_eq!(page.matches("<script").count(), 1, "only the JSON data block may be a script");
    let external = page.replace("http://www.w3.org/2000/svg", "");
    for needle in ["http://", "https://", " src=", "<link", "@import"] {
        assert!(!external.contains(needle), "the page refers to something outside it: '{needle}'");
    }
}

/// Checks common to every report: the JSON, self-containment, figures, tagged numbers; returns the
/// data marks per figure.
fn check_report(document: &Value, page: &str) -> Vec<usize> {
    let marks = check_common(document, page);
    let params: Vec<(&str, &str)> = tagged_numbers(page).into_iter().filter(|(k, _)| k.starts_with("/param")).collect();
    let known_std = document["param_std"].as_array().unwrap().iter().filter(|v| v.is_number()).count();
    assert_eq!(params.len(), 9 + known_std, "nine parameters and the standard deviations known: {params:?}");
    check_numbers(page, document);
    marks
}

/// The JSON, self-containment, figures and tagged numbers; returns the data marks per figure.
fn check_common(document: &Value, page: &str) -> Vec<usize> {
    assert_eq!(&embedded_json(page), document, "the page's JSON differs from --json of the same run");
    check_self_contained(page);
    let marks = check_figures(page);
    check_numbers(page, document);
    marks
}

/// The per-pose residuals drawn are the library's: their RMS over the poses kept equals the
/// RMSE before and after (to `f32` rounding).
fn assert_residuals_match_rmse(document: &Value) {
    let left_out: Vec<u64> =
        document["verdict"]["poses_left_out"].as_array().unwrap().iter().filter_map(Value::as_u64).collect();
    let poses = document["poses"].as_array().unwrap();
    let kept: Vec<&Value> =
        poses.iter().enumerate().filter(|(i, _)| !left_out.contains(&(*i as u64))).map(|(_, p)| p).collect();
    for (key, rmse) in [("residual_before_mg", "before"), ("residual_after_mg", "after")] {
        let sum: f64 = kept.iter().map(|p| p[key].as_f64().unwrap().powi(2)).sum();
        let rms = (sum / kept.len() as f64).sqrt();
        let expected = document["rmse_mg"][rmse].as_f64().unwrap();
        assert!((rms - expected).abs() <= 1e-4 * expected, "{key}: RMS {rms} mg, rmse_mg.{rmse} {expected} mg");
    }
}

#[test]
fn poses_left_out_are_drawn_apart_and_left_out_of_the_rmse() {
    let file = real_file("michaelwro_178pos/acceldata-example.csv");
    let (document, page) = calibrate_with_report("michaelwro", &file, &["--means"]);
    check_report(&document, &page);
    let left_out = document["verdict"]["poses_left_out"].as_array().unwrap().len();
    assert!(left_out > 0, "this set has poses left out");
    assert_residuals_match_rmse(&document);
    let figures = between(&page, "<svg", "</svg>");
    let left_out_colour = r##"fill="#c62828"><title>pose"##;
    assert_eq!(figures.len(), 3, "two stem figures and the sphere (no time or temperature column)");
    assert_eq!(figures[2].matches(left_out_colour).count(), left_out, "the sphere's dots in the left-out colour");
    assert_eq!(figures[1].matches(r##"stroke="#c62828" stroke-width"##).count(), left_out, "zoomed stems");
    assert_eq!(page.matches("(left out)").count(), left_out, "pose table");
}

#[test]
fn diagnosis_report_shows_candidates_and_allan_deviation_on_log_axes() {
    let file = real_file("imu_tk_xsens_mti/xsens_acc.csv");
    let (document, page) = run_with_report("diagnose", "diagnose", &file, &[]);
    let marks = check_common(&document, &page);
    let gains = document["candidates"].as_array().unwrap().iter().filter(|c| c["heldout_gain"].is_number()).count();
    assert!(gains >= 2, "{gains} candidates with a held-out gain");
    assert_eq!(marks[0], gains, "one stem per candidate's held-out gain: {marks:?}");
    assert_eq!(marks[1], 2, "measured and white-noise Allan curves: {marks:?}");
    let allan = between(&page, "<svg", "</svg>")[1];
    for decade in [">0.01<", ">0.1<", ">1<", ">10<"] {
        assert!(allan.contains(decade), "Allan axes lack the decade tick {decade}");
    }
    let poses = document["where"]["per_pose"].as_array().unwrap().len();
    assert_eq!(&marks[2..], &[poses, poses, poses], "stems, sphere, against time: {marks:?}");
    let tagged = tagged_numbers(&page);
    for c in 0..document["candidates"].as_array().unwrap().len() {
        let key = format!("/candidates/{c}/heldout_gain");
        assert!(tagged.iter().any(|(k, _)| *k == key), "{key} not shown");
    }
}

#[test]
fn means_with_temperature_report_draws_against_temperature_and_says_why_it_fails() {
    let file = real_file("avrlabs_mpu6050/derived_notebook_26pos_means.csv");
    let (document, page) = calibrate_with_report("avrlabs", &file, &["--means"]);
    let marks = check_report(&document, &page);
    let poses = document["poses"].as_array().unwrap().len();
    assert_eq!(poses, 26);
    assert!(document["poses"][0]["temp_c"].is_number(), "the means file has a temperature column");
    assert!(page.contains("No time column"), "a means file has no time column");
    assert_eq!(marks.len(), 4, "two stem figures, the sphere, residual against temperature: {marks:?}");
    assert_eq!(marks[3], 2 * poses, "a dot before and after per pose against temperature: {marks:?}");
    assert_eq!(document["verdict"]["pass"], Value::Bool(false));
    assert!(
        page.contains(r#"id="verdict">FAIL"#) && page.contains("poorly determined by the poses: Bx"),
        "reasons missing"
    );
    assert!(page.contains("held at nominal (the orientations do not determine them): Mxx"));
    assert!(page.contains("&plusmn; held"), "a held parameter's deviation is shown as held");
}

#[test]
fn xsens_report_matches_its_json() {
    let file = real_file("imu_tk_xsens_mti/xsens_acc.csv");
    let (document, page) = calibrate_with_report("xsens", &file, &[]);
    let marks = check_report(&document, &page);
    let poses = document["poses"].as_array().unwrap().len();
    assert!(poses >= 9, "{poses} poses");
    assert_eq!(marks[0], 2 * poses, "one stem before and one after per pose: {marks:?}");
    assert_eq!(marks[1], poses, "one stem after per pose, zoomed: {marks:?}");
    assert_eq!(marks[2], poses, "one dot per pose on the sphere: {marks:?}");
    assert_eq!(marks[3], 2 * poses, "a dot before and after per pose against time: {marks:?}");
    assert!(page.contains("No temperature column"));
    assert_residuals_match_rmse(&document);
    let numbers = check_numbers(&page, &document);
    assert!(numbers >= 18 + 5 * poses, "{numbers} numbers tagged");
}

#[test]
fn paper_report_shows_table2_beside_the_papers_values_and_draws_fig3_and_fig6() {
    let (document, page) = paper_with_report("paper");
    let marks = check_common(&document, &page);
    assert_eq!(marks.len(), 3, "Table 2, Fig. 3, Fig. 6: {marks:?}");
    let series_in_table2 = 1 + 3 + 2; // the bound, newton, taga, taga+lm, the paper's two columns
    assert_eq!(marks[0], 9 * series_in_table2, "a dot per parameter and series: {marks:?}");
    assert_eq!(marks[1], 3, "AGA, LAGA and TAGA curves: {marks:?}");
    assert_eq!(marks[2], 2, "best and mean objective per generation: {marks:?}");
    let tagged = tagged_numbers(&page);
    let shown = |key: &str| tagged.iter().find(|(k, _)| *k == key).map(|(_, v)| *v);
    for (i, (newton, taga)) in accelcal_host::paper::PAPER_TABLE2.iter().enumerate() {
        for (column, printed) in [("newton", newton), ("taga", taga)] {
            let key = format!("/paper_table2_pct/{column}/{i}");
            let text = shown(&key).unwrap_or_else(|| panic!("{key} not shown"));
            assert_shown_equals(&key, text, *printed);
        }
        for method in ["newton", "taga", "taga+lm"] {
            assert!(shown(&format!("/rel_err_pct/{method}/{i}")).is_some(), "{method} parameter {i} not shown");
        }
        assert!(shown(&format!("/crlb_rel_pct/{i}")).is_some(), "bound of parameter {i} not shown");
    }
    assert_eq!(shown("/paper_table2_pct/newton/6"), Some("-61.4388"), "the paper's Mxx for Newton as printed");
    let trace = document["trace"].as_array().unwrap().len();
    let fig6 = between(&page, "<svg", "</svg>")[2];
    let points = between(fig6, "points=\"", "\"")[0].split(' ').count();
    assert_eq!(points, trace, "Fig. 6 draws every generation of the trace");
}

/// `chromium --headless --dump-dom` of `page`: the DOM as the browser built it, and its log.
fn browser_dom(page: &Path) -> (String, String) {
    let out = Command::new("chromium")
        .args(["--headless", "--no-sandbox", "--disable-gpu", "--enable-logging=stderr", "--dump-dom"])
        .arg(format!("file://{}", page.display()))
        .output()
        .unwrap_or_else(|e| {
            panic!("cannot run chromium ({e}): install the OS package (apt-get install chromium); .ci/run does")
        });
    assert!(out.status.success(), "chromium failed: {}", String::from_utf8_lossy(&out.stderr));
    (String::from_utf8(out.stdout).unwrap(), String::from_utf8_lossy(&out.stderr).into_owned())
}

#[test]
#[ignore = "needs chromium (apt-get install chromium); .ci/run runs it"]
fn reports_open_in_a_headless_browser_with_every_figure_drawn() {
    let file = real_file("imu_tk_xsens_mti/xsens_acc.csv");
    for (command, heading) in [
        ("calibrate", "accelcal calibration report"),
        ("diagnose", "accelcal diagnosis report"),
        ("paper", "accelcal paper reproduction"),
    ] {
        let name = format!("browser_{command}");
        let (document, page) = match command {
            "paper" => paper_with_report(&name),
            _ => run_with_report(command, &name, &file, &[]),
        };
        let (dom, log) = browser_dom(&page_path(&name).canonicalize().unwrap());
        let console: Vec<&str> = log.lines().filter(|l| l.contains(":CONSOLE")).collect();
        assert!(console.is_empty(), "{command}: console messages: {console:?}");
        let start = &dom[..dom.len().min(400)];
        assert!(dom.contains(&format!("<h1>{heading}</h1>")), "{command}: the DOM lacks the page: {start}");
        let marks_in_browser = check_common(&document, &dom);
        assert_eq!(marks_in_browser, check_figures(&page), "{command}: the browser's DOM draws other marks");
    }
}
