//! Golden vectors for the blob and the compensator, and corruption of every kind.
//!
//! The expected bytes and f32 output bits are committed under tests/data/. If the
//! format changes on purpose, regenerate them with `UPDATE_GOLDEN=1 cargo test -p
//! firmware-core --test blob_loopback` and bump `FORMAT_VERSION`.
use firmware_core::blob::{example_blob, Blob, MAX_BLOB_LEN};
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::Error;
use proptest::prelude::*;
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

fn golden(name: &str, actual: &str) {
    let path = data(name);
    if std::env::var_os("UPDATE_GOLDEN").is_some() {
        std::fs::write(&path, actual).unwrap();
    }
    let expected = std::fs::read_to_string(&path).unwrap();
    assert_eq!(expected, actual, "golden file {} differs", path.display());
}

fn encoded() -> Vec<u8> {
    let mut buf = [0u8; MAX_BLOB_LEN];
    let n = example_blob().encode(&mut buf).unwrap();
    buf[..n].to_vec()
}

fn hex(bytes: &[u8]) -> String {
    let mut s = String::new();
    for line in bytes.chunks(32) {
        for b in line {
            s.push_str(&format!("{b:02x}"));
        }
        s.push('\n');
    }
    s
}

#[test]
fn golden_bytes() {
    golden("example_blob.hex", &hex(&encoded()));
}

/// Inputs for the golden compensation table: (u, temp).
pub fn golden_inputs() -> Vec<([f32; 3], f32)> {
    let mut v = Vec::new();
    let us = [
        [0.0045, -0.0044, -0.5521],
        [-0.5461, -0.0177, 0.0112],
        [0.2370, -0.4940, -0.2340],
        [0.0, 0.0, 0.0],
    ];
    for (i, t) in [-45.0f32, -40.0, -10.0, 19.95, 20.0, 33.3, 45.0, 70.0, 85.0]
        .into_iter()
        .enumerate()
    {
        v.push((us[i % us.len()], t));
    }
    v
}

#[test]
fn golden_outputs_as_bits() {
    let blob = Blob::decode(&encoded()).unwrap();
    let mut out = String::from("# method temp_bits ux uy uz -> ax ay az status (f32 bits)\n");
    for (name, m) in [
        ("m1", Method::CorrectConstants),
        ("m2full", Method::CorrectResult(ErrorModel::Full)),
        ("m2simp", Method::CorrectResult(ErrorModel::Simplified)),
    ] {
        let mut c = Compensator::new(&blob.calibration, m).unwrap();
        for (u, t) in golden_inputs() {
            let o = c.compensate(u, t);
            out.push_str(&format!(
                "{name} {:08x} {:08x} {:08x} {:08x} -> {:08x} {:08x} {:08x} {}\n",
                t.to_bits(),
                u[0].to_bits(),
                u[1].to_bits(),
                u[2].to_bits(),
                o.accel[0].to_bits(),
                o.accel[1].to_bits(),
                o.accel[2].to_bits(),
                o.status.bits()
            ));
        }
    }
    golden("example_outputs.txt", &out);
}

#[test]
fn every_single_bit_flip_is_rejected() {
    let good = encoded();
    for i in 0..good.len() {
        for bit in 0..8 {
            let mut b = good.clone();
            b[i] ^= 1 << bit;
            let r = Blob::decode(&b);
            assert!(r.is_err(), "flip byte {i} bit {bit} accepted");
            if i >= 6 {
                assert_eq!(r, Err(Error::CrcMismatch), "byte {i} bit {bit}");
            }
        }
    }
}

#[test]
fn every_truncation_is_rejected() {
    let good = encoded();
    for n in 0..good.len() {
        assert!(
            Blob::decode(&good[..n]).is_err(),
            "truncated to {n} accepted"
        );
    }
    let mut longer = good.clone();
    longer.push(0);
    assert!(Blob::decode(&longer).is_err());
}

#[test]
fn header_errors_are_specific() {
    let good = encoded();
    let mut b = good.clone();
    b[0] = b'X';
    assert_eq!(Blob::decode(&b), Err(Error::BadMagic));
    let mut b = good.clone();
    b[4] = 9;
    assert_eq!(Blob::decode(&b), Err(Error::UnsupportedVersion(9)));
    assert_eq!(Blob::decode(&good[..5]), Err(Error::TooShort));
}

/// Wrap arbitrary content in a valid header and CRC, so the content checks are reached.
fn wrap(content: &[u8]) -> Vec<u8> {
    let mut b = b"ATCB".to_vec();
    b.extend_from_slice(&firmware_core::blob::FORMAT_VERSION.to_le_bytes());
    b.extend_from_slice(content);
    let crc = crc32(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

fn crc32(data: &[u8]) -> u32 {
    // An independent bitwise CRC-32, to check the firmware's table version too.
    let mut c = !0u32;
    for &x in data {
        c ^= u32::from(x);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                (c >> 1) ^ 0xEDB8_8320
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn content_checks_behind_a_valid_crc() {
    let good = encoded();
    let content = &good[6..good.len() - 4];
    assert!(
        Blob::decode(&wrap(content)).is_ok(),
        "independent CRC agrees"
    );
    let mut extra = content.to_vec();
    extra.push(0);
    assert_eq!(Blob::decode(&wrap(&extra)), Err(Error::TrailingBytes));
    // Non-increasing breakpoints: swap -40 and +20 in the table.
    let blob = example_blob();
    let mut bad = blob.clone();
    if let firmware_core::temperature::TempModel::Pwl { breakpoints, .. } =
        &mut bad.calibration.model
    {
        breakpoints[0] = 30.0;
    }
    let mut buf = [0u8; MAX_BLOB_LEN];
    assert_eq!(bad.encode(&mut buf), Err(Error::BreakpointsNotIncreasing));
    let raw = postcard::to_allocvec(&bad).unwrap();
    assert_eq!(
        Blob::decode(&wrap(&raw)),
        Err(Error::BreakpointsNotIncreasing)
    );
    let mut nan = blob.clone();
    nan.calibration.t0_c = f32::NAN;
    let raw = postcard::to_allocvec(&nan).unwrap();
    assert_eq!(Blob::decode(&wrap(&raw)), Err(Error::NonFinite));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..1200)) {
        let _ = Blob::decode(&bytes);
        let _ = Blob::decode(&wrap(&bytes));
    }

    #[test]
    fn decoded_random_content_is_always_valid(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        if let Ok(b) = Blob::decode(&wrap(&bytes)) {
            prop_assert!(b.validate().is_ok());
        }
    }
}

/// The largest blob the format allows (32-character serial, 16 breakpoints, physics terms)
/// encodes within `MAX_BLOB_LEN`: every valid blob
/// fits the fixed buffer, so a decoded blob always re-encodes.
#[test]
fn the_largest_blob_fits_the_fixed_buffer() {
    use firmware_core::temperature::{Physics, TempModel};
    let mut b = example_blob();
    b.serial.clear();
    b.serial.push_str(&"W".repeat(32)).unwrap();
    let t0 = b.calibration.at_t0();
    let bp: Vec<f32> = (0..16).map(|i| -40.0 + 7.0 * i as f32).collect();
    b.calibration.t_min_c = -40.0;
    b.calibration.t_max_c = 65.0;
    b.calibration.model = TempModel::Pwl {
        breakpoints: bp.iter().copied().collect(),
        values: bp
            .iter()
            .map(|t| t0.map(|v| v * (1.0 + 1e-5 * t)))
            .collect(),
    };
    b.calibration.physics = Some(Physics {
        sample_period_s: 1.0,
        lag_alpha: 0.01,
        rate: [0.02, 0.01, -0.01],
        rate_alpha: 0.03,
        hysteresis: [1e-4, 2e-4, 3e-4],
        hysteresis_threshold_c: 0.5,
        hysteresis_initial: 1.0,
        k2: [1e-4, 2e-4, 3e-4],
        asymmetry: [1e-4, 2e-4, 3e-4],
        warmup: [2e-4, 1e-4, 3e-4],
        warmup_decay: 0.999,
    });
    let mut big = vec![0u8; 4 * MAX_BLOB_LEN];
    let n = b.encode(&mut big).unwrap();
    assert!(n <= MAX_BLOB_LEN, "{n} bytes > MAX_BLOB_LEN {MAX_BLOB_LEN}");
    let mut buf = [0u8; MAX_BLOB_LEN];
    assert_eq!(b.encode(&mut buf), Ok(n));
    assert_eq!(Blob::decode(&buf[..n]), Ok(b));
}
