//! `vocc view`: the viewer page of a store and its scene, written to a file or served.
//!
//! Input: a store file and the scene files (with the reader flags). Output: one self-contained
//! HTML page (`-o FILE`, written atomically), or the same page served over HTTP on a local
//! address (`--serve`) until the process is stopped. Invariant: the page is the library's
//! (`vocc::view`); this module only reads, writes and serves.

use std::io::{BufRead, BufReader, Write};
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;

use vocc::scene;
use vocc::view::{page, PageInfo, SceneGeometry};

use crate::args::ReadArgs;
use crate::files::{check_output, parse, read_store, write_atomically};

#[derive(Args)]
#[command(after_help = "Examples:
  vocc view lyon.vocc data/lyon1/buildings_lyon1.geojson --height-attr HAUTEUR -o lyon.html
  vocc view lyon.vocc data/lyon1/buildings_lyon1.geojson --height-attr HAUTEUR --serve
The page needs no network: three.js and vocc's JavaScript runtime are inside it. Click a cell (or
walk with W A S D, Q E to turn) to see its VOs and its PVS, built in the page from the store.")]
pub struct ViewArgs {
    /// Store file (2.0 or 1.0).
    pub store: PathBuf,
    /// Scene files (the objects drawn and culled).
    #[arg(required = true)]
    pub scene: Vec<PathBuf>,
    #[command(flatten)]
    pub read: ReadArgs,
    /// Output HTML file.
    #[arg(short, long, value_name = "FILE", required_unless_present = "serve")]
    pub output: Option<PathBuf>,
    /// Serve the page over HTTP instead (until stopped), on --addr.
    #[arg(long, conflicts_with = "output")]
    pub serve: bool,
    /// With --serve: the address to listen on (port 0: any free port; the address is printed).
    #[arg(
        long,
        value_name = "HOST:PORT",
        default_value = "127.0.0.1:8035",
        requires = "serve"
    )]
    pub addr: String,
}

fn name(p: &Path) -> String {
    p.file_name().map_or_else(
        || p.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}

pub fn run(a: ViewArgs) -> Result<()> {
    let inputs: Vec<&Path> = std::iter::once(a.store.as_path())
        .chain(a.scene.iter().map(PathBuf::as_path))
        .collect();
    if let Some(out) = &a.output {
        check_output(out, &inputs)?;
    }
    let t = Instant::now();
    let bytes = read_store(&a.store)?;
    let store = parse(&a.store, &bytes)?;
    let s = scene::load(&a.scene, &a.read.options())?;
    let geometry = SceneGeometry::new(&s, store.frame().origin);
    let info = PageInfo {
        title: format!("vocc view: {}", name(&a.store)),
        store: name(&a.store),
        scene: a.scene.iter().map(|p| name(p)).collect(),
    };
    let html = page(&bytes, &geometry, &info);
    match &a.output {
        Some(out) => {
            write_atomically(out, |w| w.write_all(html.as_bytes()))?;
            eprintln!(
                "wrote {} ({} objects, {} cells, {:.1} MB) in {:.2} s",
                out.display(),
                geometry.len(),
                store.cell_count(),
                html.len() as f64 / 1e6,
                t.elapsed().as_secs_f64()
            );
            Ok(())
        }
        None => serve(&a.addr, &html),
    }
}

/// Serves `html` at every path of `addr` until the process is stopped.
fn serve(addr: &str, html: &str) -> Result<()> {
    let listener = TcpListener::bind(addr).with_context(|| format!("cannot listen on {addr}"))?;
    let local = listener.local_addr()?;
    eprintln!("serving the page on http://{local}/ (Ctrl-C stops)");
    for stream in listener.incoming() {
        let Ok(mut stream) = stream else { continue };
        // The request line, then the headers up to the blank line; the page whatever the path.
        let mut reader = BufReader::new(&mut stream);
        let mut first = String::new();
        let _ = reader.read_line(&mut first);
        let mut line = String::new();
        while reader.read_line(&mut line).unwrap_or(0) > 0 && line.trim_end() != "" {
            line.clear();
        }
        let (status, len, body) = if first.starts_with("GET ") {
            ("200 OK", html.len(), html)
        } else if first.starts_with("HEAD ") {
            ("200 OK", html.len(), "")
        } else {
            ("405 Method Not Allowed", 0, "")
        };
        let _ = write!(
            stream,
            "HTTP/1.1 {status}\r\nContent-Type: text/html; charset=utf-8\r\nContent-Length: {len}\r\nConnection: close\r\n\r\n{body}"
        );
    }
    Ok(())
}
