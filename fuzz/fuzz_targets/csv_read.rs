//! Any bytes into the CSV reader (auto units, raw and means mode) and, when it reads, through the
//! accumulator: never a panic.
#![no_main]

use accelcal_host::csvio::{AccumulateOptions, ReadOptions, accumulate, read_csv_bytes};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    for means in [false, true] {
        let opts = ReadOptions { means, ..ReadOptions::default() };
        if let Ok(table) = read_csv_bytes("fuzz.csv", data, &opts) {
            assert_eq!(table.samples.len(), table.line_of_row.len());
            if !means {
                let _ = accumulate(&table, &AccumulateOptions::default());
            }
        }
    }
});
