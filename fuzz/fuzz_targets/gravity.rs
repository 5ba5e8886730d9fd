//! Fuzzes the reader of `iscene::fuzzing::Reader::Gravity` (see src/fuzzing.rs).
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    iscene::fuzzing::read(iscene::fuzzing::Reader::Gravity, data);
});
