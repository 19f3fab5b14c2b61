//! Any text as a positions file: an error or positions, never a panic
//! (`host_fit::fuzzing::positions` holds the properties; the tests replay this corpus).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| host_fit::fuzzing::positions(data));
