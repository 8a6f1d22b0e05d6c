//! The bodies of the fuzz targets (`fuzz/fuzz_targets/*.rs`), shared with the corpus replay
//! test (`tests/fuzz_corpus.rs`) so that both run exactly the same code. Not a public API.
//!
//! Input: arbitrary bytes, one function per target. Output: `Ok` with a small summary, or the
//! typed error the library gives for bad input ([`FormatError`], [`LoadError`]).
//! Invariants checked beyond "no panic" (a violated one panics, which the fuzzer reports):
//! - store and blob: each input runs as given, then with its checksum made right, so mutations
//!   reach the rules behind the checksum; both majors are read (2.0 and 1.0);
//! - store: every cell of a parsed store reads without error; a 2.0 store re-encodes to the same
//!   bytes (minor version and checksum aside), a 1.0 store's records to the same 1.0 index and
//!   payload bytes (canonical in its own layout) and to a 2.0 store that reads back the same
//!   records (unless its frame passes rule F12 at level 15 only, FORMAT.md 4.1, which no 2.0
//!   store or blob may carry); each cell's 2.0 blob round-trips; the culler returns ascending in-range ids and never
//!   culls a box that contains the cell;
//! - blob: an accepted blob re-encodes to the same bytes in its own major, an accepted frame to
//!   the same 112 bytes; the culler's invariants as for the store;
//! - scene: object indices follow input order, boxes are finite and not empty, every blocker is
//!   a strictly convex counter-clockwise polygon or a 2-vertex wall, with finite coordinates
//!   and `base < top`;
//! - walkable: every ring has at least 3 finite points;
//! - hashes (a `.hashes` file): an accepted version-2 file re-encodes to the same bytes, and an
//!   accepted shard's index is below its count;
//! - merge (shards of one bake, `merge_shards` splits the input): a merged store parses, has
//!   the shards' cell count, holds every shard's nonempty records and nothing else, carries
//!   hashes of itself that round-trip, and one shard of each index was given.
//!
//! Runtime targets build with `--no-default-features`; scene targets need the `bake` feature.

use crate::runtime::crc::crc32;
use crate::runtime::culler::{pvs, BoxTree};
use crate::runtime::format::{
    decode_blob, decode_frame, encode_blob, encode_frame, encode_store, encode_store_with,
    validate_frame, CellRecord, FormatError, Store, FRAME_LEN, HEADER_LEN,
};
use crate::runtime::{CellId, Frame, GridDescriptor};

/// Cells of a parsed store on which the store target runs the culler.
const CULLED_CELLS: usize = 4;

/// The frame the blob target decodes whole inputs with: per-cell ground (so records carry a
/// ground byte) and a grid of 2^20 cells.
pub const BLOB_FRAME: Frame = Frame {
    origin: [843000.0, 6518000.0, 0.0],
    grid: GridDescriptor {
        min_x: 0.0,
        min_y: 0.0,
        cell_size: 100.0,
        nx: 1024,
        ny: 1024,
    },
    quantum: 0.5,
    eye_lo: 1.5,
    eye_hi: 2.0,
    ground_z0: 160.0,
    ground_step: 0.5,
    h0: 4.0,
    h_ratio: 1.25,
};

/// Fuzz target `store`: [`Store::parse`], then every cell, re-encoding, blobs and the culler;
/// then the same on the input with its checksum made right (the checksum stops nearly every
/// mutation at rule S9, and whoever crafts a file can compute it). Returns the first result, the
/// number of cells.
pub fn store(data: &[u8]) -> Result<u32, FormatError> {
    let first = store_once(data);
    if data.len() >= HEADER_LEN {
        let mut fixed = data.to_vec();
        fixed[CRC_FIELD].fill(0);
        let crc = crc32(&fixed);
        fixed[CRC_FIELD].copy_from_slice(&crc.to_le_bytes());
        if fixed != data {
            let _ = store_once(&fixed);
        }
    }
    first
}

/// Where a store keeps its CRC-32 (FORMAT.md section 5.1).
const CRC_FIELD: std::ops::Range<usize> = 132..136;

fn store_once(data: &[u8]) -> Result<u32, FormatError> {
    let s = Store::parse(data)?;
    let f = *s.frame();
    let n = s.cell_count();
    // Parse checked the length: one index byte per cell, so this is bounded by the input.
    // A 2.0 store's frame passes the rules of a frame on its own; a 1.0 store's may not (F12
    // at level 15 only, FORMAT.md 4.1): then it has no 2.0 blobs or 2.0 store.
    let frame_alone = validate_frame(&f);
    assert!(
        s.major() == 1 || frame_alone.is_ok(),
        "a 2.0 store's frame: {frame_alone:?}"
    );
    let mut cells = Vec::with_capacity(n as usize);
    for id in 0..n {
        let rec = s
            .cell(id)
            .unwrap_or_else(|e| panic!("cell {id} of a parsed store: {e}"));
        if frame_alone.is_ok() {
            let blob = encode_blob(&f, id, &rec)
                .unwrap_or_else(|e| panic!("cell {id} of a parsed store does not encode: {e}"));
            assert_eq!(decode_blob(&f, &blob), Ok((id, rec)), "cell {id}'s blob");
        }
        cells.push(rec);
    }
    assert!(s.cell(n).is_err(), "a cell past the grid must be an error");
    if s.major() == 2 {
        let again = encode_store_with(&f, &cells, &s.scene_section())
            .expect("an accepted store re-encodes");
        assert_eq!(again.len(), data.len(), "re-encoded length");
        assert_eq!(again[..10], data[..10], "magic and major");
        assert_eq!(again[12..132], data[12..132], "flags, frame, payload_len");
        assert_eq!(
            again[136..],
            data[136..],
            "scene section, index, block table, payload"
        );
    } else {
        // 1.0: canonical in its own layout (the index and payload its records give), and the
        // same records as a 2.0 store, unless its frame's top of level 31 is not finite (F12).
        let index = HEADER_LEN + n as usize;
        let payload = index + 4 * (n as usize).div_ceil(64);
        let idx: Vec<u8> = cells.iter().map(|r| r.index_byte()).collect();
        assert_eq!(data[HEADER_LEN..index], idx[..], "1.0 index");
        let mut p = Vec::new();
        for rec in &cells {
            push_v1_record(&mut p, &f, rec);
        }
        assert_eq!(data[payload..], p[..], "1.0 payload");
        match encode_store(&f, &cells) {
            Ok(v2) => {
                let s2 = Store::parse(&v2).expect("a 1.0 store's records encode as 2.0");
                for (id, rec) in cells.iter().enumerate() {
                    assert_eq!(s2.cell(id as CellId).as_ref(), Ok(rec), "cell {id} in 2.0");
                }
            }
            Err(FormatError::BadFrame(r)) if frame_alone.is_err() && r.starts_with("F12") => {}
            Err(e) => panic!("a 1.0 store's records do not encode as 2.0: {e}"),
        }
    }
    let with_vos = cells
        .iter()
        .enumerate()
        .filter(|(_, r)| !r.vos().is_empty())
        .map(|(i, _)| i as CellId);
    let picks = [0, n - 1].into_iter().chain(with_vos.take(CULLED_CELLS));
    for id in picks {
        check_culler(&f, id, &cells[id as usize]);
    }
    Ok(n)
}

/// Fuzz target `blob`: the whole input as a blob of [`BLOB_FRAME`]; then, when there are at
/// least 112 bytes, the first 112 as a frame and the rest as a blob of that frame. Each blob is
/// decoded as given and again with its checksum made right (as for [`store`]). Returns the
/// result of the blob decoded as given with the input's own frame (with [`BLOB_FRAME`] when the
/// input is shorter than a frame).
pub fn blob(data: &[u8]) -> Result<CellId, FormatError> {
    let fixed = blob_with(&BLOB_FRAME, data);
    let Some((head, rest)) = data.split_first_chunk::<FRAME_LEN>() else {
        return fixed;
    };
    let f = decode_frame(head)?;
    assert_eq!(&encode_frame(&f), head, "an accepted frame re-encodes");
    blob_with(&f, rest)
}

fn blob_with(f: &Frame, bytes: &[u8]) -> Result<CellId, FormatError> {
    let first = blob_once(f, bytes);
    if let Some((body, _)) = bytes.split_last_chunk::<4>() {
        let mut fixed = body.to_vec();
        fixed.extend_from_slice(&crc32(body).to_le_bytes());
        if fixed != bytes {
            let _ = blob_once(f, &fixed);
        }
    }
    first
}

fn blob_once(f: &Frame, bytes: &[u8]) -> Result<CellId, FormatError> {
    let (id, rec) = decode_blob(f, bytes)?;
    if bytes.get(4) == Some(&1) {
        // 1.0: the same bytes in its own layout; and a 2.0 blob of the same record.
        let mut v1 = b"VOCB\x01".to_vec();
        v1.extend_from_slice(&id.to_le_bytes());
        v1.push(rec.index_byte());
        push_v1_record(&mut v1, f, &rec);
        v1.extend_from_slice(&crc32(&v1).to_le_bytes());
        assert_eq!(v1, bytes, "an accepted 1.0 blob re-encodes");
        let v2 = encode_blob(f, id, &rec).expect("a 1.0 blob's record encodes as 2.0");
        assert_eq!(decode_blob(f, &v2), Ok((id, rec)), "a 1.0 blob as 2.0");
    } else {
        assert_eq!(
            encode_blob(f, id, &rec).as_deref(),
            Ok(bytes),
            "an accepted blob re-encodes"
        );
    }
    check_culler(f, id, &rec);
    Ok(id)
}

/// A record as 1.0 stores it (FORMAT.md section 12): the ground byte when the frame has one,
/// then 5 bytes per VO. Only for records a 1.0 decoder gave.
fn push_v1_record(out: &mut Vec<u8>, f: &Frame, rec: &CellRecord) {
    if rec.vos().is_empty() {
        return;
    }
    if f.per_cell_ground() {
        out.push(rec.ground());
    }
    for q in rec.vos() {
        assert!(q.fits_v1(), "a 1.0 decoder gave {q:?}");
        out.extend_from_slice(&q.to_bytes_v1());
    }
}

/// Runs the culler on cell `id` over boxes around it: the ids come out ascending and in range,
/// and a box that contains the cell (it holds the eyes) is never culled.
fn check_culler(f: &Frame, id: CellId, rec: &CellRecord) {
    let Some(view) = f.cell_view(id, rec.stand()) else {
        panic!("cell {id} of an accepted frame has no view");
    };
    let [x0, y0, x1, y1] = view.rect;
    let s = f.grid.cell_size;
    let g = f.ground_z(rec.ground());
    // Box 0 holds the cell and its eyes; the others tile a ring of 8 cells around it, low and
    // tall, as the culler's typical occludees.
    let mut boxes = vec![[
        x0 - 0.5 * s,
        y0 - 0.5 * s,
        g,
        x1 + 0.5 * s,
        y1 + 0.5 * s,
        view.e1 + 1.0,
    ]];
    for k in 0..16 {
        let (i, j) = ((k % 4) as f64, (k / 4) as f64);
        let bx = x0 + (i - 1.5) * 2.0 * s;
        let by = y0 + (j - 1.5) * 2.0 * s;
        let top = if k % 2 == 0 { g + 1.0 } else { g + 3.0 * s };
        boxes.push([bx, by, g, bx + s, by + s, top]);
    }
    let tree = BoxTree::new(&boxes);
    let mut out = Vec::new();
    pvs(f, id, rec, &tree, &mut out);
    assert!(
        out.windows(2).all(|w| w[0] < w[1]),
        "PVS ids must ascend: {out:?}"
    );
    assert!(out.iter().all(|&i| (i as usize) < boxes.len()), "{out:?}");
    if boxes[0].iter().all(|x| x.is_finite()) {
        assert_eq!(
            out.first(),
            Some(&0),
            "cell {id}: the box holding the cell was culled"
        );
    }
}

#[cfg(feature = "bake")]
pub use bake_targets::*;
#[cfg(feature = "bake")]
pub use scene_targets::*;

#[cfg(feature = "bake")]
mod bake_targets {
    use crate::bake::incremental::{CellHashes, HashesError};
    use crate::bake::merge::{merge, MergeError, ShardBytes};
    use crate::runtime::crc::crc32;
    use crate::runtime::format::{CellRecord, Store, HEADER_LEN};

    /// Fuzz target `hashes`: [`CellHashes::decode`], then the same on the input with its
    /// trailing checksum made right. Returns the first result, the number of cells.
    pub fn hashes(data: &[u8]) -> Result<usize, HashesError> {
        let first = hashes_once(data);
        if let Some(body) = data.len().checked_sub(4).map(|n| &data[..n]) {
            let mut fixed = body.to_vec();
            fixed.extend_from_slice(&crc32(body).to_le_bytes());
            if fixed != data {
                let _ = hashes_once(&fixed);
            }
        }
        first
    }

    fn hashes_once(data: &[u8]) -> Result<usize, HashesError> {
        let h = CellHashes::decode(data)?;
        if data[8] == 2 {
            assert_eq!(
                h.encode(),
                data,
                "a version-2 hashes file re-encodes to its bytes"
            );
        }
        if let Some((i, n)) = h.shard {
            assert!(i < n, "shard {i} of {n} accepted");
        }
        Ok(h.cells.len())
    }

    /// The merge target's input as shards: the first byte gives their number (1 to 4), then
    /// each is a `u16` length and a store's bytes, a `u16` length and a `.hashes` file's bytes
    /// (little-endian; cut short where the input ends).
    pub fn merge_shards(data: &[u8]) -> Vec<(Vec<u8>, Vec<u8>)> {
        let Some((&k, mut rest)) = data.split_first() else {
            return Vec::new();
        };
        let mut take = || {
            let n = match rest {
                [a, b, ..] => u16::from_le_bytes([*a, *b]) as usize,
                _ => 0,
            };
            let r = rest.get(2..).unwrap_or(&[]);
            let (part, tail) = r.split_at(n.min(r.len()));
            rest = tail;
            part.to_vec()
        };
        (0..1 + k % 4).map(|_| (take(), take())).collect()
    }

    /// The inverse of [`merge_shards`], for seeds.
    pub fn merge_input(shards: &[(&[u8], &[u8])]) -> Vec<u8> {
        let mut out = vec![(shards.len() as u8).wrapping_sub(1)];
        for (s, h) in shards {
            for part in [s, h] {
                out.extend_from_slice(&(part.len() as u16).to_le_bytes());
                out.extend_from_slice(part);
            }
        }
        out
    }

    /// Fuzz target `merge`: [`merge`] on the shards of [`merge_shards`], then again with every
    /// store's checksum made right and every hashes file pointed at its store (its store
    /// checksum and its own checksum made right), so mutations reach the merge's own rules.
    /// Returns the first result, the merged store's length.
    pub fn merge_target(data: &[u8]) -> Result<usize, MergeError> {
        let mut shards = merge_shards(data);
        let first = merge_once(&shards);
        for (s, h) in &mut shards {
            if s.len() >= HEADER_LEN {
                s[132..136].fill(0);
                let crc = crc32(s);
                s[132..136].copy_from_slice(&crc.to_le_bytes());
            }
            if h.len() >= 24 {
                h[16..20].copy_from_slice(&crc32(s).to_le_bytes());
                let n = h.len() - 4;
                let crc = crc32(&h[..n]);
                h[n..].copy_from_slice(&crc.to_le_bytes());
            }
        }
        let _ = merge_once(&shards);
        first
    }

    fn merge_once(shards: &[(Vec<u8>, Vec<u8>)]) -> Result<usize, MergeError> {
        let given: Vec<ShardBytes> = shards
            .iter()
            .map(|(store, hashes)| ShardBytes { store, hashes })
            .collect();
        let m = merge(&given)?;
        let out = Store::parse(&m.store).expect("the merged store parses");
        let parts: Vec<Store> = shards
            .iter()
            .map(|(s, _)| Store::parse(s).expect("a merged shard parses"))
            .collect();
        assert_eq!(m.count as usize, shards.len(), "one shard of each index");
        assert_eq!(m.cells_from.len(), shards.len());
        assert_eq!(out.cell_count(), parts[0].cell_count());
        for id in 0..out.cell_count() {
            let r = out.cell(id).expect("a merged cell reads");
            let mut from = 0;
            for p in &parts {
                let q = p.cell(id).expect("a merged shard's cell reads");
                if q != CellRecord::EMPTY {
                    assert_eq!(q, r, "cell {id}: a shard's record is kept");
                    from += 1;
                }
            }
            assert!(
                from > 0 || r == CellRecord::EMPTY,
                "cell {id}: from no shard"
            );
        }
        assert_eq!(m.hashes.store_crc, crc32(&m.store));
        assert_eq!(m.hashes.shard, None);
        assert_eq!(CellHashes::decode(&m.hashes.encode()), Ok(m.hashes.clone()));
        Ok(m.store.len())
    }
}

#[cfg(feature = "bake")]
mod scene_targets {
    use std::path::{Path, PathBuf};

    use glam::DVec3;

    use crate::geom::predicates::is_convex_piece;
    use crate::scene::{load_bytes, summary, walkable, LoadError, ReadOptions};

    /// Reader options of the scene targets: GeoJSON heights from `height`, or `levels` storeys.
    pub fn scene_options() -> ReadOptions {
        ReadOptions {
            height_attr: Some("height".into()),
            levels_attr: Some("levels".into()),
            ..ReadOptions::default()
        }
    }

    /// The scene targets' body: the whole load ([`load_bytes`]: reader, local frame,
    /// ring repair, convex decomposition, solids), then the scene's invariants and its summary.
    /// Returns the number of objects.
    pub fn scene(file_name: &str, data: &[u8]) -> Result<usize, LoadError> {
        scene_with(file_name, data, &scene_options())
    }

    /// [`scene`] with other reader options.
    pub fn scene_with(
        file_name: &str,
        data: &[u8],
        opts: &ReadOptions,
    ) -> Result<usize, LoadError> {
        let s = load_bytes(&[(PathBuf::from(file_name), data)], opts)?;
        for (i, o) in s.objects.iter().enumerate() {
            assert_eq!(o.index as usize, i, "object indices follow input order");
            let b = o.bbox;
            assert!(
                !b.is_empty() && b.min.is_finite() && b.max.is_finite(),
                "object {i}: box {b:?}"
            );
        }
        assert!(
            s.objects.windows(2).all(|w| w[0].feature < w[1].feature),
            "input feature numbers out of order"
        );
        let mut last = 0;
        for (k, b) in s.blockers.iter().enumerate() {
            assert!(
                (b.object as usize) < s.objects.len() && b.object >= last,
                "blocker {k}: object {} out of order",
                b.object
            );
            last = b.object;
            assert!(
                b.polygon.iter().all(|p| p.is_finite()) && is_convex_piece(&b.polygon),
                "blocker {k} is neither strictly convex and counter-clockwise nor a wall: {:?}",
                b.polygon
            );
            assert!(
                b.base.is_finite() && b.top.is_finite() && b.base < b.top,
                "blocker {k}: base {} top {}",
                b.base,
                b.top
            );
        }
        let _ = summary::summarize(&s);
        Ok(s.objects.len())
    }

    /// Fuzz target `geojson`: [`scene`] as `fuzz.geojson`.
    pub fn geojson(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.geojson", data)
    }

    /// Fuzz target `cityjson`: [`scene`] as `fuzz.json` (GeoJSON or CityJSON by content).
    pub fn cityjson(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.json", data)
    }

    /// Fuzz target `obj`: [`scene`] as `fuzz.obj`.
    pub fn obj(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.obj", data)
    }

    /// Fuzz target `osm`: [`scene`] as `fuzz.osm.pbf` (OpenStreetMap tags give the heights).
    pub fn osm(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.osm.pbf", data)
    }

    /// Fuzz target `gpkg`: [`scene`] as `fuzz.gpkg` (a SQLite database from memory).
    pub fn gpkg(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.gpkg", data)
    }

    /// Fuzz target `fgb`: [`scene`] as `fuzz.fgb`.
    pub fn fgb(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.fgb", data)
    }

    /// Fuzz target `shp`: [`scene_with`] as `fuzz.shp`, alone (no `.dbf`, so heights come from a
    /// default height of 10 m).
    pub fn shp(data: &[u8]) -> Result<usize, LoadError> {
        let opts = ReadOptions {
            default_height: Some(10.0),
            ..ReadOptions::default()
        };
        scene_with("fuzz.shp", data, &opts)
    }

    /// Fuzz target `citygml`: [`scene`] as `fuzz.gml`.
    pub fn citygml(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.gml", data)
    }

    /// Fuzz target `cityjsonseq`: [`scene`] as `fuzz.city.jsonl`.
    pub fn cityjsonseq(data: &[u8]) -> Result<usize, LoadError> {
        scene("fuzz.city.jsonl", data)
    }

    /// World origin the walkable target subtracts (Lyon's, as the seeds are from Lyon).
    pub const WALKABLE_ORIGIN: DVec3 = DVec3::new(1_842_000.0, 5_175_000.0, 0.0);

    /// Fuzz target `dem`: a GeoTIFF DEM (`scene/dem.rs`), all of it kept, then the terrain and
    /// its blockers built from it (a small image's). Checks: every triangle finite, every
    /// terrain blocker a square standing from the floor to a top above it.
    pub fn dem(data: &[u8]) -> Result<usize, LoadError> {
        let d = crate::scene::dem::read_dem(Path::new("fuzz.tif"), data, None)?;
        assert!(d.triangles.iter().flatten().all(|p| p.is_finite()));
        let n = d.triangles.len();
        if n > 0 && n <= 20_000 {
            let o = d.triangles[0][0];
            let local = d.triangles.iter().map(|t| t.map(|p| p - o)).collect();
            if let Some(t) = crate::scene::Terrain::new(Vec::new(), local) {
                for b in &t.blockers {
                    assert!(b.polygon.len() == 4 && b.top > b.base && b.base == t.floor);
                }
            }
        }
        Ok(n)
    }

    /// Fuzz target `walkable`: the `--walkable` reader, then cell selection over a 4 x 4 grid laid
    /// on the area's extent. Returns the number of rings.
    pub fn walkable(data: &[u8]) -> Result<usize, LoadError> {
        let area = walkable::read_bytes(Path::new("fuzz-cells.geojson"), data, WALKABLE_ORIGIN)?;
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for ring in &area {
            assert!(ring.len() >= 3, "a ring of {} points", ring.len());
            for p in ring {
                assert!(p.is_finite(), "walkable point {p}");
                lo = [lo[0].min(p.x), lo[1].min(p.y)];
                hi = [hi[0].max(p.x), hi[1].max(p.y)];
            }
        }
        let (w, h) = ((hi[0] - lo[0]) / 4.0, (hi[1] - lo[1]) / 4.0);
        let mut met = 0;
        for k in 0..16 {
            let (i, j) = ((k % 4) as f64, (k / 4) as f64);
            // The last column and row end exactly at the extent, so the cells tile it.
            let edge = |lo: f64, hi: f64, step: f64, k: f64| {
                if k == 4.0 {
                    hi
                } else {
                    lo + k * step
                }
            };
            let r = [
                edge(lo[0], hi[0], w, i),
                edge(lo[1], hi[1], h, j),
                edge(lo[0], hi[0], w, i + 1.0),
                edge(lo[1], hi[1], h, j + 1.0),
            ];
            met += walkable::rect_meets_area(r, &area) as usize;
        }
        // The grid covers every ring vertex, so some cell meets the area.
        assert!(met > 0, "no cell of the area's own extent meets it");
        Ok(area.len())
    }
}
