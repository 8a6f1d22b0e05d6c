//! Hostile input, end to end: damaged store files through the `vocc` binary, scene files with
//! non-finite, huge or empty geometry, a polygon of 10^5 vertices (10^6 in an ignored test),
//! JSON nested past any sane depth, a bake killed by SIGKILL or SIGINT, and a bake or
//! `gen-city` writing to a full disk (a real 64 KiB tmpfs, mounted in a private user and mount
//! namespace with `unshare`).
//!
//! Input: stores made with the library's encoder, scenes written by the tests (or by
//! `vocc gen-city`), and the binary `common::vocc_bin()`. Output: assertions.
//! Invariants: bad input gives a non-zero exit status (CLI) or a typed error (library) naming
//! what is wrong and where, never a panic; every single-bit flip of a store is refused; an
//! interrupted or failed write leaves the output path as it was (absent, or the old store) and no
//! temporary file that parses as a store; a full disk is reported as such.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::{Duration, Instant};

use vocc::runtime::crc::crc32;
use vocc::runtime::{
    encode_store_with, CellRecord, Frame, GridDescriptor, QPoint, QVo, SceneSection, Store,
};
use vocc::scene::{load_bytes, walkable, LoadError, LoadErrorKind, Location, ReadOptions, Scene};

mod processes;
mod scenes;
mod stores;

fn vocc(args: &[&str]) -> Output {
    Command::new(common::vocc_bin())
        .args(args)
        .output()
        .expect("vocc runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A refused command: non-zero exit, an `error:` line containing `want`, no panic.
fn assert_refused(o: &Output, want: &str, what: &str) {
    let err = stderr(o);
    assert!(!o.status.success(), "{what}: accepted");
    assert_eq!(o.status.code(), Some(1), "{what}: {err}");
    assert!(!err.contains("panicked"), "{what}: {err}");
    assert!(err.starts_with("error: "), "{what}: {err}");
    assert!(err.contains(want), "{what}: wanted {want:?} in {err}");
}

// ---------------------------------------------------------------------------------------------
// Store files through the CLI

/// A 10 x 8 grid near Lyon (80 cells, two blocks of the block table) with per-cell ground.
fn frame() -> Frame {
    Frame {
        origin: [843000.0, 6518000.0, 0.0],
        grid: GridDescriptor {
            min_x: 0.0,
            min_y: 0.0,
            cell_size: 100.0,
            nx: 10,
            ny: 8,
        },
        quantum: 0.5,
        eye_lo: 1.5,
        eye_hi: 2.0,
        ground_z0: 160.0,
        ground_step: 0.5,
        h0: 4.0,
        h_ratio: 1.25,
    }
}

/// The CRS name the hostile store records: 9 bytes, so its index starts at 149 + 9 = 158.
const CRS: &str = "EPSG:2154";

/// Where the hostile store's index starts.
const INDEX: usize = 136 + 13 + CRS.len();

/// Cells with 0 to 3 VOs and some skipped: every kind of record; VOs near (exponent 0) and far
/// (an endpoint of exponent 1 to 3, canonical), of levels 0 to 31. A 2.0 store with a scene
/// section.
fn store_bytes() -> Vec<u8> {
    let cells: Vec<CellRecord> = (0..80u16)
        .map(|i| match i % 5 {
            0 => CellRecord::EMPTY,
            1 => CellRecord::Skipped,
            k => {
                let vos: Vec<QVo> = (0..k - 1)
                    .map(|j| QVo {
                        a: QPoint::fine(100 + i, 376),
                        b: QPoint {
                            e: (j % 4) as u8,
                            x: 300 + j,
                            y: 100 - j,
                        },
                        level: (i % 32) as u8,
                        deep: false,
                    })
                    .collect();
                CellRecord::new((i % 7) as u8, &vos).unwrap()
            }
        })
        .collect();
    let scene = SceneSection {
        objects: 1,
        scene: 0x1234_5678_9abc_def0,
        crs: CRS,
    };
    encode_store_with(&frame(), &cells, &scene).unwrap()
}

/// The bytes of a ```hex example:NAME block of docs/FORMAT.md.
fn doc_hex(name: &str) -> Vec<u8> {
    let doc = std::fs::read_to_string(common::repo("docs/FORMAT.md")).unwrap();
    let fence = format!("```hex example:{name}\n");
    let start = doc.find(&fence).unwrap() + fence.len();
    let end = start + doc[start..].find("```").unwrap();
    doc[start..end]
        .lines()
        .flat_map(|l| {
            let hex = l.split('#').next().unwrap().split_once(':').unwrap().1;
            hex.split_whitespace()
                .map(|t| u8::from_str_radix(t, 16).unwrap())
                .collect::<Vec<_>>()
        })
        .collect()
}

fn fix_crc(b: &mut [u8]) {
    b[132..136].fill(0);
    let crc = crc32(b);
    b[132..136].copy_from_slice(&crc.to_le_bytes());
}

/// One footprint in the store's frame, for `vocc pvs`.
const PVS_SCENE: &str = r#"{"type":"FeatureCollection","features":[{"type":"Feature","properties":{"height":10},"geometry":{"type":"Polygon","coordinates":[[[843010,6518110],[843090,6518110],[843090,6518130],[843010,6518130],[843010,6518110]]]}}]}"#;

fn opts() -> ReadOptions {
    ReadOptions {
        height_attr: Some("height".into()),
        levels_attr: Some("levels".into()),
        ..ReadOptions::default()
    }
}

fn load_one(name: &str, text: &str) -> Result<Scene, LoadError> {
    load_bytes(&[(PathBuf::from(name), text.as_bytes())], &opts())
}

fn fails(name: &str, text: &str) -> LoadError {
    let e = load_one(name, text).expect_err("hostile input must not load");
    assert_eq!(e.path, Path::new(name), "{e}");
    assert!(
        e.to_string().starts_with(name),
        "the message names the file: {e}"
    );
    e
}

const SQUARE: &str = "[[[0,0],[10,0],[10,10],[0,10],[0,0]]]";

fn feature(props: &str, geometry: &str) -> String {
    format!(r#"{{"type":"Feature","properties":{props},"geometry":{geometry}}}"#)
}

fn collection(features: &[String]) -> String {
    format!(
        r#"{{"type":"FeatureCollection","features":[{}]}}"#,
        features.join(",")
    )
}

fn polygon(coords: &str) -> String {
    format!(r#"{{"type":"Polygon","coordinates":{coords}}}"#)
}

/// A ring of `n` vertices (n even) around Lyon's centre, radii alternating between `r_even` and
/// `r_odd` metres (every other vertex reflex), rounded to millimetres as survey data is; as
/// GeoJSON `[[x, y], ...]` (closed), with the ring's area.
fn wavy_ring(n: usize, r_even: f64, r_odd: f64) -> (String, f64) {
    let (cx, cy) = (1_842_000.0, 5_176_000.0);
    let mm = |v: f64| (v * 1000.0).round() / 1000.0;
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let a = std::f64::consts::TAU * k as f64 / n as f64;
            let r = if k % 2 == 0 { r_even } else { r_odd };
            [mm(cx + r * a.cos()), mm(cy + r * a.sin())]
        })
        .collect();
    let mut twice = 0.0;
    for k in 0..n {
        let (p, q) = (pts[k], pts[(k + 1) % n]);
        twice += (p[0] - cx) * (q[1] - cy) - (q[0] - cx) * (p[1] - cy);
    }
    let mut ring: Vec<String> = pts.iter().map(|p| format!("[{},{}]", p[0], p[1])).collect();
    ring.push(ring[0].clone());
    (format!("[{}]", ring.join(",")), twice / 2.0)
}

fn footprint_file(rings: &[String]) -> String {
    collection(&[feature(
        r#"{"height":30}"#,
        &polygon(&format!("[{}]", rings.join(","))),
    )])
}

fn load_timed(what: &str, text: &str) -> (Scene, f64) {
    let t = Instant::now();
    let s = load_one("big.geojson", text).expect("a huge polygon loads");
    let secs = t.elapsed().as_secs_f64();
    eprintln!(
        "{what} ({:.1} MB of GeoJSON): {} convex pieces, {:?}, in {secs:.2} s",
        text.len() as f64 / 1e6,
        s.blockers.len(),
        s.report.no_blocker
    );
    assert_eq!(s.objects.len(), 1);
    (s, secs)
}

/// A gear of `n` vertices with teeth 2 cm deep and 2 cm apart (short edges, as a very detailed
/// survey gives): it loads, and its convex pieces cover exactly its area.
fn gear(n: usize) {
    let r = n as f64 * 0.02 / std::f64::consts::TAU;
    let (ring, area) = wavy_ring(n, r, r - 0.02);
    let (s, _) = load_timed(&format!("gear of {n} vertices"), &footprint_file(&[ring]));
    assert!(s.report.no_blocker.is_empty(), "{:?}", s.report.no_blocker);
    // n/2 reflex vertices need at least n/4 + 1 pieces.
    assert!(s.blockers.len() > n / 4, "{} pieces", s.blockers.len());
    let pieces: f64 = s
        .blockers
        .iter()
        .map(|b| vocc::scene::decompose::signed_area(&b.polygon))
        .sum();
    assert!(
        (pieces - area).abs() < 1e-6 * area,
        "pieces {pieces} vs polygon {area}"
    );
}

/// A star of `n` vertices whose spikes run from 60% of the radius to all of it: every edge is
/// long and passes near thousands of others, so the exact self-intersection check would examine
/// O(n^2) edge pairs (50 s for 10^5 vertices before the work budget). It is refused as a blocker
/// (it stays an occludee) with its reason, after linear work.
fn star(n: usize) {
    let r = n as f64 * 0.01;
    let (ring, _) = wavy_ring(n, r, 0.6 * r);
    let (s, secs) = load_timed(&format!("star of {n} vertices"), &footprint_file(&[ring]));
    assert!(s.blockers.is_empty());
    assert_eq!(
        s.report.no_blocker,
        [(
            0,
            vocc::scene::NoBlocker::InvalidRing {
                polygon: 0,
                ring: 0,
                why: vocc::scene::RingRejection::TooComplex
            }
        )]
    );
    // Linear work: generous for a debug build on a busy machine, far below the quadratic time.
    assert!(secs < n as f64 * 1e-4, "{secs} s");
}

/// `vocc gen-city` into `dir/name`.
fn gen_city(dir: &Path, name: &str, buildings: usize) -> PathBuf {
    let p = dir.join(name);
    let o = vocc(&[
        "gen-city",
        "--buildings",
        &buildings.to_string(),
        "--seed",
        "7",
        "-o",
        p.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    p
}

fn bake_args<'a>(scene: &'a str, out: &'a str) -> Vec<&'a str> {
    vec![
        "bake",
        scene,
        "--height-attr",
        "height",
        "--cell-size",
        "40",
        "--threads",
        "1",
        "-o",
        out,
    ]
}

fn temp_of(out: &Path) -> PathBuf {
    let name = out.file_name().unwrap().to_string_lossy();
    out.with_file_name(format!(".{name}.tmp"))
}

/// Whether this process ignores SIGINT (inherited by the processes it starts): bit 1 of the
/// `SigIgn` mask in /proc/self/status. False where there is no /proc.
#[cfg(unix)]
fn sigint_ignored() -> bool {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let mask = s.lines().find_map(|l| l.strip_prefix("SigIgn:"))?;
            u64::from_str_radix(mask.trim(), 16).ok()
        })
        .is_some_and(|m| m & (1 << (2 - 1)) != 0)
}

/// Runs `script` as root of a private user and mount namespace (`unshare`), where it may mount
/// a tmpfs only it sees. `None` when this machine does not allow that.
#[cfg(target_os = "linux")]
fn in_private_mount_namespace(script: &str, env: &[(&str, &str)]) -> Option<Output> {
    let o = Command::new("unshare")
        .args(["--user", "--map-root-user", "--mount", "sh", "-c", script])
        .envs(env.iter().copied())
        .output()
        .ok()?;
    (o.status.code() != Some(90)).then_some(o)
}
