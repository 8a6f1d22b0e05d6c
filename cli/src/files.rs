//! Files the commands read and write: stores in, outputs written atomically.
//!
//! Input: paths. Output: a store's bytes, or an output written through a temporary file and
//! renamed. Invariant: an output is either its old content or the new one in full, never a
//! partial file; every failure names the file.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use vocc::runtime::format::{decode_frame, Store, BLOB_MAGIC, FRAME_LEN};

/// The bytes of the store file at `path`.
pub fn read_store(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("cannot read {}", path.display()))
}

/// The store in `bytes`, read from `path` (named in the error). Another vocc file given for a
/// store (a per-cell blob, a frame, a `.hashes` file) is named as what it is.
pub fn parse<'a>(path: &Path, bytes: &'a [u8]) -> Result<Store<'a>> {
    Store::parse(bytes).map_err(|e| {
        let other = if bytes.starts_with(&BLOB_MAGIC) {
            Some("a per-cell blob (`vocc export --blob`), which an engine decodes with its store's frame; `vocc inspect` reads the store it came from")
        } else if bytes.starts_with(&vocc::bake::incremental::MAGIC) {
            Some("the content hashes of a bake (`.hashes`, read by `vocc bake --reuse`), not the store itself")
        } else if bytes.len() == FRAME_LEN && decode_frame(bytes).is_ok() {
            Some("a store's frame (the `.frame` file of `vocc export --blob`), not a store")
        } else {
            None
        };
        match other {
            Some(what) => anyhow::anyhow!("{} is not a vocc store: it is {what}", path.display()),
            None => anyhow::Error::new(e)
                .context(format!("{} is not a valid vocc store", path.display())),
        }
    })
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

/// The folder holding `path` (`.` for a bare name).
fn folder_of(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Where a report folder is assembled: inside `dir` when it exists (its files are renamed into
/// it), else beside it as `.NAME.tmp` (renamed to `dir` whole).
fn report_tmp(dir: &Path) -> Result<PathBuf> {
    if dir.is_dir() {
        return Ok(dir.join(".vocc-report.tmp"));
    }
    let name = dir
        .file_name()
        .with_context(|| format!("{} is not a folder path", dir.display()))?;
    Ok(folder_of(dir).join(format!(".{}.tmp", name.to_string_lossy())))
}

/// Checks, before any work, that the report folder `dir` can be written with files `names`:
/// the same rule as for a file output (its own folder must exist; vocc creates the output it
/// is asked for, never the folders above it), `dir` is a folder if it exists, none of its
/// report files is an input, and a temporary folder can be made where the report is assembled.
pub fn check_report_dir(dir: &Path, names: &[&str], inputs: &[&Path]) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        anyhow::bail!("the report folder {} is a file", dir.display());
    }
    if !dir.exists() && !folder_of(dir).is_dir() {
        anyhow::bail!(
            "cannot write the report {}: the folder {} does not exist",
            dir.display(),
            folder_of(dir).display()
        );
    }
    for n in names {
        let out = dir.join(n);
        if let Some(i) = inputs.iter().find(|i| same_file(&out, i)) {
            anyhow::bail!(
                "the report file {} is also an input ({}): vocc never overwrites its inputs; write the report elsewhere",
                out.display(),
                i.display()
            );
        }
    }
    let tmp = report_tmp(dir)?;
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir(&tmp).with_context(|| {
        format!(
            "cannot write the report {}: cannot create the folder {}",
            dir.display(),
            tmp.display()
        )
    })?;
    let _ = std::fs::remove_dir(&tmp);
    Ok(())
}

/// Writes and syncs one file.
fn write_synced(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    use std::io::Write;
    let mut f = std::fs::File::create(path)?;
    f.write_all(bytes)?;
    f.sync_all()
}

/// Writes the files of a report folder all or nothing, as a store is written: every file is
/// written whole into a temporary folder first (`.NAME.tmp` beside `dir`, or
/// `dir/.vocc-report.tmp` when `dir` exists), then the folder is renamed to `dir` (or, into an
/// existing `dir`, each file renamed over its old version). A failure while writing (a full
/// disk says so) removes the temporary folder and leaves `dir` as it was.
pub fn write_report(dir: &Path, files: &[(&str, &[u8])]) -> Result<()> {
    write_report_with(dir, files, &write_synced)
}

fn write_report_with(
    dir: &Path,
    files: &[(&str, &[u8])],
    write: &dyn Fn(&Path, &[u8]) -> std::io::Result<()>,
) -> Result<()> {
    let existing = dir.is_dir();
    let tmp = report_tmp(dir)?;
    let fail = |what: String, e: std::io::Error| {
        let full = if e.kind() == std::io::ErrorKind::StorageFull {
            ": the disk is full"
        } else {
            ""
        };
        anyhow::Error::new(e).context(format!(
            "cannot write the report {} ({what}){full}; nothing of it was written",
            dir.display()
        ))
    };
    let _ = std::fs::remove_dir_all(&tmp);
    let result = (|| -> Result<()> {
        std::fs::create_dir(&tmp).map_err(|e| fail(format!("creating {}", tmp.display()), e))?;
        for (name, bytes) in files {
            let p = tmp.join(name);
            write(&p, bytes).map_err(|e| fail(format!("writing {}", p.display()), e))?;
        }
        if !existing {
            return std::fs::rename(&tmp, dir)
                .map_err(|e| fail(format!("renaming {}", tmp.display()), e));
        }
        for (k, (name, _)) in files.iter().enumerate() {
            std::fs::rename(tmp.join(name), dir.join(name)).map_err(|e| {
                let done: Vec<&str> = files[..k].iter().map(|f| f.0).collect();
                anyhow::Error::new(e).context(format!(
                    "cannot move {} into {} (already replaced: {})",
                    name,
                    dir.display(),
                    if done.is_empty() {
                        "none".to_string()
                    } else {
                        done.join(", ")
                    }
                ))
            })?;
        }
        let _ = std::fs::remove_dir(&tmp);
        Ok(())
    })();
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&tmp);
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

    /// Issue 33, defect 6: `eval --report` on a full disk left half a report. The report is
    /// all or nothing: a write failing with ENOSPC on the last file leaves no new folder, or the
    /// old report's files unchanged, and no temporary folder.
    #[test]
    fn eval_report_on_a_full_disk_leaves_no_half_report() {
        let d = dir("report-full");
        let files: [(&str, &[u8]); 3] = [
            ("eval.md", b"# new"),
            ("vos.svg", b"<svg/>"),
            ("map.svg", b"<svg/>"),
        ];
        let full = |p: &Path, b: &[u8]| {
            if p.ends_with("map.svg") {
                Err(Error::from(ErrorKind::StorageFull))
            } else {
                write_synced(p, b)
            }
        };
        // A new folder: nothing at all.
        let rep = d.join("report");
        let e = write_report_with(&rep, &files, &full).unwrap_err();
        let msg = format!("{e:#}");
        assert!(
            msg.contains("the disk is full") && msg.contains("nothing of it was written"),
            "{msg}"
        );
        let left: Vec<_> = std::fs::read_dir(&d).unwrap().collect();
        assert!(left.is_empty(), "{left:?}");
        // An old report: unchanged, and no temporary folder inside it.
        std::fs::create_dir(&rep).unwrap();
        for (n, _) in files {
            std::fs::write(rep.join(n), b"old").unwrap();
        }
        assert!(write_report_with(&rep, &files, &full).is_err());
        let mut names: Vec<String> = std::fs::read_dir(&rep)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        assert_eq!(names, ["eval.md", "map.svg", "vos.svg"]);
        for (n, _) in files {
            assert_eq!(std::fs::read(rep.join(n)).unwrap(), b"old", "{n}");
        }
        // Without the failure, both forms write every file and leave no temporary folder.
        write_report(&rep, &files).unwrap();
        assert_eq!(std::fs::read(rep.join("eval.md")).unwrap(), b"# new");
        assert_eq!(std::fs::read_dir(&rep).unwrap().count(), 3);
        let fresh = d.join("fresh");
        write_report(&fresh, &files).unwrap();
        assert_eq!(std::fs::read_dir(&fresh).unwrap().count(), 3);
        assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2);
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
