//! The integration tests, one module per file of tests/, in one test binary: linking a binary
//! against the whole library is a large part of a cold build, so there is one (`[[test]] all` in
//! Cargo.toml, with `autotests = false`) instead of one per file. `tests/format/` (`main.rs`) stays a binary
//! of its own: it installs a counting global allocator and builds without default features.
//! `every_test_file_runs` fails when a file of tests/ is neither a module here nor a `[[test]]`.
//! One file's tests: `cargo test --test all incremental::`.

mod common;

mod bake_store;
mod broken_inputs;
mod broken_mesh_inputs;
mod cli;
mod eval;
mod footprints;
mod fuzz_corpus;
mod hostile_inputs;
mod incremental;
mod mesh_datasets;
mod readers;
mod stability;
mod terrain;
mod truth;
mod umbra_cases;
mod verifier;
mod view;
mod walls;

/// Every `tests/*.rs`, and every folder of tests/ with a `mod.rs` or a `main.rs`, is a `mod` of
/// this file or a `[[test]]` target of its own in Cargo.toml, so a new test file cannot be
/// silently left out of `cargo test` (autotests is off). A folder's own files are its `mod.rs`'s
/// or `main.rs`'s modules, which the compiler checks.
#[test]
fn every_test_file_runs() {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let this = include_str!("all.rs");
    let manifest = std::fs::read_to_string(root.join("Cargo.toml")).unwrap();
    let mut files = 0;
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(root.join("tests")).unwrap() {
        let path = entry.unwrap().path();
        let Some(name) = path.file_name().and_then(|n| n.to_str()) else {
            continue;
        };
        // A module file, a module folder (NAME/mod.rs) or a target folder (NAME/main.rs).
        let (stem, target) = if let Some(stem) = name.strip_suffix(".rs") {
            (stem, format!("tests/{name}"))
        } else if path.join("mod.rs").is_file() {
            (name, format!("tests/{name}/mod.rs"))
        } else if path.join("main.rs").is_file() {
            (name, format!("tests/{name}/main.rs"))
        } else {
            continue;
        };
        if stem == "all" || stem == "common" {
            continue;
        }
        files += 1;
        let as_module = this.lines().any(|l| l == format!("mod {stem};"));
        let as_target = manifest
            .lines()
            .any(|l| l.trim() == format!("path = \"{target}\""));
        if !as_module && !as_target {
            missing.push(name.to_string());
        }
    }
    assert!(files >= 17, "only {files} test files found in tests/");
    assert!(
        missing.is_empty(),
        "tests/{missing:?} would not run: add `mod NAME;` to tests/all.rs (or a [[test]] to Cargo.toml)"
    );
}
