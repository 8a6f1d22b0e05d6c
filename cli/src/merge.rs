//! `vocc merge`: the shards of one bake joined into the store a single bake writes.
//!
//! Input: the shard stores and, beside each, its `.hashes` file. Output: the merged store and its
//! hashes, written atomically, and a line on stderr. Invariant: the rules are the library's
//! ([`vocc::bake::merge`]); this file reads and writes the files and names them in its errors.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use vocc::bake::incremental::{hashes_path, CellHashes};
use vocc::bake::merge::{MergeError, ShardBytes};

use crate::files::{check_output, parse, read_store, write_atomically};

/// `vocc merge SHARD... -o STORE`: the shards of one bake (`vocc bake --shard I/N`) joined into
/// the store a single bake writes. Every shard must carry its own `.hashes` file (which records
/// its index and count), every index `0..N` must be given exactly once, and every shard must have
/// the same frame, scene section and options; the merged store (2.0) carries that scene section
/// (a 1.0 shard has an empty one); each cell's record is the one shard's that baked it (cells no
/// shard baked, and cells with no VOs, stay empty); two shards disagreeing on a cell is an error.
pub fn merge(shards: Vec<PathBuf>, output: &Path) -> Result<()> {
    anyhow::ensure!(!shards.is_empty(), "give the shard files to merge");
    let hashes_out = hashes_path(output);
    let mut inputs: Vec<PathBuf> = shards.clone();
    inputs.extend(shards.iter().map(|p| hashes_path(p)));
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    check_output(output, &inputs)?;
    check_output(&hashes_out, &inputs)?;
    let bytes: Vec<Vec<u8>> = shards
        .iter()
        .map(|p| read_store(p))
        .collect::<Result<_>>()?;
    for (p, b) in shards.iter().zip(&bytes) {
        parse(p, b)?;
    }
    // A hashes file that cannot be read is given as no bytes (the merge then refuses it as
    // damaged), so the merge's own rules are checked in their order first.
    let hashes: Vec<std::io::Result<Vec<u8>>> = shards
        .iter()
        .map(|p| std::fs::read(hashes_path(p)))
        .collect();
    let given: Vec<ShardBytes> = bytes
        .iter()
        .zip(&hashes)
        .map(|(store, h)| ShardBytes {
            store,
            hashes: h.as_deref().unwrap_or(&[]),
        })
        .collect();
    let merged = vocc::bake::merge::merge(&given)
        .map_err(|e| anyhow::anyhow!(merge_error(&e, &shards, &hashes)))?;
    // The shards' hashes, merged, so the merged store can serve `bake --reuse` (stale hashes are
    // removed before the store is written; see `bake`).
    match std::fs::remove_file(&hashes_out) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            return Err(e).with_context(|| format!("cannot remove {}", hashes_out.display()))
        }
        _ => {}
    }
    write_atomically(output, |w| w.write_all(&merged.store))?;
    write_atomically(&hashes_out, |w| w.write_all(&merged.hashes.encode()))?;
    let parts: Vec<String> = shards
        .iter()
        .zip(&merged.cells_from)
        .map(|(p, c)| format!("{} {c}", p.display()))
        .collect();
    let count = merged.count;
    eprintln!(
        "merged {count} of {count} shards ({} cells with VOs or skipped: {}) into {} ({} bytes)",
        merged.cells_from.iter().sum::<usize>(),
        parts.join(", "),
        output.display(),
        merged.store.len()
    );
    Ok(())
}

/// The merge's refusal with the shards' file names.
fn merge_error(e: &MergeError, shards: &[PathBuf], hashes: &[std::io::Result<Vec<u8>>]) -> String {
    let name = |k: usize| shards[k].display().to_string();
    let unplaced = |k: usize, why: String| {
        format!(
            "cannot tell which shard {} is: {why} (every `vocc bake --shard` writes one beside its store; keep it with the shard)",
            name(k)
        )
    };
    match e {
        MergeError::Frame { shard } => format!(
            "{} has another frame (grid, origin, eyes or quantization) than {}: shards must come from one bake",
            name(*shard),
            name(0)
        ),
        MergeError::Scene {
            shard,
            objects,
            first_objects,
            scene,
            first_scene,
            crs,
            first_crs,
        } => format!(
            "{} records another scene than {} (objects {objects} and {first_objects}, fingerprint {scene:016x} and {first_scene:016x}, CRS {crs:?} and {first_crs:?}): shards must come from one bake",
            name(*shard),
            name(0)
        ),
        MergeError::Hashes { shard, error } => {
            let hp = hashes_path(&shards[*shard]);
            match &hashes[*shard] {
                Err(io) => unplaced(*shard, format!("cannot read {} ({io})", hp.display())),
                Ok(_) => unplaced(*shard, format!("{} is damaged ({error})", hp.display())),
            }
        }
        MergeError::HashesOfAnotherStore { shard } => unplaced(
            *shard,
            format!("{} belongs to another store", hashes_path(&shards[*shard]).display()),
        ),
        MergeError::NotAShard { shard } => format!(
            "{} is not a shard: its hashes record a whole bake or a merge (bake shards with --shard I/N)",
            name(*shard)
        ),
        MergeError::Count {
            first,
            shard,
            other,
        } => format!(
            "{} is shard {}/{} but {} is shard {}/{}: shards must come from one bake",
            name(0),
            first.0,
            first.1,
            name(*shard),
            other.0,
            other.1
        ),
        MergeError::Twice {
            index,
            count,
            first,
            second,
        } => format!(
            "shard {index}/{count} is given twice: {} and {}",
            name(*first),
            name(*second)
        ),
        MergeError::Missing { .. } => format!(
            "{e} (given: {})",
            hashes
                .iter()
                .zip(shards)
                .filter_map(|(h, p)| {
                    let (i, n) = CellHashes::decode(h.as_ref().ok()?).ok()?.shard?;
                    Some(format!("{i}/{n} {}", p.display()))
                })
                .collect::<Vec<_>>()
                .join(", ")
        ),
        MergeError::CellDiffers {
            cell,
            first,
            second,
        } => format!(
            "cell {cell} differs between {} and {}: shards must come from one bake",
            name(*first),
            name(*second)
        ),
        MergeError::Store { shard, error } => format!("{}: {error}", name(*shard)),
        MergeError::NoShards | MergeError::HashesDisagree | MergeError::Encode(_) => e.to_string(),
    }
}
