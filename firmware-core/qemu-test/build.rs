//! Puts memory.x where the linker finds it; the blobs and the input table come from
//! `cargo xtask embedded` through FW_TEST_BLOB, FW_TEST_BLOB_PHYS, FW_TEST_BLOB_TERMS and
//! FW_TEST_INPUTS.
//! The two synthetic blobs of the update-cost measurement (a cubic and a 5-breakpoint
//! table built on the fitted unit's K(T0)) are encoded here, on the host, by the same
//! firmware-core code, so the firmware links no encoder.
use firmware_core::blob::{Blob, MAX_BLOB_LEN};
use firmware_core::temperature::TempModel;
use std::path::PathBuf;

fn main() {
    let out = PathBuf::from(std::env::var_os("OUT_DIR").unwrap());
    std::fs::write(out.join("memory.x"), include_bytes!("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed=memory.x");
    for v in ["FW_TEST_BLOB", "FW_TEST_BLOB_PHYS", "FW_TEST_BLOB_TERMS", "FW_TEST_INPUTS"] {
        println!("cargo:rerun-if-env-changed={v}");
        if let Some(p) = std::env::var_os(v) {
            println!("cargo:rerun-if-changed={}", PathBuf::from(p).display());
        }
    }
    let base = std::fs::read(std::env::var_os("FW_TEST_BLOB").expect("FW_TEST_BLOB")).unwrap();
    let base = Blob::decode(&base).expect("FW_TEST_BLOB decodes");
    let t0 = base.calibration.at_t0();
    for (name, poly) in [("update_poly3.blob", true), ("update_pwl5.blob", false)] {
        let mut b = base.clone();
        b.calibration.update_step_c = 0.0;
        b.calibration.physics = None;
        b.terms.clear();
        b.calibration.model = if poly {
            TempModel::Poly { terms: [t0, [1e-5; 12], [1e-7; 12], [1e-9; 12]].into_iter().collect() }
        } else {
            let bp = [-40.0f32, -10.0, 20.0, 45.0, 70.0];
            TempModel::Pwl {
                breakpoints: bp.into_iter().collect(),
                values: bp.iter().map(|t| t0.map(|v| v * (1.0 + 1e-5 * t))).collect(),
            }
        };
        let mut buf = [0u8; MAX_BLOB_LEN];
        let n = b.encode(&mut buf).expect("synthetic blob encodes");
        std::fs::write(out.join(name), &buf[..n]).unwrap();
    }
}
