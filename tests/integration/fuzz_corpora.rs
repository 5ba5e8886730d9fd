//! Replays the fuzzing corpora (`fuzz/corpus/<target>/`, kept small in the repository) through
//! the same entry points the `cargo fuzz` targets call: no reader may panic or hang on any of
//! them. CI replays; it does not fuzz (see the README's reliability section).

use std::time::{Duration, Instant};

use iscene::fuzzing::{Reader, read};

use crate::common;

#[test]
fn every_reader_survives_its_fuzzing_corpus() {
    for reader in Reader::ALL {
        let folder = common::root().join("fuzz/corpus").join(reader.name());
        let mut inputs: Vec<_> = std::fs::read_dir(&folder)
            .unwrap_or_else(|e| panic!("{}: {e}", folder.display()))
            .filter_map(Result::ok)
            .map(|e| e.path())
            .collect();
        inputs.sort();
        assert!(!inputs.is_empty(), "{}: an empty corpus", folder.display());
        let mut accepted = 0;
        for input in &inputs {
            let bytes = std::fs::read(input).expect("read");
            let start = Instant::now();
            accepted += usize::from(read(reader, &bytes));
            assert!(
                start.elapsed() < Duration::from_secs(20),
                "{}: {:?}",
                input.display(),
                start.elapsed()
            );
        }
        // The seeds are valid files: the corpus exercises each reader past its first check (the
        // folder readers get lists without their images, which they refuse at the first image).
        if !matches!(reader, Reader::Tum | Reader::Open3dLog) {
            assert!(accepted > 0, "{}: no input was accepted", folder.display());
        }
    }
}
