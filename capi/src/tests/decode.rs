//! Stores, blobs and frames through the C ABI: blobs and frames decode like the store, a 1.0
//! store and blob read as 2.0 ones (with the store's info), and bad stores are refused with the
//! rule they break and a null store.
//!
//! Input: the fixture records, `docs/FORMAT.md`'s 1.0 example, corrupted bytes. Output: pass or
//! fail. Invariant: each decode is compared with the Rust decoder's.

use super::*;

#[test]
fn blobs_and_frames_decode_like_the_store() {
    let fx = Fixture::new();
    let f = frame();
    let frame_bytes = vocc::runtime::format::encode_frame(&f);
    let mut fr = VoccFrame::from(&Frame {
        quantum: 3.0,
        ..frame()
    });
    let mut e = blank_error();
    unsafe {
        assert_eq!(
            vocc_frame_decode(frame_bytes.as_ptr(), frame_bytes.len(), &mut fr, &mut e),
            VOCC_OK
        );
        assert_eq!(fr, fx.frame);
        assert_eq!(
            vocc_frame_decode(frame_bytes.as_ptr(), 111, &mut fr, &mut e),
            VOCC_ERR_FORMAT
        );
        assert_eq!(msg(&e), "truncated: 112 bytes needed, 111 given");
    }
    for (id, rec) in records().iter().enumerate() {
        let blob = encode_blob(&f, id as u32, rec).unwrap();
        let (mut got_id, mut cell) = (0u32, VoccCell::default());
        let st = unsafe {
            vocc_blob_decode(
                &fr,
                blob.as_ptr(),
                blob.len(),
                &mut got_id,
                &mut cell,
                &mut e,
            )
        };
        assert_eq!(st, VOCC_OK);
        assert_eq!((got_id, cell), (id as u32, fx.cell(id as u32)));
    }
    let mut blob = encode_blob(&f, 12, &records()[12]).unwrap();
    blob[12] ^= 1;
    let (mut got_id, mut cell) = (0u32, VoccCell::default());
    let st = unsafe {
        vocc_blob_decode(
            &fr,
            blob.as_ptr(),
            blob.len(),
            &mut got_id,
            &mut cell,
            &mut e,
        )
    };
    assert_eq!((st, e.code), (VOCC_ERR_CHECKSUM, VOCC_ERR_CHECKSUM));
    assert!(msg(&e).starts_with("checksum mismatch"), "{}", msg(&e));
}

#[test]
fn a_1_0_store_and_blob_read_as_2_0_ones_and_the_store_info() {
    // The 1.0 store of FORMAT.md: its frame, the records of its cells.
    let v1 = unhex(STORE_V1);
    let mut s: *mut VoccStore = ptr::null_mut();
    let mut e = blank_error();
    let f = Frame {
        grid: GridDescriptor {
            nx: 3,
            ny: 1,
            ..frame().grid
        },
        ..frame()
    };
    let mut info = VoccStoreInfo {
        major: 0,
        minor: 0,
        objects: 9,
        scene: 9,
        crs_len: 9,
        crs: [b'x' as c_char; VOCC_CRS_LEN],
    };
    unsafe {
        assert_eq!(
            vocc_store_open(v1.as_ptr(), v1.len(), &mut s, &mut e),
            VOCC_OK
        );
        let mut fr = VoccFrame::from(&frame());
        assert_eq!(vocc_store_frame(s, &mut fr), VOCC_OK);
        assert_eq!(fr, VoccFrame::from(&f));
        let mut c = VoccCell::default();
        assert_eq!(vocc_store_cell(s, 0, &mut c, &mut e), VOCC_OK);
        assert_eq!((c.skipped, c.ground, c.count), (0, 4, 2));
        assert_eq!(
            c.vos[0],
            VoccVo {
                x1: 196,
                y1: 376,
                x2: 336,
                y2: 376,
                exp1: 0,
                exp2: 0,
                level: 5
            }
        );
        assert_eq!(vocc_store_info(s, &mut info), VOCC_OK);
        assert_eq!(
            (
                info.major,
                info.minor,
                info.objects,
                info.scene,
                info.crs_len
            ),
            (1, 0, 0, 0, 0)
        );
        assert_eq!(info.crs[0], 0);
        // The same cell from its 1.0 blob.
        let blob = unhex(BLOB_V1);
        let (mut id, mut b) = (9u32, VoccCell::default());
        assert_eq!(
            vocc_blob_decode(&fr, blob.as_ptr(), blob.len(), &mut id, &mut b, &mut e),
            VOCC_OK
        );
        assert_eq!((id, b), (0, c));
        vocc_store_free(s);
        // A 2.0 store with a scene section.
        let v2 = encode_store_with(
            &frame(),
            &records(),
            &SceneSection {
                objects: 3002,
                scene: 0x0123_4567_89ab_cdef,
                crs: "EPSG:2154",
            },
        )
        .unwrap();
        assert_eq!(
            vocc_store_open(v2.as_ptr(), v2.len(), &mut s, &mut e),
            VOCC_OK
        );
        assert_eq!(vocc_store_info(s, &mut info), VOCC_OK);
        assert_eq!(
            (
                info.major,
                info.minor,
                info.objects,
                info.scene,
                info.crs_len
            ),
            (2, 0, 3002, 0x0123_4567_89ab_cdef, 9)
        );
        assert_eq!(
            CStr::from_ptr(info.crs.as_ptr()).to_str().unwrap(),
            "EPSG:2154"
        );
        // Cell 18's far VO: exponents and a level above 15 come through.
        assert_eq!(vocc_store_cell(s, 18, &mut c, &mut e), VOCC_OK);
        assert_eq!(
            c.vos[0],
            VoccVo {
                x1: 181,
                y1: 406,
                x2: 406,
                y2: 406,
                exp1: 3,
                exp2: 2,
                level: 20
            }
        );
        let mut g = VoccVoGeom::default();
        let fr = VoccFrame::from(&frame());
        assert_eq!(vocc_vo_geometry(&fr, 18, &c, 0, &mut g), VOCC_OK);
        assert_eq!((g.a, g.b), ([50.0, 950.0], [650.0, 650.0]));
        assert_eq!(vocc_store_info(ptr::null(), &mut info), VOCC_ERR_NULL);
        assert_eq!(vocc_store_info(s, ptr::null_mut()), VOCC_ERR_NULL);
        vocc_store_free(s);
    }
}

#[test]
fn bad_stores_are_refused_with_the_rule_and_a_null_store() {
    let good = encode_store(&frame(), &records()).unwrap();
    let mut e = blank_error();
    let mut s: *mut VoccStore = ptr::NonNull::dangling().as_ptr();
    let cases: Vec<(Vec<u8>, i32, &str)> = vec![
        (
            good[..100].to_vec(),
            VOCC_ERR_FORMAT,
            "truncated: 136 bytes needed, 100 given",
        ),
        (
            [&b"not a store"[..], &good[11..]].concat(),
            VOCC_ERR_FORMAT,
            "bad magic number: not a vocc store or blob",
        ),
        (
            {
                let mut b = good.clone();
                b[8] = 3;
                b
            },
            VOCC_ERR_VERSION,
            "unsupported major version 3 (this reader implements 1 and 2)",
        ),
        (
            {
                let mut b = good.clone();
                let n = b.len();
                b[n - 1] ^= 0x40;
                b
            },
            VOCC_ERR_CHECKSUM,
            "checksum mismatch",
        ),
    ];
    for (bytes, code, text) in cases {
        let st = unsafe { vocc_store_open(bytes.as_ptr(), bytes.len(), &mut s, &mut e) };
        assert_eq!((st, e.code), (code, code), "{text}");
        assert!(msg(&e).starts_with(text), "{} vs {text}", msg(&e));
        assert!(s.is_null(), "the out-pointer is NULL on failure");
    }
    // A NULL byte pointer with a length, and an empty store.
    unsafe {
        assert_eq!(
            vocc_store_open(ptr::null(), 10, &mut s, &mut e),
            VOCC_ERR_NULL
        );
        assert_eq!(msg(&e), "bytes is NULL");
        assert_eq!(
            vocc_store_open(ptr::null(), 0, &mut s, &mut e),
            VOCC_ERR_FORMAT
        );
        assert_eq!(
            vocc_store_open(good.as_ptr(), good.len(), ptr::null_mut(), &mut e),
            VOCC_ERR_NULL
        );
        assert_eq!(
            vocc_store_open(good.as_ptr(), usize::MAX, &mut s, &mut e),
            VOCC_ERR_ARGUMENT
        );
    }
}
