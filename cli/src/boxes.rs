//! `vocc boxes`: a scene's object boxes, with their ids, as the text file the C example
//! (`examples/c/pvs.c`) and engine-side tests read.
//!
//! Input: scene files and reader flags (the bake's). Output: the box file, written atomically:
//! two `#` lines (the format; the scene's fingerprint, object count and CRS, which a reader
//! checks against a store's scene section), then one line per object in object order,
//! `ID XMIN YMIN ZMIN XMAX YMAX ZMAX` in world coordinates, ID the input feature number.
//! Invariant: each box is the scene object's local box plus the scene origin, the same f64
//! arithmetic as `vocc pvs`, printed in Rust's shortest round-trip form, so a reader parsing it
//! with `strtod` gets the very boxes `vocc pvs` culls, and its PVS, mapped through the ids,
//! equals `vocc pvs`'s.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Result;

use vocc::scene;

use crate::args::ReadArgs;
use crate::files::{check_output, write_atomically};

/// The first line of a box file.
pub const HEADER: &str = "# vocc boxes: one object a line, ID XMIN YMIN ZMIN XMAX YMAX ZMAX (world coordinates; ID the input feature number, as vocc pvs and vocc info give it)";

pub fn boxes(files: &[PathBuf], read: &ReadArgs, output: &Path) -> Result<()> {
    let inputs: Vec<&Path> = files.iter().map(PathBuf::as_path).collect();
    check_output(output, &inputs)?;
    let s = scene::load(files, &read.options())?;
    for n in &s.report.notes {
        eprintln!("note: {n}");
    }
    let o = s.origin;
    write_atomically(output, |w| {
        writeln!(w, "{HEADER}")?;
        writeln!(
            w,
            "# scene {:016x} objects {} crs {:?}",
            s.fingerprint(),
            s.objects.len(),
            s.crs().map_or("", |c| c.name.as_str())
        )?;
        for ob in &s.objects {
            let (a, b) = (ob.bbox.min + o, ob.bbox.max + o);
            writeln!(
                w,
                "{} {} {} {} {} {} {}",
                ob.feature, a.x, a.y, a.z, b.x, b.y, b.z
            )?;
        }
        Ok(())
    })?;
    eprintln!(
        "wrote {} to {} (scene {:016x})",
        crate::report::plural(s.objects.len(), "box", "boxes"),
        output.display(),
        s.fingerprint()
    );
    Ok(())
}
