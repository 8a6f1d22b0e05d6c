//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

use vocc::scene::{self, ReadOptions, Scene};

/// A path inside the repository.
pub fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub const LYON: &str = "data/lyon1/buildings_lyon1.geojson";

pub fn lyon_options() -> ReadOptions {
    ReadOptions {
        height_attr: Some("HAUTEUR".into()),
        ..ReadOptions::default()
    }
}

pub fn load_lyon() -> Scene {
    scene::load(&[repo(LYON)], &lyon_options()).expect("Lyon loads")
}

/// A fresh temporary directory under the target dir, unique per test name.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
