//! Damaged stores: every refusal of inspect and pvs, none a panic.

#[allow(unused_imports)]
use super::*;

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
