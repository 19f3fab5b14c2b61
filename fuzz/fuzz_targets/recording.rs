//! Any bytes as a recording: an error or a recording, never a panic
//! (`host_fit::fuzzing::recording` holds the properties; the tests replay this corpus).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| host_fit::fuzzing::recording(data));
