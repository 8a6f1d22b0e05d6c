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

#[test]
fn damaged_stores_are_refused_by_inspect_and_pvs() {
    let dir = common::temp_dir("hostile-stores");
    let good = store_bytes();
    let scene = dir.join("scene.geojson");
    std::fs::write(&scene, PVS_SCENE).unwrap();
    let path = dir.join("s.vocc");
    let p = path.to_str().unwrap();
    let sc = scene.to_str().unwrap();
    // The store's scene section is made up (one object, a fixed fingerprint, EPSG:2154), so the
    // scene check is told to go on: the damage is what is under test.
    let pvs = |p: &str| {
        vocc(&[
            "pvs",
            p,
            sc,
            "--height-attr",
            "height",
            "--cell",
            "2",
            "--allow-other-scene",
        ])
    };

    // The undamaged store works, so every refusal below is the damage's doing.
    std::fs::write(&path, &good).unwrap();
    let o = vocc(&["inspect", p]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = pvs(p);
    assert!(o.status.success(), "{}", stderr(&o));

    let refused = |bytes: &[u8], want: &str, what: &str| {
        std::fs::write(&path, bytes).unwrap();
        assert_refused(&vocc(&["inspect", p]), want, what);
        assert_refused(&pvs(p), want, what);
    };

    // Truncated anywhere: the header, the scene section, the index, the block table, the
    // payload.
    let n = good.len();
    for len in [
        0,
        1,
        8,
        100,
        135,
        136,
        137,
        148,
        149,
        152,
        INDEX,
        INDEX + 80,
        INDEX + 80 + 8,
        n / 2,
        n - 1,
    ] {
        let want = if len == 0 {
            "is not a valid vocc store"
        } else {
            "truncated"
        };
        refused(&good[..len], want, &format!("truncated to {len} bytes"));
    }
    // One byte too many.
    let mut long = good.clone();
    long.push(0);
    refused(&long, "trailing bytes", "one trailing byte");

    // Oversized length fields, with the checksum made right so that the length rules answer.
    let set_u32 = |at: usize, v: u32| {
        let mut b = good.clone();
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
        fix_crc(&mut b);
        b
    };
    refused(
        &set_u32(128, u32::MAX),
        "truncated",
        "payload_len = u32::MAX",
    );
    // nx = 2^16, ny = 2^15: 2^31 cells, the most a frame allows; a file of 2 GiB would be needed.
    let mut b = set_u32(64, 1 << 16);
    b[68..72].copy_from_slice(&(1u32 << 15).to_le_bytes());
    fix_crc(&mut b);
    refused(&b, "bytes needed", "2^31 cells");
    refused(&set_u32(64, u32::MAX), "F4", "nx = u32::MAX");
    refused(&set_u32(64, 0), "F3", "nx = 0");
    // The rules of 2.0, with the checksum made right: a CRS name that is not UTF-8, or one
    // that claims more bytes than the file has; a non-canonical endpoint (bit 47 is 2.1's deep flag).
    let set = |at: usize, v: u8| {
        let mut b = good.clone();
        b[at] = v;
        fix_crc(&mut b);
        b
    };
    refused(
        &set(151, 0xff),
        "the CRS name is not UTF-8 (at offset 151)",
        "CRS 0xff",
    );
    refused(&set(148, 200), "truncated", "crs_len = 200");
    // Cell 2, with one VO, starts the payload: its ground byte, then VO 0.
    let payload = INDEX + 80 + 8;
    // Bit 47 is the deep flag of 2.1: read, not refused.
    std::fs::write(&path, set(payload + 1 + 5, good[payload + 1 + 5] | 0x80)).unwrap();
    let o = vocc(&["inspect", p]);
    assert!(o.status.success(), "deep VO: {}", stderr(&o));
    let mut b = good.clone();
    let non_canonical = QVo {
        a: QPoint {
            e: 2,
            x: 256,
            y: 300,
        },
        b: QPoint::fine(1, 2),
        level: 3,
        deep: false,
    };
    b[payload + 1..payload + 7].copy_from_slice(&non_canonical.to_bytes());
    fix_crc(&mut b);
    refused(&b, "endpoint a is not canonical", "non-canonical endpoint");

    // Every single-bit flip, one per byte (bit = offset mod 8), through `inspect`: the checksum
    // or a header rule catches each.
    for at in 0..n {
        let mut b = good.clone();
        b[at] ^= 1 << (at % 8);
        std::fs::write(&path, &b).unwrap();
        let o = vocc(&["inspect", p]);
        assert_refused(
            &o,
            "is not a valid vocc store",
            &format!("bit flip at byte {at}"),
        );
    }
    // And through `pvs`, a few.
    for at in [0, 9, 20, 64, 128, 132, 140, 200, n - 1] {
        let mut b = good.clone();
        b[at] ^= 0x10;
        std::fs::write(&path, &b).unwrap();
        assert_refused(
            &pvs(p),
            "is not a valid vocc store",
            &format!("pvs, flip at {at}"),
        );
    }
    // Not a file at all.
    assert_refused(
        &vocc(&["inspect", dir.join("missing.vocc").to_str().unwrap()]),
        "cannot read",
        "missing file",
    );

    // A 1.0 store (FORMAT.md section 12) is read; damaged, it is refused like a 2.0 one: every
    // single-bit flip, a truncation in each part, a trailing byte.
    let v1 = doc_hex("store-1.0");
    std::fs::write(&path, &v1).unwrap();
    let o = vocc(&["inspect", p]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("vocc store 1.0"));
    for at in 0..v1.len() {
        let mut b = v1.clone();
        b[at] ^= 1 << (at % 8);
        std::fs::write(&path, &b).unwrap();
        assert_refused(
            &vocc(&["inspect", p]),
            "is not a valid vocc store",
            &format!("1.0: bit flip at byte {at}"),
        );
    }
    for len in [100, 136, 137, 140, 150, v1.len() - 1] {
        std::fs::write(&path, &v1[..len]).unwrap();
        assert_refused(
            &vocc(&["inspect", p]),
            "truncated",
            &format!("1.0 truncated to {len}"),
        );
    }
    let mut long = v1.clone();
    long.push(0);
    std::fs::write(&path, &long).unwrap();
    assert_refused(
        &vocc(&["inspect", p]),
        "trailing bytes",
        "1.0, one trailing byte",
    );
}

// ---------------------------------------------------------------------------------------------
// Scene files

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

#[test]
fn geojson_nan_infinite_and_huge_values_are_located_errors() {
    let ok = feature(r#"{"height":5}"#, &polygon(SQUARE));
    let with =
        |props: &str, coords: &str| collection(&[ok.clone(), feature(props, &polygon(coords))]);
    // JSON has no NaN literal: the strings "NaN" and "inf" are not coordinates.
    for bad in ["NaN", "inf", "-Infinity"] {
        let coords = format!(r#"[[["{bad}",0],[10,0],[10,10],[0,0]]]"#);
        let e = fails("a.geojson", &with(r#"{"height":5}"#, &coords));
        assert!(
            matches!(&e.kind, LoadErrorKind::Malformed { format: "GeoJSON", message }
                if message.starts_with("feature 1:") && message.contains(bad)),
            "{bad}: {e}"
        );
        assert!(matches!(e.location, Location::Line { line: 1, .. }), "{e}");
    }
    // As attribute strings they are not numbers (scene::attr): the feature is skipped with its
    // reason, or, under --on-bad-height error, the load fails there.
    for (props, what) in [
        (r#"{"height":"NaN"}"#, "height"),
        (r#"{"height":"inf"}"#, "height"),
        (r#"{"height":"-1e999"}"#, "height"),
        (r#"{"height":null,"levels":"NaN"}"#, "levels"),
    ] {
        let text = with(props, SQUARE);
        let s = load_one("a.geojson", &text).unwrap();
        assert_eq!(s.objects.len(), 1, "{what}");
        assert!(
            matches!(&s.report.skipped[0].1.reason, vocc::scene::SkipReason::BadHeight { attr, .. } if attr == what),
            "{what}: {:?}",
            s.report.skipped
        );
        let strict = ReadOptions {
            on_bad_height: vocc::scene::OnBadHeight::Error,
            ..opts()
        };
        let e = load_bytes(&[(PathBuf::from("a.geojson"), text.as_bytes())], &strict).unwrap_err();
        assert!(
            matches!(&e.kind, LoadErrorKind::BadAttribute { attr, .. } if attr == what),
            "{what}: {e}"
        );
        assert_eq!(e.location, Location::Feature(1), "{e}");
    }
    // 1e300 as a height, or as storeys: a bad height (issue 33, defect 7), skipped with its
    // reason, or under --on-bad-height error a located error; never an abort of the load.
    for (props, what) in [
        (r#"{"height":1e300}"#, "height"),
        (r#"{"height":null,"levels":"1e300"}"#, "levels"),
    ] {
        let text = with(props, SQUARE);
        let s = load_one("a.geojson", &text).unwrap();
        assert!(
            matches!(&s.report.skipped[0].1.reason, vocc::scene::SkipReason::BadHeight { attr, value }
                if attr == what && value.contains("1e300")),
            "{what}: {:?}",
            s.report.skipped
        );
        let strict = ReadOptions {
            on_bad_height: vocc::scene::OnBadHeight::Error,
            ..opts()
        };
        let e = load_bytes(&[(PathBuf::from("a.geojson"), text.as_bytes())], &strict).unwrap_err();
        assert!(
            matches!(&e.kind, LoadErrorKind::AbsurdHeight { attr, .. } if attr == what),
            "{what}: {e}"
        );
        assert_eq!(e.location, Location::Feature(1), "{e}");
    }
    // A coordinate of 1e300 written with a huge exponent; the largest finite f64 too.
    for (props, coords) in [
        (
            r#"{"height":5}"#,
            "[[[0,0],[10000000000000000000000e280,0],[10,10],[0,0]]]",
        ),
        (
            r#"{"height":5}"#,
            "[[[0,0],[1.7976931348623157e308,0],[10,10],[0,0]]]",
        ),
    ] {
        let e = fails("a.geojson", &with(props, coords));
        assert!(
            matches!(e.kind, LoadErrorKind::OutOfRange { .. }),
            "{props} {coords}: {e}"
        );
        assert_eq!(e.location, Location::Feature(1), "{e}");
    }
    // A literal beyond f64 is refused by the JSON parser, with its line.
    let e = fails("a.geojson", &with(r#"{"height":1e400}"#, SQUARE));
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    assert!(matches!(e.location, Location::Line { line: 1, .. }), "{e}");
}

#[test]
fn cityjson_transform_that_overflows_is_a_vertex_error() {
    let doc = |scale: &str, vertex: &str| {
        format!(
            r#"{{"type":"CityJSON","version":"1.1","transform":{{"scale":{scale},"translate":[0,0,0]}},
            "vertices":[[0,0,0],[1,0,0],[1,1,0],{vertex}],
            "CityObjects":{{"b":{{"type":"Building","geometry":[{{"type":"MultiSurface","lod":1,"boundaries":[[[0,1,2,3]]]}}]}}}}}}"#
        )
    };
    // scale 1e8 (allowed) times a vertex of 1e301 is infinite: NonFinite at that vertex.
    let e = fails("c.json", &doc("[1e8,1e8,1]", "[1e301,0,0]"));
    assert!(matches!(e.kind, LoadErrorKind::NonFinite(_)), "{e}");
    assert_eq!(e.location, Location::Vertex(3));
    // scale 1e8 times 1e10 is finite but beyond 1e9 m.
    let e = fails("c.json", &doc("[1e8,1e8,1]", "[0,10000000000,0]"));
    assert!(matches!(e.kind, LoadErrorKind::OutOfRange { .. }), "{e}");
    assert_eq!(e.location, Location::Vertex(3));
    // A scale of 1e300 is refused where it stands.
    let e = fails("c.json", &doc("[1e300,1,1]", "[0,1,0]"));
    assert!(
        matches!(e.kind, LoadErrorKind::OutOfRange { value, .. } if value == 1e300),
        "{e}"
    );
    assert_eq!(e.location, Location::File);
    // The same document with a sane transform loads.
    let s = load_one("c.json", &doc("[0.5,0.5,1]", "[0,1,0]")).unwrap();
    assert_eq!(s.objects.len(), 1);
}

#[test]
fn obj_nan_infinite_and_huge_vertices_fail_at_their_line() {
    for (v, nonfinite) in [
        ("v nan nan nan", true),
        ("v inf 0 0", true),
        ("v 0 -inf 0", true),
        ("v 1 2 3 0", true), // w = 0 divides to infinity
        ("v 1e300 0 0", false),
        ("v 0 0 -2e9", false),
    ] {
        let text = format!("v 0 0 0\nv 1 0 0\n{v}\nv 0 1 0\nf 1 2 4\nf 1 2 3\n");
        let e = fails("m.obj", &text);
        assert_eq!(
            e.location,
            Location::Line {
                line: 3,
                column: None
            },
            "{v}: {e}"
        );
        if nonfinite {
            assert!(matches!(e.kind, LoadErrorKind::NonFinite(_)), "{v}: {e}");
        } else {
            assert!(
                matches!(e.kind, LoadErrorKind::OutOfRange { .. }),
                "{v}: {e}"
            );
        }
    }
}

#[test]
fn empty_geometries_are_skipped_or_refused_never_a_panic() {
    let ok = feature(r#"{"height":5}"#, &polygon(SQUARE));
    let empties = [
        polygon("[]"),
        polygon("[[]]"),
        polygon("[[],[]]"),
        r#"{"type":"MultiPolygon","coordinates":[]}"#.to_string(),
        r#"{"type":"MultiPolygon","coordinates":[[]]}"#.to_string(),
        r#"{"type":"MultiPolygon","coordinates":[[[]]]}"#.to_string(),
        "null".to_string(),
    ];
    let mut features = vec![ok];
    features.extend(empties.iter().map(|g| feature(r#"{"height":5}"#, g)));
    let s = load_one("e.geojson", &collection(&features)).unwrap();
    assert_eq!(s.objects.len(), 1, "only the square is an object");
    assert_eq!(s.report.skipped.len(), empties.len());
    assert!(s
        .report
        .skipped
        .iter()
        .all(|(_, k)| k.reason == vocc::scene::SkipReason::EmptyGeometry));

    // Rings of one or two points: an occludee, but no blocker.
    let s = load_one(
        "e.geojson",
        &collection(&[
            feature(r#"{"height":5}"#, &polygon("[[[0,0]]]")),
            feature(r#"{"height":5}"#, &polygon("[[[0,0],[5,5]]]")),
        ]),
    )
    .unwrap();
    assert_eq!(s.objects.len(), 2);
    assert!(s.blockers.is_empty());
    assert_eq!(s.report.no_blocker.len(), 2);

    // Nothing but empty geometry: no objects, with heights present (not a missing attribute).
    let only_empty: Vec<String> = empties
        .iter()
        .map(|g| feature(r#"{"height":5}"#, g))
        .collect();
    let e = fails("e.geojson", &collection(&only_empty));
    assert_eq!(e.kind, LoadErrorKind::NoObjects, "{e}");
    let e = fails("e.geojson", &collection(&[]));
    assert_eq!(e.kind, LoadErrorKind::NoObjects, "{e}");

    // CityJSON: a building whose boundaries are empty is skipped; with nothing else, no objects.
    let cj = |geometry: &str| {
        format!(
            r#"{{"type":"CityJSON","version":"2.0","vertices":[],"CityObjects":{{"b":{{"type":"Building","geometry":{geometry}}}}}}}"#
        )
    };
    for g in [
        r#"[{"type":"Solid","lod":1,"boundaries":[]}]"#,
        r#"[{"type":"Solid","lod":1,"boundaries":[[]]}]"#,
        r#"[{"type":"MultiSurface","lod":1,"boundaries":[[[]]]}]"#,
        r#"[{"type":"MultiSolid","lod":1,"boundaries":[]}]"#,
        "[]",
    ] {
        let e = fails("c.json", &cj(g));
        assert_eq!(e.kind, LoadErrorKind::NoObjects, "{g}: {e}");
    }

    // OBJ: vertices and groups but not one face.
    for text in [
        "v 0 0 0\nv 1 0 0\nv 0 1 0\no a\ng b\n",
        "o a\n",
        "# nothing\n",
    ] {
        let e = fails("m.obj", text);
        assert_eq!(
            e.kind,
            LoadErrorKind::MalformedObj("no faces".into()),
            "{e}"
        );
    }
}

#[test]
fn json_nested_past_any_depth_is_an_error_not_a_stack_overflow() {
    let deep = |n: usize| format!("{}{}", "[".repeat(n), "]".repeat(n));
    let coords = deep(100_000);
    let text = collection(&[feature(r#"{"height":5}"#, &polygon(&coords))]);
    let e = fails("d.geojson", &text);
    assert!(
        matches!(e.kind, LoadErrorKind::MalformedJson(ref m) if m.contains("recursion")),
        "{e}"
    );
    let e = fails("d.json", &deep(100_000));
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    let e = walkable::read_bytes(
        Path::new("w.geojson"),
        polygon(&coords).as_bytes(),
        glam::DVec3::ZERO,
    )
    .unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
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

#[test]
fn polygons_of_100_000_vertices_load_or_are_refused_quickly() {
    gear(100_000);
    star(100_000);
}

/// 10^6 vertices: about 28 MB of GeoJSON each. Run with `cargo test --release --test all
/// hostile_inputs:: -- --ignored`; figures in docs/FUZZING.md.
#[test]
#[ignore]
fn polygons_of_1_000_000_vertices_load_or_are_refused_quickly() {
    gear(1_000_000);
    star(1_000_000);
}

/// 2,500 square holes in a square: each hole is checked against the exterior and every other
/// hole (by one ray per hole through the edges' R-tree, not a scan of every ring); then a hole
/// nested in another and a hole outside are refused.
#[test]
fn a_polygon_with_thousands_of_holes() {
    let sq = |x: f64, y: f64, s: f64, ccw: bool| {
        let mut p = [[x, y], [x + s, y], [x + s, y + s], [x, y + s], [x, y]];
        if !ccw {
            p.reverse();
        }
        let p: Vec<String> = p
            .iter()
            .map(|c| format!("[{},{}]", c[0] + 1_842_000.0, c[1] + 5_176_000.0))
            .collect();
        format!("[{}]", p.join(","))
    };
    let mut rings = vec![sq(0.0, 0.0, 1000.0, true)];
    for i in 0..50 {
        for j in 0..50 {
            rings.push(sq(
                5.0 + 20.0 * i as f64,
                5.0 + 20.0 * j as f64,
                10.0,
                false,
            ));
        }
    }
    let (s, _) = load_timed("2,500 holes", &footprint_file(&rings));
    assert!(s.report.no_blocker.is_empty(), "{:?}", s.report.no_blocker);
    let pieces: f64 = s
        .blockers
        .iter()
        .map(|b| vocc::scene::decompose::signed_area(&b.polygon))
        .sum();
    let area = 1000.0 * 1000.0 - 2500.0 * 100.0;
    assert!((pieces - area).abs() < 1e-6 * area, "{pieces} vs {area}");
    for (extra, what) in [
        (sq(6.0, 6.0, 2.0, false), "nested"),
        (sq(2000.0, 0.0, 5.0, false), "outside"),
    ] {
        let mut bad = rings.clone();
        bad.push(extra);
        let (s, _) = load_timed(what, &footprint_file(&bad));
        assert_eq!(
            s.report.no_blocker,
            [(
                0,
                vocc::scene::NoBlocker::InvalidRing {
                    polygon: 0,
                    ring: 2501,
                    why: vocc::scene::RingRejection::HoleOutside
                }
            )],
            "{what}"
        );
    }
}

// ---------------------------------------------------------------------------------------------
// A bake killed midway, and a full disk

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

#[cfg(unix)]
#[test]
fn a_killed_bake_leaves_no_store_and_keeps_the_old_one() {
    use std::os::unix::process::ExitStatusExt;

    let dir = common::temp_dir("hostile-kill");
    // Big enough that the bake runs for seconds, so the signal lands mid-bake.
    let city = gen_city(&dir, "city.geojson", 1500);
    let small = gen_city(&dir, "small.geojson", 60);
    let c = city.to_str().unwrap();

    // A complete small store: the "previous" output, and the bytes a killed write could have
    // left a prefix of. No proper prefix of it parses.
    let old = dir.join("old.vocc");
    let o = vocc(&bake_args(small.to_str().unwrap(), old.to_str().unwrap()));
    assert!(o.status.success(), "{}", stderr(&o));
    let old_bytes = std::fs::read(&old).unwrap();
    assert!(Store::parse(&old_bytes).is_ok());
    for len in 0..old_bytes.len() {
        assert!(
            Store::parse(&old_bytes[..len]).is_err(),
            "prefix of {len} bytes parses"
        );
    }

    for (signal, name) in [(9, "KILL"), (2, "INT")] {
        for previous in [false, true] {
            let out = dir.join(format!("sig{name}-{previous}.vocc"));
            if previous {
                std::fs::write(&out, &old_bytes).unwrap();
            }
            // A shell without job control starts background jobs with SIGINT ignored, and the
            // child inherits that (as under `make fresh-clone &`): the bake then ran to its end
            // and exited 0. Give it the default action back, as a terminal's Ctrl-C would meet.
            let mut cmd = if signal == 2 && sigint_ignored() {
                let mut e = Command::new("env");
                e.arg("--default-signal=INT").arg(common::vocc_bin());
                e
            } else {
                Command::new(common::vocc_bin())
            };
            let mut child = cmd
                .args(bake_args(c, out.to_str().unwrap()))
                .stdout(std::process::Stdio::null())
                .stderr(std::process::Stdio::null())
                .spawn()
                .unwrap();
            std::thread::sleep(Duration::from_millis(1000));
            assert!(
                child.try_wait().unwrap().is_none(),
                "the bake ended before SIG{name}: make the city bigger"
            );
            let sent = Command::new("kill")
                .args([&format!("-{name}"), &child.id().to_string()])
                .status()
                .unwrap();
            assert!(sent.success());
            let status = child.wait().unwrap();
            assert_eq!(status.signal(), Some(signal), "SIG{name}: {status:?}");
            if previous {
                assert_eq!(
                    std::fs::read(&out).unwrap(),
                    old_bytes,
                    "SIG{name} changed the old store"
                );
            } else {
                assert!(!out.exists(), "SIG{name} left a store behind");
            }
            let tmp = temp_of(&out);
            if let Ok(b) = std::fs::read(&tmp) {
                assert!(
                    Store::parse(&b).is_err(),
                    "SIG{name} left a valid temp store"
                );
            }
        }
    }
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

/// A real full disk: a 64 KiB tmpfs filled to the last block, mounted in a private namespace.
/// `vocc bake` into it must fail saying the disk is full and leave no store and no temporary file;
/// `vocc gen-city` writing more than the whole disk holds must fail the same way. Set
/// `VOCC_SKIP_FULL_DISK=1` where `unshare` cannot map a user namespace (the test then only checks
/// that the variable is the reason it did nothing).
#[cfg(target_os = "linux")]
#[test]
fn a_full_disk_is_reported_and_leaves_nothing() {
    let dir = common::temp_dir("hostile-full-disk");
    let small = gen_city(&dir, "small.geojson", 60);
    let mnt = dir.join("mnt");
    std::fs::create_dir_all(&mnt).unwrap();
    let script = r#"
        mount -t tmpfs -o size=64k tmpfs "$MNT" || exit 90
        cat /dev/zero > "$MNT/fill" 2>/dev/null
        echo "== bake"
        "$VOCC" bake "$SCENE" --height-attr height --cell-size 40 --threads 1 -o "$MNT/out.vocc" 2>&1
        echo "rc=$?"
        ls -A "$MNT"
        rm "$MNT/fill"
        echo "== gen-city"
        "$VOCC" gen-city --buildings 3000 -o "$MNT/city.geojson" 2>&1
        echo "rc=$?"
        ls -A "$MNT"
        echo "== end"
    "#;
    let env = [
        ("MNT", mnt.to_str().unwrap()),
        ("VOCC", common::vocc_bin()),
        ("SCENE", small.to_str().unwrap()),
    ];
    let Some(o) = in_private_mount_namespace(script, &env) else {
        assert!(
            std::env::var_os("VOCC_SKIP_FULL_DISK").is_some(),
            "cannot mount a tmpfs in a private namespace (unshare --user --map-root-user \
             --mount); set VOCC_SKIP_FULL_DISK=1 to skip this test on such a machine"
        );
        return;
    };
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    // The script's output in sections: "bake\n...", "gen-city\n...", "end\n".
    let section = |name: &str| -> String {
        let head = format!("{name}\n");
        text.split("== ")
            .find(|s| s.starts_with(&head))
            .unwrap_or_else(|| panic!("no section {name}: {text}"))
            .to_string()
    };
    let bake = section("bake");
    assert!(bake.contains("rc=1"), "{text}");
    assert!(bake.contains("the disk is full"), "{text}");
    assert!(bake.contains("out.vocc"), "names the output: {text}");
    assert!(!bake.contains("panicked"), "{text}");
    let listing: Vec<&str> = bake
        .lines()
        .skip_while(|l| !l.starts_with("rc="))
        .skip(1)
        .collect();
    assert_eq!(listing, ["fill"], "only the filler remains: {text}");

    let gen = section("gen-city");
    assert!(gen.contains("rc=1"), "{text}");
    assert!(gen.contains("the disk is full"), "{text}");
    assert!(gen.contains("city.geojson"), "{text}");
    let listing: Vec<&str> = gen
        .lines()
        .skip_while(|l| !l.starts_with("rc="))
        .skip(1)
        .collect();
    assert!(listing.is_empty(), "nothing remains: {text}");
    assert!(text.contains("== end"), "{text}");
}
