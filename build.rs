//! Build script of the library: a fingerprint of its sources.
//!
//! Input: every file under `src/` (paths relative to it, and contents).
//! Output: the environment variable `VOCC_SOURCE_HASH` at compile time, 16 hex digits (FNV-1a,
//! 64 bits, over the files in path order).
//! Invariant: two builds from different sources get different fingerprints (up to the hash),
//! so `vocc bake --reuse` never copies a record that another build of the same version baked
//! (`src/bake/incremental.rs` puts the fingerprint in the global hash); the same sources give
//! the same fingerprint on every machine.

use std::fs;
use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            files(&p, out);
        } else {
            out.push(p);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let src = root.join("src");
    println!("cargo:rerun-if-changed=src");
    let mut all = Vec::new();
    files(&src, &mut all);
    let mut named: Vec<(String, PathBuf)> = all
        .into_iter()
        .map(|p| {
            let rel = p.strip_prefix(&src).unwrap_or(&p).to_string_lossy();
            (rel.replace('\\', "/"), p)
        })
        .collect();
    named.sort();
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &b in bytes {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for (rel, path) in &named {
        let body = fs::read(path).unwrap_or_default();
        eat(rel.as_bytes());
        eat(&(body.len() as u64).to_le_bytes());
        eat(&body);
    }
    println!("cargo:rustc-env=VOCC_SOURCE_HASH={h:016x}");
}
