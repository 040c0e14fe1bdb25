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

/// Deterministic noise: a sum of four uniforms (about Gaussian), standard deviation `sd`.
fn noise(state: &mut u64, sd: f64) -> f64 {
    let mut sum = 0.0;
    for _ in 0..4 {
        *state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        sum += (*state >> 11) as f64 / (1u64 << 53) as f64 - 0.5;
    }
    sum * sd * 3f64.sqrt()
}

/// Fourteen still directions (faces and diagonals) in g with biases, quantised to `lsb_g` with noise
/// `sd_g`, `still` rows each, 100 Hz, as `[t, ax, ay, az]`.
fn quantised_rows(lsb_g: f64, sd_g: f64, still: usize) -> Vec<[f64; 4]> {
    let s = 1.0 / 3f64.sqrt();
    let mut dirs =
        vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]];
    dirs.extend([[s, s, s], [-s, s, -s], [s, -s, -s], [-s, -s, s], [s, s, -s], [-s, s, s], [s, -s, s], [-s, -s, -s]]);
    let bias = [0.0123, -0.0207, 0.0311];
    let (mut state, mut t, mut rows) = (5u64, 0.0, Vec::new());
    let mut push = |v: [f64; 3], rows: &mut Vec<[f64; 4]>, state: &mut u64| {
        let q = [0, 1, 2].map(|a| ((v[a] + bias[a] + noise(state, sd_g)) / lsb_g).round() * lsb_g);
        rows.push([t, q[0], q[1], q[2]]);
        t += 0.01;
    };
    for d in dirs {
        for _ in 0..still {
            push(d, &mut rows, &mut state);
        }
        for i in 0..100 {
            let w = (f64::from(i) * 0.3).sin();
            push([d[0] + w, d[1] + 0.5 * w, d[2] - w], &mut rows, &mut state);
        }
    }
    rows
}

#[test]
fn a_coarsely_quantised_sensor_keeps_its_repeated_readings() {
    let rows = quantised_rows(0.008, 0.0005, 400);
    let repeats = rows.windows(2).filter(|w| w[0][1..] == w[1][1..]).count() as f64 / (rows.len() - 1) as f64;
    assert!(repeats > 0.5, "the log must repeat in over half its rows to test this: {repeats}");
    let text: Vec<String> = rows.iter().map(|r| format!("{:.2},{:.3},{:.3},{:.3}", r[0], r[1], r[2], r[3])).collect();
    let path = write("quantised_8mg.csv", format!("t,ax,ay,az\n{}\n", text.join("\n")).as_bytes());
    let out = calibrate(&path, &[]);
    assert_eq!(out.status.code(), Some(0), "{}{}", stdout(&out), stderr(&out));
    assert!(stdout(&out).contains("7000 rows") && stdout(&out).contains("14 poses"), "{}", stdout(&out));
    assert!(!stdout(&out).contains("rows dropped"), "{}", stdout(&out));
    let json: serde_json::Value = serde_json::from_slice(&calibrate(&path, &["--json"]).stdout).unwrap();
    assert_eq!(json["rows_dropped"]["total"], 0, "{}", json["rows_dropped"]);
}

#[test]
fn rows_dropped_are_counted_by_reason_in_text_and_json() {
    let rows = quantised_rows(0.001, 0.002, 400);
    let mut text = String::from("t,ax,ay,az,stale\n");
    for (i, r) in rows.iter().enumerate() {
        // Every fifth row is a flagged stale copy of the previous one; two rows have a NaN.
        text.push_str(&format!("{:.3},{:.3},{:.3},{:.3},0\n", r[0], r[1], r[2], r[3]));
        if i % 5 == 4 {
            text.push_str(&format!("{:.3},{:.3},{:.3},{:.3},1\n", r[0] + 0.001, r[1], r[2], r[3]));
        }
        if i == 1000 || i == 3000 {
            text.push_str(&format!("{:.3},nan,0,1,0\n", r[0] + 0.002));
        }
    }
    text.push_str("99.0,0.1,");
    let path = write("flagged.csv", text.as_bytes());
    let out = calibrate(&path, &[]);
    assert_eq!(out.status.code(), Some(0), "{}{}", stdout(&out), stderr(&out));
    assert!(stdout(&out).contains("7000 rows"), "{}", stdout(&out));
    let expected = "rows dropped: 1403 (non_finite 2, stale_flag 1400, truncated_last_line 1)";
    assert!(stdout(&out).contains(expected), "{}", stdout(&out));
    let json: serde_json::Value = serde_json::from_slice(&calibrate(&path, &["--json"]).stdout).unwrap();
    let dropped = &json["rows_dropped"];
    assert_eq!((dropped["non_finite"].as_u64(), dropped["stale_flag"].as_u64()), (Some(2), Some(1400)), "{dropped}");
    assert_eq!((dropped["truncated_last_line"].as_u64(), dropped["total"].as_u64()), (Some(1), Some(1403)));
    let diagnosed = command("diagnose", &path, &["--json"]);
    let json: serde_json::Value = serde_json::from_slice(&diagnosed.stdout).unwrap();
    assert_eq!(json["rows_dropped"]["stale_flag"], 1400, "{}", stderr(&diagnosed));
}

#[test]
fn stale_reads_of_a_sensor_polled_faster_than_its_rate_are_dropped_and_counted() {
    // Every reading of a fine-resolution sensor appears 4 times (polled at 4x its data rate).
    let rows = quantised_rows(0.0001, 0.002, 1600);
    let mut text = String::from("t,ax,ay,az\n");
    for (i, r) in rows.iter().enumerate() {
        let held = &rows[i - i % 4];
        text.push_str(&format!("{:.2},{:.4},{:.4},{:.4}\n", r[0], held[1], held[2], held[3]));
    }
    let out = calibrate(&write("stale_4x.csv", text.as_bytes()), &[]);
    assert_eq!(out.status.code(), Some(0), "{}{}", stdout(&out), stderr(&out));
    assert!(stdout(&out).contains("rows dropped: 17850 (stale_repeat 17850)"), "{}", stdout(&out));
}

#[test]
fn a_streamed_read_calibrates_as_the_in_memory_one() {
    let rows = quantised_rows(0.0001, 0.002, 400);
    let text: Vec<String> = rows.iter().map(|r| format!("{:.2},{:.4},{:.4},{:.4}", r[0], r[1], r[2], r[3])).collect();
    let path = write("streamed.csv", format!("t,ax,ay,az\n{}\n", text.join("\n")).as_bytes());
    let (memory, streamed) = (calibrate(&path, &["--json"]), calibrate(&path, &["--json", "--stream"]));
    assert_eq!(streamed.status.code(), Some(0), "{}", stderr(&streamed));
    assert!(stderr(&streamed).contains("read as a stream"), "{}", stderr(&streamed));
    assert_eq!(stdout(&streamed), stdout(&memory));
    let json: serde_json::Value = serde_json::from_slice(&streamed.stdout).unwrap();
    assert_eq!(json["poses"].as_array().map(Vec::len), Some(14));
}

#[test]
fn pose_column_reads_cr_only_files_and_refuses_an_unknown_name_briefly() {
    let rows = six_face_rows(300);
    let labelled: Vec<String> = rows.iter().enumerate().map(|(i, r)| format!("\"P{}\",{r}", i / 400)).collect();
    let lf = write("labels_lf.csv", format!("pos,t,ax,ay,az\n{}\n", labelled.join("\n")).as_bytes());
    let cr = write("labels_cr.csv", format!("pos,t,ax,ay,az\r{}\r", labelled.join("\r")).as_bytes());
    let (lf_out, cr_out) = (calibrate(&lf, &["--pose-column", "pos"]), calibrate(&cr, &["--pose-column", "pos"]));
    // Each label also spans the move after its hold: the fit may fail its verdict (exit 1), the same way.
    assert_eq!(cr_out.status.code(), lf_out.status.code(), "{}", stderr(&cr_out));
    assert!(stdout(&cr_out).contains("2400 rows") && stdout(&cr_out).contains("6 poses"), "{}", stdout(&cr_out));
    assert_eq!(without_name(&stdout(&cr_out), "labels_cr.csv"), without_name(&stdout(&lf_out), "labels_lf.csv"));
    let mut wide: Vec<String> = (0..500).map(|i| format!("extra{i}")).collect();
    wide.extend(["t", "ax", "ay", "az"].map(String::from));
    let row = vec!["0"; 500].join(",");
    let text = format!("{}\n{row},0,0,0,1\n{row},0.01,0,0,1\n", wide.join(","));
    let out = calibrate(&write("labels_wide.csv", text.as_bytes()), &["--pose-column", &"q".repeat(300)]);
    assert_short_error(&out, "labels_wide.csv", &["--pose-column", "no such column", "(504 cells)"]);
}
