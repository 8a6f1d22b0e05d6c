//! Merging the shards of one bake (`vocc bake --shard I/N`, [`super::job`]) into the store a
//! single bake writes.
//!
//! Input: per shard, in any order, its store bytes and the bytes of its `.hashes` file (which
//! records its index and count, [`CellHashes::shard`]).
//! Output: [`Merged`]: the merged store (format 2.0, with the shards' scene section), its hashes
//! (the shards' merged, with the merged store's checksum, so `bake --reuse` works on it) and how
//! many cells each shard gave; or a [`MergeError`] naming the rule the input breaks.
//! Invariants (the rules, checked in this order): there is at least one shard; every store
//! parses; every shard has the first one's frame and scene section; every shard's hashes decode,
//! belong to its store (store checksum) and record a shard (not a whole bake or a merge); all
//! record the same count; every index `0..count` is given exactly once; the hashes agree (same
//! global hash, no cell hashed differently by two shards); no cell has two different nonempty
//! records. No input, however damaged, makes it panic (`fuzz/fuzz_targets/merge.rs`).

use super::incremental::{CellHashes, HashesError};
use crate::runtime::crc::crc32;
use crate::runtime::format::{encode_frame, encode_store_with, CellRecord, FormatError, Store};
use crate::runtime::grid::CellId;

/// One shard as [`merge`] reads it: its store file's bytes and its `.hashes` file's bytes.
#[derive(Clone, Copy, Debug)]
pub struct ShardBytes<'a> {
    pub store: &'a [u8],
    pub hashes: &'a [u8],
}

/// The merged bake.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Merged {
    /// The merged store file (format 2.0).
    pub store: Vec<u8>,
    /// Its hashes (not a shard; `store_crc` is the merged store's): write them beside it with
    /// [`CellHashes::encode`].
    pub hashes: CellHashes,
    /// How many shards were merged (their common count).
    pub count: u32,
    /// Per shard, in input order: the cells whose (nonempty) record came from it.
    pub cells_from: Vec<usize>,
}

/// Why shards were refused. `shard`, `first` and `second` are positions in the input slice.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
pub enum MergeError {
    #[error("no shards to merge")]
    NoShards,
    #[error("shard {shard} is not a readable store: {error}")]
    Store { shard: usize, error: FormatError },
    #[error(
        "shard {shard} has another frame (grid, origin, eyes or quantization) than shard 0: \
         shards must come from one bake"
    )]
    Frame { shard: usize },
    #[error(
        "shard {shard} records another scene than shard 0 (objects {objects} and {first_objects}, \
         fingerprint {scene:016x} and {first_scene:016x}, CRS {crs:?} and {first_crs:?}): shards \
         must come from one bake"
    )]
    Scene {
        shard: usize,
        objects: u32,
        first_objects: u32,
        scene: u64,
        first_scene: u64,
        crs: String,
        first_crs: String,
    },
    #[error("the hashes of shard {shard} are damaged ({error})")]
    Hashes { shard: usize, error: HashesError },
    #[error("the hashes given for shard {shard} belong to another store")]
    HashesOfAnotherStore { shard: usize },
    #[error("shard {shard} is not a shard: its hashes record a whole bake or a merge")]
    NotAShard { shard: usize },
    #[error(
        "shard 0 is shard {}/{} but shard {shard} is shard {}/{}: shards must come from one bake",
        first.0, first.1, other.0, other.1
    )]
    Count {
        first: (u32, u32),
        shard: usize,
        other: (u32, u32),
    },
    #[error("shard {index}/{count} is given twice: shards {first} and {second}")]
    Twice {
        index: u32,
        count: u32,
        first: usize,
        second: usize,
    },
    #[error("{} of {count} shards are missing: {}", missing.len(),
        missing.iter().map(|i| format!("{i}/{count}")).collect::<Vec<_>>().join(", "))]
    Missing { missing: Vec<u32>, count: u32 },
    #[error(
        "the shards' hashes do not agree (other options, or two shards hashing one cell \
         differently): shards must come from one bake"
    )]
    HashesDisagree,
    #[error(
        "cell {cell} differs between shards {first} and {second}: shards must come from one bake"
    )]
    CellDiffers {
        cell: CellId,
        first: usize,
        second: usize,
    },
    #[error("the merged store cannot be written: {0}")]
    Encode(FormatError),
}

/// Merges the shards of one bake; see the module's rules. The result is byte for byte the store
/// (and the hashes) the single bake writes.
pub fn merge(shards: &[ShardBytes]) -> Result<Merged, MergeError> {
    if shards.is_empty() {
        return Err(MergeError::NoShards);
    }
    let stores: Vec<Store> = shards
        .iter()
        .enumerate()
        .map(|(k, s)| Store::parse(s.store).map_err(|error| MergeError::Store { shard: k, error }))
        .collect::<Result<_, _>>()?;
    let frame = *stores[0].frame();
    let first = &stores[0];
    for (k, s) in stores.iter().enumerate().skip(1) {
        if encode_frame(s.frame()) != encode_frame(&frame) {
            return Err(MergeError::Frame { shard: k });
        }
        if s.scene_section() != first.scene_section() {
            return Err(MergeError::Scene {
                shard: k,
                objects: s.objects(),
                first_objects: first.objects(),
                scene: s.scene(),
                first_scene: first.scene(),
                crs: s.crs().to_string(),
                first_crs: first.crs().to_string(),
            });
        }
    }
    // Each shard's hashes: which shard it is, and the content hashes the merge carries on.
    let mut hashes = Vec::with_capacity(shards.len());
    let mut ids = Vec::with_capacity(shards.len());
    for (k, s) in shards.iter().enumerate() {
        let h =
            CellHashes::decode(s.hashes).map_err(|error| MergeError::Hashes { shard: k, error })?;
        if h.store_crc != crc32(s.store) {
            return Err(MergeError::HashesOfAnotherStore { shard: k });
        }
        let Some(id) = h.shard else {
            return Err(MergeError::NotAShard { shard: k });
        };
        ids.push(id);
        hashes.push(h);
    }
    let count = ids[0].1;
    if let Some(k) = ids.iter().position(|&(_, n)| n != count) {
        return Err(MergeError::Count {
            first: ids[0],
            shard: k,
            other: ids[k],
        });
    }
    // `CellHashes::decode` refuses an index at or above the count, so `i < count` here.
    let mut seen: Vec<Option<usize>> = vec![None; count as usize];
    for (k, &(i, _)) in ids.iter().enumerate() {
        if let Some(first) = seen[i as usize] {
            return Err(MergeError::Twice {
                index: i,
                count,
                first,
                second: k,
            });
        }
        seen[i as usize] = Some(k);
    }
    let missing: Vec<u32> = (0..count).filter(|&i| seen[i as usize].is_none()).collect();
    if !missing.is_empty() {
        return Err(MergeError::Missing { missing, count });
    }
    let merged = CellHashes::merge(&hashes).ok_or(MergeError::HashesDisagree)?;
    let n = first.cell_count();
    let mut cells_from = vec![0usize; stores.len()];
    let mut records = Vec::with_capacity(n as usize);
    for id in 0..n {
        let mut rec = CellRecord::EMPTY;
        let mut owner: Option<usize> = None;
        for (k, s) in stores.iter().enumerate() {
            let r = s
                .cell(id)
                .map_err(|error| MergeError::Store { shard: k, error })?;
            if r == CellRecord::EMPTY {
                continue;
            }
            match owner {
                Some(o) if rec != r => {
                    return Err(MergeError::CellDiffers {
                        cell: id,
                        first: o,
                        second: k,
                    })
                }
                Some(_) => {}
                None => {
                    owner = Some(k);
                    rec = r;
                }
            }
        }
        if let Some(o) = owner {
            cells_from[o] += 1;
        }
        records.push(rec);
    }
    let store =
        encode_store_with(&frame, &records, &first.scene_section()).map_err(MergeError::Encode)?;
    let hashes = CellHashes {
        store_crc: crc32(&store),
        ..merged
    };
    Ok(Merged {
        store,
        hashes,
        count,
        cells_from,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::runtime::format::encode_store;
    use crate::runtime::frame::{Frame, QPoint, QVo};
    use crate::runtime::grid::GridDescriptor;

    fn frame(nx: u32) -> Frame {
        Frame {
            origin: [843000.0, 6518000.0, 0.0],
            grid: GridDescriptor {
                min_x: 0.0,
                min_y: 0.0,
                cell_size: 100.0,
                nx,
                ny: 1,
            },
            quantum: 0.5,
            eye_lo: 1.5,
            eye_hi: 2.0,
            ground_z0: 160.0,
            ground_step: 0.0,
            h0: 4.0,
            h_ratio: 1.25,
        }
    }

    fn wall(x: u16) -> CellRecord {
        let vo = QVo {
            a: QPoint::fine(x, 376),
            b: QPoint::fine(x + 140, 376),
            level: 5,
            deep: false,
        };
        CellRecord::new(0, &[vo]).unwrap()
    }

    /// Shard `i` of `n` over a 2-cell grid, with these records and cell hashes.
    fn shard(i: u32, n: u32, cells: [CellRecord; 2], hashes: [u64; 2]) -> (Vec<u8>, Vec<u8>) {
        let store = encode_store(&frame(2), &cells).unwrap();
        let h = CellHashes {
            global: 77,
            cells: hashes.to_vec(),
            store_crc: crc32(&store),
            shard: Some((i, n)),
        };
        (store, h.encode())
    }

    fn inputs(v: &[(Vec<u8>, Vec<u8>)]) -> Vec<ShardBytes<'_>> {
        v.iter()
            .map(|(s, h)| ShardBytes {
                store: s,
                hashes: h,
            })
            .collect()
    }

    #[test]
    fn two_shards_merge_into_the_whole_store_in_any_order() {
        let e = CellRecord::EMPTY;
        let a = shard(0, 2, [wall(196), e], [5, 0]);
        let b = shard(1, 2, [e, wall(200)], [0, 6]);
        let whole = encode_store(&frame(2), &[wall(196), wall(200)]).unwrap();
        for set in [[a.clone(), b.clone()], [b.clone(), a.clone()]] {
            let m = merge(&inputs(&set)).unwrap();
            assert_eq!(m.store, whole);
            assert_eq!(m.count, 2);
            assert_eq!(m.cells_from, [1, 1]);
            assert_eq!(m.hashes.cells, [5, 6]);
            assert_eq!(m.hashes.shard, None);
            assert_eq!(m.hashes.store_crc, crc32(&whole));
        }
    }

    #[test]
    fn each_rule_is_named() {
        let e = CellRecord::EMPTY;
        let a = shard(0, 2, [wall(196), e], [5, 0]);
        let b = shard(1, 2, [e, wall(200)], [0, 6]);
        assert_eq!(merge(&[]), Err(MergeError::NoShards));
        assert_eq!(
            merge(&inputs(std::slice::from_ref(&a))),
            Err(MergeError::Missing {
                missing: vec![1],
                count: 2
            })
        );
        assert_eq!(
            merge(&inputs(&[a.clone(), a.clone()])),
            Err(MergeError::Twice {
                index: 0,
                count: 2,
                first: 0,
                second: 1
            })
        );
        let three = shard(1, 3, [e, wall(200)], [0, 6]);
        assert!(matches!(
            merge(&inputs(&[a.clone(), three])),
            Err(MergeError::Count { shard: 1, .. })
        ));
        let other_frame = (encode_store(&frame(3), &[e, e, e]).unwrap(), b.1.clone());
        assert_eq!(
            merge(&inputs(&[a.clone(), other_frame])),
            Err(MergeError::Frame { shard: 1 })
        );
        let swapped = (b.0.clone(), a.1.clone());
        assert_eq!(
            merge(&inputs(&[a.clone(), swapped])),
            Err(MergeError::HashesOfAnotherStore { shard: 1 })
        );
        let conflict = shard(1, 2, [wall(100), wall(200)], [0, 6]);
        assert_eq!(
            merge(&inputs(&[a.clone(), conflict])),
            Err(MergeError::CellDiffers {
                cell: 0,
                first: 0,
                second: 1
            })
        );
        let rehashed = shard(1, 2, [e, wall(200)], [9, 6]);
        assert_eq!(
            merge(&inputs(&[a.clone(), rehashed])),
            Err(MergeError::HashesDisagree)
        );
        let mut whole = CellHashes::decode(&a.1).unwrap();
        whole.shard = None;
        let not_a_shard = (a.0.clone(), whole.encode());
        assert_eq!(
            merge(&inputs(&[not_a_shard, b.clone()])),
            Err(MergeError::NotAShard { shard: 0 })
        );
        assert!(matches!(
            merge(&inputs(&[(b"VOCCSTOR".to_vec(), a.1.clone())])),
            Err(MergeError::Store { shard: 0, .. })
        ));
    }

    /// Issue 34: a `.hashes` file recording shard 3 of 2 decoded, and `vocc merge` then panicked
    /// indexing its table of the shards seen. These are that file's bytes (version 2, no cells);
    /// decoding refuses them, and the merge names the rule.
    #[test]
    fn merge_panicked_on_a_shard_index_at_or_above_the_count() {
        const SHARD_3_OF_2: [u8; 40] = [
            0x56, 0x4f, 0x43, 0x43, 0x48, 0x41, 0x53, 0x48, 0x02, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00,
            0x03, 0x00, 0x00, 0x00, 0x02, 0x00, 0x00, 0x00, 0x4a, 0x21, 0x41, 0x69,
        ];
        let refused = HashesError::ShardIndex { index: 3, count: 2 };
        assert_eq!(CellHashes::decode(&SHARD_3_OF_2), Err(refused.clone()));
        assert!(refused.to_string().contains("must be below the count"));
        let store = encode_store(&frame(2), &[CellRecord::EMPTY; 2]).unwrap();
        let shard = ShardBytes {
            store: &store,
            hashes: &SHARD_3_OF_2,
        };
        assert_eq!(
            merge(&[shard]),
            Err(MergeError::Hashes {
                shard: 0,
                error: refused
            })
        );
        // The index equal to the count is refused too; one below it is a shard.
        for (index, ok) in [(2u32, false), (1, true)] {
            let h = CellHashes {
                global: 0,
                cells: vec![],
                store_crc: 0,
                shard: Some((index, 2)),
            };
            assert_eq!(CellHashes::decode(&h.encode()).is_ok(), ok, "index {index}");
        }
    }
}
