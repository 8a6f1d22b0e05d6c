//! Writes a scene's object boxes as a text file, the input the C example (`examples/c/pvs.c`)
//! and engine-side tests read: one line per object, `xmin ymin zmin xmax ymax zmax` in world
//! coordinates, in object index order (the order `vocc pvs` numbers objects in).
//!
//! Input: scene files and the reader flags `--height-attr NAME` and `--base-attr NAME`.
//! Output: `-o FILE` (written whole or not at all: a temporary file renamed).
//! Invariant: each box is the scene object's local box plus the scene origin, the same f64
//! arithmetic as `vocc pvs`, printed in Rust's shortest round-trip form, so a reader parsing
//! it with `strtod` gets the very boxes `vocc pvs` culls.
//!
//! ```sh
//! cargo run --release --example boxes -- data/lyon1/buildings_lyon1.geojson --height-attr HAUTEUR -o lyon.boxes
//! ```

use std::io::Write;
use std::path::PathBuf;
use std::process::ExitCode;

use vocc::scene::{self, ReadOptions};

fn run() -> Result<(), String> {
    let mut files = Vec::new();
    let mut opts = ReadOptions::default();
    let mut output = None;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} takes a value"));
        match a.as_str() {
            "--height-attr" => opts.height_attr = Some(value()?),
            "--base-attr" => opts.base_attr = Some(value()?),
            "-o" => output = Some(PathBuf::from(value()?)),
            _ if a.starts_with('-') => return Err(format!("unknown option {a}")),
            _ => files.push(PathBuf::from(a)),
        }
    }
    let output = output.ok_or("give -o FILE")?;
    if files.is_empty() {
        return Err("give the scene files".into());
    }
    let s = scene::load(&files, &opts).map_err(|e| e.to_string())?;
    let o = s.origin;
    let mut text = String::new();
    for ob in &s.objects {
        let (a, b) = (ob.bbox.min + o, ob.bbox.max + o);
        text += &format!("{} {} {} {} {} {}\n", a.x, a.y, a.z, b.x, b.y, b.z);
    }
    let name = output.file_name().ok_or("-o needs a file name")?;
    let tmp = output.with_file_name(format!(".{}.tmp", name.to_string_lossy()));
    let write = || -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(text.as_bytes())?;
        f.sync_all()?;
        std::fs::rename(&tmp, &output)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        format!("{}: {e}", output.display())
    })?;
    eprintln!("wrote {} boxes to {}", s.objects.len(), output.display());
    Ok(())
}

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("boxes: {e}");
            ExitCode::FAILURE
        }
    }
}
