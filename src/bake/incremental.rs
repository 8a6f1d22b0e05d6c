//! Incremental rebake: a content hash per cell over everything that cell's bake reads, so a
//! changed scene rebakes only the cells whose neighbourhood changed.
//!
//! Input: a [`Plan`] (scene, options, frame) and the cells it bakes.
//! Output: [`CellHashes`]: one hash of everything global (the code: vocc version and source
//! fingerprint, [`CODE`]; options, frame) and one
//! hash per cell (0 for a cell this bake leaves empty); their file form (the `.hashes` file beside
//! a store, [`CellHashes::encode`]); and, against an older bake's hashes, the cells to rebake
//! ([`CellHashes::changed`]).
//! Invariant (what makes reuse exact): the bake of cell `c` reads the frame, the options, and
//! only objects (their boxes, costs and blockers) in three squares ([`Plan::reaches`]):
//! - `centre(c) ± near`, in index order: the inside test and both generators' blockers are
//!   R-tree queries within `cell ± search_m` (`cell::usable`; rays in the growth are filtered to
//!   those), the ground level within `cell ± 50 m`, or a wider square up to `cell ± search_m`
//!   when that one holds no blocker, every blocker lying inside its object's box;
//! - `centre(c) ± weigh`, as a set: the occludee weights come from boxes meeting the umbra box,
//!   clamped to the weighing square of the cell or of its block (`occludees::Occludees::hidden`),
//!   and are sums of costs over sets of occludees, so the objects' order does not enter;
//! - `centre(block(c)) ± block`, in index order: what the far field's block reads
//!   (`far::block_pieces`: its blockers, its cells' grounds);
//! - ids enter only through comparisons and sorting, so only their relative order matters, and
//!   an edit elsewhere in the file does not change a cell's hash.
//!
//! Cost: the ordered squares are listed per cell (near, about 1 km) and per block (the block's
//! reach, once for its cells); the weighing square, 20 km across by default, is hashed as a
//! set from per-bucket sums (2D prefix sums over buckets of whole cells), in constant time per
//! cell, so hashing a city of 10^6 buildings takes seconds, not the hours that listing 10 km
//! around every cell took.
//!
//! The cell hash covers those objects, the near and the block's in index order; so two bakes
//! with equal global hashes and an equal cell hash give that cell the same record, and
//! `tests/incremental.rs` checks that an incremental rebake is byte-identical to a full bake. The hash is a 64-bit mix (splitmix64
//! finalizer per word), stable across platforms and runs; it guards against accidental change,
//! not against an adversary.

use rstar::primitives::{GeomWithData, Rectangle};
use rstar::{RTree, AABB};

use super::growth::GrowParams;
use super::params::BakeParams;
use super::plan::Plan;
use crate::runtime::format::encode_frame;
use crate::runtime::grid::CellId;

/// Magic of a `.hashes` file.
pub const MAGIC: [u8; 8] = *b"VOCCHASH";
/// Version of the `.hashes` layout this vocc writes (it reads 1 and 2; 2 adds the shard).
pub const VERSION: u16 = 2;
/// Bytes before the per-cell hashes of version 1: magic, version, reserved, cell count, store
/// checksum, global hash.
const HEADER_LEN_V1: usize = 8 + 2 + 2 + 4 + 4 + 8;
/// Version 2 adds the shard index and count (`u32` each) after the global hash.
const HEADER_LEN: usize = HEADER_LEN_V1 + 4 + 4;

/// The content hashes of one bake.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CellHashes {
    /// vocc version, bake options (all but the cell selection) and frame.
    pub global: u64,
    /// Per cell, in id order; 0 where the bake left the cell empty (outside the region, walkable
    /// area or shard).
    pub cells: Vec<u64>,
    /// CRC-32 of the store file these hashes describe (0 until [`Self::encode`] is given it), so
    /// hashes beside another store than their own are never trusted.
    pub store_crc: u32,
    /// `(index, count)` when the bake was one shard of `count` (`vocc bake --shard I/N`); `None`
    /// for a whole bake or a merge, and in version 1 files.
    pub shard: Option<(u32, u32)>,
}

/// Why a `.hashes` file was refused.
#[derive(Clone, Debug, thiserror::Error, PartialEq, Eq)]
pub enum HashesError {
    #[error("not a vocc hashes file (bad magic)")]
    Magic,
    #[error("hashes file version {0} is not supported (this vocc reads 1 and 2)")]
    Version(u16),
    #[error("hashes file is {got} bytes, its header says {want}")]
    Length { got: usize, want: usize },
    #[error("hashes file checksum mismatch: the file is damaged")]
    Checksum,
    /// The rule that a shard's index is below the shard count (`--shard I/N` takes `I < N`).
    #[error("hashes file records shard {index} of {count}: a shard index must be below the count")]
    ShardIndex { index: u32, count: u32 },
}

/// The text of every bake option but the cell selection, as the global hash takes it: the
/// `Debug` form of one tuple, in the layout of the first `.hashes` files (a changed layout would
/// refuse every older bake's reuse). `search_m` is printed inside the growth's parameters, where
/// it stood then ([`GrowKey`]).
fn options_key(p: &BakeParams) -> String {
    // Every field by name, without `..`: a field added to `BakeParams` does not compile until it
    // is placed here (in the key, or named as cell selection).
    let BakeParams {
        cell_size,
        eye,
        slices,
        max_vos,
        bytes_per_cell,
        region: _,
        walkable: _,
        search_m,
        grow,
        generator,
        weigh_m,
        map,
        propose,
        budget,
        far,
    } = p;
    format!(
        "{:?}",
        (
            cell_size,
            eye,
            slices,
            max_vos,
            bytes_per_cell,
            GrowKey(grow, *search_m),
            generator,
            weigh_m,
            map,
            propose,
            budget,
            far
        )
    )
}

/// [`GrowParams`] with `search_m` among its fields, printed as the derived `Debug` printed the
/// struct that held both: `GrowParams { seeds: 8, search_m: 900.0, max_chain: 24, .. }`.
struct GrowKey<'a>(&'a GrowParams, f64);

impl std::fmt::Debug for GrowKey<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // Every field by name: a field added to `GrowParams` does not compile until it is
        // placed here.
        let GrowParams {
            seeds,
            max_chain,
            max_bridges,
            tries,
            min_vo_m,
            single_object,
            verify,
        } = self.0;
        f.debug_struct("GrowParams")
            .field("seeds", seeds)
            .field("search_m", &self.1)
            .field("max_chain", max_chain)
            .field("max_bridges", max_bridges)
            .field("tries", tries)
            .field("min_vo_m", min_vo_m)
            .field("single_object", single_object)
            .field("verify", verify)
            .finish()
    }
}

/// The objects' hashes summed per bucket (a square of whole cells, at least [`BUCKET_M`] on a
/// side) and as 2D prefix sums, so the multiset of objects meeting any square of buckets hashes
/// in constant time: each object adds, wrapping, a mix of its hash and the bucket's index to every
/// bucket its box meets. A square around a cell takes every bucket it meets, so it covers every
/// object whose box meets the square (and a little more). No ids: the weights that read these
/// objects are sums of costs over sets.
struct BucketSums {
    min: [f64; 2],
    side: f64,
    n: [usize; 2],
    /// `(n[0] + 1) * (n[1] + 1)` prefix sums, row-major.
    prefix: Vec<u64>,
}

/// The smallest bucket side, metres: coarse enough that a large object meets few buckets, fine
/// enough that a square of 10 km takes at most this much more around it.
const BUCKET_M: f64 = 100.0;

impl BucketSums {
    fn new(plan: &Plan, object: &[Mix]) -> BucketSums {
        let g = &plan.frame.grid;
        let k = (BUCKET_M / g.cell_size).ceil().max(1.0);
        let side = k * g.cell_size;
        let n = [
            (g.nx as usize).div_ceil(k as usize).max(1),
            (g.ny as usize).div_ceil(k as usize).max(1),
        ];
        let mut b = BucketSums {
            min: [g.min_x, g.min_y],
            side,
            n,
            prefix: vec![0; (n[0] + 1) * (n[1] + 1)],
        };
        let w = n[0] + 1;
        for (o, h) in plan.scene().objects.iter().zip(object) {
            let (i0, i1) = b.range(0, o.bbox.min.x, o.bbox.max.x);
            let (j0, j1) = b.range(1, o.bbox.min.y, o.bbox.max.y);
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let mut m = Mix::new(6);
                    m.word((j * n[0] + i) as u64);
                    m.word(h.0);
                    let at = &mut b.prefix[(j + 1) * w + i + 1];
                    *at = at.wrapping_add(m.0);
                }
            }
        }
        for j in 1..=n[1] {
            for i in 1..=n[0] {
                let v = b.prefix[j * w + i]
                    .wrapping_add(b.prefix[(j - 1) * w + i])
                    .wrapping_add(b.prefix[j * w + i - 1])
                    .wrapping_sub(b.prefix[(j - 1) * w + i - 1]);
                b.prefix[j * w + i] = v;
            }
        }
        b
    }

    /// The buckets along `axis` that `[lo, hi]` meets, clamped to the grid (rounding is
    /// monotone, so two intervals that meet share a bucket).
    fn range(&self, axis: usize, lo: f64, hi: f64) -> (usize, usize) {
        let at = |v: f64| {
            let f = ((v - self.min[axis]) / self.side).floor();
            if f >= (self.n[axis] - 1) as f64 {
                self.n[axis] - 1
            } else if f >= 0.0 {
                f as usize
            } else {
                0
            }
        };
        (at(lo), at(hi))
    }

    /// The hash of the objects meeting the buckets that `centre ± half` meets.
    fn sum(&self, (cx, cy): (f64, f64), half: f64) -> u64 {
        let (i0, i1) = self.range(0, cx - half, cx + half);
        let (j0, j1) = self.range(1, cy - half, cy + half);
        let w = self.n[0] + 1;
        let p = &self.prefix;
        p[(j1 + 1) * w + i1 + 1]
            .wrapping_sub(p[j0 * w + i1 + 1])
            .wrapping_sub(p[(j1 + 1) * w + i0])
            .wrapping_add(p[j0 * w + i0])
    }
}

/// A running 64-bit hash: each word is mixed in with the splitmix64 finalizer.
#[derive(Clone, Copy)]
struct Mix(u64);

impl Mix {
    fn new(tag: u64) -> Mix {
        Mix(tag ^ 0x5bd1_e995_9e37_79b9)
    }

    fn word(&mut self, w: u64) {
        let mut z = (self.0 ^ w).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        self.0 = z ^ (z >> 31);
    }

    fn f64(&mut self, x: f64) {
        self.word(x.to_bits());
    }

    fn bytes(&mut self, b: &[u8]) {
        for c in b.chunks(8) {
            let mut w = [0u8; 8];
            w[..c.len()].copy_from_slice(c);
            self.word(u64::from_le_bytes(w));
        }
        self.word(b.len() as u64);
    }

    /// Never 0 (0 marks an unbaked cell).
    fn finish(self) -> u64 {
        self.0.max(1)
    }
}

/// The code that bakes, as the global hash takes it: the package version and the fingerprint of
/// the library's sources (`build.rs`), so that hashes written by another build, even of the same
/// version, never let `--reuse` copy a record this build would bake differently.
pub const CODE: &str = concat!(env!("CARGO_PKG_VERSION"), "+", env!("VOCC_SOURCE_HASH"));

impl CellHashes {
    /// The hashes of `cells` (ascending ids) under `plan`; every other cell gets 0.
    pub fn new(plan: &Plan, cells: &[CellId]) -> CellHashes {
        Self::by_code(plan, cells, CODE)
    }

    /// [`Self::new`] as the build named `code` (its [`CODE`]) would write them.
    fn by_code(plan: &Plan, cells: &[CellId], code: &str) -> CellHashes {
        use rayon::prelude::*;
        let scene = plan.scene();
        let mut g = Mix::new(1);
        g.bytes(code.as_bytes());
        // Every option but the cell selection (region, walkable area), which the zero hash of an
        // unbaked cell records.
        g.bytes(options_key(plan.params()).as_bytes());
        g.bytes(&encode_frame(&plan.frame));
        // The terrain's blockers and every cell's ground (bake/terrain.rs) in the global hash:
        // a changed terrain rebakes every cell.
        for b in scene.terrain_blockers() {
            for v in &b.polygon {
                g.f64(v.x);
                g.f64(v.y);
            }
            g.f64(b.base);
            g.f64(b.top);
        }
        if let Some(t) = &plan.ground {
            g.bytes(&t.levels);
            g.bytes(&t.rises);
            for &f in &t.fits {
                g.word(f as u64);
            }
        }
        // One hash per object: its box, cost and blockers (blockers are grouped by object).
        let mut object = vec![Mix::new(2); scene.objects.len()];
        for (h, o) in object.iter_mut().zip(&scene.objects) {
            for x in [o.bbox.min, o.bbox.max] {
                h.f64(x.x);
                h.f64(x.y);
                h.f64(x.z);
            }
            h.word(o.cost);
        }
        for b in &scene.blockers {
            let h = &mut object[b.object as usize];
            h.word(b.polygon.len() as u64);
            for v in &b.polygon {
                h.f64(v.x);
                h.f64(v.y);
            }
            h.f64(b.base);
            h.f64(b.top);
        }
        let tree: RTree<GeomWithData<Rectangle<[f64; 2]>, u32>> = RTree::bulk_load(
            scene
                .objects
                .iter()
                .enumerate()
                .map(|(i, o)| {
                    GeomWithData::new(
                        Rectangle::from_corners(
                            [o.bbox.min.x, o.bbox.min.y],
                            [o.bbox.max.x, o.bbox.max.y],
                        ),
                        i as u32,
                    )
                })
                .collect(),
        );
        // The objects meeting `centre ± half`, ascending ids, each one's hash in that order.
        let ordered = |tag: u64, (cx, cy): (f64, f64), half: f64| {
            let mut ids: Vec<u32> = tree
                .locate_in_envelope_intersecting(AABB::from_corners(
                    [cx - half, cy - half],
                    [cx + half, cy + half],
                ))
                .map(|o| o.data)
                .collect();
            ids.sort_unstable();
            let mut h = Mix::new(tag);
            h.word(ids.len() as u64);
            for i in ids {
                h.word(object[i as usize].0);
            }
            h.finish()
        };
        let grid = &plan.frame.grid;
        let reaches = plan.reaches();
        // The far field's blocks: one ordered hash per block that a baked cell belongs to.
        let blocks = plan.blocks;
        let mut wanted = vec![false; blocks.count()];
        for b in cells.iter().filter_map(|&id| plan.block_of(id)) {
            wanted[b] = true;
        }
        let block_hash: Vec<u64> = (0..wanted.len())
            .into_par_iter()
            .map(|b| {
                if !wanted[b] {
                    return 0;
                }
                let side = blocks.side as f64 * grid.cell_size;
                let (bi, bj) = (b % blocks.nx as usize, b / blocks.nx as usize);
                let centre = (
                    grid.min_x + (bi as f64 + 0.5) * side,
                    grid.min_y + (bj as f64 + 0.5) * side,
                );
                ordered(4, centre, reaches.block)
            })
            .collect();
        let weights = BucketSums::new(plan, &object);
        let per_cell: Vec<(CellId, u64)> = cells
            .par_iter()
            .map(|&id| {
                let [cx, cy] = plan.frame.cell_centre(id).unwrap_or([0.0; 2]);
                let mut h = Mix::new(3);
                h.word(g.0);
                h.word(ordered(5, (cx, cy), reaches.near));
                h.word(weights.sum((cx, cy), reaches.weigh));
                if let Some(b) = plan.block_of(id) {
                    h.word(block_hash[b]);
                }
                (id, h.finish())
            })
            .collect();
        let mut out = vec![0u64; plan.frame.grid.cell_count() as usize];
        for (id, h) in per_cell {
            out[id as usize] = h;
        }
        CellHashes {
            global: g.finish(),
            cells: out,
            store_crc: 0,
            shard: None,
        }
    }

    /// The cells of `wanted` to bake given an older bake's hashes `old`: all of them if the
    /// global hashes or the cell counts differ, else those whose hash differs.
    pub fn changed(&self, old: &CellHashes, wanted: &[CellId]) -> Vec<CellId> {
        if self.global != old.global || self.cells.len() != old.cells.len() {
            return wanted.to_vec();
        }
        wanted
            .iter()
            .copied()
            .filter(|&id| {
                let i = id as usize;
                self.cells[i] == 0 || self.cells[i] != old.cells[i]
            })
            .collect()
    }

    /// The file form (version 2): magic, version (u16), reserved (u16, 0), cell count (u32),
    /// CRC-32 of the store (u32), global hash (u64), shard index (u32) and count (u32; 0 when
    /// not a shard), one u64 per cell, CRC-32 of all before it; little-endian.
    pub fn encode(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(HEADER_LEN + 8 * self.cells.len() + 4);
        b.extend_from_slice(&MAGIC);
        b.extend_from_slice(&VERSION.to_le_bytes());
        b.extend_from_slice(&0u16.to_le_bytes());
        b.extend_from_slice(&(self.cells.len() as u32).to_le_bytes());
        b.extend_from_slice(&self.store_crc.to_le_bytes());
        b.extend_from_slice(&self.global.to_le_bytes());
        let (i, n) = self.shard.unwrap_or((0, 0));
        b.extend_from_slice(&i.to_le_bytes());
        b.extend_from_slice(&n.to_le_bytes());
        for h in &self.cells {
            b.extend_from_slice(&h.to_le_bytes());
        }
        let crc = crate::runtime::crc::crc32(&b);
        b.extend_from_slice(&crc.to_le_bytes());
        b
    }

    /// The hashes in the file form [`Self::encode`] writes (or version 1). Refuses, naming the
    /// rule: another magic, another version, a length other than the header's cell count says, a
    /// wrong checksum, and a shard index at or above the shard count.
    pub fn decode(b: &[u8]) -> Result<CellHashes, HashesError> {
        if b.len() < HEADER_LEN_V1 + 4 || b[..8] != MAGIC {
            return Err(HashesError::Magic);
        }
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        let u32_at = |i: usize| u32::from_le_bytes(b[i..i + 4].try_into().expect("4 bytes"));
        let u64_at = |i: usize| u64::from_le_bytes(b[i..i + 8].try_into().expect("8 bytes"));
        let head = match u16_at(8) {
            1 => HEADER_LEN_V1,
            2 if b.len() >= HEADER_LEN + 4 => HEADER_LEN,
            2 => return Err(HashesError::Magic),
            v => return Err(HashesError::Version(v)),
        };
        let n = u32_at(12) as usize;
        let want = (n as u64)
            .checked_mul(8)
            .and_then(|x| x.checked_add(head as u64 + 4))
            .unwrap_or(u64::MAX);
        if b.len() as u64 != want {
            return Err(HashesError::Length {
                got: b.len(),
                want: want.min(usize::MAX as u64) as usize,
            });
        }
        let want = want as usize;
        let body = &b[..want - 4];
        if crate::runtime::crc::crc32(body).to_le_bytes() != b[want - 4..] {
            return Err(HashesError::Checksum);
        }
        let shard = (head == HEADER_LEN && u32_at(32) != 0).then(|| (u32_at(28), u32_at(32)));
        if let Some((index, count)) = shard {
            if index >= count {
                return Err(HashesError::ShardIndex { index, count });
            }
        }
        Ok(CellHashes {
            global: u64_at(20),
            cells: (0..n).map(|i| u64_at(head + 8 * i)).collect(),
            store_crc: u32_at(16),
            shard,
        })
    }

    /// Joins the hashes of shards of one bake: per cell, the one nonzero hash (the store checksum
    /// is left 0 for the merged store's own).
    pub fn merge(parts: &[CellHashes]) -> Option<CellHashes> {
        let first = parts.first()?;
        let mut out = CellHashes {
            store_crc: 0,
            shard: None,
            ..first.clone()
        };
        for p in &parts[1..] {
            if p.global != first.global || p.cells.len() != first.cells.len() {
                return None;
            }
            for (o, &h) in out.cells.iter_mut().zip(&p.cells) {
                if h != 0 {
                    if *o != 0 && *o != h {
                        return None;
                    }
                    *o = h;
                }
            }
        }
        Some(out)
    }
}

/// Where the hashes of the store at `store` live: beside it, `NAME.hashes`.
pub fn hashes_path(store: &std::path::Path) -> std::path::PathBuf {
    let mut s = store.as_os_str().to_owned();
    s.push(".hashes");
    std::path::PathBuf::from(s)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The options' text the global hash takes, for the default bake, pinned: a change to it
    /// makes every old `.hashes` file refuse reuse (which a bake then says), so it is made on
    /// purpose (the far field, issue 31, changed it, then the store's byte budget, then the far
    /// field's certification budget, then its sparse blocks' split).
    #[test]
    fn the_options_key_keeps_its_layout() {
        let p = BakeParams::default();
        assert_eq!(
            options_key(&p),
            "(100.0, (1.5, 2.0), Auto, 10, 52.0, GrowParams { seeds: 8, search_m: 900.0, max_chain: 24, \
             max_bridges: 2, tries: 6, min_vo_m: 1.0, single_object: false, verify: false }, \
             Long, 10000.0, MapParams { edge_eyes: 3, bins: 512, px: 4.0, half: 1024.0 }, \
             ProposeParams { directions: 16, spacing: 32.0, step: 2, max_offset: 900.0, \
             min_len: 60.0, per_direction: 1 }, 25, FarParams { block_m: 400.0, \
             reach_m: 3000.0, px: 12.0, spacing_m: 64.0, min_len_m: 120.0, budget: 24, \
             keep: 12, full_budget_blockers: 40000, split_blockers: 40000 })"
        );
    }

    /// The hash of the first cell (x in [0, 100)) of a row of 20 m squares every 100 m along
    /// x = 0..4000 (10 m tall, one 30 m tower at x = 2000), listed in the order `xs` gives with
    /// heights changed by `raise`, baked with `far` on or off, search 300 m, weights 1.5 km.
    fn first_cell_hash(xs: &[f64], raise: Option<f64>, far: bool) -> u64 {
        let items: Vec<([f64; 3], f64, f64)> = xs
            .iter()
            .map(|&x| {
                let h = if x == 2000.0 {
                    30.0
                } else if Some(x) == raise {
                    12.0
                } else {
                    10.0
                };
                ([x, 0.0, 20.0], 0.0, h)
            })
            .collect();
        let scene = crate::testutil::squares(&items);
        let mut p = BakeParams {
            search_m: 300.0,
            weigh_m: 1500.0,
            ..BakeParams::default()
        };
        if !far {
            p.far.block_m = 0.0;
        }
        let plan = Plan::new(&scene, p).unwrap();
        let cell = plan
            .frame
            .grid
            .cell_at(50.0 - scene.origin.x, 10.0 - scene.origin.y)
            .unwrap();
        CellHashes::new(&plan, &[cell]).cells[cell as usize]
    }

    /// Regression (the 10^6 city's bake spent its first minutes, and would have spent hours,
    /// hashing: every cell listed and sorted the ids of every object within 10 km). The hash
    /// now reads three parts of what the bake reads (`Plan::reaches`): the near objects in
    /// order, the weighed ones as a set by buckets, the block's in order once per block. Each
    /// part must see what it covers, and the set part must not see order.
    #[test]
    fn cell_hashes_see_near_order_far_content_and_nothing_beyond() {
        let row: Vec<f64> = (0..=40).map(|i| 100.0 * i as f64).collect();
        let swapped = |a: usize, b: usize| {
            let mut v = row.clone();
            v.swap(a, b);
            v
        };
        for far in [false, true] {
            let base = first_cell_hash(&row, None, far);
            assert_ne!(base, 0);
            assert_eq!(base, first_cell_hash(&row, None, far), "deterministic");
            // Near (within 300 m of the cell): order counts.
            assert_ne!(
                base,
                first_cell_hash(&swapped(1, 2), None, far),
                "near order"
            );
            assert_ne!(
                base,
                first_cell_hash(&row, Some(300.0), far),
                "near content"
            );
            // Weighed (1 km away): content counts.
            assert_ne!(
                base,
                first_cell_hash(&row, Some(1000.0), far),
                "weighed content"
            );
            // Beyond every reach (3.5 km; the far field's block reads 3.4 km past its 400 m).
            assert_eq!(base, first_cell_hash(&row, Some(3900.0), far), "beyond");
        }
        // Weighed but outside the near search and, the far field off, outside any block: their
        // order is not read.
        assert_eq!(
            first_cell_hash(&row, None, false),
            first_cell_hash(&swapped(10, 12), None, false),
            "order of weighed objects"
        );
        // The far field on, the block reads them in order.
        assert_ne!(
            first_cell_hash(&row, None, true),
            first_cell_hash(&swapped(10, 12), None, true),
            "order within the block's reach"
        );
    }

    /// Regression (`--reuse` trusted hashes written by any build of the same version, so a
    /// store rebaked after the bake code changed could mix records of two builds): the global
    /// hash takes the sources' fingerprint, so another build rebakes every cell.
    #[test]
    fn hashes_of_another_build_of_the_same_version_differ_globally() {
        let (digits, version) = (&CODE[CODE.len() - 16..], env!("CARGO_PKG_VERSION"));
        assert!(digits.bytes().all(|b| b.is_ascii_hexdigit()), "{CODE}");
        assert_eq!(CODE, format!("{version}+{digits}"));
        let scene = crate::testutil::squares(&[([0.0, 0.0, 20.0], 0.0, 10.0)]);
        let plan = Plan::new(&scene, BakeParams::default()).unwrap();
        let cells: Vec<CellId> = (0..plan.frame.grid.cell_count() as CellId).collect();
        let ours = CellHashes::new(&plan, &cells);
        let other = CellHashes::by_code(&plan, &cells, &format!("{version}+{:016x}", 1));
        assert_ne!(ours.global, other.global);
        assert_eq!(
            ours.changed(&other, &cells),
            cells,
            "another build rebakes every cell"
        );
    }

    #[test]
    fn file_form_round_trips_and_refuses_damage() {
        let h = CellHashes {
            global: 0x0123_4567_89ab_cdef,
            cells: vec![0, 7, u64::MAX],
            store_crc: 0xdead_beef,
            shard: Some((2, 5)),
        };
        let b = h.encode();
        assert_eq!(b.len(), HEADER_LEN + 24 + 4);
        assert_eq!(&b[..8], b"VOCCHASH");
        assert_eq!(&b[8..10], &[2, 0], "version 2");
        assert_eq!(&b[28..36], &[2, 0, 0, 0, 5, 0, 0, 0], "shard 2 of 5");
        assert_eq!(CellHashes::decode(&b), Ok(h.clone()));
        let whole = CellHashes {
            shard: None,
            ..h.clone()
        };
        assert_eq!(&whole.encode()[28..36], &[0; 8], "count 0: not a shard");
        assert_eq!(CellHashes::decode(&whole.encode()), Ok(whole.clone()));
        let mut bad = b.clone();
        bad[HEADER_LEN + 9] ^= 1;
        assert_eq!(CellHashes::decode(&bad), Err(HashesError::Checksum));
        assert_eq!(
            CellHashes::decode(&b[..b.len() - 1]),
            Err(HashesError::Length {
                got: b.len() - 1,
                want: b.len()
            })
        );
        let mut v3 = b.clone();
        v3[8] = 3;
        assert_eq!(CellHashes::decode(&v3), Err(HashesError::Version(3)));
        assert_eq!(CellHashes::decode(b"VOCCSTOR"), Err(HashesError::Magic));
        // Version 1 (no shard fields), as vocc wrote it before: still read.
        let mut v1 = Vec::new();
        v1.extend_from_slice(b"VOCCHASH");
        v1.extend_from_slice(&1u16.to_le_bytes());
        v1.extend_from_slice(&0u16.to_le_bytes());
        v1.extend_from_slice(&3u32.to_le_bytes());
        v1.extend_from_slice(&0xdead_beefu32.to_le_bytes());
        v1.extend_from_slice(&h.global.to_le_bytes());
        for c in &h.cells {
            v1.extend_from_slice(&c.to_le_bytes());
        }
        let crc = crate::runtime::crc::crc32(&v1);
        v1.extend_from_slice(&crc.to_le_bytes());
        assert_eq!(CellHashes::decode(&v1), Ok(whole));
    }

    #[test]
    fn merge_takes_the_one_nonzero_hash_and_refuses_conflicts() {
        let a = CellHashes {
            global: 5,
            cells: vec![11, 0, 13],
            store_crc: 1,
            shard: Some((0, 2)),
        };
        let b = CellHashes {
            global: 5,
            cells: vec![0, 12, 0],
            store_crc: 2,
            shard: Some((1, 2)),
        };
        assert_eq!(
            CellHashes::merge(&[a.clone(), b.clone()]).unwrap().cells,
            vec![11, 12, 13]
        );
        let c = CellHashes {
            global: 5,
            cells: vec![99, 0, 0],
            store_crc: 3,
            shard: None,
        };
        assert_eq!(CellHashes::merge(&[a.clone(), c]), None);
        let d = CellHashes { global: 6, ..b };
        assert_eq!(CellHashes::merge(&[a, d]), None);
    }
}
