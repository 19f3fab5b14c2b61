//! firmware-core on the target: validate the embedded blobs in place, compensate the
//! embedded input table with every method reading the tables from those bytes, print
//! each result's f32 bits (compared bit for bit with the host by `cargo xtask
//! embedded`), then count instructions and measure the stack. Built three times: with
//! the `physics` and `terms` features (the physics blob and the blob with discovered terms
//! compensated too), with `physics` only (the terms blob must be refused) and with neither
//! (both must be refused).
#![no_std]
#![no_main]

use core::hint::black_box;
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use firmware_core::blob::BlobView;
use firmware_core::compensate::{Compensator, ErrorModel, FlashCompensator, Method};
use panic_semihosting as _;

static BLOB: &[u8] = include_bytes!(env!("FW_TEST_BLOB"));
/// A blob from `host-fit diagnose --out`: tables plus in-flight physics terms.
static BLOB_PHYS: &[u8] = include_bytes!(env!("FW_TEST_BLOB_PHYS"));
/// The golden blob with physics terms and 8 discovered terms.
static BLOB_TERMS: &[u8] = include_bytes!(env!("FW_TEST_BLOB_TERMS"));
static INPUTS: &[u8] = include_bytes!(env!("FW_TEST_INPUTS"));
/// Synthetic tables for the update cost (build.rs): a cubic and 5 breakpoints.
static BLOB_POLY3: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/update_poly3.blob"));
static BLOB_PWL5: &[u8] = include_bytes!(concat!(env!("OUT_DIR"), "/update_pwl5.blob"));

const METHODS: [(&str, Method); 3] = [
    ("m1", Method::CorrectConstants),
    ("m2full", Method::CorrectResult(ErrorModel::Full)),
    ("m2simp", Method::CorrectResult(ErrorModel::Simplified)),
];

/// Bytes of one input record: ux uy uz temp dt (f32 LE; dt the sample's own time step).
const RECORD: usize = 20;
/// The sample period the compensators are made with (a 100 Hz MCU), s.
const PERIOD: f32 = 0.01;

fn input(i: usize) -> ([f32; 3], f32, f32) {
    let f = |k: usize| {
        let o = i * RECORD + k * 4;
        f32::from_le_bytes([INPUTS[o], INPUTS[o + 1], INPUTS[o + 2], INPUTS[o + 3]])
    };
    ([f(0), f(1), f(2)], f(3), f(4))
}

/// A compensator, or a failed run. Not `unwrap`: its `Debug` formatting of the error
/// would be linked in and counted against the library's flash.
fn new(blob: BlobView<'static>, m: Method) -> FlashCompensator<'static> {
    match Compensator::from_blob(blob, m, PERIOD) {
        Ok(c) => c,
        Err(_) => {
            hprintln!("error: Compensator::new refused a test calibration");
            debug::exit(debug::EXIT_FAILURE);
            loop {}
        }
    }
}

/// A call of `compensate`'s shape that does nothing: the harness's share of a window.
#[inline(never)]
fn noop(c: &mut FlashCompensator<'_>, u: [f32; 3], t: f32) -> firmware_core::compensate::Output<f32> {
    black_box(c);
    firmware_core::compensate::Output { accel: [u[0], u[1], t], status: Default::default() }
}

/// Start of a counted window (distinct bodies, so the linker cannot merge them).
#[inline(never)]
#[no_mangle]
pub extern "C" fn fw_mark_start() {
    cortex_m::asm::nop();
}

/// End of a counted window.
#[inline(never)]
#[no_mangle]
pub extern "C" fn fw_mark_stop() {
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}

// Stack painting: the harness may use unsafe; firmware-core itself forbids it.
const PAINT: u32 = 0xA5A5_5A5A;
const PAINT_WORDS: usize = 2048;

#[inline(never)]
fn paint() {
    let sp = cortex_m::register::msp::read() as usize;
    let base = (sp - 64 - PAINT_WORDS * 4) & !3;
    for w in 0..PAINT_WORDS {
        unsafe { core::ptr::write_volatile((base + w * 4) as *mut u32, PAINT) };
    }
}

#[inline(never)]
fn used(sp_at_call: usize) -> usize {
    let base = (sp_at_call - 64 - PAINT_WORDS * 4) & !3;
    for w in 0..PAINT_WORDS {
        if unsafe { core::ptr::read_volatile((base + w * 4) as *const u32) } != PAINT {
            return sp_at_call - (base + w * 4);
        }
    }
    0
}

#[inline(never)]
fn decode_once(bytes: &'static [u8]) -> Option<BlobView<'static>> {
    // the one call of BlobView::new, so its code is inlined here as in a firmware
    BlobView::new(black_box(bytes)).ok()
}

fn view(bytes: &'static [u8], what: &str) -> BlobView<'static> {
    match decode_once(bytes) {
        Some(b) => b,
        None => {
            hprintln!("error: the embedded {} blob does not validate", what);
            debug::exit(debug::EXIT_FAILURE);
            loop {}
        }
    }
}

#[entry]
fn main() -> ! {
    let n_inputs = INPUTS.len() / RECORD;

    let sp = cortex_m::register::msp::read() as usize;
    paint();
    let blob = view(BLOB, "PWL");
    let stack_decode = used(sp);

    let phys = view(BLOB_PHYS, "physics");
    #[cfg(feature = "terms")]
    let terms = view(BLOB_TERMS, "terms");
    #[cfg(feature = "terms")]
    let sets = [("", blob), ("p", phys), ("t", terms)];
    #[cfg(not(feature = "terms"))]
    {
        // built without the terms: the terms blob (format 5) must be refused when opened,
        // never half-applied (the refusal's kind, TermsNotBuiltIn, is held by
        // firmware-core's tests without the feature: here one call of BlobView::new keeps
        // it inlined as in a firmware, so the flash compares with the builds before)
        match decode_once(BLOB_TERMS) {
            None if BLOB_TERMS.get(4) == Some(&5) => hprintln!("terms refused"),
            _ => {
                hprintln!("error: a blob with discovered terms was accepted without the terms feature");
                debug::exit(debug::EXIT_FAILURE);
            }
        }
    }
    #[cfg(all(feature = "physics", not(feature = "terms")))]
    let sets = [("", blob), ("p", phys)];
    #[cfg(not(feature = "physics"))]
    let sets = {
        // built without the physics terms: the physics blob must be refused too
        match Compensator::from_blob(phys, Method::CorrectConstants, PERIOD) {
            Err(firmware_core::Error::PhysicsNotBuiltIn) => hprintln!("physics refused"),
            _ => {
                hprintln!("error: a physics blob was accepted without the physics feature");
                debug::exit(debug::EXIT_FAILURE);
            }
        }
        [("", blob)]
    };
    for (prefix, b) in sets {
        for (tag, m) in METHODS {
            let mut c = new(b, m);
            for i in 0..n_inputs {
                let (u, t, dt) = input(i);
                let o = c.compensate_dt(u, t, dt);
                hprintln!("vec {}{} {} {:08x} {:08x} {:08x} {}", prefix, tag, i, o.accel[0].to_bits(), o.accel[1].to_bits(), o.accel[2].to_bits(), o.status.bits());
            }
        }
    }

    // Stack of compensate, including a temperature update.
    let mut c = new(blob, Method::CorrectResult(ErrorModel::Full));
    let sp = cortex_m::register::msp::read() as usize;
    paint();
    let (u, _, _) = input(0);
    black_box(c.compensate(black_box(u), black_box(-20.0)));
    black_box(c.compensate(black_box(u), black_box(60.0)));
    let stack_compensate = used(sp);

    // Instruction counts: the icount plugin counts from the first instruction of
    // `fw_mark_start` to that of `fw_mark_stop`; windows come in the order printed.
    let (u, t, _) = input(1);
    hprintln!("measure empty");
    fw_mark_start();
    fw_mark_stop();
    // the same call with the same arguments and result, doing nothing
    let mut dummy = new(blob, Method::CorrectConstants);
    hprintln!("measure call_overhead");
    fw_mark_start();
    black_box(noop(&mut dummy, black_box([u[0] + 1e-6, u[1], u[2]]), black_box(t)));
    fw_mark_stop();
    for (tag, m) in METHODS {
        let mut c = new(blob, m);
        c.compensate(u, t);
        let du = [u[0] + 1e-6, u[1], u[2]];
        hprintln!("measure sample_{}", tag);
        fw_mark_start();
        black_box(c.compensate(black_box(du), black_box(t)));
        fw_mark_stop();
    }
    #[cfg(feature = "physics")]
    for (tag, m) in METHODS {
        // a sample between the machines' steps (at 100 Hz, nine in ten)
        let mut c = new(phys, m);
        c.compensate(u, t);
        let du = [u[0] + 1e-6, u[1], u[2]];
        hprintln!("measure sample_p{}", tag);
        fw_mark_start();
        black_box(c.compensate(black_box(du), black_box(t)));
        fw_mark_stop();
    }
    #[cfg(feature = "physics")]
    {
        // a sample at which the machines step (every 0.1 s), the temperature unchanged:
        // no recomputation of the cached matrices
        let mut c = new(phys, Method::CorrectConstants);
        c.compensate(u, t);
        let du = [u[0] + 1e-6, u[1], u[2]];
        hprintln!("measure step_pm1");
        fw_mark_start();
        black_box(c.compensate_dt(black_box(du), black_box(t), black_box(0.2)));
        fw_mark_stop();
        // ... and one at which they step to a temperature 5 C away: the cached matrices
        // recomputed too (the physics path's temperature update)
        let mut c = new(phys, Method::CorrectConstants);
        c.compensate(u, t);
        hprintln!("measure update_pm1");
        fw_mark_start();
        black_box(c.compensate_dt(black_box(du), black_box(t + 5.0), black_box(0.2)));
        fw_mark_stop();
    }
    #[cfg(feature = "terms")]
    for (tag, m) in METHODS {
        // the physics terms and a full table of 8 discovered terms, between the steps
        let mut c = new(terms, m);
        c.compensate(u, t);
        let du = [u[0] + 1e-6, u[1], u[2]];
        hprintln!("measure sample_t{}", tag);
        fw_mark_start();
        black_box(c.compensate(black_box(du), black_box(t)));
        fw_mark_stop();
    }
    #[cfg(feature = "terms")]
    {
        // a step of the machines with the 8 terms' state parts renewed, the temperature
        // unchanged (the cached matrices kept)
        let mut c = new(terms, Method::CorrectConstants);
        c.compensate(u, t);
        let du = [u[0] + 1e-6, u[1], u[2]];
        hprintln!("measure step_tm1");
        fw_mark_start();
        black_box(c.compensate_dt(black_box(du), black_box(t), black_box(0.2)));
        fw_mark_stop();
    }
    for (tag, bytes) in [("update_poly3", BLOB_POLY3), ("update_pwl5", BLOB_PWL5)] {
        let mut c = new(view(bytes, tag), Method::CorrectConstants);
        c.compensate(u, -12.5);
        hprintln!("measure {}", tag);
        fw_mark_start();
        black_box(c.compensate(black_box(u), black_box(33.0)));
        fw_mark_stop();
    }
    hprintln!("measure decode");
    fw_mark_start();
    black_box(decode_once(BLOB));
    fw_mark_stop();
    hprintln!("stack decode {}", stack_decode);
    hprintln!("stack compensate {}", stack_compensate);
    hprintln!("size compensator {}", core::mem::size_of::<FlashCompensator<'static>>());
    hprintln!("size blob {}", core::mem::size_of::<BlobView<'static>>());
    hprintln!("done");
    debug::exit(debug::EXIT_SUCCESS);
    loop {}
}
