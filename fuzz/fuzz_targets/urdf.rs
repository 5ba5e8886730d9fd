//! Fuzzes the reader of `iscene::fuzzing::Reader::Urdf` (see src/fuzzing.rs).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    iscene::fuzzing::read(iscene::fuzzing::Reader::Urdf, data);
});
