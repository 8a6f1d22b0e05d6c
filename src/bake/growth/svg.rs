//! Pictures of one cell's growth.
//!
//! Input: the cell, the blockers, and the growth output. Output: an SVG document (top view,
//! y up): blockers grey, seeds blue, the cell yellow, supporting lines (umbra boundaries) purple,
//! separating polylines red, dense VOs black.
//! Invariant: drawing only; nothing here decides anything.

use std::fmt::Write;

use glam::DVec2;

use super::dense::CellVos;
use crate::bake::{bounds, BlockerSet};

/// Renders the cell, its growth trace and VOs, and the blockers around them. The frame holds
/// the cell, every chain's blockers and every VO, plus `margin` metres.
pub fn render(cell: &[DVec2], set: &BlockerSet, vos: &CellVos, margin: f64) -> String {
    let (mut lo, mut hi) = bounds(cell);
    for t in &vos.traces {
        for step in &t.steps {
            for &id in &step.chain {
                let (a, b) = bounds(&set.polys[id as usize]);
                lo = lo.min(a);
                hi = hi.max(b);
            }
        }
    }
    for v in &vos.vos {
        lo = lo.min(v.a).min(v.b);
        hi = hi.max(v.a).max(v.b);
    }
    let lo = lo - DVec2::splat(margin);
    let hi = hi + DVec2::splat(margin);
    let radius = (hi - lo).max_element();
    let size = hi - lo;
    let scale = 900.0 / size.x.max(size.y);
    let tx = |p: DVec2| ((p.x - lo.x) * scale, (hi.y - p.y) * scale);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{:.0}" height="{:.0}" viewBox="0 0 {:.0} {:.0}" font-family="sans-serif" font-size="12">"#,
        size.x * scale,
        size.y * scale,
        size.x * scale,
        size.y * scale
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let poly = |s: &mut String, p: &[DVec2], style: &str| {
        let pts: Vec<String> = p
            .iter()
            .map(|&v| {
                let (x, y) = tx(v);
                format!("{x:.2},{y:.2}")
            })
            .collect();
        let _ = writeln!(s, r#"<polygon points="{}" {style}/>"#, pts.join(" "));
    };
    let line = |s: &mut String, a: DVec2, b: DVec2, style: &str| {
        let ((x0, y0), (x1, y1)) = (tx(a), tx(b));
        let _ = writeln!(
            s,
            r#"<line x1="{x0:.2}" y1="{y0:.2}" x2="{x1:.2}" y2="{y1:.2}" {style}/>"#
        );
    };
    let seeds: Vec<u32> = vos.traces.iter().map(|t| t.seed).collect();
    for id in set.in_box(lo, hi) {
        let style = if seeds.contains(&id) {
            r##"fill="#6fa8dc" stroke="#1c4587" stroke-width="1""##
        } else {
            r##"fill="#cccccc" stroke="#666666" stroke-width="0.5""##
        };
        poly(&mut s, &set.polys[id as usize], style);
    }
    poly(
        &mut s,
        cell,
        r##"fill="#ffe599" stroke="#bf9000" stroke-width="1.5""##,
    );
    // The last step of each seed's growth: its final lines, extended beyond the contacts.
    let reach = radius * 2.0;
    for t in &vos.traces {
        let Some(step) = t.steps.last() else { continue };
        for (a, b) in [step.support_left, step.support_right] {
            let d = (b - a).normalize_or_zero();
            line(
                &mut s,
                a,
                b + d * reach,
                r##"stroke="#8e44ad" stroke-width="1" stroke-dasharray="6,3""##,
            );
        }
        for pl in [&step.separating_left, &step.separating_right] {
            if pl.len() >= 2 {
                let d = (pl[1] - pl[0]).normalize_or_zero();
                line(
                    &mut s,
                    pl[0],
                    pl[1] + d * reach * 0.25,
                    r##"stroke="#cc0000" stroke-width="1""##,
                );
                for w in pl[2..].chunks(2) {
                    if let [a, b] = w {
                        line(&mut s, *a, *b, r##"stroke="#cc0000" stroke-width="1.5""##);
                    }
                }
            }
        }
    }
    for v in &vos.vos {
        line(&mut s, v.a, v.b, r##"stroke="black" stroke-width="2.5""##);
    }
    let _ = writeln!(
        s,
        r##"<text x="8" y="16">cell (yellow), seeds (blue), supporting lines (purple, dashed), separating lines (red)</text>"##
    );
    let _ = writeln!(
        s,
        r##"<text x="8" y="32">{} dense VOs (black), verifier rejections: {}</text>"##,
        vos.vos.len(),
        vos.rejected()
    );
    s.push_str("</svg>\n");
    s
}
