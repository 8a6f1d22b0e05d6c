//! The binary of this package, run as a user runs it. Its being here also makes `cargo test` at
//! the root build `target/<profile>/vocc`, which the root's integration tests (tests/cli/ and
//! others, through `common::vocc_bin`) run: cargo builds a package's binaries for its own
//! integration tests only.
//!
//! Input: the `vocc` binary. Output: assertions on its exit status and output.

use std::process::Command;

fn vocc(args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vocc"))
        .args(args)
        .output()
        .expect("vocc runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn help_lists_the_commands() {
    let (rc, out, err) = vocc(&["--help"]);
    assert_eq!(rc, Some(0), "{err}");
    for command in ["bake", "merge", "inspect", "pvs", "info"] {
        assert!(out.contains(command), "{command} missing from:\n{out}");
    }
}

#[test]
fn merge_of_a_missing_shard_names_the_file() {
    let dir = std::env::temp_dir().join(format!("vocc-cli-smoke-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shard = dir.join("absent.vocc");
    let out = dir.join("out.vocc");
    let (rc, _, err) = vocc(&[
        "merge",
        shard.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(rc, Some(1), "{err}");
    assert!(err.contains("absent.vocc"), "{err}");
    assert!(!out.exists(), "no output after a refused merge");
    let _ = std::fs::remove_dir_all(&dir);
}
