//! The top view of one cell, like the paper's Fig. 8 (`vocc render STORE SCENE --cell ID`).
//!
//! Input: the scene, a store's frame and one cell's record, the cell's PVS, and optionally the
//! PVS of the single-building baseline. Output: an SVG: the cell, its VOs, and every building
//! coloured as visible (in the PVS), culled only thanks to fusion (hidden by the VOs but not by
//! single buildings), or culled by single buildings alone.
//! Invariant: drawing only; every colour comes from the given sets.

use std::fmt::Write;

use crate::runtime::format::CellRecord;
use crate::runtime::{CellId, Frame};
use crate::scene::{Scene, Shape};

/// Draws cell `id`; the view spans `radius` metres around the cell's centre.
pub fn cell_picture(
    scene: &Scene,
    f: &Frame,
    id: CellId,
    rec: &CellRecord,
    pvs: &[u32],
    baseline: Option<&[u32]>,
    radius: f64,
) -> String {
    let r = f.grid.cell_rect(id).unwrap_or([0.0; 4]);
    let (cx, cy) = (0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]));
    let size = 900.0;
    let k = size / (2.0 * radius);
    let p = |x: f64, y: f64| {
        format!(
            "{:.1},{:.1}",
            (x - cx + radius) * k,
            (radius - (y - cy)) * k
        )
    };
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{size}" height="{}" font-family="sans-serif" font-size="13"><rect width="100%" height="100%" fill="white"/>"#,
        size + 60.0
    );
    let (mut n_vis, mut n_fused, mut n_single) = (0, 0, 0);
    for o in &scene.objects {
        let b = o.bbox;
        if b.max.x < cx - radius
            || b.min.x > cx + radius
            || b.max.y < cy - radius
            || b.min.y > cy + radius
        {
            continue;
        }
        let visible = pvs.binary_search(&o.index).is_ok();
        let single = baseline.is_some_and(|bl| bl.binary_search(&o.index).is_err());
        let fill = if visible {
            n_vis += 1;
            "#c8c8c8"
        } else if single {
            n_single += 1;
            "#f0a030"
        } else {
            n_fused += 1;
            "#d62728"
        };
        let rings: Vec<Vec<(f64, f64)>> = match &o.shape {
            Shape::Footprint(fp) => fp
                .polygons
                .iter()
                .flat_map(|poly| poly.iter())
                .map(|ring| ring.iter().map(|v| (v.x, v.y)).collect())
                .collect(),
            Shape::Mesh(_) => vec![vec![
                (b.min.x, b.min.y),
                (b.max.x, b.min.y),
                (b.max.x, b.max.y),
                (b.min.x, b.max.y),
            ]],
        };
        let d: String = rings
            .iter()
            .filter(|ring| !ring.is_empty())
            .map(|ring| {
                let pts: Vec<String> = ring.iter().map(|&(x, y)| p(x, y)).collect();
                format!("M{}Z", pts.join("L"))
            })
            .collect();
        let _ = write!(
            s,
            r##"<path d="{d}" fill="{fill}" fill-rule="evenodd" stroke="#555" stroke-width="0.4"/>"##
        );
    }
    let _ = write!(
        s,
        r##"<polygon points="{} {} {} {}" fill="#ffe08a" fill-opacity="0.6" stroke="#b08000" stroke-width="2"/>"##,
        p(r[0], r[1]),
        p(r[2], r[1]),
        p(r[2], r[3]),
        p(r[0], r[3])
    );
    for (i, q) in rec.vos().iter().enumerate() {
        if let Some(g) = f.dequantize(id, rec.ground(), q) {
            let (a, b) = (p(g.a[0], g.a[1]), p(g.b[0], g.b[1]));
            let (a, b) = (
                a.split_once(',').unwrap_or(("0", "0")),
                b.split_once(',').unwrap_or(("0", "0")),
            );
            let _ = write!(
                s,
                r##"<line x1="{}" y1="{}" x2="{}" y2="{}" stroke="#0050d0" stroke-width="3"/><text x="{}" y="{}" fill="#0050d0">{}</text>"##,
                a.0,
                a.1,
                b.0,
                b.1,
                a.0,
                a.1,
                i + 1
            );
        }
    }
    // The caption in two lines, each well within the picture's width (at most about 110
    // characters of 13 px sans-serif).
    let _ = write!(
        s,
        r##"<text x="10" y="{}">cell {id}: {} VOs (blue, numbered in stored order)</text><text x="10" y="{}">buildings: visible {n_vis} (grey), culled thanks to fusion {n_fused} (red){}</text></svg>"##,
        size + 24.0,
        rec.vos().len(),
        size + 46.0,
        if baseline.is_some() {
            format!(", culled by single buildings alone {n_single} (orange)")
        } else {
            String::new()
        }
    );
    s.push('\n');
    s
}
