//! Exact geometric predicates. The only place that decides signs.
//!
//! Input: points in f64 (local frame). Output: enums, never raw signs or tolerances.
//! Invariants: every answer is exact for the given f64 inputs (Shewchuk's adaptive predicates
//! through the `robust` crate); no epsilon appears here. Constructed points (intersections,
//! snapped coordinates) are not handled here: callers shrink them conservatively and re-check
//! them with these predicates.
//!
//! ## Convex pieces, segments included
//! A *convex piece* is either a strictly convex counter-clockwise polygon (3 or more vertices,
//! non-zero area) or a *segment*: exactly 2 distinct vertices, the closed segment between them
//! (a wall seen from above, docs/DESIGN.md section 4c). A segment is a degenerate convex set with an
//! empty interior: every point of it is a boundary point. Every predicate below that takes a
//! "convex polygon" accepts both kinds and answers exactly for the closed set: for a segment,
//! [`point_in_convex`] is `Boundary` on it and `Outside` off it (a point on its line beyond its
//! ends is outside), [`segment_meets_convex`] is closed segment against closed segment,
//! [`tangent_vertices`] gives its two ends in angular order (one end twice when seen edge-on),
//! [`convex_interiors_disjoint`] is weak separation, and [`common_tangents`] counts a segment
//! lying on a line as lying on both of its closed sides.

use glam::DVec2;

/// Orientation of an ordered point triple.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Orientation {
    /// Counter-clockwise: `c` lies left of the directed line `a -> b`.
    Ccw,
    /// Clockwise: `c` lies right of the directed line `a -> b`.
    Cw,
    /// The three points are collinear (or coincide).
    Collinear,
}

#[inline]
fn coord(p: DVec2) -> robust::Coord<f64> {
    robust::Coord { x: p.x, y: p.y }
}

/// Exact orientation of `(a, b, c)`.
#[inline]
pub fn orient(a: DVec2, b: DVec2, c: DVec2) -> Orientation {
    let d = robust::orient2d(coord(a), coord(b), coord(c));
    if d > 0.0 {
        Orientation::Ccw
    } else if d < 0.0 {
        Orientation::Cw
    } else {
        Orientation::Collinear
    }
}

/// Where a point lies relative to a closed region.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Containment {
    /// In the open interior.
    Inside,
    /// On the boundary.
    Boundary,
    /// In the open exterior.
    Outside,
}

/// Exact test of `p` against a convex polygon given counter-clockwise (collinear vertices
/// allowed, at least 3 vertices, non-zero area), or a segment (2 vertices: `Boundary` on the
/// closed segment, `Outside` elsewhere; it has no interior).
pub fn point_in_convex(poly: &[DVec2], p: DVec2) -> Containment {
    if poly.len() == 2 {
        return if on_segment(poly[0], poly[1], p) {
            Containment::Boundary
        } else {
            Containment::Outside
        };
    }
    let mut on_edge = false;
    for (i, &a) in poly.iter().enumerate() {
        let b = poly[(i + 1) % poly.len()];
        match orient(a, b, p) {
            Orientation::Cw => return Containment::Outside,
            Orientation::Collinear => on_edge = true,
            Orientation::Ccw => {}
        }
    }
    if on_edge {
        Containment::Boundary
    } else {
        Containment::Inside
    }
}

/// Exact test of `p` against a simple closed ring (either orientation), by crossing parity with
/// exact orientation tests. The ring is given without its closing repeat.
pub fn point_in_ring(ring: &[DVec2], p: DVec2) -> Containment {
    let n = ring.len();
    let mut inside = false;
    for i in 0..n {
        let a = ring[i];
        let b = ring[(i + 1) % n];
        if on_segment(a, b, p) {
            return Containment::Boundary;
        }
        // Half-open rule on y: the edge counts when it straddles the horizontal line through p.
        if (a.y > p.y) != (b.y > p.y) {
            // The crossing is right of p when p lies on the side of the edge that faces -x.
            let o = orient(a, b, p);
            let upward = b.y > a.y;
            if (upward && o == Orientation::Ccw) || (!upward && o == Orientation::Cw) {
                inside = !inside;
            }
        }
    }
    if inside {
        Containment::Inside
    } else {
        Containment::Outside
    }
}

/// Exact test of `p` against the even-odd region of a set of edges that form closed cycles mod 2
/// (every vertex used by an even number of edges, as the edges of any rings, or what is left of
/// several polygons' rings after edges used twice cancel). `Boundary` on an edge; otherwise the
/// crossing parity of a ray from `p`, with the half-open rule of [`point_in_ring`].
pub fn point_in_edge_cycles(edges: &[[DVec2; 2]], p: DVec2) -> Containment {
    let mut inside = false;
    for &[a, b] in edges {
        if on_segment(a, b, p) {
            return Containment::Boundary;
        }
        if (a.y > p.y) != (b.y > p.y) {
            let o = orient(a, b, p);
            let upward = b.y > a.y;
            if (upward && o == Orientation::Ccw) || (!upward && o == Orientation::Cw) {
                inside = !inside;
            }
        }
    }
    if inside {
        Containment::Inside
    } else {
        Containment::Outside
    }
}

/// Exact test: does the closed segment `[a, b]` (or the point `a` when `a == b`) meet the open
/// interior of the convex polygon `poly` (counter-clockwise, non-degenerate)? Touching its
/// boundary, or running along an edge, does not count.
pub fn segment_meets_interior(a: DVec2, b: DVec2, poly: &[DVec2]) -> bool {
    if a == b {
        return point_in_convex(poly, a) == Containment::Inside;
    }
    !convex_interiors_disjoint(poly, &[a, b])
}

/// True when `p` lies on the closed segment `[a, b]`.
pub fn on_segment(a: DVec2, b: DVec2, p: DVec2) -> bool {
    orient(a, b, p) == Orientation::Collinear
        && p.x >= a.x.min(b.x)
        && p.x <= a.x.max(b.x)
        && p.y >= a.y.min(b.y)
        && p.y <= a.y.max(b.y)
}

/// How two closed segments meet.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SegmentIntersection {
    /// No common point.
    Disjoint,
    /// They cross at one point interior to both.
    Proper,
    /// They share at least one point, and an endpoint of one lies on the other (touching,
    /// shared endpoints, or collinear overlap).
    Touch,
}

/// Exact classification of closed segments `[a, b]` and `[c, d]`.
pub fn segment_intersection(a: DVec2, b: DVec2, c: DVec2, d: DVec2) -> SegmentIntersection {
    let o1 = orient(a, b, c);
    let o2 = orient(a, b, d);
    let o3 = orient(c, d, a);
    let o4 = orient(c, d, b);
    use Orientation::*;
    let strict = |x: Orientation, y: Orientation| matches!((x, y), (Ccw, Cw) | (Cw, Ccw));
    if strict(o1, o2) && strict(o3, o4) {
        return SegmentIntersection::Proper;
    }
    if on_segment(a, b, c) || on_segment(a, b, d) || on_segment(c, d, a) || on_segment(c, d, b) {
        return SegmentIntersection::Touch;
    }
    SegmentIntersection::Disjoint
}

/// Exact orientation of a simple ring, read off the turn at its lowest-leftmost vertex, which is
/// a strictly convex corner of any simple ring of non-zero area. `Collinear` for a degenerate
/// ring (fewer than three distinct points, or all on one line through that corner).
pub fn ring_orientation(ring: &[DVec2]) -> Orientation {
    let n = ring.len();
    if n < 3 {
        return Orientation::Collinear;
    }
    // The lowest, then leftmost, vertex is a convex corner of a simple ring.
    let mut k = 0;
    for i in 1..n {
        let (p, q) = (ring[i], ring[k]);
        if p.y < q.y || (p.y == q.y && p.x < q.x) {
            k = i;
        }
    }
    // Skip neighbours that coincide with the corner.
    let corner = ring[k];
    let prev = (1..n).map(|s| ring[(k + n - s) % n]).find(|&p| p != corner);
    let next = (1..n).map(|s| ring[(k + s) % n]).find(|&p| p != corner);
    match (prev, next) {
        (Some(a), Some(c)) => orient(a, corner, c),
        _ => Orientation::Collinear,
    }
}

/// True when a line has the convex piece `p` on one closed side and `q` on the other, decided
/// exactly by looking among the edge lines of either (which suffices for convex polygons, the
/// separating axis theorem; a segment's edge line is its own line). For two polygons of non-zero
/// area this says their interiors are disjoint. A segment is separated from a polygon exactly
/// when it misses the polygon's interior (touching its boundary is allowed), and from another
/// segment unless the two cross at a point interior to both.
pub fn convex_interiors_disjoint(p: &[DVec2], q: &[DVec2]) -> bool {
    fn separates(p: &[DVec2], q: &[DVec2]) -> bool {
        (0..p.len()).any(|i| {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            q.iter().all(|&x| orient(a, b, x) != Orientation::Ccw)
        })
    }
    separates(p, q) || separates(q, p)
}

/// True when a polygon is convex and counter-clockwise with no collinear or repeated vertex.
pub fn is_strictly_convex_ccw(poly: &[DVec2]) -> bool {
    let n = poly.len();
    n >= 3
        && (0..n).all(|i| orient(poly[i], poly[(i + 1) % n], poly[(i + 2) % n]) == Orientation::Ccw)
        && winding_turns_once(poly)
}

/// True when `poly` is a convex piece (module header): strictly convex and counter-clockwise, or
/// a segment of two distinct finite points.
pub fn is_convex_piece(poly: &[DVec2]) -> bool {
    match poly.len() {
        2 => poly[0] != poly[1] && poly.iter().all(|p| p.is_finite()),
        _ => is_strictly_convex_ccw(poly),
    }
}

/// A polygon whose every corner turns left is convex only if it turns around once; a star
/// pentagon turns left everywhere but twice around. Checks that the edge directions sweep a
/// total angle of one turn by counting how often the edge direction crosses the +x axis.
fn winding_turns_once(poly: &[DVec2]) -> bool {
    let n = poly.len();
    let mut crossings = 0;
    for i in 0..n {
        let d0 = poly[(i + 1) % n] - poly[i];
        let d1 = poly[(i + 2) % n] - poly[(i + 1) % n];
        // Direction angle passes from below the +x axis to at-or-above it.
        let below = |d: DVec2| d.y < 0.0 || (d.y == 0.0 && d.x < 0.0);
        if below(d0) && !below(d1) {
            crossings += 1;
        }
    }
    crossings == 1
}

/// Exact test: does the closed segment `[a, b]` meet the closed convex piece `poly`
/// (counter-clockwise and non-degenerate, or a segment)?
pub fn segment_meets_convex(a: DVec2, b: DVec2, poly: &[DVec2]) -> bool {
    if point_in_convex(poly, a) != Containment::Outside
        || point_in_convex(poly, b) != Containment::Outside
    {
        return true;
    }
    (0..poly.len()).any(|i| {
        segment_intersection(a, b, poly[i], poly[(i + 1) % poly.len()])
            != SegmentIntersection::Disjoint
    })
}

/// Exact test: does the point `p` lie in the closed umbra of the segment `[a, b]` seen from the
/// convex polygon `cell` (counter-clockwise): does every closed segment from a point of `cell`
/// to `p` meet `[a, b]`? `false` when the line of `[a, b]` meets the cell (its umbra is then
/// taken as empty).
///
/// With the cell strictly on one side of the line, the cell points whose segment to `p` (on the
/// line or beyond it) meets `[a, b]` form the closed cone from `p` through `[a, b]`, which is
/// convex: the whole cell lies in it exactly when its vertices do, i.e. when each vertex `c` sees
/// `p` between its rays to `a` and `b` (cell on the left of `a -> b`: `orient(c, a, p)` and
/// `orient(c, p, b)` not clockwise).
pub fn point_in_umbra(cell: &[DVec2], a: DVec2, b: DVec2, p: DVec2) -> bool {
    use Orientation::*;
    let (a, b) = match cell.first().map(|&c| orient(a, b, c)) {
        Some(Ccw) => (a, b),
        Some(Cw) => (b, a),
        _ => return false,
    };
    if cell.iter().any(|&c| orient(a, b, c) != Ccw) || orient(a, b, p) == Ccw {
        return false;
    }
    cell.iter()
        .all(|&c| orient(c, a, p) != Cw && orient(c, p, b) != Cw)
}

/// The extreme vertices of a convex polygon as seen from a point outside it: `(l, r)` with every
/// vertex `v` satisfying `orient(q, l, v) != Cw` and `orient(q, v, r) != Cw`, so the polygon is
/// seen within the counter-clockwise angle from the direction of `poly[l]` to that of `poly[r]`
/// (less than a half-turn). `None` when `q` is inside the polygon or on its boundary.
/// Among vertices in the same direction, the nearest to `q` is returned; so a segment seen
/// edge-on (from a point of its line beyond an end) gives its nearer end twice.
pub fn tangent_vertices(q: DVec2, poly: &[DVec2]) -> Option<(usize, usize)> {
    // A point strictly outside the bounding box is outside (comparisons of input coordinates
    // are exact); otherwise the exact test decides.
    let outside_box = poly.iter().all(|v| v.x < q.x)
        || poly.iter().all(|v| v.x > q.x)
        || poly.iter().all(|v| v.y < q.y)
        || poly.iter().all(|v| v.y > q.y);
    if !outside_box && point_in_convex(poly, q) != Containment::Outside {
        return None;
    }
    let closer =
        |i: usize, j: usize| (poly[i] - q).length_squared() < (poly[j] - q).length_squared();
    let (mut l, mut r) = (0, 0);
    for i in 1..poly.len() {
        match orient(q, poly[l], poly[i]) {
            Orientation::Cw => l = i,
            Orientation::Collinear if closer(i, l) => l = i,
            _ => {}
        }
        match orient(q, poly[r], poly[i]) {
            Orientation::Ccw => r = i,
            Orientation::Collinear if closer(i, r) => r = i,
            _ => {}
        }
    }
    Some((l, r))
}

/// Which side of a directed line a set lies on, with touching allowed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SetSide {
    /// Every point is left of or on the line.
    Left,
    /// Every point is right of or on the line.
    Right,
    /// Points lie strictly on both sides.
    Both,
}

/// Exact side of a polygon's vertices (so, of the polygon) relative to the directed line `a -> b`.
pub fn set_side(a: DVec2, b: DVec2, pts: &[DVec2]) -> SetSide {
    let (mut left, mut right) = (false, false);
    for &p in pts {
        match orient(a, b, p) {
            Orientation::Ccw => left = true,
            Orientation::Cw => right = true,
            Orientation::Collinear => {}
        }
    }
    match (left, right) {
        (true, true) => SetSide::Both,
        (false, true) => SetSide::Right,
        // All on the line counts as left (only a segment can be): a caller asking for `Right`
        // then gets no, which drops a candidate line and never admits a wrong one.
        _ => SetSide::Left,
    }
}

/// Whether every point of `pts` lies left of or on the directed line `a -> b`, and whether every
/// point lies right of or on it (both for points all on the line).
fn closed_sides(a: DVec2, b: DVec2, pts: &[DVec2]) -> (bool, bool) {
    let (mut left, mut right) = (true, true);
    for &p in pts {
        match orient(a, b, p) {
            Orientation::Ccw => right = false,
            Orientation::Cw => left = false,
            Orientation::Collinear => {}
        }
    }
    (left, right)
}

/// A common tangent of two convex polygons `p` and `q`: the directed line from vertex `p[i]` to
/// vertex `q[j]`, with each polygon wholly on one closed side of it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Tangent {
    pub i: usize,
    pub j: usize,
}

/// The four common tangents of disjoint-interior convex polygons `p` and `q`, each directed from a
/// vertex of `p` to a vertex of `q`:
/// - `outer_left`: both polygons on its right (seen from `p` looking at `q`, it passes on their
///   left), and `outer_right`: both on its left. These bound `q`'s umbra from `p`.
/// - `cross_left`: `p` on its left, `q` on its right (it leaves `p` on the right and passes `q`
///   on the left), and `cross_right`: `p` on its right, `q` on its left. These bound the penumbra.
///
/// Found by exact orientation tests over all vertex pairs; a tangent through collinear vertices
/// takes the pair nearest each other. `None` for a tangent that does not exist (overlapping
/// polygons have no crossing tangents). A segment that lies on the line counts as lying on both
/// of its closed sides, so that line may serve as an outer and as a crossing tangent.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct CommonTangents {
    pub outer_left: Option<Tangent>,
    pub outer_right: Option<Tangent>,
    pub cross_left: Option<Tangent>,
    pub cross_right: Option<Tangent>,
}

/// Computes the common tangents of `p` and `q`. See [`CommonTangents`].
pub fn common_tangents(p: &[DVec2], q: &[DVec2]) -> CommonTangents {
    let mut out = CommonTangents {
        outer_left: None,
        outer_right: None,
        cross_left: None,
        cross_right: None,
    };
    let len = |t: &Option<Tangent>| t.map(|t| (q[t.j] - p[t.i]).length_squared());
    let keep = |slot: &mut Option<Tangent>, t: Tangent| {
        let d = (q[t.j] - p[t.i]).length_squared();
        if len(slot).is_none_or(|old| d < old) {
            *slot = Some(t);
        }
    };
    for i in 0..p.len() {
        for j in 0..q.len() {
            if p[i] == q[j] {
                continue;
            }
            let t = Tangent { i, j };
            let (pl, pr) = closed_sides(p[i], q[j], p);
            let (ql, qr) = closed_sides(p[i], q[j], q);
            if pr && qr {
                keep(&mut out.outer_left, t);
            }
            if pl && ql {
                keep(&mut out.outer_right, t);
            }
            if pl && qr {
                keep(&mut out.cross_left, t);
            }
            if pr && ql {
                keep(&mut out.cross_right, t);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn umbra_of_a_segment_seen_from_a_cell() {
        let cell = [
            DVec2::new(0.0, 0.0),
            DVec2::new(10.0, 0.0),
            DVec2::new(10.0, 10.0),
            DVec2::new(0.0, 10.0),
        ];
        let (a, b) = (DVec2::new(-20.0, 20.0), DVec2::new(30.0, 20.0));
        for (p, inside) in [
            (DVec2::new(5.0, 30.0), true),
            (DVec2::new(5.0, 20.0), true),    // on the segment
            (DVec2::new(-20.0, 20.0), true),  // its end
            (DVec2::new(5.0, 15.0), false),   // in front
            (DVec2::new(45.0, 30.0), false),  // beside: corner (10, 0) sees it past b
            (DVec2::new(40.0, 30.0), true),   // on that corner's ray through b (closed)
            (DVec2::new(-30.0, 30.0), true),  // on corner (0, 0)'s ray through a (closed)
            (DVec2::new(-31.0, 30.0), false), // just outside it
        ] {
            assert_eq!(point_in_umbra(&cell, a, b, p), inside, "{p}");
            assert_eq!(point_in_umbra(&cell, b, a, p), inside, "{p} (reversed)");
        }
        // A segment whose line meets the cell has no umbra.
        let (c, d) = (DVec2::new(5.0, -10.0), DVec2::new(5.0, 40.0));
        assert!(!point_in_umbra(&cell, c, d, DVec2::new(20.0, 5.0)));
    }

    fn v(x: f64, y: f64) -> DVec2 {
        DVec2::new(x, y)
    }

    #[test]
    fn orientation_is_exact_near_degeneracy() {
        // Classic failure case of naive evaluation: points almost on a line at large offsets.
        let a = v(1.0e7 + 0.5, 1.0e7 + 0.5);
        let b = v(1.0e7 + 12.0, 1.0e7 + 12.0);
        let c = v(1.0e7 + 24.0, 1.0e7 + 24.0);
        assert_eq!(orient(a, b, c), Orientation::Collinear);
        let c2 = v(1.0e7 + 24.0, 1.0e7 + 24.000000001);
        assert_eq!(orient(a, b, c2), Orientation::Ccw);
        assert_eq!(orient(a, c2, b), Orientation::Cw);
    }

    #[test]
    fn point_in_convex_classifies_all_three() {
        let sq = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        assert_eq!(point_in_convex(&sq, v(1.0, 1.0)), Containment::Inside);
        assert_eq!(point_in_convex(&sq, v(2.0, 1.0)), Containment::Boundary);
        assert_eq!(point_in_convex(&sq, v(0.0, 0.0)), Containment::Boundary);
        assert_eq!(
            point_in_convex(&sq, v(2.0000001, 1.0)),
            Containment::Outside
        );
    }

    #[test]
    fn point_in_ring_handles_vertices_at_query_height() {
        // Non-convex ring with a vertex exactly at the query point's y.
        let ring = [
            v(0.0, 0.0),
            v(4.0, 0.0),
            v(4.0, 4.0),
            v(2.0, 2.0),
            v(0.0, 4.0),
        ];
        assert_eq!(point_in_ring(&ring, v(1.0, 2.0)), Containment::Inside);
        assert_eq!(point_in_ring(&ring, v(2.0, 3.0)), Containment::Outside);
        assert_eq!(point_in_ring(&ring, v(2.0, 2.0)), Containment::Boundary);
        assert_eq!(point_in_ring(&ring, v(5.0, 2.0)), Containment::Outside);
        assert_eq!(point_in_ring(&ring, v(-1.0, 2.0)), Containment::Outside);
        let cw: Vec<_> = ring.iter().rev().copied().collect();
        assert_eq!(point_in_ring(&cw, v(1.0, 2.0)), Containment::Inside);
    }

    #[test]
    fn segment_intersection_cases() {
        use SegmentIntersection::*;
        assert_eq!(
            segment_intersection(v(0., 0.), v(2., 2.), v(0., 2.), v(2., 0.)),
            Proper
        );
        assert_eq!(
            segment_intersection(v(0., 0.), v(2., 0.), v(1., 0.), v(1., 5.)),
            Touch
        );
        assert_eq!(
            segment_intersection(v(0., 0.), v(2., 0.), v(1., 0.), v(3., 0.)),
            Touch
        );
        assert_eq!(
            segment_intersection(v(0., 0.), v(2., 0.), v(2.5, 0.), v(3., 0.)),
            Disjoint
        );
        assert_eq!(
            segment_intersection(v(0., 0.), v(2., 0.), v(1., 1e-300), v(1., 5.)),
            Disjoint
        );
    }

    #[test]
    fn ring_orientation_and_convexity() {
        let sq = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        assert_eq!(ring_orientation(&sq), Orientation::Ccw);
        let rev: Vec<_> = sq.iter().rev().copied().collect();
        assert_eq!(ring_orientation(&rev), Orientation::Cw);
        assert!(is_strictly_convex_ccw(&sq));
        assert!(!is_strictly_convex_ccw(&rev));
        let with_collinear = [v(0.0, 0.0), v(1.0, 0.0), v(2.0, 0.0), v(2.0, 2.0)];
        assert!(!is_strictly_convex_ccw(&with_collinear));
        // A pentagram turns left at every corner but is not convex.
        let star: Vec<DVec2> = (0..5)
            .map(|k| {
                let t = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                v(t.cos(), t.sin())
            })
            .collect();
        assert!(!is_strictly_convex_ccw(&star));
    }

    #[test]
    fn convex_disjointness() {
        let a = [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        let b = [v(1.0, 0.0), v(2.0, 0.0), v(2.0, 1.0), v(1.0, 1.0)];
        let c = [v(0.5, 0.5), v(1.5, 0.5), v(1.5, 1.5)];
        assert!(convex_interiors_disjoint(&a, &b));
        assert!(!convex_interiors_disjoint(&a, &c));
    }

    #[test]
    fn segment_meets_convex_cases() {
        let sq = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        assert!(segment_meets_convex(v(-1.0, 1.0), v(3.0, 1.0), &sq));
        assert!(segment_meets_convex(v(1.0, 1.0), v(1.5, 1.5), &sq));
        assert!(
            segment_meets_convex(v(-1.0, 2.0), v(3.0, 2.0), &sq),
            "touching counts"
        );
        assert!(!segment_meets_convex(
            v(-1.0, 2.0000001),
            v(3.0, 2.0000001),
            &sq
        ));
        assert!(!segment_meets_convex(v(3.0, 0.0), v(3.0, 2.0), &sq));
    }

    #[test]
    fn tangent_vertices_from_outside() {
        let sq = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        // Seen from below: the angle runs from (2,0) counter-clockwise to (0,0).
        let (l, r) = tangent_vertices(v(1.0, -5.0), &sq).unwrap();
        for &x in &sq {
            assert_ne!(orient(v(1.0, -5.0), sq[l], x), Orientation::Cw);
            assert_ne!(orient(v(1.0, -5.0), x, sq[r]), Orientation::Cw);
        }
        assert_eq!((l, r), (1, 0));
        // Collinear vertices along the tangent: the nearer one is returned.
        let (l, r) = tangent_vertices(v(4.0, 0.0), &sq).unwrap();
        assert_eq!((sq[l], sq[r]), (v(2.0, 2.0), v(2.0, 0.0)));
        assert_eq!(tangent_vertices(v(1.0, 1.0), &sq), None);
        assert_eq!(tangent_vertices(v(2.0, 1.0), &sq), None);
    }

    #[test]
    fn common_tangents_of_two_squares() {
        // Cell at the origin, blocker straight ahead (+y).
        let c = [v(-0.5, -0.5), v(0.5, -0.5), v(0.5, 0.5), v(-0.5, 0.5)];
        let b = [v(-0.5, 9.5), v(0.5, 9.5), v(0.5, 10.5), v(-0.5, 10.5)];
        let t = common_tangents(&c, &b);
        let ol = t.outer_left.unwrap();
        assert_eq!((c[ol.i], b[ol.j]), (v(-0.5, 0.5), v(-0.5, 9.5)));
        let or = t.outer_right.unwrap();
        assert_eq!((c[or.i], b[or.j]), (v(0.5, 0.5), v(0.5, 9.5)));
        let cl = t.cross_left.unwrap();
        assert_eq!((c[cl.i], b[cl.j]), (v(0.5, 0.5), v(-0.5, 9.5)));
        let cr = t.cross_right.unwrap();
        assert_eq!((c[cr.i], b[cr.j]), (v(-0.5, 0.5), v(0.5, 9.5)));
        // Overlapping polygons have no crossing tangent.
        let o = [v(0.0, 0.0), v(1.0, 0.0), v(1.0, 1.0), v(0.0, 1.0)];
        let t = common_tangents(&c, &o);
        assert!(t.cross_left.is_none() && t.cross_right.is_none());
    }
    #[test]
    fn point_in_segment_is_boundary_on_it_and_outside_beyond_its_ends() {
        let seg = [v(0.0, 0.0), v(4.0, 2.0)];
        assert_eq!(point_in_convex(&seg, v(2.0, 1.0)), Containment::Boundary);
        assert_eq!(point_in_convex(&seg, v(0.0, 0.0)), Containment::Boundary);
        assert_eq!(point_in_convex(&seg, v(4.0, 2.0)), Containment::Boundary);
        // On its line but beyond an end: outside (every edge test alone says collinear).
        assert_eq!(point_in_convex(&seg, v(6.0, 3.0)), Containment::Outside);
        assert_eq!(point_in_convex(&seg, v(-2.0, -1.0)), Containment::Outside);
        assert_eq!(
            point_in_convex(&seg, v(2.0, 1.0000001)),
            Containment::Outside
        );
        assert!(is_convex_piece(&seg));
        assert!(!is_convex_piece(&[v(1.0, 1.0), v(1.0, 1.0)]));
        assert!(!is_convex_piece(&[v(1.0, 1.0), v(f64::NAN, 1.0)]));
        assert!(!is_strictly_convex_ccw(&seg));
    }

    #[test]
    fn segment_meets_segment_blocker() {
        let wall = [v(0.0, 0.0), v(4.0, 0.0)];
        assert!(
            segment_meets_convex(v(1.0, -1.0), v(1.0, 1.0), &wall),
            "crossing"
        );
        assert!(segment_meets_convex(v(1.0, 0.0), v(1.0, 1.0), &wall), "T");
        assert!(
            segment_meets_convex(v(4.0, 0.0), v(5.0, 1.0), &wall),
            "shared end"
        );
        assert!(
            segment_meets_convex(v(3.0, 0.0), v(6.0, 0.0), &wall),
            "overlap"
        );
        assert!(
            !segment_meets_convex(v(5.0, 0.0), v(6.0, 0.0), &wall),
            "collinear apart"
        );
        assert!(
            !segment_meets_convex(v(0.0, 1.0), v(4.0, 1.0), &wall),
            "parallel"
        );
        assert!(
            !segment_meets_convex(v(4.5, -1.0), v(4.5, 1.0), &wall),
            "past the end"
        );
    }

    #[test]
    fn tangent_vertices_of_a_segment() {
        let seg = [v(0.0, 10.0), v(4.0, 10.0)];
        // Seen from below: counter-clockwise from (4,10) to (0,10).
        assert_eq!(tangent_vertices(v(2.0, 0.0), &seg), Some((1, 0)));
        // From above, the other way round.
        assert_eq!(tangent_vertices(v(2.0, 20.0), &seg), Some((0, 1)));
        // Edge-on: the nearer end, twice.
        assert_eq!(tangent_vertices(v(-3.0, 10.0), &seg), Some((0, 0)));
        assert_eq!(tangent_vertices(v(9.0, 10.0), &seg), Some((1, 1)));
        // On it: none.
        assert_eq!(tangent_vertices(v(1.0, 10.0), &seg), None);
        assert_eq!(tangent_vertices(v(4.0, 10.0), &seg), None);
    }

    #[test]
    fn separation_of_segments() {
        let sq = [v(0.0, 0.0), v(2.0, 0.0), v(2.0, 2.0), v(0.0, 2.0)];
        let s = |a: DVec2, b: DVec2| [a, b];
        // Through the square, inside it, and poking in: not separated.
        assert!(!convex_interiors_disjoint(
            &s(v(-1.0, 1.0), v(3.0, 1.0)),
            &sq
        ));
        assert!(!convex_interiors_disjoint(
            &s(v(0.5, 0.5), v(1.5, 1.5)),
            &sq
        ));
        assert!(!convex_interiors_disjoint(
            &sq,
            &s(v(1.0, 1.0), v(1.0, 5.0))
        ));
        // Along an edge, touching a corner, apart: separated.
        assert!(convex_interiors_disjoint(&s(v(0.0, 2.0), v(2.0, 2.0)), &sq));
        assert!(convex_interiors_disjoint(&s(v(2.0, 2.0), v(3.0, 5.0)), &sq));
        assert!(convex_interiors_disjoint(&s(v(3.0, 0.0), v(3.0, 2.0)), &sq));
        // On the line of an edge, but past it on a diagonal: the square's edge x = 2 separates.
        assert!(convex_interiors_disjoint(&s(v(2.5, 0.5), v(3.0, 3.0)), &sq));
        // Two segments: crossing is not separated; T, shared end, collinear overlap are.
        let w = s(v(0.0, 0.0), v(4.0, 0.0));
        assert!(!convex_interiors_disjoint(
            &w,
            &s(v(1.0, -1.0), v(1.0, 1.0))
        ));
        assert!(convex_interiors_disjoint(&w, &s(v(1.0, 0.0), v(1.0, 1.0))));
        assert!(convex_interiors_disjoint(&w, &s(v(4.0, 0.0), v(5.0, 3.0))));
        assert!(convex_interiors_disjoint(&w, &s(v(2.0, 0.0), v(6.0, 0.0))));
    }

    /// Checks a tangent's defining sides by brute force over every vertex.
    fn sides_hold(p: &[DVec2], q: &[DVec2], t: Tangent, p_left: bool, q_left: bool) -> bool {
        let (a, b) = (p[t.i], q[t.j]);
        let ok = |pts: &[DVec2], left: bool| {
            pts.iter().all(|&x| {
                let o = orient(a, b, x);
                o == Orientation::Collinear || (o == Orientation::Ccw) == left
            })
        };
        ok(p, p_left) && ok(q, q_left)
    }

    #[test]
    fn common_tangents_of_cell_and_segment() {
        let c = [v(-0.5, -0.5), v(0.5, -0.5), v(0.5, 0.5), v(-0.5, 0.5)];
        let walls = [
            [v(-2.0, 10.0), v(3.0, 11.0)],
            [v(3.0, 11.0), v(-2.0, 10.0)],
            // Along the line through two cell corners (edge-on, its own line is a tangent).
            [v(-0.5, 3.0), v(-0.5, 8.0)],
            // Radial, seen end-on from the cell centre.
            [v(0.0, 5.0), v(0.0, 9.0)],
        ];
        for w in &walls {
            let t = common_tangents(&c, w);
            let ol = t.outer_left.unwrap();
            let or = t.outer_right.unwrap();
            let cl = t.cross_left.unwrap();
            let cr = t.cross_right.unwrap();
            assert!(sides_hold(&c, w, ol, false, false), "{w:?}");
            assert!(sides_hold(&c, w, or, true, true), "{w:?}");
            assert!(sides_hold(&c, w, cl, true, false), "{w:?}");
            assert!(sides_hold(&c, w, cr, false, true), "{w:?}");
        }
        // The edge-on wall's own line (x = -0.5, the cell on its right) is both its left outer
        // and its right crossing tangent.
        let t = common_tangents(&c, &walls[2]);
        let ol = t.outer_left.unwrap();
        assert_eq!((c[ol.i], walls[2][ol.j]), (v(-0.5, 0.5), v(-0.5, 3.0)));
        let cr = t.cross_right.unwrap();
        assert_eq!((c[cr.i], walls[2][cr.j]), (v(-0.5, 0.5), v(-0.5, 3.0)));
        // A wall crossing the cell has no crossing tangent.
        let t = common_tangents(&c, &[v(-2.0, 0.0), v(2.0, 0.1)]);
        assert!(t.cross_left.is_none() && t.cross_right.is_none());
    }
}
