//! Files the commands read and write: stores in, outputs written atomically.
//!
//! Input: paths. Output: a store's bytes, or an output written through a temporary file and
//! renamed. Invariant: an output is either its old content or the new one in full, never a
//! partial file; every failure names the file.

use std::path::Path;

use anyhow::{Context, Result};

use vocc::runtime::format::Store;

/// The bytes of the store file at `path`.
pub fn read_store(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))
}

/// The store in `bytes`, read from `path` (named in the error).
pub fn parse<'a>(path: &Path, bytes: &'a [u8]) -> Result<Store<'a>> {
    Store::parse(bytes).with_context(|| format!("{} is not a valid vocc store", path.display()))
}

/// Whether `a` and `b` name one existing file (same device and inode on Unix; the same
/// canonical path elsewhere), however they are spelled.
pub fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}

/// Checks, before any work, that `output` can be written: it is none of `inputs` (compared as
/// files, not names), not a folder, and its folder exists and takes a new file (its temporary
/// file is created and removed).
pub fn check_output(output: &Path, inputs: &[&Path]) -> Result<()> {
    let name = output
        .file_name()
        .with_context(|| format!("{} is not a file path", output.display()))?;
    if let Some(i) = inputs.iter().find(|i| same_file(output, i)) {
        anyhow::bail!(
            "the output {} is also an input ({}): vocc never overwrites its inputs; write to another file",
            output.display(),
            i.display()
        );
    }
    if output.is_dir() {
        anyhow::bail!("the output {} is a folder", output.display());
    }
    let dir = match output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        anyhow::bail!(
            "cannot write {}: the folder {} does not exist",
            output.display(),
            dir.display()
        );
    }
    let tmp = output.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
    std::fs::File::create(&tmp).with_context(|| {
        format!(
            "cannot write {}: cannot create a file in {}",
            output.display(),
            dir.display()
        )
    })?;
    let _ = std::fs::remove_file(&tmp);
    Ok(())
}

/// Writes through a temporary file in the same folder (`.NAME.tmp`), then renames, so an
/// interrupted run never leaves a complete-looking output: the output path holds either its old
/// content or the new one in full. Every failure names the output and the temporary file and
/// removes the temporary file; a full disk (ENOSPC) says so. A run killed by a signal while the
/// temporary file is open leaves it behind (it is overwritten by the next run and is never a
/// valid store before the write completes).
pub fn write_atomically(
    path: &std::path::Path,
    write: impl FnOnce(&mut std::io::BufWriter<std::fs::File>) -> std::io::Result<()>,
) -> Result<()> {
    let name = path
        .file_name()
        .with_context(|| format!("{} is not a file path", path.display()))?;
    let tmp = path.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
    let fail = |step: &str, e: std::io::Error| {
        let full = if e.kind() == std::io::ErrorKind::StorageFull {
            ": the disk is full"
        } else {
            ""
        };
        anyhow::Error::new(e).context(format!(
            "cannot write {} ({step} {}){full}",
            path.display(),
            tmp.display()
        ))
    };
    let result = (|| -> Result<()> {
        let f = std::fs::File::create(&tmp).map_err(|e| fail("creating", e))?;
        let mut w = std::io::BufWriter::new(f);
        write(&mut w).map_err(|e| fail("writing", e))?;
        let f = w
            .into_inner()
            .map_err(|e| fail("writing", e.into_error()))?;
        f.sync_all().map_err(|e| fail("syncing", e))?;
        std::fs::rename(&tmp, path).map_err(|e| fail("renaming", e))?;
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::{Error, ErrorKind, Write};
    use std::path::PathBuf;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("vocc-write-atomically-{name}"));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    /// A writer that fails with ENOSPC halfway, as on a full disk: an error that names the
    /// output and says the disk is full, no temporary file, and the old output unchanged.
    #[test]
    fn a_full_disk_is_an_error_and_leaves_the_old_output() {
        let d = dir("full");
        let out = d.join("city.vocc");
        std::fs::write(&out, b"old store").unwrap();
        let e = write_atomically(&out, |w| {
            w.write_all(&[7; 100_000])?;
            Err(Error::from(ErrorKind::StorageFull))
        })
        .unwrap_err();
        let msg = format!("{e:#}");
        assert!(msg.contains("the disk is full"), "{msg}");
        assert!(msg.contains(&out.display().to_string()), "{msg}");
        assert!(msg.contains(".city.vocc.tmp"), "{msg}");
        assert_eq!(std::fs::read(&out).unwrap(), b"old store");
        assert!(!d.join(".city.vocc.tmp").exists(), "temporary file left");
        // Without an old output, nothing is left at all.
        let fresh = d.join("new.vocc");
        assert!(write_atomically(&fresh, |_| Err(Error::from(ErrorKind::StorageFull))).is_err());
        let left: Vec<_> = std::fs::read_dir(&d)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(left, ["city.vocc"], "only the old output remains");
    }

    #[test]
    fn other_write_errors_name_the_output_but_not_a_full_disk() {
        let d = dir("other");
        let out = d.join("x.svg");
        let e = write_atomically(&out, |_| Err(Error::other("boom"))).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains(&out.display().to_string()) && msg.contains("boom"),
            "{msg}"
        );
        assert!(!msg.contains("disk is full"), "{msg}");
        assert!(!out.exists() && !d.join(".x.svg.tmp").exists());
        // A missing folder fails at creation, naming it.
        let e = write_atomically(&d.join("no/such/dir/x.svg"), |_| Ok(())).unwrap_err();
        assert!(format!("{e:#}").contains("creating"), "{e:#}");
    }

    #[test]
    fn a_successful_write_replaces_the_output_and_leaves_no_temporary_file() {
        let d = dir("ok");
        let out = d.join("a.txt");
        std::fs::write(&out, b"old").unwrap();
        write_atomically(&out, |w| w.write_all(b"new")).unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"new");
        assert!(!d.join(".a.txt.tmp").exists());
    }
}
