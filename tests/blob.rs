//! Blob v2: round trips, version 1 compatibility, and every refusal of `Blob::from_bytes`.

use accelcal::blob::{BLOB_LEN, BLOB_V1_LEN, Blob, BlobError, Effects, Field, SensorSetup, crc32, decode, encode};
use accelcal::model::Params;

const G: f32 = 9.806_65;
const P: Params = Params { bias: [0.1, -0.2, 0.3], scale: [0.97, 1.01, 0.99], nonorth: [-0.01, 0.02, 0.005] };

/// The version 1 encoder as it was written (magic, version 1, 3 zero bytes, 9 + 1 f32, CRC-32).
fn encode_v1(params: &Params, gravity: f32) -> [u8; BLOB_V1_LEN] {
    let mut out = [0u8; BLOB_V1_LEN];
    out[..4].copy_from_slice(b"ACAL");
    out[4] = 1;
    let mut at = 8;
    for v in params.to_array().iter().chain(core::iter::once(&gravity)) {
        out[at..at + 4].copy_from_slice(&v.to_le_bytes());
        at += 4;
    }
    let crc = crc32(&out[..at]);
    out[at..].copy_from_slice(&crc.to_le_bytes());
    out
}

fn full_blob() -> Blob {
    Blob {
        params: P,
        gravity: G,
        sensor: Some(SensorSetup { full_scale_g: 4.0, lsb_per_g: 8192.0, sensor_id: 0x68 }),
        temperature_c: Some(23.5),
        effects: Some(Effects {
            bias_per_c: [1e-3, -2e-3, 0.0],
            scale_per_c: [1e-4, 0.0, -1e-4],
            square: [0.0, 1e-5, 0.0],
        }),
    }
}

/// Re-signs bytes after an edit, so the CRC passes and the content check is what answers.
fn resign(mut bytes: Vec<u8>) -> Vec<u8> {
    let n = bytes.len() - 4;
    let crc = crc32(&bytes[..n]);
    bytes[n..].copy_from_slice(&crc.to_le_bytes());
    bytes
}

/// A blob whose checks are skipped: `to_bytes` writes whatever it is given.
fn bytes_of(blob: &Blob) -> Vec<u8> {
    blob.to_bytes().to_vec()
}

#[test]
fn full_blob_round_trips_and_every_bit_flip_is_refused() {
    let blob = full_blob();
    let bytes = blob.to_bytes();
    assert_eq!(Blob::from_bytes(&bytes), Ok(blob));
    for bit in 0..BLOB_LEN * 8 {
        let mut bad = bytes;
        bad[bit / 8] ^= 1 << (bit % 8);
        assert!(Blob::from_bytes(&bad).is_err(), "bit {bit} flip accepted");
    }
}

#[test]
fn encode_decode_keep_their_meaning() {
    let bytes = encode(&P, G);
    assert_eq!(bytes.len(), BLOB_LEN);
    assert_eq!(bytes[4], 2);
    assert_eq!(decode(&bytes), Ok((P, G)));
    assert_eq!(Blob::from_bytes(&bytes), Ok(Blob::new(P, G)));
}

#[test]
fn version_1_blobs_still_load() {
    let v1 = encode_v1(&P, G);
    assert_eq!(decode(&v1), Ok((P, G)));
    assert_eq!(Blob::from_bytes(&v1), Ok(Blob::new(P, G)));
    let mut reserved = v1.to_vec();
    reserved[6] = 1;
    assert_eq!(Blob::from_bytes(&resign(reserved)), Err(BlobError::ReservedBitsSet));
}

#[test]
fn framing_refusals() {
    let bytes = full_blob().to_bytes();
    assert_eq!(Blob::from_bytes(&bytes[..10]), Err(BlobError::WrongLength { got: 10 }));
    assert_eq!(Blob::from_bytes(&[0xFF; BLOB_LEN]), Err(BlobError::BadMagic));
    assert_eq!(Blob::from_bytes(&[0xFF; BLOB_V1_LEN]), Err(BlobError::BadMagic));
    let mut corrupted = bytes;
    corrupted[20] ^= 0x10;
    assert_eq!(Blob::from_bytes(&corrupted), Err(BlobError::BadChecksum));
    let mut magic = bytes.to_vec();
    magic[0] = b'X';
    assert_eq!(Blob::from_bytes(&resign(magic)), Err(BlobError::BadMagic));
}

#[test]
fn version_and_length_must_agree() {
    let mut v3 = full_blob().to_bytes().to_vec();
    v3[4] = 3;
    assert_eq!(Blob::from_bytes(&resign(v3)), Err(BlobError::UnsupportedVersion { found: 3 }));
    let mut v2_short = encode_v1(&P, G).to_vec();
    v2_short[4] = 2;
    assert_eq!(Blob::from_bytes(&resign(v2_short)), Err(BlobError::UnsupportedVersion { found: 2 }));
    let mut v1_long = encode(&P, G).to_vec();
    v1_long[4] = 1;
    assert_eq!(Blob::from_bytes(&resign(v1_long)), Err(BlobError::UnsupportedVersion { found: 1 }));
}

#[test]
fn reserved_bits_and_absent_fields_must_be_zero() {
    let base = encode(&P, G).to_vec();
    for (at, value) in [(5, 0x08), (6, 1), (7, 0x80), (50, 1), (62, 1), (99, 1)] {
        let mut bad = base.clone();
        bad[at] = value;
        assert_eq!(Blob::from_bytes(&resign(bad)), Err(BlobError::ReservedBitsSet), "byte {at}");
    }
}

/// A change to a blob that one check must refuse.
type Edit = fn(&mut Blob);

#[test]
fn non_finite_values_name_their_field() {
    let cases: [(Edit, Field); 10] = [
        (|b| b.params.bias[1] = f32::NAN, Field::Bias),
        (|b| b.params.scale[2] = f32::INFINITY, Field::Scale),
        (|b| b.params.nonorth[0] = f32::NAN, Field::Nonorth),
        (|b| b.gravity = f32::NAN, Field::Gravity),
        (|b| b.sensor.as_mut().unwrap().full_scale_g = f32::NAN, Field::FullScale),
        (|b| b.sensor.as_mut().unwrap().lsb_per_g = f32::INFINITY, Field::LsbPerG),
        (|b| b.temperature_c = Some(f32::NAN), Field::Temperature),
        (|b| b.effects.as_mut().unwrap().bias_per_c[2] = f32::NAN, Field::BiasTempco),
        (|b| b.effects.as_mut().unwrap().scale_per_c[0] = f32::NEG_INFINITY, Field::ScaleTempco),
        (|b| b.effects.as_mut().unwrap().square[1] = f32::NAN, Field::Square),
    ];
    for (edit, field) in cases {
        let mut blob = full_blob();
        edit(&mut blob);
        assert_eq!(blob.check(), Err(BlobError::NotFinite { field }));
        assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Err(BlobError::NotFinite { field }));
    }
}

#[test]
fn zero_or_negative_scale_is_refused_per_axis() {
    for (axis, value) in [(0, 0.0), (1, -1.0), (2, -0.0)] {
        let mut blob = full_blob();
        blob.params.scale[axis] = value;
        assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Err(BlobError::NonPositiveScale { axis: axis as u8 }));
    }
}

#[test]
fn non_positive_gravity_and_sensor_setup_are_refused() {
    let mut blob = full_blob();
    blob.gravity = 0.0;
    assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Err(BlobError::NonPositiveGravity));
    for edit in [|s: &mut SensorSetup| s.full_scale_g = 0.0, |s: &mut SensorSetup| s.lsb_per_g = -8192.0] {
        let mut blob = full_blob();
        edit(blob.sensor.as_mut().unwrap());
        assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Err(BlobError::NonPositiveSensorSetup));
    }
}

#[test]
fn bias_beyond_full_scale_is_refused() {
    let mut blob = full_blob();
    blob.params.bias[2] = -4.01 * G;
    assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Err(BlobError::BiasBeyondFullScale { axis: 2 }));
    blob.params.bias[2] = -3.99 * G;
    assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Ok(blob));
    // Without a sensor set-up there is no full scale to compare with.
    blob.sensor = None;
    blob.params.bias[2] = -100.0 * G;
    assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Ok(blob));
}

#[test]
fn effects_need_a_temperature() {
    let mut blob = full_blob();
    blob.temperature_c = None;
    assert_eq!(Blob::from_bytes(&bytes_of(&blob)), Err(BlobError::EffectsWithoutTemperature));
}

#[test]
fn apply_uses_the_effect_terms() {
    let blob = full_blob();
    let f_s = [1.0, -2.0, 9.0];
    // At the calibration temperature only the square terms add to the 9-parameter model.
    let plain = P.apply(f_s);
    let at_cal = blob.apply(f_s, Some(23.5));
    assert_eq!(at_cal[0], plain[0]);
    assert!((at_cal[1] - (plain[1] + 1e-5 * 4.0)).abs() < 1e-6);
    assert_eq!(blob.apply(f_s, None), at_cal);
    // 10 deg C warmer: x bias grows by 1e-3 * 10, x scale by 1e-4 * 10.
    let warm = blob.apply(f_s, Some(33.5));
    let k = P.ka_times(f_s);
    assert!((warm[0] - (1.001 * k[0] - (0.1 + 0.01))).abs() < 1e-6);
    assert!((warm[2] - (0.999 * k[2] - 0.3)).abs() < 1e-5);
    assert_eq!(Blob::new(P, G).apply(f_s, Some(60.0)), plain);
}
