//! Fuzz target `dem`: arbitrary bytes into `vocc::fuzzing::dem` (a GeoTIFF DEM, then the terrain
//! and its blockers), the same function `tests/fuzz_corpus.rs` replays the committed corpus
//! through. Errors are expected; only a panic, an abort, a timeout or an OOM is a finding.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = vocc::fuzzing::dem(data);
});
