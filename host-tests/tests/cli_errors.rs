//! The CLI on bad input: one clear line on stderr naming the file (and line), exit code 2, never a
//! panic; tolerated defects are warnings; a failed verdict is exit code 1.

use std::path::PathBuf;
use std::process::{Command, Output};

fn dir() -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("cli_errors");
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(name: &str, content: &[u8]) -> PathBuf {
    let p = dir().join(name);
    std::fs::write(&p, content).unwrap();
    p
}

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_accelcal")).args(args).env("RUST_BACKTRACE", "1").output().unwrap()
}

fn calibrate(path: &std::path::Path, extra: &[&str]) -> Output {
    let mut args = vec!["calibrate", path.to_str().unwrap()];
    args.extend_from_slice(extra);
    run(&args)
}

/// Exit code 2, one stderr line that names the file and contains every `needles`, no panic.
fn assert_input_error(out: &Output, file: &str, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(!stderr.contains("panicked") && !stderr.contains("backtrace"), "{stderr}");
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.contains("warning")).collect();
    assert_eq!(lines.len(), 1, "one line expected: {stderr}");
    assert!(lines[0].contains(file), "file not named: {stderr}");
    for n in needles {
        assert!(lines[0].to_lowercase().contains(&n.to_lowercase()), "'{n}' missing: {stderr}");
    }
}

/// A still pose of `n` rows at `v` (g) with a little noise, then a move, from time `t0`.
fn pose_rows(out: &mut String, t0: &mut f64, v: [f64; 3], n: usize) {
    for i in 0..n {
        let e = ((i * 7919) % 13) as f64 * 1e-4 - 6e-4;
        out.push_str(&format!("{:.3},{:.5},{:.5},{:.5}\n", *t0, v[0] + e, v[1] - e, v[2] + e));
        *t0 += 0.01;
    }
    for i in 0..100 {
        let w = (i as f64 * 0.3).sin();
        out.push_str(&format!("{:.3},{:.5},{:.5},{:.5}\n", *t0, v[0] + w, v[1] + 0.5 * w, v[2] - w));
        *t0 += 0.01;
    }
}

fn six_faces() -> Vec<[f64; 3]> {
    vec![[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
}

#[test]
fn missing_empty_header_only_and_binary_files() {
    let missing = dir().join("does_not_exist.csv");
    assert_input_error(&calibrate(&missing, &[]), "does_not_exist.csv", &[]);
    let empty = write("empty.csv", b"");
    assert_input_error(&calibrate(&empty, &[]), "empty.csv", &["empty"]);
    let header = write("header_only.csv", b"t,ax,ay,az\n");
    assert_input_error(&calibrate(&header, &[]), "header_only.csv", &[]);
    let binary = write("binary.csv", &[0x7f, b'E', b'L', b'F', 0, 0, 1, 2, 3, 0xff, 0xfe, 0]);
    assert_input_error(&calibrate(&binary, &[]), "binary.csv", &["binary"]);
}

#[test]
fn columns_cells_and_time_stamps() {
    let unknown = write("unknown_columns.csv", b"time,foo,bar,baz\n0,1,2,3\n");
    assert_input_error(&calibrate(&unknown, &[]), "unknown_columns.csv", &[]);
    let ok = write("three_columns.csv", b"t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n");
    assert_input_error(&calibrate(&ok, &["--columns", "t,ax,ay,nope"]), "three_columns.csv", &["nope"]);
    let text = write("non_numeric.csv", b"t,ax,ay,az\n0,0,0,1\n0.01,0,abc,1\n0.02,0,0,1\n");
    assert_input_error(&calibrate(&text, &[]), "non_numeric.csv", &[".csv:3:", "abc"]);
    let backwards = write("backwards.csv", b"t,ax,ay,az\n0,0,0,1\n0.02,0,0,1\n0.01,0,0,1\n");
    assert_input_error(&calibrate(&backwards, &[]), "backwards.csv", &[".csv:4:"]);
    let duplicated = write("duplicated.csv", b"t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n0.01,0,0,1\n");
    assert_input_error(&calibrate(&duplicated, &[]), "duplicated.csv", &[".csv:4:"]);
}

#[test]
fn wrong_units_and_gigantic_values() {
    let counts = write("counts.csv", b"t,ax,ay,az\n0,120,-40,16384\n0.01,118,-41,16390\n0.02,121,-39,16380\n");
    assert_input_error(&calibrate(&counts, &["--units", "g"]), "counts.csv", &["g"]);
    let huge = write("huge.csv", b"t,ax,ay,az\n0,0,0,1\n0.01,0,1e30,1\n0.02,0,0,1\n");
    assert_input_error(&calibrate(&huge, &[]), "huge.csv", &[]);
}

#[test]
fn no_static_pose_and_too_few_poses() {
    let mut moving = String::from("t,ax,ay,az\n");
    for i in 0..3000 {
        let w = i as f64 * 0.05;
        moving.push_str(&format!("{:.2},{:.4},{:.4},{:.4}\n", i as f64 * 0.01, w.sin(), w.cos(), (2.0 * w).sin()));
    }
    let moving = write("moving.csv", moving.as_bytes());
    assert_input_error(&calibrate(&moving, &[]), "moving.csv", &["0 static poses"]);
    let mut five = String::from("t,ax,ay,az\n");
    let mut t = 0.0;
    for v in six_faces().into_iter().take(5) {
        pose_rows(&mut five, &mut t, v, 400);
    }
    let five = write("five_poses.csv", five.as_bytes());
    assert_input_error(&calibrate(&five, &[]), "five_poses.csv", &["5 static poses", "at least 6"]);
    // Six faces fit the biases and scales; the non-orthogonality is held at 0 and said so.
    let mut six = String::from("t,ax,ay,az\n");
    let mut t = 0.0;
    for v in six_faces() {
        pose_rows(&mut six, &mut t, v, 400);
    }
    let six = write("six_poses.csv", six.as_bytes());
    let out = calibrate(&six, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("do not determine Mxx Myy Mzz: held at nominal"), "{stdout}");
}

#[test]
fn truncated_last_line_and_isolated_nan_are_warnings_and_the_rest_is_used() {
    let mut log = String::from("t,ax,ay,az\n");
    let mut t = 0.0;
    let s = 1.0 / 3f64.sqrt();
    let mut dirs = six_faces();
    dirs.extend([[s, s, s], [-s, s, -s], [s, -s, -s], [-s, -s, s], [s, s, -s], [-s, s, s]]);
    for v in dirs {
        pose_rows(&mut log, &mut t, v, 400);
    }
    // A glitch in the middle of the first pose, and a power cut in the last line.
    let glitch_at = log.match_indices('\n').nth(200).unwrap().0 + 1;
    log.insert_str(glitch_at, "1.999,nan,0,1\n");
    log.push_str("99.0,0.1,");
    let path = write("glitchy.csv", log.as_bytes());
    let out = calibrate(&path, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(stderr.contains("warning") && stderr.to_lowercase().contains("nan"), "{stderr}");
    assert!(stderr.to_lowercase().contains("truncated") || stderr.to_lowercase().contains("last line"), "{stderr}");
    assert!(out.status.code() == Some(0) || out.status.code() == Some(1), "{stderr}");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("12 poses"), "{stdout}");
}

#[test]
fn a_failed_verdict_exits_1() {
    // Means of 14 directions whose moduli scatter by +-30 mg: no 9-parameter model fits.
    let s = 1.0 / 3f64.sqrt();
    let mut dirs = six_faces();
    dirs.extend([[s, s, s], [-s, s, -s], [s, -s, -s], [-s, -s, s], [s, s, -s], [-s, s, s], [s, -s, s], [-s, -s, -s]]);
    let mut text = String::from("ax,ay,az\n");
    for (i, d) in dirs.iter().enumerate() {
        let m = 1.0 + if i % 2 == 0 { 0.03 } else { -0.03 } * ((i % 5) as f64 / 4.0);
        text.push_str(&format!("{},{},{}\n", d[0] * m, d[1] * m, d[2] * m));
    }
    let path = write("misfit_means.csv", text.as_bytes());
    let out = calibrate(&path, &["--means"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("FAIL"), "{stdout}");
}

#[test]
fn bad_arguments_are_exit_2() {
    assert_eq!(run(&["calibrate"]).status.code(), Some(2));
    assert_eq!(run(&["paper", "--runs", "0"]).status.code(), Some(2));
    assert_eq!(run(&["simulate", "--plan", "hexagon", "-o", "/dev/null"]).status.code(), Some(2));
    let ok = write("g.csv", b"t,ax,ay,az\n0,0,0,1\n");
    assert_eq!(calibrate(&ok, &["--method", "magic"]).status.code(), Some(2));
    assert_eq!(calibrate(&ok, &["--gravity", "-9.8"]).status.code(), Some(2));
}

/// A free-hand log: `--init six-position` refuses it naming the missing face (exit 2); the default
/// (ellipsoid) start calibrates it (exit 0).
#[test]
fn a_free_hand_log_needs_no_face_unless_the_six_position_start_is_asked_for() {
    let csv = dir().join("freehand.csv");
    let out = run(&["simulate", "--plan", "freehand:14", "--seed", "3", "-o", csv.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
    let out = calibrate(&csv, &["--init", "six-position"]);
    assert_input_error(&out, "freehand.csv", &["six-position", "down"]);
    let out = calibrate(&csv, &[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(0), "{stdout}{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("verdict: PASS"), "{stdout}");
}

/// Output piped into a reader that goes away (`accelcal ... | head`): a quiet exit 0, not a panic.
#[test]
fn a_closed_stdout_ends_quietly() {
    let g = 9.80665;
    let mut csv = String::from("t,ax,ay,az\n");
    let faces = [[0.0, 0.0, g], [0.0, 0.0, -g], [g, 0.0, 0.0], [-g, 0.0, 0.0], [0.0, g, 0.0], [0.0, -g, 0.0]];
    let mut t = 0.0;
    for (k, f) in faces.iter().enumerate() {
        for i in 0..400 {
            let n = (((i * 7919 + k * 104_729) % 1000) as f64 / 1000.0 - 0.5) * 0.01;
            csv.push_str(&format!("{t:.3},{},{},{}\n", f[0] + n, f[1] - n, f[2] + 0.5 * n));
            t += 0.005;
        }
    }
    let path = write("closed_stdout.csv", csv.as_bytes());
    let mut child = Command::new(env!("CARGO_BIN_EXE_accelcal"))
        .args(["calibrate", path.to_str().unwrap(), "--json"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(out.status.code().is_some_and(|c| c <= 1), "{:?}: {stderr}", out.status);
}
