//! Walls: segment blockers from the vertical faces of any mesh (docs/DESIGN.md section 4c).
//!
//! Input: a polygon-face [`Mesh`] in local coordinates, closed or open, a polygon soup with
//! duplicated or overlapping faces allowed. Output: [`WallPiece`]s, each a 2D segment `[a, b]`
//! (the xy of two input vertices) with `base < top`, such that the vertical rectangle over
//! `[a, b]` from `base` to `top` lies in the union of the mesh's faces. A ray that crosses that
//! rectangle meets a face, whether or not the mesh around it is closed.
//! Invariant: every piece passes an exact containment test ([`crate::geom::predicates`]) against
//! the faces it comes from; everything computed in floating point only proposes, and is shrunk
//! toward the conservative side before that test.
//!
//! ## The rule, and why it is sound
//! 1. *Vertical faces.* A face is vertical when the xy of every vertex of every ring lies on one
//!    line, decided by exact orientation tests against two distinct vertices. Such a face lies in
//!    the vertical plane `V` over that line: it is exactly planar, and as a set it is the region
//!    its rings bound in `V` (even-odd, as the ground truth reads faces). Faces whose vertices
//!    are not all on one line (leaning walls, roofs, and walls whose vertices stray from one
//!    plane by rounding) give no wall; see "What is dropped" below.
//! 2. *Lines.* Vertical faces of the object lying on the same line (exactly: both defining
//!    vertices of one on the other's line) are taken together. Along the line, points are named
//!    by one coordinate `u` (x, or y when the line is steeper than 45 degrees); `(x, y, z) ->
//!    (u, z)` is an affine bijection from `V` onto the plane, so containment in `V` is decided
//!    exactly on the input numbers `(u, z)`, with no constructed coordinate.
//! 3. *Regions.* Exactly repeated faces count once. Faces that meet along an edge from opposite
//!    sides (the triangles of a triangulated wall) form a cluster, whose region is read as the
//!    even-odd region of all its rings' edges (edges used twice cancel; a point inside an odd
//!    number of the cluster's faces lies in one of them, so this region lies in the faces'
//!    union, whichever faces were put together). Faces that overlap (levels of detail over one
//!    another, even on a shared base edge) stay in different clusters and are united below.
//! 4. *Envelopes.* The `u` of all edge ends cut the line into strips. In a strip every edge of a
//!    cluster either spans it or misses its inside, so the cluster's region there is a stack of
//!    trapezoids between consecutive spanning edges. The rectangle a trapezoid holds reaches
//!    from the higher end of its bottom edge to the lower end of its top edge; rectangles of
//!    different clusters that overlap in a strip are united (each keeps a part of the height).
//!    Neighbouring strips whose height ranges overlap form runs, and a run gives the rectangle
//!    from the *upper envelope of the bottom edges* to the *lower envelope of the top edges*
//!    over it; runs are also split where a strip limits the top or the base, so that a taller or
//!    lower part gives its own piece (at most [`MAX_PIECES_PER_RUN`] per run). Pieces whose base
//!    is more than [`WALL_FOOT_M`] above the mesh's lowest vertex stand on a roof and are left
//!    out (they could support no VO from the street).
//! 5. *Check.* The base is rounded up and the top down by [`WALL_SHRINK_M`]; the `u` ends are
//!    input values, so the segment's ends are input vertices' xy. Then the rectangle
//!    `[u0, u1] x [base, top]`, split where its height is shared between clusters, is tested
//!    exactly against each part's cluster: no edge of the cluster meets the open rectangle, and
//!    its centre lies in the cluster's region (exact crossing parity). The open rectangle is
//!    connected and crosses no edge, so parity is constant on it: it lies in the region, and the
//!    closed rectangle in its closure, which is in the union of the faces. A rectangle that fails
//!    is shrunk further (each step of [`WALL_SHRINK_M`]) or dropped.
//!
//! ## What is dropped, and why
//! A planar face that is not vertical contains no vertical segment, and for any vertical
//! rectangle `W` of positive height some nearly horizontal ray through `W` misses it: take a
//! height `z` of `W` other than where the face's plane meets `W`'s plane; the face's points at
//! height `z` lie on one horizontal line `l_z` off `W`; a horizontal ray through `W` at height
//! `z` whose direction is parallel to `l_z` (or nearly, if `l_z` is parallel to `W`, crossing
//! `W`'s line at a grazing angle) meets the face's plane only far away or never, outside the
//! bounded face. So no segment blocker follows from a non-vertical face alone, however small
//! its lean: sloped walls and roofs give no wall (a unit test exhibits the ray). A face whose
//! vertices are not coplanar has no one surface (renderers triangulate it in different ways),
//! so it gives nothing either. Space enclosed by such faces together with others is
//! [`super::solid`]'s business: closed meshes keep their solid prisms, and gain their walls.

use std::collections::HashMap;

use glam::{DVec2, DVec3};

use super::Mesh;
use crate::geom::predicates::{
    orient, point_in_edge_cycles, ring_orientation, segment_meets_interior, Containment,
    Orientation,
};

/// A wall: the vertical rectangle over `[a, b]` from `base` to `top` lies in the mesh's faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WallPiece {
    pub a: DVec2,
    pub b: DVec2,
    pub base: f64,
    pub top: f64,
}

/// How far the base is raised and the top lowered before the exact check, metres, tried in
/// turn; the first covers rounding of interpolated heights, the larger ones faces whose edges
/// meet inside a strip.
pub const WALL_SHRINK_M: [f64; 3] = [1e-9, 1e-6, 1e-3];
/// Walls whose base stands more than this above the mesh's lowest vertex (walls on a lower
/// roof) are left out, metres. Rule 2 wants a blocker's base at or below the cell's ground and
/// eyes, so they support no VO from the street, and they would pull the cell's ground level up
/// (the bake takes it from the bases of the blockers near the cell). Leaving a wall out is
/// always sound.
pub const WALL_FOOT_M: f64 = 2.0;
/// Most pieces one run of strips gives.
pub const MAX_PIECES_PER_RUN: usize = 8;
/// Most sub-runs of one run tried.
const MAX_RUN_PARTS_TRIED: usize = 64;
/// Faces whose line directions (radians) and offsets (metres) differ by less than this are
/// compared exactly for lying on one line; a miss only keeps two faces apart.
const THETA_WINDOW: f64 = 1e-9;
const OFFSET_WINDOW_M: f64 = 1e-6;

/// A vertical face: its index and two distinct points of its line.
struct Vertical {
    face: usize,
    p: DVec2,
    q: DVec2,
    theta: f64,
    offset: f64,
}

/// The walls of `mesh`. See the module header.
pub fn wall_pieces(mesh: &Mesh) -> Vec<WallPiece> {
    let mut verticals: Vec<Vertical> = mesh
        .faces
        .iter()
        .enumerate()
        .filter_map(|(fi, _)| vertical(mesh, fi))
        .collect();
    let mut out = Vec::new();
    for group in group_by_line(&mut verticals) {
        line_walls(mesh, &group, &mut out);
    }
    let zmin = mesh
        .faces
        .iter()
        .flat_map(|f| f.rings.iter().flatten())
        .filter_map(|&i| mesh.vertices.get(i as usize))
        .map(|v| v.z)
        .fold(f64::INFINITY, f64::min);
    out.retain(|w| w.base <= zmin + WALL_FOOT_M);
    out
}

/// Face `fi` if it is vertical (module header, step 1) and its outer ring bounds an area in its
/// plane; faces with a bad vertex index are skipped.
fn vertical(mesh: &Mesh, fi: usize) -> Option<Vertical> {
    let f = &mesh.faces[fi];
    let outer = f.rings.first()?;
    if outer.len() < 3 {
        return None;
    }
    let mut pts: Vec<DVec3> = Vec::new();
    for &i in f.rings.iter().flatten() {
        pts.push(*mesh.vertices.get(i as usize)?);
    }
    let p = pts[0].truncate();
    let q = pts.iter().map(|v| v.truncate()).find(|&v| v != p)?;
    if pts
        .iter()
        .any(|v| orient(p, q, v.truncate()) != Orientation::Collinear)
    {
        return None;
    }
    // The outer ring must span an area in the plane (not all on one line of it).
    let use_x = (q.x - p.x).abs() >= (q.y - p.y).abs();
    let uz = |v: DVec3| DVec2::new(if use_x { v.x } else { v.y }, v.z);
    let ring: Vec<DVec2> = outer
        .iter()
        .map(|&i| uz(mesh.vertices[i as usize]))
        .collect();
    let a = ring[0];
    let b = ring.iter().copied().find(|&v| v != a)?;
    if ring
        .iter()
        .all(|&c| orient(a, b, c) == Orientation::Collinear)
    {
        return None;
    }
    let mut d = q - p;
    if d.x < 0.0 || (d.x == 0.0 && d.y < 0.0) {
        d = -d;
    }
    let theta = d.y.atan2(d.x);
    let offset = d.perp_dot(p) / d.length();
    Some(Vertical {
        face: fi,
        p,
        q,
        theta,
        offset,
    })
}

/// Groups of vertical faces on one line, each as (two points of the line, face indices).
fn group_by_line(vs: &mut [Vertical]) -> Vec<(DVec2, DVec2, Vec<usize>)> {
    vs.sort_by(|a, b| a.theta.total_cmp(&b.theta).then(a.face.cmp(&b.face)));
    let mut groups: Vec<(DVec2, DVec2, Vec<usize>)> = Vec::new();
    let mut start = 0;
    while start < vs.len() {
        // A run of directions within the window of their neighbour.
        let mut end = start + 1;
        while end < vs.len() && vs[end].theta - vs[end - 1].theta < THETA_WINDOW {
            end += 1;
        }
        let cluster = &mut vs[start..end];
        cluster.sort_by(|a, b| a.offset.total_cmp(&b.offset).then(a.face.cmp(&b.face)));
        let mut s = 0;
        while s < cluster.len() {
            let mut e = s + 1;
            while e < cluster.len() && cluster[e].offset - cluster[e - 1].offset < OFFSET_WINDOW_M {
                e += 1;
            }
            let first = groups.len();
            for v in &cluster[s..e] {
                let on = |g: &(DVec2, DVec2, Vec<usize>)| {
                    orient(g.0, g.1, v.p) == Orientation::Collinear
                        && orient(g.0, g.1, v.q) == Orientation::Collinear
                };
                match groups[first..].iter_mut().find(|g| on(g)) {
                    Some(g) => g.2.push(v.face),
                    None => groups.push((v.p, v.q, vec![v.face])),
                }
            }
            s = e;
        }
        start = end;
    }
    for g in &mut groups {
        g.2.sort_unstable();
    }
    groups
}

fn bits(p: DVec2) -> [u64; 2] {
    [(p.x + 0.0).to_bits(), (p.y + 0.0).to_bits()]
}

fn edge_key(a: DVec2, b: DVec2) -> [u64; 4] {
    let (ka, kb) = (bits(a), bits(b));
    if ka <= kb {
        [ka[0], ka[1], kb[0], kb[1]]
    } else {
        [kb[0], kb[1], ka[0], ka[1]]
    }
}

/// Per edge key, the edge and how often the cluster's faces use it.
type EdgeCounts = HashMap<[u64; 4], ([DVec2; 2], usize)>;

/// A run being built: its strips so far, and the height range they all hold.
type OpenRun = (Vec<(usize, Span)>, f64, f64);

/// One cluster's height range in one strip.
#[derive(Clone, Copy, Debug)]
struct Piece {
    cluster: usize,
    b: f64,
    t: f64,
}

/// A strip's united height range and the clusters' parts of it, bottom to top.
#[derive(Clone, Debug)]
struct Span {
    b: f64,
    t: f64,
    parts: Vec<Piece>,
}

/// The walls of the faces `faces` lying on the line through `p` and `q`.
fn line_walls(mesh: &Mesh, (p, q, faces): &(DVec2, DVec2, Vec<usize>), out: &mut Vec<WallPiece>) {
    let use_x = (q.x - p.x).abs() >= (q.y - p.y).abs();
    let uz = |v: DVec3| DVec2::new(if use_x { v.x } else { v.y }, v.z);
    // Each face's edges in (u, z), zero-length ones left out, each with the side of it the face
    // lies on (left or right of the edge directed from its smaller end, by key); exactly
    // repeated faces once.
    let mut xy_at: HashMap<u64, DVec2> = HashMap::new();
    let mut seen: std::collections::HashSet<Vec<[u64; 4]>> = std::collections::HashSet::new();
    let mut face_edges: Vec<Vec<[DVec2; 2]>> = Vec::new();
    let mut face_sides: Vec<Vec<bool>> = Vec::new();
    for &fi in faces {
        let mut edges = Vec::new();
        let mut sides = Vec::new();
        for (ri, ring) in mesh.faces[fi].rings.iter().enumerate() {
            let pts: Vec<DVec2> = ring
                .iter()
                .map(|&i| uz(mesh.vertices[i as usize]))
                .collect();
            // The face lies left of a counter-clockwise outer ring's edges, and of a clockwise
            // hole's (for simple rings; a wrong guess only keeps two faces apart, below).
            let ccw = ring_orientation(&pts) == Orientation::Ccw;
            let left_of_ring = ccw == (ri == 0);
            let n = ring.len();
            for k in 0..n {
                let va = mesh.vertices[ring[k] as usize];
                let (a, b) = (pts[k], pts[(k + 1) % n]);
                xy_at.entry((a.x + 0.0).to_bits()).or_insert(va.truncate());
                if a != b {
                    edges.push([a, b]);
                    let forward = bits(a) <= bits(b);
                    sides.push(left_of_ring == forward);
                }
            }
        }
        let mut key: Vec<[u64; 4]> = edges.iter().map(|e| edge_key(e[0], e[1])).collect();
        key.sort_unstable();
        if !edges.is_empty() && seen.insert(key) {
            face_edges.push(edges);
            face_sides.push(sides);
        }
    }
    // Clusters: faces that meet along an edge from opposite sides (the pieces of one tiled
    // wall, such as its triangles), by union-find; then each cluster's edges used an odd number
    // of times. Faces on the same side of a shared edge overlap there (levels of detail on one
    // base line) and stay apart: their union is taken later, not their even-odd sum.
    let nf = face_edges.len();
    let mut parent: Vec<usize> = (0..nf).collect();
    fn find(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    // Per edge, the first face seen on each side.
    let mut owner: HashMap<[u64; 4], [Option<usize>; 2]> = HashMap::new();
    for (fi, edges) in face_edges.iter().enumerate() {
        for (e, &left) in edges.iter().zip(&face_sides[fi]) {
            let slot = owner.entry(edge_key(e[0], e[1])).or_insert([None, None]);
            let (mine, other) = if left { (0, 1) } else { (1, 0) };
            if slot[mine].is_none() {
                slot[mine] = Some(fi);
            }
            if let Some(o) = slot[other] {
                let (ra, rb) = (find(&mut parent, fi), find(&mut parent, o));
                if ra != rb {
                    parent[ra.max(rb)] = ra.min(rb);
                }
            }
        }
    }
    let mut cluster_of: HashMap<usize, usize> = HashMap::new();
    let mut counts: Vec<EdgeCounts> = Vec::new();
    for (fi, edges) in face_edges.iter().enumerate() {
        let r = find(&mut parent, fi);
        let next = cluster_of.len();
        let c = *cluster_of.entry(r).or_insert(next);
        if c == counts.len() {
            counts.push(HashMap::new());
        }
        for e in edges {
            counts[c].entry(edge_key(e[0], e[1])).or_insert((*e, 0)).1 += 1;
        }
    }
    let clusters: Vec<Vec<[DVec2; 2]>> = counts
        .into_iter()
        .map(|m| {
            let mut v: Vec<([u64; 4], [DVec2; 2])> = m
                .into_iter()
                .filter(|(_, (_, n))| n % 2 == 1)
                .map(|(k, (e, _))| (k, e))
                .collect();
            // Deterministic order (the hash map's is not).
            v.sort_unstable_by_key(|(k, _)| *k);
            v.into_iter().map(|(_, e)| e).collect()
        })
        .collect();

    // Strips between the u of all edge ends.
    let mut us: Vec<f64> = clusters
        .iter()
        .flatten()
        .flat_map(|e| [e[0].x, e[1].x])
        .collect();
    us.sort_by(f64::total_cmp);
    us.dedup();
    if us.len() < 2 {
        return;
    }
    let spans: Vec<Vec<Span>> = (0..us.len() - 1)
        .map(|i| strip_spans(&clusters, us[i], us[i + 1]))
        .collect();

    // Runs of strips whose ranges overlap, then their pieces.
    for run in runs(&spans) {
        let mut queue = std::collections::VecDeque::from([(0usize, run.len())]);
        let mut done: std::collections::HashSet<(usize, usize)> = Default::default();
        let mut emitted = 0;
        while let Some((lo, hi)) = queue.pop_front() {
            if emitted >= MAX_PIECES_PER_RUN || done.len() >= MAX_RUN_PARTS_TRIED {
                break;
            }
            if !done.insert((lo, hi)) {
                continue;
            }
            let part = &run[lo..hi];
            let b = part
                .iter()
                .map(|(_, s)| s.b)
                .fold(f64::NEG_INFINITY, f64::max);
            let t = part.iter().map(|(_, s)| s.t).fold(f64::INFINITY, f64::min);
            if !(t > b) {
                continue;
            }
            let (u0, u1) = (us[part[0].0], us[part[part.len() - 1].0 + 1]);
            if let Some((base, top)) = check(&clusters, part, &us, b, t) {
                if let (Some(&a), Some(&bb)) = (
                    xy_at.get(&(u0 + 0.0).to_bits()),
                    xy_at.get(&(u1 + 0.0).to_bits()),
                ) {
                    out.push(WallPiece {
                        a,
                        b: bb,
                        base,
                        top,
                    });
                    emitted += 1;
                }
            }
            // Taller parts between the strips that limit the top, lower ones between those that
            // limit the base.
            for limit in [
                &(|s: &Span| s.t == t) as &dyn Fn(&Span) -> bool,
                &|s: &Span| s.b == b,
            ] {
                let mut k = lo;
                while k < hi {
                    while k < hi && limit(&run[k].1) {
                        k += 1;
                    }
                    let s = k;
                    while k < hi && !limit(&run[k].1) {
                        k += 1;
                    }
                    if s < k && (s, k) != (lo, hi) {
                        queue.push_back((s, k));
                    }
                }
            }
        }
    }
}

/// The united height ranges of the clusters in the strip `(u0, u1)`.
fn strip_spans(clusters: &[Vec<[DVec2; 2]>], u0: f64, u1: f64) -> Vec<Span> {
    // Height of edge `e` at `u`: exact at its ends, interpolated between.
    let z_at = |e: &[DVec2; 2], u: f64| -> f64 {
        let [a, b] = *e;
        if u == a.x {
            a.y
        } else if u == b.x {
            b.y
        } else {
            a.y + (b.y - a.y) * ((u - a.x) / (b.x - a.x))
        }
    };
    let mut pieces: Vec<Piece> = Vec::new();
    for (c, edges) in clusters.iter().enumerate() {
        let mut spanning: Vec<(f64, f64, f64)> = edges
            .iter()
            .filter(|e| e[0].x != e[1].x && e[0].x.min(e[1].x) <= u0 && e[0].x.max(e[1].x) >= u1)
            .map(|e| {
                let (z0, z1) = (z_at(e, u0), z_at(e, u1));
                (z0 + z1, z0, z1)
            })
            .collect();
        if spanning.len() % 2 == 1 {
            continue;
        }
        spanning.sort_by(|a, b| a.0.total_cmp(&b.0));
        for pair in spanning.chunks(2) {
            let b = pair[0].1.max(pair[0].2);
            let t = pair[1].1.min(pair[1].2);
            if t > b {
                pieces.push(Piece { cluster: c, b, t });
            }
        }
    }
    pieces.sort_by(|x, y| x.b.total_cmp(&y.b).then(x.t.total_cmp(&y.t)));
    // Unite ranges that overlap by a positive height; each part keeps a slice of the union.
    let mut spans: Vec<Span> = Vec::new();
    for p in pieces {
        match spans.last_mut() {
            Some(s) if p.b < s.t => {
                if p.t > s.t {
                    // The new part starts halfway into the overlap.
                    let c = 0.5 * (p.b + s.t);
                    if let Some(last) = s.parts.last_mut() {
                        last.t = c;
                    }
                    s.parts.push(Piece { b: c, ..p });
                    s.t = p.t;
                }
            }
            _ => spans.push(Span {
                b: p.b,
                t: p.t,
                parts: vec![p],
            }),
        }
    }
    spans
}

/// Runs of consecutive strips with overlapping ranges: (strip index, span) per strip. Each
/// span of a strip continues at most one run, the one it overlaps most.
fn runs(spans: &[Vec<Span>]) -> Vec<Vec<(usize, Span)>> {
    let mut done: Vec<Vec<(usize, Span)>> = Vec::new();
    let mut open: Vec<OpenRun> = Vec::new();
    for (i, strip) in spans.iter().enumerate() {
        let mut next: Vec<OpenRun> = Vec::new();
        let mut used = vec![false; strip.len()];
        for (run, b, t) in open.drain(..) {
            let best = strip
                .iter()
                .enumerate()
                .filter(|(k, _)| !used[*k])
                .map(|(k, s)| (k, s.t.min(t) - s.b.max(b)))
                .filter(|(_, o)| *o > 0.0)
                .max_by(|x, y| x.1.total_cmp(&y.1).then(y.0.cmp(&x.0)));
            match best {
                Some((k, _)) => {
                    used[k] = true;
                    let s = &strip[k];
                    let (nb, nt) = (b.max(s.b), t.min(s.t));
                    let mut run = run;
                    run.push((i, s.clone()));
                    next.push((run, nb, nt));
                }
                None => done.push(run),
            }
        }
        for (k, s) in strip.iter().enumerate() {
            if !used[k] {
                next.push((vec![(i, s.clone())], s.b, s.t));
            }
        }
        open = next;
    }
    done.extend(open.into_iter().map(|(r, _, _)| r));
    done
}

/// Shrinks `[b, t]` and checks the rectangle over the strips of `part` exactly; the checked
/// range, or `None`.
fn check(
    clusters: &[Vec<[DVec2; 2]>],
    part: &[(usize, Span)],
    us: &[f64],
    b: f64,
    t: f64,
) -> Option<(f64, f64)> {
    let (u0, u1) = (us[part[0].0], us[part[part.len() - 1].0 + 1]);
    'shrink: for m in WALL_SHRINK_M {
        let (b, t) = (b + m, t - m);
        if !(t > b) {
            return None;
        }
        // One cluster holding the whole height in every strip: one test over the rectangle.
        let single = part[0]
            .1
            .parts
            .iter()
            .find(|p| p.b <= b && p.t >= t)
            .map(|p| p.cluster)
            .filter(|&c| {
                part.iter().all(|(_, s)| {
                    s.parts
                        .iter()
                        .any(|p| p.cluster == c && p.b <= b && p.t >= t)
                })
            });
        if let Some(c) = single {
            if rect_in_region(&clusters[c], u0, u1, b, t) {
                return Some((b, t));
            }
        }
        // Otherwise strip by strip, each part of the height against its own cluster.
        for (i, s) in part {
            let (s0, s1) = (us[*i], us[i + 1]);
            for p in &s.parts {
                let (pb, pt) = (p.b.max(b), p.t.min(t));
                if pt <= pb {
                    continue;
                }
                if !rect_in_region(&clusters[p.cluster], s0, s1, pb, pt) {
                    continue 'shrink;
                }
            }
            // The parts must cover [b, t] with no gap: they meet at shared split heights.
            let mut reach = b;
            for p in &s.parts {
                if p.b <= reach && p.t > reach {
                    reach = p.t;
                }
            }
            if reach < t {
                continue 'shrink;
            }
        }
        return Some((b, t));
    }
    None
}

/// Exact test: the rectangle `[u0, u1] x [b, t]` lies in the even-odd region of `edges` (module
/// header, step 5).
fn rect_in_region(edges: &[[DVec2; 2]], u0: f64, u1: f64, b: f64, t: f64) -> bool {
    if !(u0 < u1 && b < t) {
        return false;
    }
    let rect = [
        DVec2::new(u0, b),
        DVec2::new(u1, b),
        DVec2::new(u1, t),
        DVec2::new(u0, t),
    ];
    for e in edges {
        let (lo, hi) = (e[0].min(e[1]), e[0].max(e[1]));
        if hi.x > u0
            && lo.x < u1
            && hi.y > b
            && lo.y < t
            && segment_meets_interior(e[0], e[1], &rect)
        {
            return false;
        }
    }
    let m = DVec2::new(0.5 * (u0 + u1), 0.5 * (b + t));
    u0 < m.x
        && m.x < u1
        && b < m.y
        && m.y < t
        && point_in_edge_cycles(edges, m) == Containment::Inside
}

#[cfg(test)]
mod tests;
