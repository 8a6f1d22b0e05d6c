//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::sync::OnceLock;
use std::time::SystemTime;

use vocc::scene::{self, ReadOptions, Scene};

/// A path inside the repository.
pub fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

pub const LYON: &str = "data/lyon1/buildings_lyon1.geojson";

pub fn lyon_options() -> ReadOptions {
    ReadOptions {
        height_attr: Some("HAUTEUR".into()),
        ..ReadOptions::default()
    }
}

pub fn load_lyon() -> Scene {
    scene::load(&[repo(LYON)], &lyon_options()).expect("Lyon loads")
}

/// A fresh temporary directory under the target dir, unique per test name.
pub fn temp_dir(name: &str) -> PathBuf {
    let d = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Uniform numbers in `[0, 1)` from a seed: splitmix64, the top 53 bits of each state.
pub fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut v = state;
        v = (v ^ (v >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        v = (v ^ (v >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        ((v ^ (v >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
}

use glam::DVec2;
use vocc::geom::predicates::{
    orient, point_in_convex, segment_meets_convex, Containment, Orientation,
};

/// Closed segments `[a, b]` and `[c, d]` share a point: written here from orientation signs
/// alone, apart from the predicates module's segment code (which the verifier uses).
pub fn segments_meet(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> bool {
    let s = |p: DVec2, q: DVec2, r: DVec2| match orient(p, q, r) {
        Orientation::Ccw => 1,
        Orientation::Cw => -1,
        Orientation::Collinear => 0,
    };
    let (d1, d2, d3, d4) = (s(a, b, c), s(a, b, d), s(c, d, a), s(c, d, b));
    if d1 * d2 < 0 && d3 * d4 < 0 {
        return true;
    }
    // Collinear triples: the point lies within the other segment's box.
    let within = |p: DVec2, q: DVec2, r: DVec2| {
        r.x >= p.x.min(q.x) && r.x <= p.x.max(q.x) && r.y >= p.y.min(q.y) && r.y <= p.y.max(q.y)
    };
    (d1 == 0 && within(a, b, c))
        || (d2 == 0 && within(a, b, d))
        || (d3 == 0 && within(c, d, a))
        || (d4 == 0 && within(c, d, b))
}

/// Does the closed segment `[q, c]` meet blocker `b`? A 2-vertex blocker is a wall segment,
/// tested with [`segments_meet`]; a polygon with the predicates' convex test.
pub fn meets_blocker(q: DVec2, c: DVec2, b: &[DVec2]) -> bool {
    if b.len() == 2 {
        segments_meet(q, c, b[0], b[1])
    } else {
        segment_meets_convex(q, c, b)
    }
}

/// Brute-force oracle, independent of the verifier: is `q` hidden from the convex `cell` by the
/// blockers (convex polygons, or 2-vertex wall segments)? Casts
/// exact segments from `q` to `n` points just inside the cell's boundary and to points near each
/// vertex; `q` is visible if any of them misses every blocker. (If `q` sees any point of the
/// cell it sees a boundary point, so boundary sampling suffices up to its density.)
pub fn brute_hidden(cell: &[DVec2], blockers: &[Vec<DVec2>], q: DVec2, n: usize) -> bool {
    if point_in_convex(cell, q) != Containment::Outside {
        return false;
    }
    let centre = cell.iter().copied().sum::<DVec2>() / cell.len() as f64;
    let perimeter: f64 = (0..cell.len())
        .map(|i| cell[i].distance(cell[(i + 1) % cell.len()]))
        .sum();
    let mut targets: Vec<DVec2> = Vec::with_capacity(n + cell.len());
    for k in 0..n {
        let mut d = perimeter * (k as f64 + 0.5) / n as f64;
        for i in 0..cell.len() {
            let (a, b) = (cell[i], cell[(i + 1) % cell.len()]);
            let len = a.distance(b);
            if d <= len {
                targets.push(a + (b - a) * (d / len));
                break;
            }
            d -= len;
        }
    }
    targets.extend(cell.iter().copied());
    targets.iter().all(|&t| {
        // Pull the target a hair inside so it surely belongs to the cell.
        let c = centre + (t - centre) * (1.0 - 1e-9);
        debug_assert!(point_in_convex(cell, c) != Containment::Outside);
        blockers.iter().any(|b| meets_blocker(q, c, b))
    })
}

/// Points exactly on `[a, b]` at parameters k / 2^levels (exact for dyadic endpoints).
pub fn dyadic_points(a: DVec2, b: DVec2, levels: u32) -> Vec<DVec2> {
    let n = 1u32 << levels;
    (0..=n)
        .map(|k| {
            let t = k as f64 / n as f64;
            let p = a + (b - a) * t;
            assert_eq!(p, a * (1.0 - t) + b * t, "sample point is not exact");
            p
        })
        .collect()
}

/// Checks every stored VO of `store`, decoded as an engine decodes it, against rule 2 and rule 1:
/// the exact verifier and [`brute_hidden`], over the blockers that rule 2 admits (filtered here
/// again, apart from the bake's own filter). Returns (cells with VOs, VOs checked); panics on the
/// first VO that fails.
pub fn check_stored_vos(s: &Scene, store: &vocc::runtime::format::Store) -> (usize, usize) {
    use vocc::geom::predicates::convex_interiors_disjoint;
    use vocc::geom::verify::Verifier;
    let f = *store.frame();
    let mut checked = 0;
    let mut cells_with_vos = 0;
    for id in 0..store.cell_count() {
        let rec = store.cell(id).unwrap();
        assert!(rec.vos().len() <= 10);
        if rec.vos().is_empty() {
            continue;
        }
        cells_with_vos += 1;
        let r = f.grid.cell_rect(id).unwrap();
        let cell = [
            DVec2::new(r[0], r[1]),
            DVec2::new(r[2], r[1]),
            DVec2::new(r[2], r[3]),
            DVec2::new(r[0], r[3]),
        ];
        let view = f.cell_view(id, rec.stand()).unwrap();
        for q in rec.vos() {
            let vo = f.dequantize(id, rec.stand(), q).unwrap();
            let (a, b) = (DVec2::from(vo.a), DVec2::from(vo.b));
            assert!(vo.h >= view.e1 && vo.g <= view.e0);
            // Rule 2, with the brief's bound and lambda <= 1 (ARCHITECTURE.md).
            let d_near = rect_segment_distance(r, a, b);
            assert!(d_near > 0.0, "cell {id}: a VO touches its cell");
            // Blockers outside the box of the cell and the VO meet no segment between them.
            let lo = cell[0].min(a).min(b);
            let hi = cell[2].max(a).max(b);
            // Rule 2 for a VO at least `dn` from the cell (`dn <= d_near` only raises the
            // bound, so these blockers support the VO too).
            let used_for = |dn: f64, beside: bool| -> Vec<Vec<DVec2>> {
                // The objects' blockers and the terrain's (solid ground).
                s.blockers
                    .iter()
                    .chain(s.terrain_blockers())
                    .filter(|bl| {
                        let (bl_lo, bl_hi) = bl
                            .polygon
                            .iter()
                            .fold((DVec2::INFINITY, DVec2::NEG_INFINITY), |(l, h), v| {
                                (l.min(*v), h.max(*v))
                            });
                        bl_lo.x <= hi.x && bl_hi.x >= lo.x && bl_lo.y <= hi.y && bl_hi.y >= lo.y
                    })
                    .filter(|bl| {
                        let d_far = cell
                            .iter()
                            .flat_map(|c| bl.polygon.iter().map(move |v| c.distance(*v)))
                            .fold(0.0, f64::max);
                        // With `beside`, rule 2's tighter bounds for this segment too:
                        // lambda <= d_far / (d_far + dist(B, s)), and lambda <= 1 - (the
                        // blocker's least distance from the VO's line) / (the cell's greatest)
                        // (ARCHITECTURE.md).
                        let beside = if beside {
                            let along = d_far / (d_far + poly_segment_distance(&bl.polygon, a, b));
                            along.min(line_ratio(&cell, &bl.polygon, a, b))
                        } else {
                            1.0
                        };
                        let lambda = (d_far / dn).min(beside).min(1.0);
                        let high = view.e1 + (vo.h - view.e1) * lambda;
                        let low = view.e0 - (view.e0 - vo.g) * lambda;
                        (bl.base <= view.e0.min(vo.g) || bl.base <= low - 1e-6)
                            && bl.top >= high
                            && convex_interiors_disjoint(&bl.polygon, &cell)
                    })
                    .map(|bl| bl.polygon.clone())
                    .collect()
            };
            // The verifier's search is not monotone in its blockers (a different set leads its
            // sweep through other certificates, and at the exit from a blocker it may find none
            // for a centimetre), and the bake certifies over the supporters of a distance band
            // within its search distance: the VO passes when the verifier certifies it over the
            // rule-2 supporters for its own distance or any lower one, all of them or those
            // within the search distance (each such set supports it).
            let mut floors = vec![d_near];
            floors.extend(
                (0..8)
                    .map(|k| 50.0 * f64::from(1u32 << k))
                    .filter(|&d| d < d_near)
                    .rev(),
            );
            floors.push(f64::MIN_POSITIVE);
            // Each also within the bake's search distance of the cell (900 m per axis).
            let search = 900.0;
            // The bake raises a stored VO by rule 2's tighter bound over the supporters of its
            // own segment: that set is tried too.
            let sets = floors.iter().map(|&dn| (dn, false)).chain([(d_near, true)]);
            let certified = sets.into_iter().any(|(dn, beside)| {
                let set = used_for(dn, beside);
                [false, true].into_iter().any(|within| {
                    let refs: Vec<&[DVec2]> = set
                        .iter()
                        .filter(|p| {
                            !within
                                || p.iter().any(|v| {
                                    v.x >= cell[0].x - search
                                        && v.x <= cell[2].x + search
                                        && v.y >= cell[0].y - search
                                        && v.y <= cell[2].y + search
                                })
                        })
                        .map(|p| p.as_slice())
                        .collect();
                    Verifier::new(&cell, refs.iter().copied()).is_hidden(a, b)
                })
            });
            let used = used_for(d_near, true);
            // The sweep's search may miss a certificate over a centimetre where the segment
            // leaves a blocker (module header of `geom/verify.rs`), where the bake's own sweep,
            // from other certificates, did not. Then the verifier over this VO's own supporters
            // must certify all of it but gaps under GAP_M, and the brute-force oracle must find
            // each gap hidden, densely.
            const GAP_M: f64 = 0.05;
            let certified = certified || {
                let refs: Vec<&[DVec2]> = used.iter().map(|p| p.as_slice()).collect();
                let parts = Verifier::new(&cell, refs.iter().copied()).hidden_parts(a, b);
                let mut edges = vec![0.0];
                for h in &parts {
                    edges.push(h.t0);
                    edges.push(h.t1);
                }
                edges.push(1.0);
                let len = a.distance(b);
                !parts.is_empty()
                    && edges.chunks(2).all(|g| {
                        let (t0, t1) = (g[0], g[1]);
                        (t1 - t0) * len < GAP_M
                            && (0..=8).all(|k| {
                                let t = t0 + (t1 - t0) * k as f64 / 8.0;
                                brute_hidden(&cell, &used, a + (b - a) * t, 2000)
                            })
                    })
            };
            assert!(
                certified,
                "cell {id}: stored VO {q:?} ({a} - {b}, top {}) is not certified hidden",
                vo.h
            );
            // The brute-force oracle, on points along the VO.
            for k in 0..=8 {
                let p = a + (b - a) * (k as f64 / 8.0);
                assert!(
                    brute_hidden(&cell, &used, p, 400),
                    "cell {id}: a ray reaches {p} on VO {q:?}"
                );
            }
            checked += 1;
        }
    }
    (cells_with_vos, checked)
}

/// `1 - d_poly / d_line` for the line through `a`, `b`: `d_line` the greatest distance of a cell
/// corner from it, `d_poly` the least distance of a polygon vertex from it on the cell's side (1
/// when the polygon reaches the line or the line meets the cell; written here again, apart from
/// the bake's own).
fn line_ratio(cell: &[DVec2; 4], poly: &[DVec2], a: DVec2, b: DVec2) -> f64 {
    let n = (b - a).perp().normalize();
    let centre = (cell[0] + cell[2]) * 0.5;
    let sign = if n.dot(centre - a) > 0.0 { 1.0 } else { -1.0 };
    let dist = |p: DVec2| sign * n.dot(p - a);
    let d_line = cell
        .iter()
        .map(|&c| dist(c))
        .fold(f64::NEG_INFINITY, f64::max);
    let nearest = cell.iter().map(|&c| dist(c)).fold(f64::INFINITY, f64::min);
    let d_poly = poly.iter().map(|&v| dist(v)).fold(f64::INFINITY, f64::min);
    if nearest > 0.0 && d_poly > 0.0 {
        1.0 - d_poly / d_line
    } else {
        1.0
    }
}

/// Least distance between a convex polygon (or a 2-point wall) and the segment `a`-`b`, 0 when
/// they meet (written here again, apart from the bake's own): for disjoint convex sets it is
/// between a vertex of one and an edge of the other.
fn poly_segment_distance(poly: &[DVec2], a: DVec2, b: DVec2) -> f64 {
    let seg = |p: DVec2, u: DVec2, v: DVec2| {
        let d = v - u;
        let l2 = d.length_squared();
        let t = if l2 > 0.0 {
            ((p - u).dot(d) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        p.distance(u + d * t)
    };
    let n = if poly.len() == 2 { 1 } else { poly.len() };
    let edges = || (0..n).map(|i| (poly[i], poly[(i + 1) % poly.len()]));
    let cross = |p: DVec2, q: DVec2, r: DVec2| (q - p).perp_dot(r - p);
    let mut m = f64::INFINITY;
    for (u, v) in edges() {
        // Crossing (or touching) edges: distance 0.
        let (d1, d2) = (cross(a, b, u), cross(a, b, v));
        let (d3, d4) = (cross(u, v, a), cross(u, v, b));
        if d1 * d2 <= 0.0 && d3 * d4 <= 0.0 {
            return 0.0;
        }
        m = m.min(seg(a, u, v)).min(seg(b, u, v));
    }
    for &p in poly {
        m = m.min(seg(p, a, b));
    }
    // The segment inside the polygon (counter-clockwise): distance 0.
    if poly.len() >= 3
        && (0..poly.len()).all(|i| cross(poly[i], poly[(i + 1) % poly.len()], a) >= 0.0)
    {
        return 0.0;
    }
    m
}

/// Least distance between an axis-aligned rectangle and a segment that misses it (written here
/// again, apart from the bake's own).
fn rect_segment_distance(r: [f64; 4], a: DVec2, b: DVec2) -> f64 {
    let to_rect = |p: DVec2| {
        let dx = (r[0] - p.x).max(p.x - r[2]).max(0.0);
        let dy = (r[1] - p.y).max(p.y - r[3]).max(0.0);
        dx.hypot(dy)
    };
    let to_seg = |p: DVec2| {
        let d = b - a;
        let t = ((p - a).dot(d) / d.length_squared()).clamp(0.0, 1.0);
        p.distance(a + d * t)
    };
    let corners = [
        DVec2::new(r[0], r[1]),
        DVec2::new(r[2], r[1]),
        DVec2::new(r[2], r[3]),
        DVec2::new(r[0], r[3]),
    ];
    corners
        .iter()
        .map(|&c| to_seg(c))
        .chain([to_rect(a), to_rect(b)])
        .fold(f64::INFINITY, f64::min)
}

/// The `vocc` binary of the CLI package (cli/, `vocc-cli`), which `cargo test` at the root builds
/// beside these tests (cargo gives `CARGO_BIN_EXE_*` to a package's own tests only). Panics,
/// naming the command that builds it, when it is missing or older than a source file of the
/// library or the CLI (`cargo test --test all ...` alone does not rebuild it).
pub fn vocc_bin() -> &'static str {
    static BIN: OnceLock<String> = OnceLock::new();
    BIN.get_or_init(|| {
        let exe = std::env::current_exe().expect("the test binary's path");
        // target/<profile>/deps/<test>-<hash>: the binary is in target/<profile>/.
        let dir = exe
            .parent()
            .and_then(Path::parent)
            .expect("the profile's target folder");
        let bin = dir.join(format!("vocc{}", std::env::consts::EXE_SUFFIX));
        let build =
            "`cargo test` at the root builds it, or `cargo build --profile test -p vocc-cli`";
        let built = std::fs::metadata(&bin)
            .and_then(|m| m.modified())
            .unwrap_or_else(|e| panic!("the CLI {} is missing ({e}): {build}", bin.display()));
        let mut newest: Option<(SystemTime, PathBuf)> = None;
        for d in ["src", "cli/src"] {
            newest_file(&repo(d), &mut newest);
        }
        if let Some((t, p)) = newest {
            assert!(
                t <= built,
                "the CLI {} is older than {}: {build}",
                bin.display(),
                p.display()
            );
        }
        bin.to_string_lossy().into_owned()
    })
}

/// The most recently modified file under `dir`.
fn newest_file(dir: &Path, newest: &mut Option<(SystemTime, PathBuf)>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            newest_file(&p, newest);
        } else if let Ok(t) = e.metadata().and_then(|m| m.modified()) {
            if newest.as_ref().is_none_or(|(n, _)| t > *n) {
                *newest = Some((t, p));
            }
        }
    }
}
