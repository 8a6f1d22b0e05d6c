//! Convex decomposition of a valid footprint polygon.
//!
//! Input: rings accepted by [`super::footprint::repair_polygon`] (exterior counter-clockwise,
//! holes clockwise, simple, not touching), local coordinates.
//! Output: strictly convex counter-clockwise pieces whose union is the polygon and whose
//! interiors are pairwise disjoint.
//! Method: spade's constrained Delaunay triangulation with every ring edge as a constraint;
//! triangles inside the polygon found by crossing parity from the outer face; then
//! Hertel–Mehlhorn merging: diagonals are removed, longest first, whenever both of their
//! endpoints stay convex, which gives at most four times the optimal number of pieces.
//! Invariants: pieces use only input vertices (no constructed points); every convexity decision
//! is an exact orientation test; collinear vertices are dropped from the output, which changes
//! no area.

use glam::DVec2;
use spade::handles::FixedVertexHandle;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use super::Ring;
use crate::geom::predicates::{is_strictly_convex_ccw, orient, Orientation};

/// Why a polygon could not be decomposed. After ring validation none of these is expected; they
/// are reported rather than trusted away.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DecomposeError {
    #[error("spade refused a vertex: {0}")]
    Insertion(String),
    #[error("a ring edge could not be added as a constraint")]
    ConstraintRefused,
    #[error("a merged piece is not strictly convex")]
    NotConvex,
}

type Cdt = ConstrainedDelaunayTriangulation<Point2<f64>>;

/// Splits a valid polygon into convex pieces.
pub fn convex_pieces(rings: &[Ring]) -> Result<Vec<Vec<DVec2>>, DecomposeError> {
    // A convex exterior without holes is its own piece.
    if rings.len() == 1 {
        let simplified = drop_collinear(rings[0].clone());
        if is_strictly_convex_ccw(&simplified) {
            return Ok(vec![simplified]);
        }
    }
    let mut cdt = Cdt::new();
    for ring in rings {
        let handles: Vec<FixedVertexHandle> = ring
            .iter()
            .map(|p| cdt.insert(Point2::new(p.x, p.y)))
            .collect::<Result<_, _>>()
            .map_err(|e| DecomposeError::Insertion(format!("{e:?}")))?;
        for i in 0..handles.len() {
            let (a, b) = (handles[i], handles[(i + 1) % handles.len()]);
            if cdt.try_add_constraint(a, b).is_empty() && !cdt.exists_constraint(a, b) {
                return Err(DecomposeError::ConstraintRefused);
            }
        }
    }
    let inside = classify_faces(&cdt);

    // One piece per inside triangle: three half-edges `3f + k` from its vertex k to vertex
    // k + 1 (counter-clockwise), linked in a cycle. Merging two pieces across a diagonal
    // relinks four half-edges, so the whole merge is linear in the number of triangles (copying
    // vertex lists made a piece of m vertices cost O(m) per merge: quadratic for a polygon of
    // 10^6 vertices).
    let nf = cdt.num_all_faces();
    let mut piece_of: Vec<usize> = (0..nf).collect();
    let mut from: Vec<usize> = vec![usize::MAX; 3 * nf];
    let mut next: Vec<usize> = (0..3 * nf).collect();
    let mut prev: Vec<usize> = (0..3 * nf).collect();
    // A live half-edge of each piece, where its vertex cycle starts.
    let mut start: Vec<usize> = (0..nf).map(|f| 3 * f).collect();
    for f in cdt.inner_faces() {
        let fi = f.fix().index();
        if inside[fi] {
            for (k, v) in f.vertices().iter().enumerate() {
                from[3 * fi + k] = v.fix().index();
                next[3 * fi + k] = 3 * fi + (k + 1) % 3;
                prev[3 * fi + k] = 3 * fi + (k + 2) % 3;
            }
        }
    }
    let pos: Vec<DVec2> = cdt
        .vertices()
        .map(|v| DVec2::new(v.position().x, v.position().y))
        .collect();
    // The half-edge u -> v of inside triangle f.
    let half_edge = |from: &[usize], f: usize, u: usize, v: usize| {
        (3 * f..3 * f + 3).find(|&h| from[h] == u && from[3 * f + (h - 3 * f + 1) % 3] == v)
    };

    // Diagonals: unconstrained edges with an inside triangle on both sides.
    let mut diagonals: Vec<(f64, usize, usize, usize, usize)> = Vec::new();
    for e in cdt.undirected_edges() {
        if cdt.is_constraint_edge(e.fix()) {
            continue;
        }
        let d = e.as_directed();
        let (Some(fa), Some(fb)) = (d.face().as_inner(), d.rev().face().as_inner()) else {
            continue;
        };
        let (fa, fb) = (fa.fix().index(), fb.fix().index());
        if inside[fa] && inside[fb] {
            let (u, v) = (d.from().fix().index(), d.to().fix().index());
            diagonals.push(((pos[u] - pos[v]).length_squared(), u, v, fa, fb));
        }
    }
    // Longest first; ties broken by indices so the result is deterministic.
    diagonals.sort_by(|a, b| {
        b.0.total_cmp(&a.0)
            .then((a.1, a.2, a.3, a.4).cmp(&(b.1, b.2, b.3, b.4)))
    });

    fn find(piece_of: &mut [usize], mut f: usize) -> usize {
        while piece_of[f] != f {
            piece_of[f] = piece_of[piece_of[f]];
            f = piece_of[f];
        }
        f
    }
    for &(_, u, v, fa, fb) in &diagonals {
        let (pa, pb) = (find(&mut piece_of, fa), find(&mut piece_of, fb));
        if pa == pb {
            continue;
        }
        // `fa` lies left of u->v, so its piece runs u->v; the other piece runs v->u. Each
        // half-edge of a diagonal stays in its piece until that diagonal is removed.
        let (Some(h1), Some(h2)) = (half_edge(&from, fa, u, v), half_edge(&from, fb, v, u)) else {
            continue;
        };
        let (p1, n1, p2, n2) = (prev[h1], next[h1], prev[h2], next[h2]);
        let to = |h: usize| from[next[h]];
        // Around u the merged piece runs a_prev -> u -> b_next; around v, b_prev -> v -> a_next.
        let (a_prev, a_next, b_prev, b_next) = (from[p1], to(n1), from[p2], to(n2));
        if a_prev == b_next || b_prev == a_next {
            continue;
        }
        if orient(pos[a_prev], pos[u], pos[b_next]) == Orientation::Cw
            || orient(pos[b_prev], pos[v], pos[a_next]) == Orientation::Cw
        {
            continue;
        }
        next[p1] = n2;
        prev[n2] = p1;
        next[p2] = n1;
        prev[n1] = p2;
        // The merged cycle starts at v: v, a_next, ..., a_prev, u, b_next, ..., b_prev.
        start[pa] = n1;
        piece_of[pb] = pa;
    }

    let mut pieces = Vec::new();
    for f in 0..nf {
        if inside[f] && find(&mut piece_of, f) == f {
            let mut cycle = Vec::new();
            let mut h = start[f];
            loop {
                cycle.push(pos[from[h]]);
                h = next[h];
                if h == start[f] || cycle.len() > 3 * nf {
                    break;
                }
            }
            let poly = drop_collinear(cycle);
            if !is_strictly_convex_ccw(&poly) {
                return Err(DecomposeError::NotConvex);
            }
            pieces.push(poly);
        }
    }
    Ok(pieces)
}

/// Marks the faces inside the polygon: crossing a constraint edge flips inside and outside.
fn classify_faces(cdt: &Cdt) -> Vec<bool> {
    let nf = cdt.num_all_faces();
    let mut state: Vec<Option<bool>> = vec![None; nf];
    let mut stack = Vec::new();
    for f in cdt.inner_faces() {
        for e in f.adjacent_edges() {
            if e.rev().face().is_outer() {
                let s = cdt.is_constraint_edge(e.as_undirected().fix());
                if state[f.fix().index()].is_none() {
                    state[f.fix().index()] = Some(s);
                    stack.push(f.fix());
                }
            }
        }
    }
    while let Some(fh) = stack.pop() {
        let f = cdt.face(fh);
        let s = state[fh.index()].unwrap_or(false);
        for e in f.adjacent_edges() {
            if let Some(g) = e.rev().face().as_inner() {
                let gi = g.fix().index();
                if state[gi].is_none() {
                    state[gi] = Some(s ^ cdt.is_constraint_edge(e.as_undirected().fix()));
                    stack.push(g.fix());
                }
            }
        }
    }
    state.into_iter().map(|s| s == Some(true)).collect()
}

/// Removes vertices where the boundary goes straight on. One pass keeps the vertices that turn
/// against their neighbours in the input (for a boundary without spikes that is the answer: a
/// vertex whose neighbours are dropped keeps lines through the same points); then any collinear
/// triple left (a spike) is removed one at a time, as before, which costs nothing when none is.
fn drop_collinear(poly: Vec<DVec2>) -> Vec<DVec2> {
    let n = poly.len();
    if n <= 3 {
        return poly;
    }
    let mut out: Vec<DVec2> = (0..n)
        .filter(|&i| {
            orient(poly[(i + n - 1) % n], poly[i], poly[(i + 1) % n]) != Orientation::Collinear
        })
        .map(|i| poly[i])
        .collect();
    if out.len() < 3 {
        out = poly;
    }
    let mut changed = true;
    while changed && out.len() > 3 {
        changed = false;
        let n = out.len();
        for i in 0..n {
            let (a, b, c) = (out[(i + n - 1) % n], out[i], out[(i + 1) % n]);
            if orient(a, b, c) == Orientation::Collinear {
                out.remove(i);
                changed = true;
                break;
            }
        }
    }
    out
}

/// Signed area (shoelace), for checks and reports; not used to decide anything.
pub fn signed_area(ring: &[DVec2]) -> f64 {
    let n = ring.len();
    (0..n)
        .map(|i| ring[i].perp_dot(ring[(i + 1) % n]))
        .sum::<f64>()
        / 2.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::predicates::convex_interiors_disjoint;

    fn ring(pts: &[(f64, f64)]) -> Ring {
        pts.iter().map(|&(x, y)| DVec2::new(x, y)).collect()
    }

    fn check(rings: &[Ring]) -> Vec<Vec<DVec2>> {
        let pieces = convex_pieces(rings).unwrap();
        let want: f64 = rings.iter().map(|r| signed_area(r)).sum();
        let got: f64 = pieces.iter().map(|p| signed_area(p)).sum();
        assert!(((got - want) / want).abs() < 1e-12, "area {got} vs {want}");
        for (i, p) in pieces.iter().enumerate() {
            assert!(is_strictly_convex_ccw(p));
            for q in &pieces[i + 1..] {
                assert!(convex_interiors_disjoint(p, q));
            }
        }
        pieces
    }

    #[test]
    fn convex_polygon_is_one_piece() {
        let p = check(&[ring(&[(0., 0.), (2., 0.), (4., 0.), (4., 4.), (0., 4.)])]);
        assert_eq!(p.len(), 1);
        assert_eq!(p[0].len(), 4);
    }

    #[test]
    fn l_shape_is_two_pieces() {
        let p = check(&[ring(&[
            (0., 0.),
            (4., 0.),
            (4., 1.),
            (1., 1.),
            (1., 4.),
            (0., 4.),
        ])]);
        assert_eq!(p.len(), 2);
    }

    #[test]
    fn courtyard_is_four_pieces() {
        let outer = ring(&[(0., 0.), (10., 0.), (10., 10.), (0., 10.)]);
        let hole = ring(&[(3., 3.), (3., 7.), (7., 7.), (7., 3.)]);
        let p = check(&[outer, hole]);
        assert!(p.len() >= 4 && p.len() <= 8, "{} pieces", p.len());
    }

    #[test]
    fn comb_gives_one_piece_per_tooth_and_spine() {
        // Spine along y = 0..1, teeth up to y = 5 at x = 0..1, 2..3, 4..5.
        let p = check(&[ring(&[
            (0., 0.),
            (5., 0.),
            (5., 5.),
            (4., 5.),
            (4., 1.),
            (3., 1.),
            (3., 5.),
            (2., 5.),
            (2., 1.),
            (1., 1.),
            (1., 5.),
            (0., 5.),
        ])]);
        assert!(p.len() <= 5, "{} pieces", p.len());
    }
}
