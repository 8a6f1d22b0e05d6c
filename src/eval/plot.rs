//! Plots as plain SVG: line and scatter charts with axes, and a cell map.
//!
//! Input: series of (x, y) points with labels, or per-cell values on a grid.
//! Output: an SVG document as a string. Invariant: no dependency; every number printed is
//! finite (non-finite points are left out).

use std::fmt::Write;

/// One series of a chart.
pub struct Series {
    pub label: String,
    pub points: Vec<(f64, f64)>,
    /// Draw lines between points (else markers only).
    pub line: bool,
}

const W: f64 = 640.0;
const H: f64 = 400.0;
const L: f64 = 70.0;
const R: f64 = 180.0;
const T: f64 = 40.0;
const B: f64 = 55.0;
const COLOURS: [&str; 11] = [
    "#000000", "#bcbd22", "#7f7f7f", "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd",
    "#8c564b", "#e377c2", "#17becf",
];

fn nice_range(lo: f64, hi: f64) -> (f64, f64) {
    if !(lo.is_finite() && hi.is_finite()) {
        return (0.0, 1.0);
    }
    if hi - lo < 1e-12 {
        return (lo - 0.5, hi + 0.5);
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

/// A chart of `series` with axis labels and a title.
pub fn chart(title: &str, x_label: &str, y_label: &str, series: &[Series]) -> String {
    let pts = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in pts {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (x0, x1) = nice_range(x0, x1);
    let (y0, y1) = nice_range(y0.min(0.0), y1);
    let px = |x: f64| L + (x - x0) / (x1 - x0) * (W - L - R);
    let py = |y: f64| H - B - (y - y0) / (y1 - y0) * (H - T - B);
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12"><rect width="100%" height="100%" fill="white"/>"#
    );
    let _ = write!(
        s,
        r#"<text x="{}" y="22" font-size="14" font-weight="bold">{}</text>"#,
        L,
        esc(title)
    );
    // Axes and ticks.
    let _ = write!(
        s,
        r##"<line x1="{L}" y1="{}" x2="{}" y2="{}" stroke="#000"/><line x1="{L}" y1="{T}" x2="{L}" y2="{}" stroke="#000"/>"##,
        H - B,
        W - R,
        H - B,
        H - B
    );
    for i in 0..=5 {
        let fx = x0 + (x1 - x0) * i as f64 / 5.0;
        let fy = y0 + (y1 - y0) * i as f64 / 5.0;
        let _ = write!(
            s,
            r##"<line x1="{0:.1}" y1="{1}" x2="{0:.1}" y2="{2}" stroke="#ccc"/><text x="{0:.1}" y="{3}" text-anchor="middle">{4}</text>"##,
            px(fx),
            T,
            H - B,
            H - B + 16.0,
            fmt_num(fx)
        );
        let _ = write!(
            s,
            r##"<line x1="{0}" y1="{1:.1}" x2="{2}" y2="{1:.1}" stroke="#eee"/><text x="{3}" y="{4:.1}" text-anchor="end">{5}</text>"##,
            L,
            py(fy),
            W - R,
            L - 6.0,
            py(fy) + 4.0,
            fmt_num(fy)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{}" y="{}" text-anchor="middle">{}</text>"#,
        (L + W - R) / 2.0,
        H - 12.0,
        esc(x_label)
    );
    let _ = write!(
        s,
        r#"<text transform="translate(16,{}) rotate(-90)" text-anchor="middle">{}</text>"#,
        (T + H - B) / 2.0,
        esc(y_label)
    );
    for (k, ser) in series.iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        let p: Vec<(f64, f64)> = ser
            .points
            .iter()
            .copied()
            .filter(|p| p.0.is_finite() && p.1.is_finite())
            .collect();
        if ser.line && p.len() > 1 {
            let d: Vec<String> = p
                .iter()
                .map(|&(x, y)| format!("{:.1},{:.1}", px(x), py(y)))
                .collect();
            let _ = write!(
                s,
                r#"<polyline points="{}" fill="none" stroke="{c}" stroke-width="2"/>"#,
                d.join(" ")
            );
        }
        for &(x, y) in &p {
            let _ = write!(
                s,
                r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{c}"/>"#,
                px(x),
                py(y)
            );
        }
        let ly = T + 16.0 * k as f64;
        let _ = write!(
            s,
            r#"<rect x="{}" y="{}" width="10" height="10" fill="{c}"/><text x="{}" y="{}">{}</text>"#,
            W - R + 12.0,
            ly,
            W - R + 26.0,
            ly + 9.0,
            esc(&ser.label)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// A map of a grid: each cell filled by `value` (None: grey) on a colour ramp from `lo` (green)
/// to `hi` (red), with the object footprints' boxes drawn thin.
pub fn cell_map(
    title: &str,
    nx: u32,
    ny: u32,
    value: &dyn Fn(u32) -> Option<f64>,
    lo: f64,
    hi: f64,
    legend: &str,
) -> String {
    let cell = (560.0 / nx.max(ny) as f64).clamp(2.0, 40.0);
    let (w, h) = (nx as f64 * cell + 40.0, ny as f64 * cell + 80.0);
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" font-family="sans-serif" font-size="12"><rect width="100%" height="100%" fill="white"/><text x="20" y="22" font-size="14" font-weight="bold">{}</text>"#,
        esc(title)
    );
    for j in 0..ny {
        for i in 0..nx {
            let id = j * nx + i;
            let fill = match value(id) {
                Some(v) if v.is_finite() => ramp(((v - lo) / (hi - lo)).clamp(0.0, 1.0)),
                _ => "#dddddd".to_string(),
            };
            // Row 0 is the southernmost: draw it at the bottom.
            let _ = write!(
                s,
                r##"<rect x="{:.1}" y="{:.1}" width="{cell:.1}" height="{cell:.1}" fill="{fill}" stroke="#fff" stroke-width="0.5"/>"##,
                20.0 + i as f64 * cell,
                40.0 + (ny - 1 - j) as f64 * cell
            );
        }
    }
    let y = h - 28.0;
    for k in 0..=10 {
        let t = k as f64 / 10.0;
        let _ = write!(
            s,
            r#"<rect x="{}" y="{y}" width="20" height="10" fill="{}"/>"#,
            20.0 + 20.0 * k as f64,
            ramp(t)
        );
    }
    let _ = write!(
        s,
        r#"<text x="20" y="{}">{}</text><text x="250" y="{}">{} (grey: no value)</text></svg>"#,
        y + 24.0,
        fmt_num(lo),
        y + 9.0,
        esc(&format!("{legend}: {} .. {}", fmt_num(lo), fmt_num(hi)))
    );
    s.push('\n');
    s
}

fn ramp(t: f64) -> String {
    // green (low) -> yellow -> red (high)
    let (r, g) = if t < 0.5 {
        (2.0 * t, 1.0)
    } else {
        (1.0, 2.0 * (1.0 - t))
    };
    format!(
        "#{:02x}{:02x}{:02x}",
        (40.0 + 200.0 * r) as u8,
        (40.0 + 160.0 * g) as u8,
        60
    )
}

fn fmt_num(v: f64) -> String {
    if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.2}")
    }
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}
