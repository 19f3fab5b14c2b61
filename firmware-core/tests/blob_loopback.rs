//! Golden vectors of the blob (format 4, and format 5 with discovered terms) and the
//! compensator reading it in place (the tables alone, with physics terms, and with
//! physics and discovered terms on an uneven clock), and corruption of every kind, each
//! refused with the right error.
//!
//! The expected bytes and f32 output bits are committed under tests/data/ and checked
//! against an independent reading of the documented layout. If the format changes on
//! purpose, regenerate them with `UPDATE_GOLDEN=1 cargo test -p firmware-core --test
//! blob_loopback` and bump `FORMAT_VERSION`. The tables' output bits did not change from
//! format 2 to 3 to 4 to 5 (example_outputs.txt): the tables read from flash give the
//! same bits as the owned ones. The physics outputs are new in format 4 (time constants
//! in seconds, the machines on the sample's own time step), and did not change with
//! format 5 (example_outputs_physics.txt); the discovered terms' are new in format 5
//! (example_blob_terms.hex, example_outputs_terms.txt).
use firmware_core::blob::{
    example_blob, example_terms, Blob, BlobView, OutputUnit, RunId, FORMAT_VERSION, MAX_BLOB_LEN,
    OLDEST_FORMAT_VERSION,
};
use firmware_core::compensate::{Compensator, ErrorModel, Method};
use firmware_core::temperature::{Physics, TempModel};
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

fn encode(b: &Blob) -> Vec<u8> {
    let mut buf = [0u8; MAX_BLOB_LEN];
    let n = b.encode(&mut buf).unwrap();
    buf[..n].to_vec()
}

fn encoded() -> Vec<u8> {
    encode(&example_blob())
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

fn unhex(text: &str) -> Vec<u8> {
    let digits: Vec<u8> = text.bytes().filter(u8::is_ascii_hexdigit).collect();
    digits
        .chunks(2)
        .map(|p| u8::from_str_radix(std::str::from_utf8(p).unwrap(), 16).unwrap())
        .collect()
}

/// An independent bitwise CRC-32, to check the firmware's table version too.
fn crc32(data: &[u8]) -> u32 {
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

/// Recompute the trailing CRC after an edit, so the checks behind it are reached.
fn reseal(mut b: Vec<u8>) -> Vec<u8> {
    let n = b.len() - 4;
    let c = crc32(&b[..n]);
    b[n..].copy_from_slice(&c.to_le_bytes());
    b
}

fn f32_le(b: &[u8], off: usize) -> f32 {
    f32::from_le_bytes(b[off..off + 4].try_into().unwrap())
}

#[test]
fn golden_bytes_follow_the_documented_layout() {
    let b = encoded();
    golden("example_blob.hex", &hex(&b));
    // read back by hand, as the table in blob.rs documents it
    assert_eq!(b.len(), 220);
    assert_eq!(&b[0..4], b"ATCB");
    assert_eq!(u16::from_le_bytes([b[4], b[5]]), 4);
    assert_eq!(u16::from_le_bytes([b[6], b[7]]), 220);
    assert_eq!(u16::from_le_bytes([b[8], b[9]]), !220u16);
    // pwl, 3 rows, no clamp, serial 10, no physics, output unit V (code 1)
    assert_eq!(&b[10..16], &[2, 3, 0, 10, 0, 1]);
    assert_eq!(&b[16..28], b"PAPER-UNIT\0\0");
    assert_eq!(&b[28..44], &[0; 16]); // no run id
    let scalars: Vec<f32> = (0..4).map(|k| f32_le(&b, 44 + 4 * k)).collect();
    assert_eq!(scalars, [20.0, -40.0, 70.0, 0.1]);
    let bps: Vec<f32> = (0..3).map(|k| f32_le(&b, 60 + 4 * k)).collect();
    assert_eq!(bps, [-40.0, 20.0, 70.0]);
    assert_eq!(f32_le(&b, 72), -0.550_742_6); // kxx at -40 C, the paper's Table 1
    assert_eq!(f32_le(&b, 72 + 48 + 44), -0.003_470_99); // u0z at +20 C
    assert_eq!(
        u32::from_le_bytes(b[216..220].try_into().unwrap()),
        crc32(&b[..216])
    );
}

/// The physics section in format 4: every time constant in seconds, in the documented
/// word order, behind the tables; the run id and the output unit where the layout says.
#[test]
fn golden_physics_blob_follows_the_documented_layout() {
    let b = encode(&physics_blob());
    golden("example_blob_physics.hex", &hex(&b));
    assert_eq!(b.len(), 220 + 80);
    assert_eq!(b[14], 20); // physics words
    assert_eq!(b[15], 3); // m/s2
    assert_eq!(&b[28..44], &RUN_ID.0);
    let words: Vec<f32> = (0..20).map(|k| f32_le(&b, 216 + 4 * k)).collect();
    let p = physics();
    assert_eq!(words[0], p.lag_tau_s);
    assert_eq!(words[1..4], p.rate);
    assert_eq!(words[4], p.rate_tau_s);
    assert_eq!(words[19], p.warmup_tau_s);
    let v = BlobView::new(&b).unwrap();
    assert_eq!(v.run_id().to_string(), "a1a2a3a4a5a6a7a8b1b2b3b4b5b6b7b8");
    assert_eq!(v.output_unit(), OutputUnit::MetrePerSecond2);
}

/// Built without `physics`, the physics blob is refused, never compensated without its
/// terms.
#[cfg(not(feature = "physics"))]
#[test]
fn without_the_feature_the_physics_blob_is_refused() {
    let bytes = unhex(&std::fs::read_to_string(data("example_blob_physics.hex")).unwrap());
    let view = BlobView::new(&bytes).unwrap();
    assert_eq!(
        Compensator::from_blob(view, Method::CorrectConstants, 0.01).err(),
        Some(Error::PhysicsNotBuiltIn)
    );
}

const RUN_ID: RunId = RunId([
    0xa1, 0xa2, 0xa3, 0xa4, 0xa5, 0xa6, 0xa7, 0xa8, 0xb1, 0xb2, 0xb3, 0xb4, 0xb5, 0xb6, 0xb7, 0xb8,
]);

fn physics_blob() -> Blob {
    let mut p = example_blob();
    p.calibration.physics = Some(physics());
    p.output_unit = OutputUnit::MetrePerSecond2;
    p.run_id = RUN_ID;
    p
}

/// The physics path on an uneven clock, as bits: the blob's compensator, sample by
/// sample with each sample's own time step (a cold start, a warming at 6 C/min logged at
/// 0.2-10 s spacings, a 1 ms burst, a power cycle of the sensor), equal to the committed
/// ones, and the same from flash and owned.
#[cfg(feature = "physics")]
#[test]
fn golden_physics_outputs_on_an_uneven_clock() {
    let bytes = unhex(&std::fs::read_to_string(data("example_blob_physics.hex")).unwrap());
    let view = BlobView::new(&bytes).unwrap();
    let owned = Blob::decode(&bytes).unwrap();
    let mut out = String::from(
        "# method dt_bits temp_bits ux uy uz -> ax ay az status (f32 bits); P = the sensor powered on 2 s before the next sample\n",
    );
    let u = [0.0045f32, -0.0044, -0.5521];
    for (name, m) in METHODS {
        let mut flash = Compensator::from_blob(view, m, 0.01).unwrap();
        let mut host = Compensator::new(&owned.calibration, m, 0.01).unwrap();
        let mut t = 0.0f32;
        for (i, dt) in [
            0.0f32, 0.2, 1.0, 1.0, 10.0, 10.0, 0.001, 0.001, 0.05, 0.05, 3.0,
        ]
        .into_iter()
        .cycle()
        .take(40)
        .enumerate()
        {
            if i == 30 {
                flash.power_on(2.0);
                host.power_on(2.0);
                out.push_str("P\n");
            }
            t += dt;
            let temp = -30.0 + 0.1 * t.min(600.0);
            let o = flash.compensate_dt(u, temp, dt);
            let h = host.compensate_dt(u, temp, dt);
            assert_eq!(o.accel.map(f32::to_bits), h.accel.map(f32::to_bits));
            assert_eq!(o.status, h.status);
            out.push_str(&format!(
                "{name} {:08x} {:08x} {:08x} {:08x} {:08x} -> {:08x} {:08x} {:08x} {}\n",
                dt.to_bits(),
                temp.to_bits(),
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
    golden("example_outputs_physics.txt", &out);
}

/// Inputs for the golden compensation table: (u, temp).
fn golden_inputs() -> Vec<([f32; 3], f32)> {
    let us = [
        [0.0045, -0.0044, -0.5521],
        [-0.5461, -0.0177, 0.0112],
        [0.2370, -0.4940, -0.2340],
        [0.0, 0.0, 0.0],
    ];
    [-45.0f32, -40.0, -10.0, 19.95, 20.0, 33.3, 45.0, 70.0, 85.0]
        .into_iter()
        .enumerate()
        .map(|(i, t)| (us[i % us.len()], t))
        .collect()
}

const METHODS: [(&str, Method); 3] = [
    ("m1", Method::CorrectConstants),
    ("m2full", Method::CorrectResult(ErrorModel::Full)),
    ("m2simp", Method::CorrectResult(ErrorModel::Simplified)),
];

/// The compensator reading the tables from the blob's bytes in place, and the host's
/// owned f32 calibration: the same bits, equal to the committed ones.
#[test]
fn golden_outputs_as_bits_from_flash_and_owned() {
    let bytes = std::fs::read_to_string(data("example_blob.hex")).unwrap();
    let bytes = unhex(&bytes);
    let view = BlobView::new(&bytes).unwrap();
    let owned = Blob::decode(&bytes).unwrap();
    assert_eq!(owned, example_blob());
    let mut out = String::from("# method temp_bits ux uy uz -> ax ay az status (f32 bits)\n");
    for (name, m) in METHODS {
        let mut flash = Compensator::from_blob(view, m, 1.0).unwrap();
        let mut host = Compensator::new(&owned.calibration, m, 1.0).unwrap();
        for (u, t) in golden_inputs() {
            let o = flash.compensate(u, t);
            let h = host.compensate(u, t);
            assert_eq!(o.accel.map(f32::to_bits), h.accel.map(f32::to_bits));
            assert_eq!(o.status, h.status);
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
fn every_single_bit_flip_reads_as_corruption() {
    let good = encoded();
    for i in 0..good.len() {
        for bit in 0..8 {
            let mut b = good.clone();
            b[i] ^= 1 << bit;
            // the version byte and the length field included
            assert_eq!(
                BlobView::new(&b).err(),
                Some(Error::CrcMismatch),
                "byte {i} bit {bit}"
            );
        }
    }
}

#[test]
fn every_truncation_reads_as_truncation() {
    let good = encoded();
    for n in 0..good.len() {
        assert_eq!(
            BlobView::new(&good[..n]).err(),
            Some(Error::Truncated),
            "truncated to {n}"
        );
    }
    let mut longer = good.clone();
    longer.push(0);
    assert_eq!(BlobView::new(&longer).err(), Some(Error::TrailingBytes));
    // in a flash sector the header's length decides where the blob ends
    let mut sector = good.clone();
    sector.resize(1024, 0xFF);
    assert_eq!(BlobView::from_region(&sector).unwrap().bytes(), &good[..]);
    assert_eq!(
        BlobView::from_region(&good[..100]).err(),
        Some(Error::Truncated)
    );
}

/// A blob of format 3 (the committed bytes of the paper unit as format 3 wrote them:
/// the same header, per-sample constants, no run id) and one of format 2 (postcard
/// content, CRC last, no length field), each with its own valid CRC, are recognised as
/// old blobs, not as corruption; any flipped bit in them is corruption.
#[test]
fn an_old_blob_names_its_version() {
    let v3 = unhex(&std::fs::read_to_string(data("example_blob_v3.hex")).unwrap());
    assert_eq!(&v3[..6], b"ATCB\x03\x00");
    assert_eq!(BlobView::new(&v3).err(), Some(Error::UnsupportedVersion(3)));
    assert_eq!(
        Error::UnsupportedVersion(3).to_string(),
        "unsupported blob format version 3 (this firmware reads versions 4 to 5)"
    );
    let v2 = unhex(&std::fs::read_to_string(data("example_blob_v2.hex")).unwrap());
    assert_eq!(&v2[..6], b"ATCB\x02\x00");
    assert_eq!(BlobView::new(&v2).err(), Some(Error::UnsupportedVersion(2)));
    for old in [v2, v3] {
        let mut flipped = old.clone();
        flipped[4] ^= 1;
        assert_eq!(BlobView::new(&flipped).err(), Some(Error::CrcMismatch));
    }
    // a newer version with a valid CRC and length
    let mut v6 = encoded();
    v6[4] = 6;
    assert_eq!(
        BlobView::new(&reseal(v6)).err(),
        Some(Error::UnsupportedVersion(6))
    );
    let mut magic = encoded();
    magic[0] = b'X';
    assert_eq!(BlobView::new(&reseal(magic)).err(), Some(Error::BadMagic));
}

#[test]
fn content_checks_behind_a_valid_crc() {
    let good = encoded();
    let edit = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut b = good.clone();
        f(&mut b);
        BlobView::new(&reseal(b)).err()
    };
    let put =
        |b: &mut Vec<u8>, off: usize, v: f32| b[off..off + 4].copy_from_slice(&v.to_le_bytes());
    assert_eq!(edit(&|_| {}), None, "the independent CRC agrees");
    assert_eq!(
        edit(&|b| put(b, 60, 30.0)),
        Some(Error::BreakpointsNotIncreasing)
    );
    assert_eq!(edit(&|b| put(b, 64, f32::NAN)), Some(Error::NonFinite));
    assert_eq!(edit(&|b| put(b, 44, f32::NAN)), Some(Error::NonFinite)); // T0
    assert_eq!(edit(&|b| put(b, 76, f32::INFINITY)), Some(Error::NonFinite)); // a table value
    assert_eq!(edit(&|b| put(b, 48, 80.0)), Some(Error::BadRange)); // t_min > t_max
    assert_eq!(edit(&|b| put(b, 56, -1.0)), Some(Error::BadRange)); // negative step
    assert_eq!(edit(&|b| b[10] = 3), Some(Error::Malformed)); // unknown model
    assert_eq!(edit(&|b| b[11] = 1), Some(Error::TableSize));
    assert_eq!(edit(&|b| b[11] = 17), Some(Error::TableSize));
    assert_eq!(edit(&|b| b[11] = 4), Some(Error::Malformed)); // rows disagree with the length
    assert_eq!(edit(&|b| b[12] = 2), Some(Error::Malformed)); // unknown flag
    assert_eq!(edit(&|b| b[15] = 8), Some(Error::Malformed)); // unknown output unit
    assert_eq!(edit(&|b| b[15] = 7), None); // "other": a valid unit
    assert_eq!(edit(&|b| b[30] = 0xFF), None); // any run id
    assert_eq!(edit(&|b| b[14] = 5), Some(Error::Malformed)); // physics words
    assert_eq!(edit(&|b| b[13] = 65), Some(Error::Malformed)); // serial too long
    assert_eq!(edit(&|b| b[27] = 1), Some(Error::Malformed)); // padding
    assert_eq!(edit(&|b| b[16] = 0xFF), Some(Error::Malformed)); // serial not printable ASCII
                                                                 // K(T0) singular: the +20 C row's K made all zero
    assert_eq!(
        edit(&|b| (0..9).for_each(|i| put(b, 72 + 48 + 4 * i, 0.0))),
        Some(Error::Singular)
    );
    // a physics term out of range, behind a valid CRC
    let mut p = example_blob();
    p.calibration.physics = Some(physics());
    let bytes = encode(&p);
    assert!(BlobView::new(&bytes).is_ok());
    let section = bytes.len() - 4 - 80;
    for (word, value) in [(0, -1.0), (19, -1.0), (9, 0.5)] {
        // lag and warm-up time constants negative; an initial direction that is none of
        // -1, 0, +1
        let mut b = bytes.clone();
        put(&mut b, section + 4 * word, value);
        assert_eq!(
            BlobView::new(&reseal(b)).err(),
            Some(Error::BadRange),
            "word {word}"
        );
    }
    // a physics word set to `value` behind a valid CRC, read back through the view
    let read_with = |word: usize, value: f32| {
        let mut b = bytes.clone();
        put(&mut b, section + 4 * word, value);
        let b = reseal(b);
        let view = BlobView::new(&b).unwrap_or_else(|e| panic!("word {word} = {value}: {e}"));
        view.to_blob()
            .calibration
            .physics
            .expect("the physics section")
    };
    // the rate's time constant negative is the zero-lag estimator, read as such
    let read = read_with(4, -5.0);
    assert!(read.rate_zero_lag());
    assert_eq!(read.rate_tau_s, -5.0);
    // the hysteresis threshold negative is a play operator of that half-width, read as such
    assert_eq!(read_with(8, -4.0).hysteresis_threshold_c, -4.0);
}

fn physics() -> Physics<f32> {
    Physics {
        lag_tau_s: 120.0,
        rate: [0.02, 0.01, -0.01],
        rate_tau_s: 8.0,
        hysteresis: [1e-4, 2e-4, 3e-4],
        hysteresis_threshold_c: 0.5,
        hysteresis_initial: -1.0,
        k2: [1e-4, 2e-4, 3e-4],
        asymmetry: [1e-4, 2e-4, 3e-4],
        warmup: [2e-4, 1e-4, 3e-4],
        warmup_tau_s: 900.0,
    }
}

/// Encoding is canonical: a decoded blob encodes to the very same bytes, with and
/// without physics terms, polynomial or piecewise-linear.
#[test]
fn decode_then_encode_gives_the_same_bytes() {
    let mut blobs = vec![example_blob()];
    let mut p = example_blob();
    p.calibration.physics = Some(physics());
    p.calibration.clamp = true;
    blobs.push(p);
    let mut poly = example_blob();
    let t0 = poly.calibration.at_t0();
    poly.calibration.model = TempModel::Poly {
        terms: [t0, [1e-5; 12], [1e-7; 12], [1e-9; 12]]
            .into_iter()
            .collect(),
    };
    poly.serial.clear();
    if cfg!(feature = "terms") {
        poly.terms = example_terms().into_iter().take(3).collect();
        blobs.push(terms_blob());
    }
    blobs.push(poly);
    for b in blobs {
        let bytes = encode(&b);
        let d = Blob::decode(&bytes).unwrap();
        assert_eq!(d, b);
        assert_eq!(encode(&d), bytes);
        assert_eq!(BlobView::new(&bytes).unwrap().to_blob(), b);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]
    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..1200)) {
        let _ = BlobView::new(&bytes);
        let _ = Blob::decode(&bytes);
    }

    /// Random content behind a valid header, length and CRC: refused or valid, never
    /// a panic.
    #[test]
    fn random_content_behind_a_valid_crc(head in prop::collection::vec(any::<u8>(), 6..7),
                                         body in prop::collection::vec(any::<u8>(), 0..400)) {
        let mut b = b"ATCB".to_vec();
        // the version that goes with the flags' term-table bit
        let v = if head[2] & 2 != 0 { FORMAT_VERSION } else { OLDEST_FORMAT_VERSION };
        b.extend_from_slice(&v.to_le_bytes());
        let n = (16 + body.len() + 4) as u16;
        b.extend_from_slice(&n.to_le_bytes());
        b.extend_from_slice(&(!n).to_le_bytes());
        b.extend_from_slice(&head);
        b.extend_from_slice(&body);
        b.extend_from_slice(&[0; 4]);
        let b = reseal(b);
        if let Ok(v) = BlobView::new(&b) {
            prop_assert!(v.to_blob().validate().is_ok());
        }
    }
}

/// The largest blob the format allows (64-character serial, 16 breakpoints, physics
/// terms, 8 discovered terms)
/// encodes to exactly `MAX_BLOB_LEN` (also a compile-time assertion in blob.rs).
#[test]
fn the_largest_blob_fits_the_fixed_buffer() {
    let mut b = example_blob();
    b.serial.clear();
    b.serial
        .push_str(&"W".repeat(firmware_core::blob::MAX_SERIAL_LEN))
        .unwrap();
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
    b.calibration.physics = Some(physics());
    b.terms = example_terms();
    let mut big = vec![0u8; 4 * MAX_BLOB_LEN];
    let n = b.encode(&mut big).unwrap();
    assert_eq!(n, 1028 + 4 + 8 * 12);
    assert_eq!(n, MAX_BLOB_LEN);
    if cfg!(feature = "terms") {
        assert_eq!(Blob::decode(&big[..n]), Ok(b));
    } else {
        assert_eq!(Blob::decode(&big[..n]), Err(Error::TermsNotBuiltIn));
    }
}

/// The golden blob of format 5: the paper unit with physics terms and a full table of
/// discovered terms of every kind of factor ([`example_terms`]).
fn terms_blob() -> Blob {
    let mut b = physics_blob();
    b.terms = example_terms();
    b
}

/// Format 5: the version, the flag, the table's head and its entries where the layout
/// says, read back by hand; the tables and the physics section as in format 4.
#[cfg(feature = "terms")]
#[test]
fn golden_terms_blob_follows_the_documented_layout() {
    let b = encode(&terms_blob());
    golden("example_blob_terms.hex", &hex(&b));
    let with_physics = encode(&physics_blob());
    assert_eq!(b.len(), with_physics.len() + 4 + 8 * 12);
    assert_eq!(u16::from_le_bytes([b[4], b[5]]), 5);
    assert_eq!(b[12], 2, "flags: no clamp, a term table");
    // everything up to the physics section's end is format 4's, but the flag
    let head = with_physics.len() - 4;
    assert_eq!(b[10..12], with_physics[10..12]);
    assert_eq!(b[13..head], with_physics[13..head]);
    assert_eq!(&b[head..head + 4], &[8, 0, 0, 0]);
    let terms = example_terms();
    for (j, e) in terms.iter().enumerate() {
        let at = head + 4 + 12 * j;
        assert_eq!(b[at], e.axis as u8, "entry {j}");
        assert_eq!(b[at + 1..at + 4], e.term.codes());
        assert_eq!(f32_le(&b, at + 4), e.term.tau_s());
        assert_eq!(f32_le(&b, at + 8), e.coefficient);
    }
    // entry 0: a_x*a_y on z; entry 5: dT*decay(power_on,20min) on z
    assert_eq!(&b[head + 4..head + 8], &[2, 1, 3, 0]);
    assert_eq!(&b[head + 4 + 60..head + 4 + 64], &[2, 7, 9, 0]);
    assert_eq!(f32_le(&b, head + 4 + 64), 1200.0);
    let v = BlobView::new(&b).unwrap();
    assert_eq!(v.version(), 5);
    assert_eq!(v.to_blob().terms, terms);
    assert_eq!(
        terms.iter().map(|e| e.term.to_string()).collect::<Vec<_>>(),
        [
            "a_x*a_y",
            "a_x^3",
            "a_z^2*dT",
            "abs(a_y)",
            "a_y*dTdt",
            "dT*decay(power_on,20min)",
            "decay(power_on,25s)",
            "a_x*abs(a_x)*a_z",
        ]
    );
    // a blob without terms is still format 4, byte for byte
    assert_eq!(BlobView::new(&with_physics).unwrap().version(), 4);
    assert_eq!(
        std::fs::read_to_string(data("example_blob_physics.hex")).unwrap(),
        hex(&with_physics)
    );
}

/// Built without `terms`, the blob with discovered terms is refused when it is opened,
/// never compensated without them (its table not even validated: flash); the committed
/// bytes are still the encoder's.
#[cfg(not(feature = "terms"))]
#[test]
fn without_the_feature_the_terms_blob_is_refused() {
    let bytes = unhex(&std::fs::read_to_string(data("example_blob_terms.hex")).unwrap());
    assert_eq!(bytes, encode(&terms_blob()));
    assert_eq!(BlobView::new(&bytes).err(), Some(Error::TermsNotBuiltIn));
    assert_eq!(Blob::decode(&bytes).err(), Some(Error::TermsNotBuiltIn));
}

/// The discovered terms on an uneven clock, as bits: the golden blob's compensator in
/// place and the owned one (calibration and terms), sample by sample with each sample's
/// own time step, over a tilt sweep (the force factors move) while the temperature warms
/// (dT and dTdt move) from power-on (the decays), with a power cycle of the sensor.
#[cfg(feature = "terms")]
#[test]
fn golden_terms_outputs_on_an_uneven_clock() {
    let bytes = unhex(&std::fs::read_to_string(data("example_blob_terms.hex")).unwrap());
    let view = BlobView::new(&bytes).unwrap();
    let owned = Blob::decode(&bytes).unwrap();
    let mut out = String::from(
        "# method dt_bits temp_bits ux uy uz -> ax ay az status (f32 bits); P = the sensor powered on 2 s before the next sample\n",
    );
    for (name, m) in METHODS {
        let mut flash = Compensator::from_blob(view, m, 0.01).unwrap();
        let mut host = Compensator::with_terms(&owned.calibration, &owned.terms, m, 0.01).unwrap();
        let mut t = 0.0f32;
        for (i, dt) in [
            0.0f32, 0.2, 1.0, 1.0, 10.0, 10.0, 0.001, 0.001, 0.05, 0.05, 3.0,
        ]
        .into_iter()
        .cycle()
        .take(40)
        .enumerate()
        {
            if i == 30 {
                flash.power_on(2.0);
                host.power_on(2.0);
                out.push_str("P\n");
            }
            t += dt;
            let temp = -30.0 + 0.1 * t.min(600.0);
            // the paper unit's outputs tilted about y by i * 9 degrees (rough volts)
            let ang = i as f32 * 0.157;
            let u = [0.55 * ang.sin(), -0.0044, -0.55 * ang.cos()];
            let o = flash.compensate_dt(u, temp, dt);
            let h = host.compensate_dt(u, temp, dt);
            assert_eq!(o.accel.map(f32::to_bits), h.accel.map(f32::to_bits));
            assert_eq!(o.status, h.status);
            out.push_str(&format!(
                "{name} {:08x} {:08x} {:08x} {:08x} {:08x} -> {:08x} {:08x} {:08x} {}\n",
                dt.to_bits(),
                temp.to_bits(),
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
    golden("example_outputs_terms.txt", &out);
}

/// Every check of the term table behind a valid CRC: each failure its own error.
#[cfg(feature = "terms")]
#[test]
fn term_table_checks_behind_a_valid_crc() {
    let good = encode(&terms_blob());
    let head = good.len() - 4 - 4 - 8 * 12;
    let entry = |j: usize| head + 4 + 12 * j;
    let edit = |f: &dyn Fn(&mut Vec<u8>)| {
        let mut b = good.clone();
        f(&mut b);
        BlobView::new(&reseal(b)).err()
    };
    let put =
        |b: &mut Vec<u8>, off: usize, v: f32| b[off..off + 4].copy_from_slice(&v.to_le_bytes());
    assert_eq!(edit(&|_| {}), None);
    assert_eq!(edit(&|b| b[head] = 0), Some(Error::Malformed)); // no entry declared
    assert_eq!(edit(&|b| b[head] = 9), Some(Error::TooManyTerms));
    assert_eq!(edit(&|b| b[head] = 7), Some(Error::Malformed)); // disagrees with the length
    assert_eq!(edit(&|b| b[head + 2] = 1), Some(Error::Malformed)); // reserved
    assert_eq!(edit(&|b| b[entry(0)] = 3), Some(Error::TermAxis));
    assert_eq!(edit(&|b| b[entry(0) + 1] = 10), Some(Error::TermFactors)); // unknown
    assert_eq!(edit(&|b| b[entry(0) + 1] = 4), Some(Error::TermFactors)); // out of order
    assert_eq!(edit(&|b| b[entry(0) + 2] = 0), None); // a_x alone: a valid term
    assert_eq!(edit(&|b| b[entry(0) + 1] = 0), Some(Error::TermFactors)); // a gap
    assert_eq!(
        edit(&|b| b[entry(3)..entry(3) + 4].copy_from_slice(&[0, 4, 4, 0])),
        Some(Error::TermFactors) // abs(a_y)^2: not canonical
    );
    assert_eq!(
        edit(&|b| put(b, entry(6) + 4, -25.0)),
        Some(Error::TermTimeConstant)
    );
    assert_eq!(
        edit(&|b| put(b, entry(6) + 4, 0.0)),
        Some(Error::TermTimeConstant)
    );
    assert_eq!(
        edit(&|b| put(b, entry(6) + 4, f32::NAN)),
        Some(Error::TermTimeConstant)
    );
    assert_eq!(
        edit(&|b| put(b, entry(0) + 4, 5.0)),
        Some(Error::TermTimeConstant)
    ); // no decay
    assert_eq!(
        edit(&|b| put(b, entry(0) + 8, f32::INFINITY)),
        Some(Error::NonFinite)
    );
    // entry 3 made a copy of entry 0 (a_x*a_y on z)
    assert_eq!(
        edit(&|b| b.copy_within(entry(0)..entry(0) + 12, entry(3))),
        Some(Error::DuplicateTerm)
    );
    // the same term on another axis is another entry
    assert_eq!(
        edit(&|b| {
            b.copy_within(entry(0)..entry(0) + 12, entry(3));
            b[entry(3)] = 0;
        }),
        None
    );
    // version and flag disagree: format 5 without the flag, format 4 with it
    assert_eq!(edit(&|b| b[12] = 0), Some(Error::Malformed));
    assert_eq!(edit(&|b| b[4] = 4), Some(Error::Malformed));
    let plain = encoded();
    let mut v5 = plain.clone();
    v5[4] = 5;
    assert_eq!(BlobView::new(&reseal(v5)).err(), Some(Error::Malformed));
    // every flipped bit of the terms blob is corruption too
    for i in 0..good.len() {
        let mut b = good.clone();
        b[i] ^= 1 << (i % 8);
        assert_eq!(
            BlobView::new(&b).err(),
            Some(Error::CrcMismatch),
            "byte {i}"
        );
    }
    // the owned form refuses what it cannot encode
    let mut dup = terms_blob();
    let first = dup.terms[0];
    dup.terms[3] = first;
    let mut buf = [0u8; MAX_BLOB_LEN];
    assert_eq!(dup.encode(&mut buf), Err(Error::DuplicateTerm));
}
