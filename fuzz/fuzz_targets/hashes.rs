//! Fuzz target `hashes`: arbitrary bytes into `vocc::fuzzing::hashes`, the same function
//! `tests/fuzz_corpus.rs` replays the committed corpus through (its doc lists the invariants it
//! checks). Errors are expected; only a panic, an abort, a timeout or an OOM is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = vocc::fuzzing::hashes(data);
});
