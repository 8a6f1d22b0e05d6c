//! The long generator's debug picture (`vocc render --debug`, the default generator): one
//! cell's trace drawn as SVG.
//!
//! Input: a [`CellTrace`] (`vocc::bake::trace`, taken on the bake job's own plan, so the cell,
//! grid and parameters are the bake's). Output: an SVG string: the
//! hidden map of the cell's lowest slice (runs of hidden pixels), the cell's blockers,
//! the cell, the proposals, the pieces the selection certified, the VOs stored along the way and
//! those the record keeps, numbered most effective first.
//! Invariant: drawing only; every element of a kind carries its class (`hidden`, `blocker`,
//! `cell`, `proposal`, `certified`, `stored`, `picked`), one element per item, so the picture can
//! be counted against the trace.

use std::fmt::Write;

use glam::DVec2;
use vocc::bake::trace::CellTrace;

/// The SVG of `t` (its blockers drawn where they meet the view).
pub fn render(t: &CellTrace) -> String {
    // The view: the maps' extent, or the cell and what was proposed when there is no map.
    let (mut lo, mut hi) = t.cell.iter().fold(
        (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY)),
        |(l, h), &p| (l.min(p), h.max(p)),
    );
    for (_, m) in &t.maps {
        lo = lo.min(m.lo);
        hi = hi.max(m.lo + DVec2::splat(m.px * m.n as f64));
    }
    for &(_, a, b) in &t.proposals {
        (lo, hi) = (lo.min(a).min(b), hi.max(a).max(b));
    }
    let size = hi - lo;
    // y grows up in the local frame, down in SVG.
    let p = |v: DVec2| (v.x - lo.x, hi.y - v.y);
    let w = size.x.max(size.y) / 800.0;
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {:.1} {:.1}" width="800" height="{:.0}">"#,
        size.x,
        size.y,
        800.0 * size.y / size.x.max(1e-9)
    );
    let _ = writeln!(
        s,
        "<title>cell {}: {} slices, {} proposals, {} certified pieces, {} stored, {} picked</title>",
        t.id,
        t.maps.len(),
        t.proposals.len(),
        t.certified.len(),
        t.stored.len(),
        t.picked.len()
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    // The lowest slice's map (most blockers, most hidden), one rectangle per run of a row.
    if let Some((top, m)) = t.maps.first() {
        let _ = writeln!(
            s,
            r##"<g id="hidden-map" fill="#c8c8e6"><title>hidden map, slice top {top:.1} m</title>"##
        );
        for iy in 0..m.n as i64 {
            let mut ix = 0;
            while ix < m.n as i64 {
                if !m.hidden_px(ix, iy) {
                    ix += 1;
                    continue;
                }
                let start = ix;
                while ix < m.n as i64 && m.hidden_px(ix, iy) {
                    ix += 1;
                }
                let (x, y) = p(m.lo + DVec2::new(start as f64, (iy + 1) as f64) * m.px);
                let _ = writeln!(
                    s,
                    r#"<rect class="hidden" x="{x:.1}" y="{y:.1}" width="{:.1}" height="{:.1}"/>"#,
                    (ix - start) as f64 * m.px,
                    m.px
                );
            }
        }
        let _ = writeln!(s, "</g>");
    }
    let _ = writeln!(
        s,
        r##"<g fill="#888" fill-opacity="0.6" stroke="#444" stroke-width="{w:.2}">"##
    );
    for b in &t.blockers {
        let inside = b
            .iter()
            .any(|v| v.x >= lo.x && v.x <= hi.x && v.y >= lo.y && v.y <= hi.y);
        if !inside {
            continue;
        }
        let pts: Vec<String> = b
            .iter()
            .map(|&v| {
                let (x, y) = p(v);
                format!("{x:.1},{y:.1}")
            })
            .collect();
        let _ = writeln!(
            s,
            r#"<polygon class="blocker" points="{}"/>"#,
            pts.join(" ")
        );
    }
    let _ = writeln!(s, "</g>");
    let pts: Vec<String> = t
        .cell
        .iter()
        .map(|&v| {
            let (x, y) = p(v);
            format!("{x:.1},{y:.1}")
        })
        .collect();
    let _ = writeln!(
        s,
        r#"<polygon class="cell" points="{}" fill="none" stroke="black" stroke-width="{:.2}"/>"#,
        pts.join(" "),
        3.0 * w
    );
    let line = |s: &mut String, class: &str, a: DVec2, b: DVec2, style: &str, top: f64| {
        let ((x1, y1), (x2, y2)) = (p(a), p(b));
        let _ = writeln!(
            s,
            r#"<line class="{class}" x1="{x1:.1}" y1="{y1:.1}" x2="{x2:.1}" y2="{y2:.1}" {style}><title>{class}, top {top:.1} m</title></line>"#
        );
    };
    let style = |colour: &str, width: f64, extra: &str| {
        format!(
            r#"stroke="{colour}" stroke-width="{:.2}"{extra}"#,
            width * w
        )
    };
    for &(top, a, b) in &t.proposals {
        line(&mut s, "proposal", a, b, &style("#3060c0", 1.0, ""), top);
    }
    for &(top, a, b) in &t.certified {
        line(&mut s, "certified", a, b, &style("#20a040", 2.5, ""), top);
    }
    for g in &t.stored {
        let (a, b) = (DVec2::from(g.a), DVec2::from(g.b));
        let dash = format!(r#" stroke-dasharray="{:.1}""#, 6.0 * w);
        line(&mut s, "stored", a, b, &style("#e08000", 2.0, &dash), g.h);
    }
    for (k, g) in t.picked.iter().enumerate() {
        let (a, b) = (DVec2::from(g.a), DVec2::from(g.b));
        line(&mut s, "picked", a, b, &style("#d01010", 4.0, ""), g.h);
        let (x, y) = p((a + b) * 0.5);
        let _ = writeln!(
            s,
            r##"<text x="{x:.1}" y="{y:.1}" font-size="{:.1}" fill="#d01010">{}</text>"##,
            14.0 * w,
            k + 1
        );
    }
    let _ = writeln!(s, "</svg>");
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use vocc::bake::job::BakeJob;
    use vocc::bake::params::BakeParams;
    use vocc::runtime::format::Store;

    /// A street of squares: a row north of the cell at (250, 50), another east, and blocks
    /// behind them as occludees.
    fn scene() -> vocc::scene::Scene {
        let mut sq: Vec<(f64, f64, f64, f64)> = Vec::new();
        for k in 0..12 {
            sq.push((40.0 + 30.0 * k as f64, 160.0, 30.0, 40.0));
            sq.push((400.0, -200.0 + 30.0 * k as f64, 30.0, 35.0));
        }
        for k in 0..20 {
            sq.push((
                20.0 + 40.0 * (k % 10) as f64,
                260.0 + 60.0 * (k / 10) as f64,
                20.0,
                12.0,
            ));
        }
        sq.push((0.0, -300.0, 2.0, 3.0));
        let feats: Vec<String> = sq
            .iter()
            .map(|&(x, y, d, h)| {
                format!(
                    r#"{{"type":"Feature","properties":{{"h":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                    x + d,
                    x + d,
                    y + d,
                    y + d
                )
            })
            .collect();
        let text = format!(
            r#"{{"type":"FeatureCollection","features":[{}]}}"#,
            feats.join(",")
        );
        let opts = vocc::scene::ReadOptions {
            height_attr: Some("h".into()),
            ..Default::default()
        };
        vocc::scene::load_bytes(&[("street.geojson".into(), text.as_bytes())], &opts).unwrap()
    }

    fn count(svg: &str, class: &str) -> usize {
        svg.matches(&format!(r#"class="{class}""#)).count()
    }

    #[test]
    fn the_picture_shows_what_the_bake_stores_for_the_cell_on_its_grid() {
        let s = scene();
        let job = BakeJob::new(&s, BakeParams::default()).unwrap();
        let plan = job.plan();
        let local = DVec2::new(250.0, 50.0) - DVec2::new(s.origin.x, s.origin.y);
        let id = plan.frame.grid.cell_at(local.x, local.y).unwrap();
        let t = vocc::bake::trace::trace_cell(plan, id).unwrap();
        // The bake's own cell and grid.
        assert_eq!(t.cell, plan.cell_polygon(id));
        // What it stores for the cell is what the picture says it picked.
        let out = job.cells(&[id]).unwrap().run(&|_| {}).unwrap();
        let store = Store::parse(&out.store).unwrap();
        let rec = store.cell(id).unwrap();
        let stored: Vec<_> = rec
            .vos()
            .iter()
            .map(|q| store.frame().dequantize(id, rec.stand(), q).unwrap())
            .collect();
        assert!(!stored.is_empty(), "the street hides something");
        assert_eq!(t.picked, stored);
        assert!(t.proposals.len() >= t.picked.len() && !t.certified.is_empty());
        assert!(t.stored.len() >= t.picked.len());
        let svg = render(&t);
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert_eq!(count(&svg, "cell"), 1);
        assert_eq!(count(&svg, "proposal"), t.proposals.len());
        assert_eq!(count(&svg, "certified"), t.certified.len());
        assert_eq!(count(&svg, "stored"), t.stored.len());
        assert_eq!(count(&svg, "picked"), t.picked.len());
        assert!(count(&svg, "hidden") > 0 && count(&svg, "blocker") >= 24);
        // The hidden runs cover what the map says is hidden, pixel for pixel.
        let m = &t.maps[0].1;
        let hidden_px = (0..m.n as i64)
            .flat_map(|y| (0..m.n as i64).map(move |x| (x, y)))
            .filter(|&(x, y)| m.hidden_px(x, y))
            .count() as f64;
        let drawn: f64 = svg
            .lines()
            .filter(|l| l.contains(r#"class="hidden""#))
            .map(|l| {
                let w = l.split(r#"width=""#).nth(1).unwrap();
                w[..w.find('"').unwrap()].parse::<f64>().unwrap()
            })
            .sum();
        assert!((drawn / m.px - hidden_px).abs() < 0.5 * hidden_px.sqrt() + 1.0);
    }
}
