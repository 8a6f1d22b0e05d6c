//! The top view of one cell, like the paper's Fig. 8 (`vocc render STORE SCENE --cell ID`).
//!
//! Input: the scene, a store's frame and one cell's record, the cell's PVS, and optionally the
//! PVS of the single-building baseline. Output: an SVG: the cell, its VOs (each numbered where
//! it enters the view, the label kept on the canvas), every building in the view coloured as
//! visible (in the PVS), culled only thanks to fusion (hidden by the VOs but not by single
//! buildings), or culled by single buildings alone, a scale bar, and a caption that says which
//! counts are the view's and which the whole scene's.
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
        size + 80.0
    );
    // The terrain, shaded: height as a green-to-brown tint, lit from the north-west.
    if let Some(t) = &scene.terrain {
        let span = (t.zmax - t.zmin).max(1.0);
        for tri in &t.triangles {
            let lo = tri[0].min(tri[1]).min(tri[2]);
            let hi = tri[0].max(tri[1]).max(tri[2]);
            if hi.x < cx - radius || lo.x > cx + radius || hi.y < cy - radius || lo.y > cy + radius
            {
                continue;
            }
            let n = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero();
            let light = glam::DVec3::new(-0.5, 0.5, 0.7).normalize();
            let shade = (0.55 + 0.45 * n.dot(light).abs()).clamp(0.0, 1.0);
            let h = ((tri[0].z + tri[1].z + tri[2].z) / 3.0 - t.zmin) / span;
            let rgb = [
                (170.0 + 60.0 * h) * shade,
                (200.0 - 40.0 * h) * shade,
                (150.0 - 30.0 * h) * shade,
            ]
            .map(|v| v.clamp(0.0, 255.0) as u8);
            let _ = write!(
                s,
                r##"<polygon points="{} {} {}" fill="#{:02x}{:02x}{:02x}" stroke="#{:02x}{:02x}{:02x}" stroke-width="0.8"/>"##,
                p(tri[0].x, tri[0].y),
                p(tri[1].x, tri[1].y),
                p(tri[2].x, tri[2].y),
                rgb[0],
                rgb[1],
                rgb[2],
                rgb[0],
                rgb[1],
                rgb[2]
            );
        }
    }
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
        let path = |rings: &[Vec<(f64, f64)>], close: bool| -> String {
            rings
                .iter()
                .filter(|ring| ring.len() >= 2)
                .map(|ring| {
                    let pts: Vec<String> = ring.iter().map(|&(x, y)| p(x, y)).collect();
                    format!("M{}{}", pts.join("L"), if close { "Z" } else { "" })
                })
                .collect()
        };
        match &o.shape {
            Shape::Footprint(fp) => {
                let rings: Vec<Vec<(f64, f64)>> = fp
                    .polygons
                    .iter()
                    .flat_map(|poly| poly.iter())
                    .map(|ring| ring.iter().map(|v| (v.x, v.y)).collect())
                    .collect();
                let d = path(&rings, true);
                let _ = write!(
                    s,
                    r##"<path d="{d}" fill="{fill}" fill-rule="evenodd" stroke="#555" stroke-width="0.4"/>"##
                );
            }
            Shape::Mesh(m) => {
                // The real footprint: faces seen from above (roofs, floors, sloped walls) filled,
                // vertical faces (walls) drawn as their lines, so an open mesh of walls alone
                // still shows its outline.
                let (covers, walls) = mesh_top_view(m);
                let d = path(&covers, true);
                if !d.is_empty() {
                    let _ = write!(
                        s,
                        r##"<path d="{d}" fill="{fill}" fill-rule="nonzero" stroke="none"/>"##
                    );
                }
                let w = path(&walls, false);
                if !w.is_empty() {
                    let _ = write!(
                        s,
                        r##"<path d="{w}" fill="none" stroke="{fill}" stroke-width="2"/><path d="{w}" fill="none" stroke="#555" stroke-width="0.4"/>"##
                    );
                }
            }
        }
    }
    // Objects the readers skipped (no height, ...), where their outline is known: light grey,
    // dashed.
    let mut n_skipped = 0;
    for (_, k) in &scene.report.skipped {
        let near = k
            .outline
            .iter()
            .flatten()
            .any(|v| (v.x - cx).abs() <= radius && (v.y - cy).abs() <= radius);
        if !near {
            continue;
        }
        n_skipped += 1;
        let d: String = k
            .outline
            .iter()
            .filter(|ring| ring.len() >= 2)
            .map(|ring| {
                let pts: Vec<String> = ring.iter().map(|v| p(v.x, v.y)).collect();
                format!("M{}Z", pts.join("L"))
            })
            .collect();
        let _ = write!(
            s,
            r##"<path d="{d}" fill="#eeeeee" fill-rule="evenodd" stroke="#999" stroke-width="0.6" stroke-dasharray="3 2"/>"##
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
    let view = [cx - radius, cy - radius, cx + radius, cy + radius];
    let px = |x: f64, y: f64| ((x - cx + radius) * k, (radius - (y - cy)) * k);
    let mut beyond = 0;
    for (i, q) in rec.vos().iter().enumerate() {
        let Some(g) = f.dequantize(id, rec.stand(), q) else {
            continue;
        };
        // Only the part of the VO inside the view is drawn, and its number stands where that
        // part begins, moved onto the canvas when it would fall off.
        let Some((a, b)) = clip(g.a, g.b, view) else {
            beyond += 1;
            continue;
        };
        let (a, b) = (px(a[0], a[1]), px(b[0], b[1]));
        let (lx, ly) = (a.0.clamp(4.0, size - 22.0), a.1.clamp(16.0, size - 6.0));
        let _ = write!(
            s,
            r##"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="#0050d0" stroke-width="3"/><text x="{lx:.1}" y="{ly:.1}" fill="#0050d0">{}</text>"##,
            a.0,
            a.1,
            b.0,
            b.1,
            i + 1
        );
    }
    // The scale bar, bottom left: a round length near a fifth of the view.
    let bar = scale_length(0.4 * radius);
    let (x0, y0) = (16.0, size - 18.0);
    let x1 = x0 + bar * k;
    let _ = write!(
        s,
        r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="30" fill="white" fill-opacity="0.8"/><polyline points="{x0:.1},{:.1} {x0:.1},{y0:.1} {x1:.1},{y0:.1} {x1:.1},{:.1}" fill="none" stroke="black" stroke-width="2"/><text x="{:.1}" y="{:.1}" text-anchor="middle">{} m</text>"##,
        x0 - 8.0,
        y0 - 24.0,
        x1 - x0 + 16.0,
        y0 - 6.0,
        y0 - 6.0,
        0.5 * (x0 + x1),
        y0 - 8.0,
        bar
    );
    // The caption, each line well within the picture's width (at most about 110 characters of
    // 13 px sans-serif): the whole scene's counts first, then the view's.
    let outside = if beyond > 0 {
        format!(", {beyond} beyond this view")
    } else {
        String::new()
    };
    let mut third = Vec::new();
    if baseline.is_some() {
        third.push(format!(
            "culled by single buildings alone {n_single} (orange)"
        ));
    }
    if n_skipped > 0 {
        third.push(format!("{n_skipped} skipped objects (dashed)"));
    }
    let _ = write!(
        s,
        r##"<text x="10" y="{}">cell {id}: {} VOs (blue, numbered in stored order{outside}); whole scene: PVS {} of {} objects</text><text x="10" y="{}">in this view ({:.0} m square): visible {n_vis} (grey), culled thanks to fusion {n_fused} (red)</text><text x="10" y="{}">{}</text></svg>"##,
        size + 24.0,
        rec.vos().len(),
        pvs.len(),
        scene.objects.len(),
        size + 46.0,
        2.0 * radius,
        size + 68.0,
        third.join("; ")
    );
    s.push('\n');
    s
}

/// The part of segment `a`-`b` inside the rectangle `[x0, y0, x1, y1]` (Liang-Barsky), or
/// `None` when none of it is.
fn clip(a: [f64; 2], b: [f64; 2], r: [f64; 4]) -> Option<([f64; 2], [f64; 2])> {
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (pk, qk) in [
        (-d[0], a[0] - r[0]),
        (d[0], r[2] - a[0]),
        (-d[1], a[1] - r[1]),
        (d[1], r[3] - a[1]),
    ] {
        if pk == 0.0 {
            if qk < 0.0 {
                return None;
            }
        } else {
            let t = qk / pk;
            if pk < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    (t0 <= t1).then(|| {
        (
            [a[0] + t0 * d[0], a[1] + t0 * d[1]],
            [a[0] + t1 * d[0], a[1] + t1 * d[1]],
        )
    })
}

/// The largest of 1, 2 and 5 times a power of ten that is at most `most` metres (at least 1).
fn scale_length(most: f64) -> f64 {
    let mut best = 1.0;
    let mut p = 1.0;
    while p <= most {
        for m in [1.0, 2.0, 5.0] {
            if m * p <= most {
                best = m * p;
            }
        }
        p *= 10.0;
    }
    best
}

/// Points in the plane, in order.
type Polyline = Vec<(f64, f64)>;

/// A mesh seen from above: the outer rings of the faces that cover area, counter-clockwise, with
/// their holes clockwise (so a nonzero fill unites them), and the lines of the vertical faces.
fn mesh_top_view(m: &crate::scene::Mesh) -> (Vec<Polyline>, Vec<Polyline>) {
    let mut covers = Vec::new();
    let mut walls = Vec::new();
    for f in &m.faces {
        let rings: Vec<Vec<(f64, f64)>> = f
            .rings
            .iter()
            .map(|r| {
                r.iter()
                    .filter_map(|&i| m.vertices.get(i as usize))
                    .map(|v| (v.x, v.y))
                    .collect()
            })
            .collect();
        let Some(outer) = rings.first() else { continue };
        let area2 = |r: &[(f64, f64)]| -> f64 {
            (0..r.len())
                .map(|k| {
                    let (a, b) = (r[k], r[(k + 1) % r.len()]);
                    a.0 * b.1 - b.0 * a.1
                })
                .sum()
        };
        let perimeter: f64 = (0..outer.len())
            .map(|k| {
                let (a, b) = (outer[k], outer[(k + 1) % outer.len()]);
                (b.0 - a.0).hypot(b.1 - a.1)
            })
            .sum();
        let a = area2(outer);
        // Drawing only: a face whose outline encloses (almost) no area is a wall.
        if a.abs() <= 1e-9 * perimeter * perimeter {
            walls.push(outer.clone());
            continue;
        }
        for (k, r) in rings.iter().enumerate() {
            let ccw = area2(r) > 0.0;
            let want_ccw = k == 0;
            let mut r = r.clone();
            if ccw != want_ccw {
                r.reverse();
            }
            covers.push(r);
        }
    }
    (covers, walls)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_keeps_the_part_inside_and_scale_lengths_are_round() {
        let r = [0.0, 0.0, 10.0, 10.0];
        assert_eq!(
            clip([-5.0, 5.0], [5.0, 5.0], r),
            Some(([0.0, 5.0], [5.0, 5.0]))
        );
        assert_eq!(clip([-5.0, -5.0], [-1.0, 20.0], r), None);
        assert_eq!(
            clip([2.0, 2.0], [3.0, 3.0], r),
            Some(([2.0, 2.0], [3.0, 3.0]))
        );
        assert_eq!(scale_length(200.0), 200.0);
        assert_eq!(scale_length(399.0), 200.0);
        assert_eq!(scale_length(499.0), 200.0);
        assert_eq!(scale_length(500.0), 500.0);
        assert_eq!(scale_length(0.5), 1.0);
    }
}
