//! Bad input the CLI used to handle badly (issue 15, item 5): each gets a short, clear error that
//! names the file (and line), or an honest warning, never silence and never a page of quoted input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The longest stderr line an error may print (the file name, the message, 80 quoted characters).
const MAX_ERROR_LINE_CHARS: usize = 400;

fn dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("bad_input");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(name: &str, content: &[u8]) -> PathBuf {
    let p = dir().join(name);
    std::fs::write(&p, content).unwrap();
    p
}

fn calibrate(path: &Path, extra: &[&str]) -> Output {
    command("calibrate", path, extra)
}

fn command(name: &str, path: &Path, extra: &[&str]) -> Output {
    let mut args = vec![name, path.to_str().unwrap()];
    args.extend_from_slice(extra);
    Command::new(env!("CARGO_BIN_EXE_accelcal")).args(&args).env("RUST_BACKTRACE", "1").output().unwrap()
}

fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Exit code 2, one short stderr error line naming the file and containing every `needles`.
fn assert_short_error(out: &Output, file: &str, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(2), "stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("warning")).collect();
    assert_eq!(lines.len(), 1, "one line expected: {err}");
    assert!(lines[0].len() <= MAX_ERROR_LINE_CHARS, "{} chars: {}", lines[0].len(), lines[0]);
    assert!(lines[0].contains(file), "file not named: {err}");
    for n in needles {
        assert!(lines[0].to_lowercase().contains(&n.to_lowercase()), "'{n}' missing: {err}");
    }
}

/// Six still faces of `rows` rows each (in g, with a little deterministic noise), a move after each,
/// 100 Hz, as CSV rows `t,ax,ay,az` without line ends.
fn six_face_rows(rows: usize) -> Vec<String> {
    let faces =
        [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    let mut out = Vec::new();
    let mut t = 0.0;
    for v in faces {
        for i in 0..rows {
            let e = ((i * 7919) % 13) as f64 * 1e-4 - 6e-4;
            out.push(format!("{t:.3},{:.5},{:.5},{:.5}", v[0] + e, v[1] - e, v[2] + e));
            t += 0.01;
        }
        for i in 0..100 {
            let w = (i as f64 * 0.3).sin();
            out.push(format!("{t:.3},{:.5},{:.5},{:.5}", v[0] + w, v[1] + 0.5 * w, v[2] - w));
            t += 0.01;
        }
    }
    out
}

/// The calibration's output with the file name taken out (to compare two files' results).
fn without_name(text: &str, name: &str) -> String {
    text.replace(name, "FILE")
}

#[test]
fn cr_only_line_ends_read_as_the_same_poses_as_lf() {
    let rows = six_face_rows(300);
    let lf = write("lf.csv", format!("t,ax,ay,az\n{}\n", rows.join("\n")).as_bytes());
    let cr = write("cr.csv", format!("t,ax,ay,az\r{}\r", rows.join("\r")).as_bytes());
    let (lf_out, cr_out) = (calibrate(&lf, &[]), calibrate(&cr, &[]));
    assert_eq!(cr_out.status.code(), Some(0), "{}", stderr(&cr_out));
    assert!(stdout(&cr_out).contains("2400 rows") && stdout(&cr_out).contains("6 poses"), "{}", stdout(&cr_out));
    assert_eq!(without_name(&stdout(&cr_out), "cr.csv"), without_name(&stdout(&lf_out), "lf.csv"));
}

#[test]
fn cr_only_line_numbers_count_each_line() {
    let text = "t,ax,ay,az\r0,0,0,1\r0.01,0,zero,1\r0.02,0,0,1\r";
    let out = calibrate(&write("cr_text.csv", text.as_bytes()), &[]);
    assert_short_error(&out, "cr_text.csv", &["cr_text.csv:3:", "zero"]);
}

#[test]
fn errors_quote_at_most_80_characters_of_input() {
    let long_cell = "x".repeat(5000);
    let text = format!("t,ax,ay,az\n0,0,0,1\n0.01,0,{long_cell},1\n");
    let out = calibrate(&write("long_cell.csv", text.as_bytes()), &[]);
    assert_short_error(&out, "long_cell.csv", &["long_cell.csv:3:", "not a number"]);
    let wide_header: Vec<String> = (0..2000).map(|i| format!("col{i}")).collect();
    let text = format!("{}\n{}\n", wide_header.join(","), vec!["1"; 2000].join(","));
    let out = calibrate(&write("wide_header.csv", text.as_bytes()), &[]);
    assert_short_error(&out, "wide_header.csv", &["no column for ax", "2000 cells"]);
    let numbers: Vec<String> = (0..3000).map(|i| format!("{i}.5")).collect();
    let out = calibrate(&write("no_header.csv", format!("{}\n", numbers.join(",")).as_bytes()), &[]);
    assert_short_error(&out, "no_header.csv", &["header"]);
}

/// `n` directions spread over the sphere (a Fibonacci spiral).
fn spiral(n: usize) -> Vec<[f64; 3]> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let z = 1.0 - 2.0 * (k as f64 + 0.5) / n as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * k as f64;
            [r * phi.cos(), r * phi.sin(), z]
        })
        .collect()
}

/// A raw log at 100 Hz holding still for `still` rows in each of `dirs`, moving 30 rows between.
fn raw_log(dirs: &[[f64; 3]], still: usize) -> String {
    let mut text = String::from("t,ax,ay,az\n");
    let mut t = 0.0;
    for v in dirs {
        for i in 0..still {
            let e = ((i * 7919) % 13) as f64 * 1e-4 - 6e-4;
            text.push_str(&format!("{t:.2},{:.5},{:.5},{:.5}\n", v[0] + e, v[1] - e, v[2] + e));
            t += 0.01;
        }
        for i in 0..30 {
            let w = (i as f64 * 0.3).sin();
            text.push_str(&format!("{t:.2},{:.5},{:.5},{:.5}\n", v[0] + w, v[1] + 0.5 * w, v[2] - w));
            t += 0.01;
        }
    }
    text
}

#[test]
fn more_poses_than_the_limit_is_an_error_naming_both() {
    let out = calibrate(&write("520_poses.csv", raw_log(&spiral(520), 150).as_bytes()), &[]);
    assert_short_error(&out, "520_poses.csv", &["520 poses found", "at most 512", "split", "ends at line"]);
    let out = command("diagnose", &dir().join("520_poses.csv"), &[]);
    assert_short_error(&out, "520_poses.csv", &["520 poses found", "at most 512"]);
    let mut means = String::from("ax,ay,az\n");
    for v in spiral(600) {
        means.push_str(&format!("{:.5},{:.5},{:.5}\n", v[0], v[1], v[2]));
    }
    let out = calibrate(&write("600_means.csv", means.as_bytes()), &["--means"]);
    assert_short_error(&out, "600_means.csv", &["600 poses found", "at most 512"]);
    // At the limit itself the log calibrates.
    let out = calibrate(&write("512_poses.csv", raw_log(&spiral(512), 150).as_bytes()), &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stdout(&out).contains("512 poses"), "{}", stdout(&out));
}

#[test]
fn an_all_nan_or_empty_temperature_column_is_dropped_with_a_warning_naming_it() {
    let rows = six_face_rows(300);
    let plain = calibrate(&write("no_temp.csv", format!("t,ax,ay,az\n{}\n", rows.join("\n")).as_bytes()), &[]);
    assert_eq!(plain.status.code(), Some(0), "{}", stderr(&plain));
    for (name, cell) in [("nan_temp.csv", "nan"), ("empty_temp.csv", ""), ("inf_temp.csv", "inf")] {
        let text: Vec<String> = rows.iter().map(|r| format!("{r},{cell}")).collect();
        let out = calibrate(&write(name, format!("t,ax,ay,az,temp_C\n{}\n", text.join("\n")).as_bytes()), &[]);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        let warning = stderr(&out);
        assert!(warning.contains("warning") && warning.contains("`temp_C`"), "{name}: {warning}");
        assert!(warning.contains("2400 of 2400 rows"), "{name}: {warning}");
        assert_eq!(without_name(&stdout(&out), name), without_name(&stdout(&plain), "no_temp.csv"));
    }
}

#[test]
fn a_temperature_column_with_one_nan_skips_that_row_only() {
    let mut text: Vec<String> = six_face_rows(300).iter().map(|r| format!("{r},25.0")).collect();
    text[10] = text[10].replace(",25.0", ",nan");
    let out = calibrate(&write("one_nan_temp.csv", format!("t,ax,ay,az,temp\n{}\n", text.join("\n")).as_bytes()), &[]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stderr(&out).contains("1 of 2400 rows skipped"), "{}", stderr(&out));
    assert!(!stderr(&out).contains("temperature column"), "{}", stderr(&out));
}

#[test]
fn an_implausible_gravity_is_refused_saying_what_was_measured() {
    let rows = six_face_rows(300);
    let g_file = write("gravity_g.csv", format!("t,ax,ay,az\n{}\n", rows.join("\n")).as_bytes());
    for gravity in ["1e-30", "1", "30", "9.8e6"] {
        let out = calibrate(&g_file, &["--gravity", gravity]);
        assert_short_error(&out, "gravity_g.csv", &["--gravity", "implausible", "measure |a| = 9.80", "m/s^2"]);
    }
    for gravity in ["0", "-9.8", "nan", "inf"] {
        let out = calibrate(&g_file, &[&format!("--gravity={gravity}")]);
        assert_eq!(out.status.code(), Some(2), "{gravity}: {}", stderr(&out));
        assert!(stderr(&out).contains("must be a positive number"), "{gravity}: {}", stderr(&out));
    }
    let out = command("diagnose", &g_file, &["--gravity", "1e-30"]);
    assert_short_error(&out, "gravity_g.csv", &["implausible"]);
    // Local gravity (here Quito's) is accepted.
    let out = calibrate(&g_file, &["--gravity", "9.7803"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    // The same poses in m/s^2 measure the same.
    let mps2: Vec<String> = rows
        .iter()
        .map(|r| {
            let c: Vec<f64> = r.split(',').map(|v| v.parse().unwrap()).collect();
            format!("{},{:.5},{:.5},{:.5}", c[0], c[1] * 9.80665, c[2] * 9.80665, c[3] * 9.80665)
        })
        .collect();
    let mps2_file = write("gravity_mps2.csv", format!("t,ax,ay,az\n{}\n", mps2.join("\n")).as_bytes());
    let out = calibrate(&mps2_file, &["--gravity", "1"]);
    assert_short_error(&out, "gravity_mps2.csv", &["implausible", "measure |a| = 9.80"]);
}

#[test]
fn a_columns_index_past_the_last_column_counts_the_columns_right() {
    let path = write("four_columns.csv", b"t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n");
    let out = calibrate(&path, &["--columns", "t,ax,ay,9"]);
    assert_short_error(&out, "four_columns.csv:1:", &["column index 9", "the header has 4 columns (indices 0-3)"]);
    let out = calibrate(&path, &["--columns", "0,1,7"]);
    assert_short_error(&out, "four_columns.csv:2:", &["column index 7", "first data row has 4 columns (indices 0-3)"]);
    let out = calibrate(&path, &["--columns", "t,ax,ay,nope"]);
    assert_short_error(&out, "four_columns.csv:1:", &["`nope` is not in the header [`t`, `ax`, `ay`, `az`]"]);
}

/// The six-face log with its values multiplied by `factor` and the header `header`.
fn six_faces_scaled(header: &str, factor: f64) -> String {
    let mut text = format!("{header}\n");
    for r in six_face_rows(300) {
        let c: Vec<f64> = r.split(',').map(|v| v.parse().unwrap()).collect();
        text.push_str(&format!("{},{:.6},{:.6},{:.6}\n", c[0], c[1] * factor, c[2] * factor, c[3] * factor));
    }
    text
}

#[test]
fn unit_labels_in_headers_are_honoured_and_reported() {
    let reference = calibrate(&write("units_plain.csv", six_faces_scaled("t,ax,ay,az", 1.0).as_bytes()), &[]);
    let params = |out: &Output| -> Vec<String> { stdout(out).lines().skip(1).take(4).map(str::to_string).collect() };
    let cases = [
        ("units_mg.csv", "t,ax_mg,ay_mg,az_mg", 1000.0, "g (header `ax_mg`: mg, scaled by 0.001"),
        ("units_g.csv", "t,ax_g,ay_g,az_g", 1.0, "g (header `ax_g`"),
        ("units_paren.csv", "t,ax (g),ay (g),az (g)", 1.0, "g (header `ax (g)`"),
        ("units_mps2.csv", "t,acc_x_mps2,acc_y_mps2,acc_z_mps2", 9.80665, "mps2 (header `acc_x_mps2`"),
        ("units_bracket.csv", "t,ax[m/s^2],ay[m/s^2],az[m/s^2]", 9.80665, "mps2 (header `ax[m/s^2]`"),
    ];
    for (name, header, factor, summary) in cases {
        let out = calibrate(&write(name, six_faces_scaled(header, factor).as_bytes()), &[]);
        assert_eq!(out.status.code(), Some(0), "{name}: {}", stderr(&out));
        assert!(stdout(&out).contains(summary), "{name}: {}", stdout(&out));
        assert!(stdout(&out).contains("6 poses"), "{name}: {}", stdout(&out));
        if factor == 1000.0 || factor == 1.0 {
            assert_eq!(params(&out), params(&reference), "{name}");
        }
    }
    let json = calibrate(&dir().join("units_mg.csv"), &["--json"]);
    let value: serde_json::Value = serde_json::from_slice(&json.stdout).unwrap();
    assert_eq!(value["units"], "g");
    assert_eq!(value["units_header"]["unit"], "mg");
    assert_eq!(value["units_header"]["factor"], 0.001);
}

#[test]
fn an_explicit_units_option_wins_over_the_header_and_a_wrong_label_is_an_error() {
    let mg = dir().join("units_mg_explicit.csv");
    std::fs::write(&mg, six_faces_scaled("t,ax_mg,ay_mg,az_mg", 1000.0)).unwrap();
    let out = calibrate(&mg, &["--units", "counts"]);
    assert_eq!(out.status.code(), Some(0), "{}", stderr(&out));
    assert!(stdout(&out).contains("counts (declared"), "{}", stdout(&out));
    assert!(stderr(&out).contains("--units counts overrides the unit mg in the header (`ax_mg`)"), "{}", stderr(&out));
    // Values in m/s^2 under a `_g` header: the header is wrong, said so.
    let wrong = write("units_wrong_label.csv", six_faces_scaled("t,ax_g,ay_g,az_g", 9.80665).as_bytes());
    assert_short_error(&calibrate(&wrong, &[]), "units_wrong_label.csv", &["header `ax_g`", "--units mps2"]);
    assert_eq!(calibrate(&wrong, &["--units", "mps2"]).status.code(), Some(0));
}
