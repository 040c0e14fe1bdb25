//! Any bytes into the calibration-blob decoder: never a panic; a decoded blob re-encodes to itself.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok((params, gravity)) = accelcal::blob::decode(data) {
        assert_eq!(&accelcal::blob::encode(&params, gravity)[..], data);
    }
});
