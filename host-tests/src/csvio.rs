//! The CSV input as the host tools and tests name it: reading is in [`crate::io`] (through the `csv`
//! crate: records to samples, units, columns, streaming) and pose detection in [`crate::poses`];
//! both are re-exported here. What is left maps a means file's rows to poses.
//!
//! ```
//! use accelcal_host::csvio::{read_csv_str, ReadOptions, Units};
//! let text = "time_s,ax,ay,az\n0.00,0.01,0.02,0.99\n0.01,0.01,0.03,1.01\n";
//! let table = read_csv_str("demo.csv", text, &ReadOptions::default()).unwrap();
//! assert_eq!(table.units, Units::G);
//! assert_eq!(table.samples.len(), 2);
//! assert_eq!(table.line_of_row, vec![2, 3]);
//! ```

#[cfg(test)]
use accelcal::accumulator::AccumulatorError;
use accelcal::accumulator::Pose;
#[cfg(test)]
use std::path::Path;

pub use crate::io::*;
pub use crate::poses::*;

/// Each row of a means table as a pose: the mean, the variance from the `std_*` columns (0 without
/// them) and `n` from the count column (0 without it).
pub fn to_poses_from_means(table: &Table) -> Vec<Pose> {
    table
        .samples
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let n = table.counts_n.as_ref().map_or(0, |c| c[i]);
            let mut pose = Pose::from_mean(s.map(|v| v as f32), n);
            if let Some(std) = &table.std_devs {
                pose.variance = std[i].map(|d| (d * d) as f32);
            }
            pose
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<Table, CsvError> {
        read_csv_str("test.csv", text, &ReadOptions::default())
    }

    fn read_with(text: &str, opts: &ReadOptions) -> Result<Table, CsvError> {
        read_csv_str("test.csv", text, opts)
    }

    /// Display of an error, checked to name the file.
    fn message(e: &CsvError) -> String {
        let m = e.to_string();
        assert!(m.contains("test.csv"), "no file name in: {m}");
        m
    }

    #[test]
    fn reads_g_with_time_and_temperature() {
        let t = read("time_s,ax_g,ay_g,az_g,temp_C\n0.0,0.01,0.02,0.99,25.0\n0.01,0.02,0.01,1.01,25.1\n").unwrap();
        assert_eq!(t.units, Units::G);
        assert!(!t.units_detected);
        assert_eq!(t.units_header.as_ref().map(|h| (h.column.as_str(), h.label)), Some(("ax_g", "g")));
        assert_eq!(t.times_s, Some(vec![0.0, 0.01]));
        assert_eq!(t.temps_c, Some(vec![25.0, 25.1]));
        assert_eq!(t.samples[1], [0.02, 0.01, 1.01]);
        assert_eq!(t.line_of_row, vec![2, 3]);
        assert!(t.warnings.is_empty());
        assert!(t.units_summary().starts_with("g (header `ax_g`"), "{}", t.units_summary());
        assert!((t.sample_rate_hz().unwrap() - 100.0).abs() < 1e-9);
    }

    #[test]
    fn detects_units_from_magnitudes() {
        let t = read("ax,ay,az\n0.1,0.2,9.7\n0.1,0.3,9.8\n").unwrap();
        assert_eq!(t.units, Units::Mps2);
        let t = read("acc_x_raw,acc_y_raw,acc_z_raw\n33108,33329,36429\n33096,33336,36437\n").unwrap();
        assert_eq!(t.units, Units::Counts);
        assert_eq!(t.samples[0], [33108.0, 33329.0, 36429.0]);
        let e = read("x,y,z\n0.1,0.2,3.0\n").unwrap_err();
        assert!(matches!(e, CsvError::UnknownUnits { .. }));
        assert!(message(&e).contains("--units"));
    }

    #[test]
    fn wrong_declared_units_are_an_error() {
        let opts = ReadOptions { units: Units::G, ..ReadOptions::default() };
        let e = read_with("ax,ay,az\n100,200,16000\n110,190,16010\n", &opts).unwrap_err();
        let m = message(&e);
        assert!(m.contains("values no accelerometer reads in g"), "{m}");
        assert!(m.contains("--units counts"), "{m}");
        let opts = ReadOptions { units: Units::Counts, ..ReadOptions::default() };
        let e = read_with("ax,ay,az\n0.0,0.0,1.0\n", &opts).unwrap_err();
        assert!(matches!(e, CsvError::WrongUnits { looks_like: Some(Units::G), .. }), "{e}");
        let opts = ReadOptions { units: Units::Mps2, ..ReadOptions::default() };
        assert_eq!(read_with("ax,ay,az\n0.0,0.0,9.8\n", &opts).unwrap().units, Units::Mps2);
    }

    #[test]
    fn units_parse() {
        assert_eq!("auto".parse::<Units>(), Ok(Units::Auto));
        assert_eq!("COUNTS".parse::<Units>(), Ok(Units::Counts));
        assert_eq!("g".parse::<Units>(), Ok(Units::G));
        assert_eq!("mps2".parse::<Units>(), Ok(Units::Mps2));
        assert_eq!("m/s^2".parse::<Units>(), Ok(Units::Mps2));
        assert!("furlongs".parse::<Units>().unwrap_err().to_string().contains("furlongs"));
        assert_eq!(Units::G.calibration_gravity(), 1.0);
        assert_eq!(Units::Counts.before_model(), None);
    }

    #[test]
    fn missing_file_and_io() {
        let e = read_csv(Path::new("/nonexistent/dir/rec.csv"), &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Missing { .. }));
        assert!(e.to_string().contains("/nonexistent/dir/rec.csv"));
        let e = read_csv(Path::new("/"), &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Io { .. }), "{e:?}");
        assert!(e.to_string().starts_with("/:"));
    }

    #[test]
    fn empty_and_header_only() {
        assert!(matches!(read("").unwrap_err(), CsvError::Empty { .. }));
        assert!(matches!(read("\n\n# comment\n").unwrap_err(), CsvError::Empty { .. }));
        let e = read("ax,ay,az\n").unwrap_err();
        assert_eq!(e, CsvError::HeaderOnly { file: "test.csv".into(), line: 1 });
        assert!(message(&e).contains("test.csv:1:"));
        assert!(matches!(read("# made by logger\nax,ay,az\n\n").unwrap_err(), CsvError::HeaderOnly { line: 2, .. }));
    }

    #[test]
    fn headerless_file_is_an_error() {
        let e = read("0.01\t-0.05\t1.02\n0.06\t-0.05\t1.02\n").unwrap_err();
        assert!(matches!(e, CsvError::NoHeader { line: 1, .. }));
        assert!(message(&e).contains("header"));
    }

    #[test]
    fn missing_columns_list_the_header() {
        let e = read("time,gx,gy,gz\n0,1,2,3\n").unwrap_err();
        let m = message(&e);
        assert!(matches!(e, CsvError::MissingColumns { line: 1, .. }));
        assert!(m.contains("ax, ay, az") && m.contains("`gx`"), "{m}");
        let e = read("ax,ay,acc_x\n1,2,3\n").unwrap_err();
        assert!(matches!(e, CsvError::AmbiguousColumn { role: "ax", .. }), "{e:?}");
    }

    #[test]
    fn column_names_are_recognised() {
        let cases = [
            ("t,ax,ay,az", true),
            ("Time,AccX,AccY,AccZ", true),
            ("timestamp_ms,ax_raw,ay_raw,az_raw", true),
            ("time (s),x (g),y (g),z (g)", true),
            ("measurement,ax_g,ay_g,az_g,norm_g", false),
            (
                "interval,t_start_s,t_end_s,n_samples,mean_x_raw,mean_y_raw,mean_z_raw,std_x_raw,std_y_raw,std_z_raw",
                false,
            ),
            ("x_true (g),x_mean (g),x_std,y_true (g),y_mean (g),y_std,z_true (g),z_mean (g),z_std", false),
            ("t_center_s,ax_g_1s_mean,ay_g_1s_mean,az_g_1s_mean", true),
            ("acc_x [m/s^2];acc_y [m/s^2];acc_z [m/s^2]", false),
        ];
        for (header, has_time) in cases {
            let cells = split_cells(header, Delimiter::detect(header)).len();
            // A value the header's unit reads at rest (|a| = 1.73 g, or 9.87 m/s^2).
            let value = if header.contains("m/s^2") { "5.7" } else { "1" };
            let row = vec![value; cells].join(if header.contains(';') { ";" } else { "," });
            let t = read(&format!("{header}\n{row}\n")).unwrap_or_else(|e| panic!("{header}: {e}"));
            assert_eq!(t.times_s.is_some(), has_time, "{header}");
        }
        let t = read("interval,n_samples,mean_x_raw,mean_y_raw,mean_z_raw,std_x_raw,std_y_raw,std_z_raw\n1,100,3,4,33000,1,2,3\n")
            .unwrap();
        assert_eq!(t.counts_n, Some(vec![100]));
        assert_eq!(t.std_devs, Some(vec![[1.0, 2.0, 3.0]]));
        assert_eq!(t.columns.accel[2], "mean_z_raw");
        let t = read("timestamp_ms,ax,ay,az\n100,0,0,1\n110,0,0,1\n").unwrap();
        assert_eq!(t.times_s, Some(vec![0.1, 0.11]));
    }

    #[test]
    fn delimiters_and_quotes() {
        let t = read("ax;ay;az\n0,01;0,02;0,99\n").unwrap();
        assert_eq!(t.delimiter, Delimiter::Semicolon);
        assert_eq!(t.samples[0], [0.01, 0.02, 0.99]);
        let t = read("ax\tay\taz\n0.01\t0.02\t0.99\n").unwrap();
        assert_eq!(t.delimiter, Delimiter::Tab);
        let t = read("  ax   ay  az \n 0.01  0.02   0.99\r\n").unwrap();
        assert_eq!(t.delimiter, Delimiter::Whitespace);
        assert_eq!(t.samples[0], [0.01, 0.02, 0.99]);
        let t = read("\u{feff}\"ax\",\"ay\",\"az\"\r\n\"0.01\", 0.02 ,0.99\r\n").unwrap();
        assert_eq!(t.samples[0], [0.01, 0.02, 0.99]);
    }

    #[test]
    fn column_spec_parses_and_overrides() {
        let spec: ColumnSpec = "t,ax,ay,az".parse().unwrap();
        assert_eq!(spec.time, Some(ColumnRef::Name("t".into())));
        assert_eq!(spec.temp, None);
        let spec: ColumnSpec = "0,1,2".parse().unwrap();
        assert_eq!(spec.accel, [ColumnRef::Index(0), ColumnRef::Index(1), ColumnRef::Index(2)]);
        assert!("a,b".parse::<ColumnSpec>().is_err());
        assert!("t,-,ay,az".parse::<ColumnSpec>().unwrap_err().to_string().contains("x column"));
        assert!("1,2,3,4,5,6,7".parse::<ColumnSpec>().is_err());

        // Concatenated captures: the time column goes backwards, so leave it out.
        let text =
            "pos,timestamp_ms,ax_raw,ay_raw,az_raw,temp_C\nH1,171,17076,36,1216,24.1\nH2,100,16766,63,-1810,24.9\n";
        let e = read(text).unwrap_err();
        assert!(matches!(e, CsvError::NonMonotonicTime { line: 3, previous_line: 2, .. }), "{e:?}");
        assert!(message(&e).contains("test.csv:3:"));
        let opts =
            ReadOptions { columns: Some("-,ax_raw,ay_raw,az_raw,temp_c".parse().unwrap()), ..ReadOptions::default() };
        let t = read_with(text, &opts).unwrap();
        assert_eq!(t.times_s, None);
        assert_eq!(t.temps_c, Some(vec![24.1, 24.9]));
        assert_eq!(t.units, Units::Counts);

        let opts = ReadOptions { columns: Some("0,1,2,3".parse().unwrap()), ..ReadOptions::default() };
        let e =
            read_with("ax,ay,az\n1,2,3\n", &ReadOptions { columns: Some("ax,ay,bz".parse().unwrap()), ..opts.clone() })
                .unwrap_err();
        assert!(message(&e).contains("`bz`"));
        let e = read_with("ax,ay,az\n1,2,3\n", &ReadOptions { columns: Some("0,1,7".parse().unwrap()), ..opts })
            .unwrap_err();
        let expected = CsvError::ColumnIndexOutOfRange {
            file: "test.csv".into(),
            line: 2,
            index: 7,
            columns: 3,
            from_header: false,
        };
        assert_eq!(e, expected);
        assert!(message(&e).contains("column index 7, but the first data row has 3 columns (indices 0-2)"));
    }

    #[test]
    fn non_numeric_cell_names_line_column_and_text() {
        let e = read("t,ax,ay,az\n0,0,0,1\n0.01,0,zero,1\n").unwrap_err();
        assert_eq!(
            e,
            CsvError::NonNumeric { file: "test.csv".into(), line: 3, column: "ay".into(), text: "zero".into() }
        );
        let m = message(&e);
        assert!(m.contains("test.csv:3:") && m.contains("`ay`") && m.contains("`zero`"), "{m}");
        let e = read("ax,ay,az,n\n0,0,1,1.5\n").unwrap_err();
        assert!(matches!(e, CsvError::BadCount { line: 2, .. }));
    }

    #[test]
    fn time_must_increase() {
        let e = read("t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n0.01,0,0,1\n").unwrap_err();
        assert!(matches!(e, CsvError::DuplicateTime { line: 4, previous_line: 3, .. }), "{e:?}");
        assert!(message(&e).contains("repeats line 3"));
        let e = read("t,ax,ay,az\n0,0,0,1\n0.02,0,0,1\n0.01,0,0,1\n").unwrap_err();
        assert!(matches!(e, CsvError::NonMonotonicTime { line: 4, .. }));
    }

    #[test]
    fn binary_files_are_rejected() {
        let e = read_csv_bytes("test.csv", b"MATLAB 5.0 MAT-file\n\x00\x01\x02", &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Binary { line: 2, .. }), "{e:?}");
        message(&e);
        let e = read_csv_bytes("test.csv", b"ax,ay,az\n\xff\xfe\x01,1,2\n", &ReadOptions::default()).unwrap_err();
        assert!(matches!(e, CsvError::Binary { line: 2, what: "invalid UTF-8", .. }), "{e:?}");
        let noise: Vec<u8> = (0..400u32).map(|i| 0x80 | (i.wrapping_mul(2_654_435_761) >> 25) as u8).collect();
        let e = read_csv_bytes("test.csv", &[b"ax,ay,az\n".as_slice(), &noise].concat(), &ReadOptions::default())
            .unwrap_err();
        assert!(matches!(e, CsvError::Binary { line: 2, .. }), "{e:?}");
        let e = read_csv_bytes("test.csv", b"\xff\xfea\x00x\x00", &ReadOptions::default()).unwrap_err();
        assert!(message(&e).contains("UTF-16"));
    }

    #[test]
    fn preamble_before_the_header_is_skipped() {
        let t = read(
            "Fs,100\nLogging Type,0\n\nax,ay,az,gx,gy,gz\n-12,-812,15032,-447,156,-86\n-208,-828,14796,-398,132,-63\n",
        )
        .unwrap();
        assert_eq!(t.line_of_row, vec![5, 6]);
        assert_eq!(t.units, Units::Counts);
        assert!(t.warnings[0].contains("lines 1-3 before the header (line 4) skipped"), "{:?}", t.warnings);
        // A title line, then a header with two names run together: columns by index.
        let text = "Data Collected on Level Surface. Z up.\ntime (s)x (g),y (g),z (g)\n0.005,0.099,0.064,0.774\n0.011,0.098,0.063,0.771\n";
        let e = read(text).unwrap_err();
        assert!(matches!(e, CsvError::MissingColumns { line: 2, .. }), "{e:?}");
        assert!(message(&e).contains("`time (s)x (g)`"));
        let opts = ReadOptions { columns: Some("0,1,2,3".parse().unwrap()), ..ReadOptions::default() };
        let t = read_with(text, &opts).unwrap();
        assert_eq!(t.times_s, Some(vec![0.005, 0.011]));
        assert_eq!(t.samples[1], [0.098, 0.063, 0.771]);
        // A corrupt first data line is data (and an error), not a header.
        let e = read("t,ax,ay,az\n0.1,0,0,103.79.00\n0.2,0,0,1\n").unwrap_err();
        assert!(matches!(e, CsvError::NonNumeric { line: 2, .. }), "{e:?}");
        // A text label column: no all-numeric line, the first line is the header.
        let t = read("pos,ax,ay,az\nH1,0,0,1\nH2,0,1,0\n").unwrap();
        assert_eq!(t.samples.len(), 2);
        assert!(t.warnings.is_empty());
    }

    #[test]
    fn latin1_text_is_read_with_a_warning() {
        let t = read_csv_bytes(
            "test.csv",
            b"Timestamp,aX (g),aY (g),aZ (g),gX (\xb0/s)\n0,0,0,1,0\n",
            &ReadOptions::default(),
        )
        .unwrap();
        assert_eq!(t.header[4], "gX (\u{b0}/s)");
        assert!(t.warnings[0].contains("test.csv:1: not UTF-8; read as Latin-1"), "{:?}", t.warnings);
    }

    #[test]
    fn a_clock_in_milliseconds_is_flagged() {
        let t = read("Timestamp,ax,ay,az\n410,0,0,9.8\n427,0,0,9.8\n442,0,0,9.8\n").unwrap();
        assert!(t.warnings.iter().any(|w| w.contains("`Timestamp` steps by 16 per row")), "{:?}", t.warnings);
        let t = read("time_ms,ax,ay,az\n410,0,0,9.8\n427,0,0,9.8\n442,0,0,9.8\n").unwrap();
        assert!(t.warnings.is_empty());
    }

    #[test]
    fn gigantic_values_are_rejected() {
        let mut text = String::from("ax,ay,az\n");
        for _ in 0..10 {
            text.push_str("0.0,0.0,1.0\n");
        }
        text.push_str("0.0,3e7,1.0\n");
        let e = read(&text).unwrap_err();
        assert!(matches!(e, CsvError::Gigantic { line: 12, units: Units::G, .. }), "{e:?}");
        assert!(message(&e).contains("`ay`"));
        let e = read("ax,ay,az\n1e300,0,0\n1e300,0,0\n").unwrap_err();
        assert!(matches!(e, CsvError::Gigantic { units: Units::Counts, .. }), "{e:?}");
    }

    #[test]
    fn truncated_last_line_is_tolerated() {
        let t = read("t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n0.02,0.1").unwrap();
        assert_eq!(t.samples.len(), 2);
        assert_eq!(t.warnings.len(), 1);
        assert!(t.warnings[0].contains("test.csv:4:") && t.warnings[0].contains("truncated"), "{:?}", t.warnings);
        // Cut inside a number, no line end.
        let t = read("t,ax,ay,az\n0,0,0,1\n0.01,0,0,1\n0.02,0.1,0,1.0e").unwrap();
        assert_eq!(t.samples.len(), 2);
        assert_eq!(t.warnings.len(), 1);
        // A short line in the middle is an error.
        let e = read("t,ax,ay,az\n0,0,0,1\n0.01,0\n0.02,0,0,1\n").unwrap_err();
        assert_eq!(e, CsvError::RaggedRow { file: "test.csv".into(), line: 3, cells: 2, expected: 4 });
        message(&e);
    }

    #[test]
    fn isolated_non_finite_rows_are_skipped() {
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..40 {
            let az = match i {
                7 => "NaN".to_string(),
                20 => "inf".to_string(),
                31 => String::new(),
                _ => "1.0".to_string(),
            };
            text.push_str(&format!("{},0.0,0.0,{az}\n", i as f64 * 0.01));
        }
        let t = read(&text).unwrap();
        assert_eq!(t.samples.len(), 37);
        assert_eq!(t.times_s.as_ref().unwrap().len(), 37);
        assert_eq!(t.warnings.len(), 1);
        assert!(
            t.warnings[0].contains("3 of 40 rows") && t.warnings[0].contains("lines 9, 22, 33"),
            "{:?}",
            t.warnings
        );
        assert_eq!(t.line_of_row[7], 10);

        let mut text = String::from("ax,ay,az\n");
        for i in 0..10 {
            text.push_str(if i % 2 == 0 { "0,0,nan\n" } else { "0,0,1\n" });
        }
        let e = read(&text).unwrap_err();
        assert!(matches!(e, CsvError::TooManyNonFinite { skipped: 5, rows: 10, first_line: 2, .. }), "{e:?}");
        message(&e);
    }

    #[test]
    fn means_rows_become_poses() {
        let opts = ReadOptions { means: true, ..ReadOptions::default() };
        let t = read_with(
            "position,mean_x_g,mean_y_g,mean_z_g,n,std_x,std_y,std_z\n1,0,0,1,200,0.001,0.002,0.003\n",
            &opts,
        )
        .unwrap();
        let poses = to_poses_from_means(&t);
        assert_eq!(poses.len(), 1);
        assert_eq!(poses[0].mean, [0.0, 0.0, 1.0]);
        assert_eq!(poses[0].n, 200);
        assert!((poses[0].variance[2] - 9e-6).abs() < 1e-9);
        let t = read_with("ax,ay,az\n0,0,1\n", &opts).unwrap();
        assert_eq!(to_poses_from_means(&t)[0].n, 0);
    }

    #[test]
    fn block_choice_follows_the_rate() {
        assert_eq!(choose_block_samples(None), DEFAULT_BLOCK_SAMPLES);
        assert_eq!(choose_block_samples(Some(100.0)), 16);
        assert_eq!(choose_block_samples(Some(400.0)), 64);
        assert_eq!(choose_block_samples(Some(180.0)), 32);
        assert_eq!(choose_block_samples(Some(9.5)), 8);
        assert_eq!(choose_block_samples(Some(f64::NAN)), DEFAULT_BLOCK_SAMPLES);
        assert!(
            (quantisation_variance(&[[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [1.0, 0.0, 3.0]]) - (1.0 + 4.0 + 9.0) / 12.0)
                .abs()
                < 1e-6
        );
    }

    #[test]
    fn accumulate_finds_static_poses_and_their_times() {
        // Three holds of 3 s at 100 Hz, counts with +-2 LSB noise, separated by 1 s turns.
        let holds = [[33000.0, 32800.0, 36900.0], [29000.0, 32800.0, 32700.0], [33000.0, 28700.0, 32700.0]];
        let mut text = String::from("time_s,ax_raw,ay_raw,az_raw\n");
        let mut i = 0u32;
        let mut lcg = 12345u32;
        let mut push = |text: &mut String, s: [f64; 3]| {
            lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let n = f64::from(lcg >> 29) - 3.5; // -3.5..3.5
            text.push_str(&format!("{:.2},{:.0},{:.0},{:.0}\n", f64::from(i) * 0.01, s[0] + n, s[1] - n, s[2] + n));
            i += 1;
        };
        for (h, hold) in holds.iter().enumerate() {
            for _ in 0..300 {
                push(&mut text, *hold);
            }
            if h + 1 < holds.len() {
                let next = holds[h + 1];
                for k in 0..100 {
                    let f = f64::from(k) / 100.0;
                    push(&mut text, [0, 1, 2].map(|a| hold[a] + f * (next[a] - hold[a]) + 900.0 * (f * 6.3).sin()));
                }
            }
        }
        let table = read(&text).unwrap();
        assert_eq!(table.units, Units::Counts);
        let acc = accumulate(&table, &AccumulateOptions::default()).unwrap();
        assert_eq!(acc.block_samples, 16);
        assert_eq!(acc.poses.len(), 3, "{acc:?}");
        for (pose, hold) in acc.poses.iter().zip(holds) {
            for (mean, expected) in pose.mean.iter().zip(hold) {
                assert!((f64::from(*mean) - expected).abs() < 1.0, "{pose:?}");
            }
        }
        let span = acc.spans[1];
        assert!(span.start_s.unwrap() >= 4.0 && span.end_s.unwrap() <= 7.0, "{span:?}");
        assert_eq!(span.first_line, table.line_of_row[span.first_row]);
        assert!((acc.min_noise_variance - 0.25).abs() < 1e-6);
    }

    #[test]
    fn stale_repeated_reads_are_skipped() {
        // A 100 Hz sensor polled at 400 Hz: every reading appears 4 times.
        let mut text = String::from("ax,ay,az\n");
        let mut lcg = 7u32;
        for _ in 0..500 {
            lcg = lcg.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let n = f64::from(lcg >> 24) / 256.0 - 0.5;
            for _ in 0..4 {
                text.push_str(&format!("{:.4},{:.4},{:.4}\n", 0.01 * n, -0.01 * n, 1.0 + 0.01 * n));
            }
        }
        let table = read(&text).unwrap();
        assert!((repeat_fraction(&table.samples) - 0.75).abs() < 0.01);
        let acc = accumulate(&table, &AccumulateOptions::default()).unwrap();
        assert!(acc.skipped_repeats >= 1490, "{acc:?}");
        assert_eq!(acc.poses.len(), 1);
        assert_eq!(acc.spans[0].first_row % 4, 0, "spans refer to table rows");
        let kept = AccumulateOptions { skip_repeats: Some(false), ..AccumulateOptions::default() };
        assert_eq!(accumulate(&table, &kept).unwrap().skipped_repeats, 0);
    }

    #[test]
    fn time_gaps_interrupt_the_stream() {
        let mut text = String::from("t,ax,ay,az\n");
        for i in 0..400 {
            let t = f64::from(i) * 0.01 + if i >= 200 { 5.0 } else { 0.0 };
            text.push_str(&format!("{t:.2},0.0,0.0,{}\n", 1.0 + 0.001 * f64::from(i % 3)));
        }
        let table = read(&text).unwrap();
        let acc = accumulate(&table, &AccumulateOptions::default()).unwrap();
        assert_eq!(acc.interruptions, 1);
        assert_eq!(acc.poses.len(), 2, "{acc:?}");
        let bad = AccumulateOptions { block_samples: Some(12), ..AccumulateOptions::default() };
        assert_eq!(accumulate(&table, &bad).unwrap_err(), AccumulatorError::InvalidConfig);
    }
}
