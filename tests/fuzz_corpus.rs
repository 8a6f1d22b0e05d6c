//! Replays the committed fuzz corpora on stable Rust, as part of `cargo test`.
//!
//! Input: every file of `fuzz/corpus/<target>/` for every target of `fuzz/`
//! (docs/FUZZING.md).
//! Output: each file goes through the very function its fuzz target calls (`vocc::fuzzing`),
//! which checks the library's invariants and panics on a violation.
//! Invariants: no file panics (each runs under `catch_unwind`, and every failure is listed with
//! its path); a result is `Ok` or a typed error (`FormatError`, `LoadError`) whose message is
//! not empty (or `HashesError`, `MergeError`); a corpus directory that is missing or empty fails the test, so the replay cannot
//! silently check nothing.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use vocc::fuzzing;
use vocc::runtime::{decode_blob, decode_frame, Store};

/// Runs `entry` on every file of `fuzz/corpus/<target>`; returns (files, accepted).
fn replay<E: std::fmt::Display>(
    target: &str,
    entry: impl Fn(&[u8]) -> Result<(), E>,
) -> (usize, usize) {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("corpus {} is missing: {e}", dir.display()))
        .map(|e| e.expect("corpus entry").path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "corpus {} is empty", dir.display());
    let mut failures = Vec::new();
    let mut accepted = 0;
    for f in &files {
        let bytes = std::fs::read(f).expect("read a corpus file");
        match catch_unwind(AssertUnwindSafe(|| entry(&bytes))) {
            Ok(Ok(())) => accepted += 1,
            Ok(Err(e)) if e.to_string().trim().is_empty() => {
                failures.push(format!("{}: an error without a message", name(f)))
            }
            Ok(Err(_)) => {}
            Err(_) => failures.push(format!("{}: panicked", name(f))),
        }
    }
    assert!(
        failures.is_empty(),
        "{target}: {} of {} corpus files failed:\n{}",
        failures.len(),
        files.len(),
        failures.join("\n")
    );
    (files.len(), accepted)
}

fn name(p: &Path) -> String {
    p.file_name().unwrap_or_default().to_string_lossy().into()
}

/// How many files of `fuzz/corpus/<target>/` are accepted as version 1 and 2 by `major`.
fn accepted_majors(target: &str, major: impl Fn(&[u8]) -> Option<u16>) -> [usize; 2] {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut n = [0; 2];
    for e in std::fs::read_dir(dir).expect("corpus") {
        let bytes = std::fs::read(e.expect("entry").path()).expect("read");
        match major(&bytes) {
            Some(1) => n[0] += 1,
            Some(2) => n[1] += 1,
            _ => {}
        }
    }
    n
}

#[test]
fn store_corpus() {
    let (n, ok) = replay("store", |b| fuzzing::store(b).map(drop));
    // Seeds include valid stores (FORMAT.md's examples and bakes), so some must be accepted,
    // of both versions.
    assert!(ok > 0, "none of {n} store files was accepted");
    let [v1, v2] = accepted_majors("store", |b| Store::parse(b).ok().map(|s| s.major()));
    assert!(
        v1 > 0 && v2 > 0,
        "accepted stores: {v1} of 1.0, {v2} of 2.0"
    );
}

#[test]
fn blob_corpus() {
    let (n, ok) = replay("blob", |b| fuzzing::blob(b).map(drop));
    assert!(ok > 0, "none of {n} blob files was accepted");
    // Framed blobs of both versions decode with their own frame.
    let [v1, v2] = accepted_majors("blob", |b| {
        let (frame, blob) = b.split_at_checked(112)?;
        decode_blob(&decode_frame(frame).ok()?, blob).ok()?;
        Some(blob[4] as u16)
    });
    assert!(
        v1 > 0 && v2 > 0,
        "accepted framed blobs: {v1} of 1.0, {v2} of 2.0"
    );
}

#[test]
fn geojson_corpus() {
    let (n, ok) = replay("geojson", |b| fuzzing::geojson(b).map(drop));
    assert!(ok > 0, "none of {n} GeoJSON files loaded");
}

#[test]
fn cityjson_corpus() {
    let (n, ok) = replay("cityjson", |b| fuzzing::cityjson(b).map(drop));
    assert!(ok > 0, "none of {n} CityJSON files loaded");
}

#[test]
fn dem_corpus() {
    let (n, ok) = replay("dem", |b| fuzzing::dem(b).map(drop));
    assert!(ok > 0, "none of {n} DEMs loaded");
}

#[test]
fn obj_corpus() {
    let (n, ok) = replay("obj", |b| fuzzing::obj(b).map(drop));
    assert!(ok > 0, "none of {n} OBJ files loaded");
}

#[test]
fn osm_corpus() {
    let (n, ok) = replay("osm", |b| fuzzing::osm(b).map(drop));
    assert!(ok > 0, "none of {n} OpenStreetMap files loaded");
}

#[test]
fn gpkg_corpus() {
    let (n, ok) = replay("gpkg", |b| fuzzing::gpkg(b).map(drop));
    assert!(ok > 0, "none of {n} GeoPackage files loaded");
}

#[test]
fn fgb_corpus() {
    let (n, ok) = replay("fgb", |b| fuzzing::fgb(b).map(drop));
    assert!(ok > 0, "none of {n} FlatGeobuf files loaded");
}

#[test]
fn shp_corpus() {
    let (n, ok) = replay("shp", |b| fuzzing::shp(b).map(drop));
    assert!(ok > 0, "none of {n} Shapefiles loaded");
}

#[test]
fn citygml_corpus() {
    let (n, ok) = replay("citygml", |b| fuzzing::citygml(b).map(drop));
    assert!(ok > 0, "none of {n} CityGML files loaded");
}

#[test]
fn cityjsonseq_corpus() {
    let (n, ok) = replay("cityjsonseq", |b| fuzzing::cityjsonseq(b).map(drop));
    assert!(ok > 0, "none of {n} CityJSONSeq files loaded");
}

#[test]
fn walkable_corpus() {
    let (n, ok) = replay("walkable", |b| fuzzing::walkable(b).map(drop));
    assert!(ok > 0, "none of {n} walkable-area files was read");
}

#[test]
fn hashes_corpus() {
    let (n, ok) = replay("hashes", |b| fuzzing::hashes(b).map(drop));
    assert!(ok > 0, "none of {n} hashes files was accepted");
    // The shard index at the count (issue 34: `vocc merge` panicked on it) is among the seeds and
    // refused by name.
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/hashes");
    let refused = std::fs::read_dir(dir)
        .expect("corpus")
        .filter_map(|e| std::fs::read(e.expect("entry").path()).ok())
        .filter_map(|b| vocc::bake::incremental::CellHashes::decode(&b).err())
        .filter(|e| {
            e.to_string()
                .contains("a shard index must be below the count")
        })
        .count();
    assert!(
        refused >= 2,
        "{refused} hashes files refused for their shard index"
    );
}

#[test]
fn merge_corpus() {
    let (n, ok) = replay("merge", |b| fuzzing::merge_target(b).map(drop));
    // One shard of one, and two shards of two with equal records, merge.
    assert!(ok > 0, "none of {n} merge inputs merged");
}

/// Every target of `fuzz/Cargo.toml` has a corpus that a test of this file replays.
#[test]
fn every_fuzz_target_is_replayed() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let manifest = std::fs::read_to_string(root.join("fuzz/Cargo.toml")).expect("fuzz manifest");
    let this = include_str!("fuzz_corpus.rs");
    let targets: Vec<&str> = manifest
        .lines()
        .filter_map(|l| l.strip_prefix("path = \"fuzz_targets/"))
        .filter_map(|l| l.strip_suffix(".rs\""))
        .collect();
    assert!(targets.len() >= 15, "targets: {targets:?}");
    for t in targets {
        assert!(
            this.contains(&format!("replay(\"{t}\"")),
            "fuzz target {t} has no corpus replay here"
        );
    }
}
