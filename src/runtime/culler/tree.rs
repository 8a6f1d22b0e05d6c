//! The culler's bounding volume hierarchy: [`BoxTree`], built once per scene, and the walk that
//! finds the runs of tree positions a VO hides ([`BoxTree::hidden_runs`], the bake's weighing).
//!
//! Input: object boxes `[xmin, ymin, zmin, xmax, ymax, zmax]` in the store's local frame (or
//! world coordinates with the frame's origin). Output: nodes of up to 4 children laid out in
//! 64 bytes, leaves of up to [`LEAF_SIZE`] boxes side by side in [`Lanes`], object ids in tree
//! order, the invalid boxes apart.
//! Invariants: every node's bounds contain the boxes below it (rounded outward to `f32`); the
//! depth is bounded (`STACK` holds any walk); invalid boxes are kept out of the tree and always
//! in the PVS; at most [`MAX_BOXES`] boxes.

use crate::runtime::occlusion::{Cover, Lanes, PreparedVo, ALL_PLANES, LANES};

/// Most boxes in a leaf. A box costs less to test than a node (it is tested with the VOs its
/// leaf kept, for `Hidden` alone, from memory laid out in tree order): on the generated 10^5
/// city, with nodes of 4 children and the median split, leaves of 8 took 2.03M instructions per
/// cell entry in [`pvs`] (callgrind), leaves of 4 2.16M, of 6 2.04M, of 12 2.13M, of 16 2.18M;
/// with the binned split, 6, 8 and 12 are within 1% of each other.
///
/// A leaf's boxes sit side by side in one [`Lanes`] and are tested at once: on the same city,
/// that took 0.89 to 0.95 of the time of testing them one by one (medians of 7 to 15 paired
/// runs of a timing loop, docs/EMBEDDING.md), and leaves of 12 and 16 in as many lanes were
/// slower than 8.
pub(crate) const LEAF_SIZE: usize = 8;
const _: () = assert!(LEAF_SIZE <= LANES);
/// How a metre of box top weighs against a metre of horizontal extent in the key a box is
/// split by ([`centre`]) when the median split picks its axis. Splitting by top puts boxes of
/// like heights together, so rule 3's height test decides more groups whole (a node hidden, or
/// too tall for a VO): on the generated 10^5 city, 10 took about two thirds of the nodes and
/// time of 1.
pub(super) const TOP_WEIGHT: f64 = 10.0;
/// Bins of keys per axis in [`binned_split`]: 32 tests 2% fewer nodes than 16.
pub(super) const SPLIT_BINS: usize = 32;
/// How a metre of spread in the tops of a group weighs against a metre of its footprint's
/// half-perimeter in [`Bin::cost`]. On the generated 10^5 city, 5, 7, 10 and 14 give 1.68M,
/// 1.65M, 1.69M and 1.72M instructions per cell entry (callgrind, our timing loop).
pub(super) const TOPS_COST: f64 = 7.0;
/// The least share of a node's boxes on each side of a binned split: 0.05, 0.1 and 0.2 give
/// 1.65M, 1.66M and 1.72M instructions per cell entry; 0.1 keeps the tree shallower.
pub(super) const MIN_SIDE: f64 = 0.1;
/// Binary levels that [`binned_split`] may split; below them the median split, whose depth is
/// `log2`, takes over, so a tree is at most `BINNED_LEVELS + 30` binary levels deep for `u32`
/// indices.
pub(super) const BINNED_LEVELS: usize = 48;
/// Children per node, at most: the binary tree with its every other level left out. A node's
/// test costs the same whatever its size, and most tested nodes straddle an umbra's edge, so
/// fewer levels test fewer nodes: on the generated 10^5 city with the median split, 4,013
/// nodes and 2.03M instructions per cell entry against 4,970 and 2.31M with 2 children (8:
/// 4,077 and 2.02M, no better).
pub(super) const WIDTH: usize = 4;
/// Depth of the traversal stack. A tree is at most `BINNED_LEVELS + 30 = 78` binary levels
/// deep, and each level of [`WIDTH`] 4 takes two binary levels off every path that goes on
/// below it, so at most 40 levels of nodes; the walk holds at most 3 siblings of each node of
/// its path, and the children of the last: 124.
pub(super) const STACK: usize = 128;
const _: () = assert!(STACK >= 3 * (1 + (BINNED_LEVELS + 30).div_ceil(2)) + WIDTH);

/// One node of the flat hierarchy. Its subtree's boxes are `start..end` in tree order; its
/// children's ranges follow each other in that order, and the children themselves follow each
/// other in [`BoxTree::nodes`].
///
/// 64 bytes, aligned to 64: one cache line per node tested (the walk's loads wait on memory,
/// and a node of 88 bytes spanned two lines).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(super) struct Node {
    pub(super) bounds: [f64; 6],
    /// The least top (`zmax`) of the boxes below, rounded down to an `f32`: with the bounds,
    /// it lets a VO be dropped for a subtree whose every box is too tall for it (see
    /// [`PreparedVo::cover_group`]). A lower bound drops fewer VOs, never one that hides a box
    /// below, so the rounding changes no answer.
    pub(super) min_top: f32,
    pub(super) start: u32,
    pub(super) end: u32,
    /// `first << LINK_BITS | len`: the `len` children are nodes `first..first + len`; a leaf
    /// has none, and its `first` is the index of its boxes in [`BoxTree::lanes`].
    pub(super) link: u32,
}
const _: () = assert!(std::mem::size_of::<Node>() == 64);

/// Low bits of [`Node::link`] that hold the number of children.
pub(super) const LINK_BITS: u32 = 3;
const _: () = assert!(WIDTH < 1 << LINK_BITS);
/// Nodes and leaves, at most: their indices fit in [`Node::link`] above its `LINK_BITS`.
pub(super) const MAX_LINK: usize = (u32::MAX >> LINK_BITS) as usize;
/// The most boxes a [`BoxTree`] takes: 268,435,455. Every split leaves boxes on both sides, so
/// the binary tree over `n` boxes has at most `2n - 1` nodes, and widening only removes nodes:
/// below `MAX_LINK` for `n <= MAX_LINK / 2`. Object indices, below `u32::MAX`, fit too.
pub const MAX_BOXES: usize = MAX_LINK / 2;

impl Node {
    /// The children: none for a leaf.
    pub(super) fn kids(&self) -> std::ops::Range<u32> {
        let first = self.link >> LINK_BITS;
        first..first + (self.link & ((1 << LINK_BITS) - 1))
    }

    /// A leaf's index in [`BoxTree::lanes`].
    pub(super) fn lanes(&self) -> usize {
        (self.link >> LINK_BITS) as usize
    }
}

/// `x` rounded down to an `f32` (to `f32::MAX` above it; `x` is not NaN).
pub(super) fn f32_below(x: f64) -> f32 {
    let f = x as f32;
    if f64::from(f) <= x {
        return f;
    }
    // The next `f32` below `f` (`f32::next_down`, newer than our MSRV): `f > x`, so `f` is
    // neither NaN nor -inf; +inf steps down to `f32::MAX`.
    if f == 0.0 {
        -f32::from_bits(1)
    } else if f > 0.0 {
        f32::from_bits(f.to_bits() - 1)
    } else {
        f32::from_bits(f.to_bits() + 1)
    }
}

/// A node of the binary tree that [`BoxTree::new`] builds first.
#[derive(Clone, Copy, Debug)]
pub(super) struct BinNode {
    pub(super) node: Node,
    /// Children, or [`LEAF`].
    pub(super) left: u32,
    pub(super) right: u32,
}

pub(super) const LEAF: u32 = u32::MAX;

/// A bounding volume hierarchy over object boxes in the store's local frame; object `i` is
/// `boxes[i]` of the input.
#[derive(Clone, Debug, Default)]
pub struct BoxTree {
    pub(super) nodes: Vec<Node>,
    /// Object indices in tree order (each subtree is a contiguous range).
    pub(super) ids: Vec<u32>,
    /// The boxes of each leaf, side by side ([`Node::lanes`] indexes them).
    pub(super) lanes: Vec<Lanes>,
    /// The objects whose boxes are invalid ([`box_is_valid`]), ascending: always in the PVS.
    pub(super) invalid: Vec<u32>,
    pub(super) len: usize,
}

/// Finite, and `min <= max` on every axis.
pub(crate) fn box_is_valid(b: &[f64; 6]) -> bool {
    b.iter().all(|x| x.is_finite()) && b[0] <= b[3] && b[1] <= b[4] && b[2] <= b[5]
}

/// The key a box is split by on `axis`: its centre in x and y, [`TOP_WEIGHT`] times its top
/// on the third axis.
pub(super) fn centre(b: &[f64; 6], axis: usize) -> f64 {
    if axis == 2 {
        return TOP_WEIGHT * b[5];
    }
    // Halves first: no overflow for finite boxes.
    0.5 * b[axis] + 0.5 * b[axis + 3]
}

impl BoxTree {
    /// Builds the hierarchy over `boxes` (local frame), leaves of at most `LEAF_SIZE` (8) boxes.
    /// A node's boxes are split by `binned_split` (the least cost of groups that umbras'
    /// edges cross) in its first `BINNED_LEVELS` binary levels, else at the median of their
    /// keys (`centre`: x, y, and the top weighted by `TOP_WEIGHT`) along the longest extent.
    ///
    /// # Panics
    /// With more than [`MAX_BOXES`] boxes (the C and Python bindings refuse them first).
    pub fn new(boxes: &[[f64; 6]]) -> BoxTree {
        assert!(
            boxes.len() <= MAX_BOXES,
            "BoxTree: more than {MAX_BOXES} boxes"
        );
        let mut items: Vec<(u32, [f64; 6])> = Vec::with_capacity(boxes.len());
        let mut invalid = Vec::new();
        for (i, b) in boxes.iter().enumerate() {
            if box_is_valid(b) {
                items.push((i as u32, *b));
            } else {
                invalid.push(i as u32);
            }
        }
        let mut nodes: Vec<BinNode> = Vec::with_capacity(2 * items.len().div_ceil(LEAF_SIZE));
        if !items.is_empty() {
            let blank = BinNode {
                node: Node {
                    bounds: [0.0; 6],
                    min_top: 0.0,
                    start: 0,
                    end: 0,
                    link: 0,
                },
                left: LEAF,
                right: LEAF,
            };
            nodes.push(blank);
            let mut todo = vec![(0usize, 0usize, items.len(), 0usize)];
            while let Some((ni, s, e, depth)) = todo.pop() {
                let part = &mut items[s..e];
                let mut bounds = part[0].1;
                let mut min_top = f64::INFINITY;
                let mut cmin = [f64::INFINITY; 3];
                let mut cmax = [f64::NEG_INFINITY; 3];
                for (_, b) in part.iter() {
                    min_top = min_top.min(b[5]);
                    for k in 0..3 {
                        bounds[k] = bounds[k].min(b[k]);
                        bounds[k + 3] = bounds[k + 3].max(b[k + 3]);
                        let c = centre(b, k);
                        cmin[k] = cmin[k].min(c);
                        cmax[k] = cmax[k].max(c);
                    }
                }
                let mut node = BinNode {
                    node: Node {
                        bounds,
                        min_top: f32_below(min_top),
                        start: s as u32,
                        end: e as u32,
                        ..blank.node
                    },
                    ..blank
                };
                if e - s > LEAF_SIZE {
                    let binned = if depth < BINNED_LEVELS {
                        binned_split(part, &cmin, &cmax)
                    } else {
                        None
                    };
                    let half = binned.unwrap_or_else(|| {
                        let axis = (0..3)
                            .max_by(|&a, &b| (cmax[a] - cmin[a]).total_cmp(&(cmax[b] - cmin[b])))
                            .unwrap_or(0);
                        let half = (e - s) / 2;
                        part.select_nth_unstable_by(half, |a, b| {
                            centre(&a.1, axis).total_cmp(&centre(&b.1, axis))
                        });
                        half
                    });
                    let left = nodes.len();
                    nodes.push(blank);
                    nodes.push(blank);
                    node.left = left as u32;
                    node.right = left as u32 + 1;
                    todo.push((left + 1, s + half, e, depth + 1));
                    todo.push((left, s, s + half, depth + 1));
                }
                nodes[ni] = node;
            }
        }
        let mut nodes = widen(&nodes);
        debug_assert!(nodes.len() <= MAX_LINK, "{} nodes", nodes.len());
        let mut lanes = Vec::new();
        for node in nodes.iter_mut().filter(|n| n.kids().is_empty()) {
            node.link = (lanes.len() as u32) << LINK_BITS;
            let leaf: Vec<[f64; 6]> = items[node.start as usize..node.end as usize]
                .iter()
                .map(|&(_, b)| b)
                .collect();
            lanes.push(Lanes::new(&leaf));
        }
        BoxTree {
            nodes,
            ids: items.iter().map(|&(i, _)| i).collect(),
            lanes,
            invalid,
            len: boxes.len(),
        }
    }

    /// Builds the hierarchy over boxes in world coordinates: `local = world - origin`, with the
    /// frame's `origin`. (With the bake's origin, a multiple of 1 km below every coordinate,
    /// the subtraction is exact; in any case rule 3's margin dwarfs its rounding.)
    pub fn from_world(boxes: &[[f64; 6]], origin: [f64; 3]) -> BoxTree {
        let local: Vec<[f64; 6]> = boxes
            .iter()
            .map(|b| {
                [
                    b[0] - origin[0],
                    b[1] - origin[1],
                    b[2] - origin[2],
                    b[3] - origin[0],
                    b[4] - origin[1],
                    b[5] - origin[2],
                ]
            })
            .collect();
        BoxTree::new(&local)
    }

    /// Number of objects (valid or not).
    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Depth of the hierarchy (0 when it is empty).
    pub fn depth(&self) -> usize {
        let mut best = 0;
        let mut todo = Vec::new();
        if !self.nodes.is_empty() {
            todo.push((0usize, 1usize));
        }
        while let Some((ni, d)) = todo.pop() {
            best = best.max(d);
            for k in self.nodes[ni].kids() {
                todo.push((k as usize, d + 1));
            }
        }
        best
    }
}

/// A bin of [`binned_split`]: the footprint bounds, the spread of tops and the number of the
/// boxes whose keys fall in it (or in a run of bins).
#[derive(Clone, Copy)]
pub(super) struct Bin {
    pub(super) lo: [f64; 2],
    pub(super) hi: [f64; 2],
    pub(super) top_lo: f64,
    pub(super) top_hi: f64,
    pub(super) n: usize,
}

impl Bin {
    const EMPTY: Bin = Bin {
        lo: [f64::INFINITY; 2],
        hi: [f64::NEG_INFINITY; 2],
        top_lo: f64::INFINITY,
        top_hi: f64::NEG_INFINITY,
        n: 0,
    };

    fn add(&mut self, b: &[f64; 6]) {
        for k in 0..2 {
            self.lo[k] = self.lo[k].min(b[k]);
            self.hi[k] = self.hi[k].max(b[k + 3]);
        }
        self.top_lo = self.top_lo.min(b[5]);
        self.top_hi = self.top_hi.max(b[5]);
        self.n += 1;
    }

    fn merge(mut self, o: &Bin) -> Bin {
        for k in 0..2 {
            self.lo[k] = self.lo[k].min(o.lo[k]);
            self.hi[k] = self.hi[k].max(o.hi[k]);
        }
        self.top_lo = self.top_lo.min(o.top_lo);
        self.top_hi = self.top_hi.max(o.top_hi);
        self.n += o.n;
        self
    }

    /// The boxes times their group's half-perimeter and weighted spread of tops.
    fn cost(&self) -> f64 {
        let size = (self.hi[0] - self.lo[0])
            + (self.hi[1] - self.lo[1])
            + TOPS_COST * (self.top_hi - self.top_lo);
        self.n as f64 * size
    }
}

/// The bin of [`binned_split`] that box `b`'s key on `axis` falls in, for keys spanning
/// `lo..=hi` (`lo < hi`).
pub(super) fn bin_of(b: &[f64; 6], axis: usize, lo: f64, hi: f64) -> usize {
    (((centre(b, axis) - lo) * (SPLIT_BINS as f64 / (hi - lo))) as usize).min(SPLIT_BINS - 1)
}

/// Splits `part` (more than [`LEAF_SIZE`] boxes, keys within `cmin..=cmax` per axis) in two by
/// the cost of [`Bin::cost`]: over [`SPLIT_BINS`] bins of the keys along each axis, the
/// boundary between bins with the least summed cost of the two sides, each side holding at
/// least [`MIN_SIDE`] of the boxes. Reorders `part` so the left side comes first and returns its
/// length, or `None` (`part` untouched) when no boundary qualifies.
///
/// Why this cost: a node is tested when its parent is, and a parent's children are tested
/// when an umbra's edge or its height bound crosses the parent. For a random line the chance of
/// crossing a convex footprint is proportional to its perimeter (Cauchy–Crofton), and the
/// spread of tops is what rule 3's height bound splits; each box pays for the groups above it.
pub(super) fn binned_split(
    part: &mut [(u32, [f64; 6])],
    cmin: &[f64; 3],
    cmax: &[f64; 3],
) -> Option<usize> {
    let n = part.len();
    let least = ((MIN_SIDE * n as f64).ceil() as usize).max(1);
    let mut best: Option<(f64, usize, usize)> = None;
    for axis in 0..3 {
        if !(cmax[axis] > cmin[axis]) {
            continue;
        }
        let bin = |b: &[f64; 6]| bin_of(b, axis, cmin[axis], cmax[axis]);
        let mut bins = [Bin::EMPTY; SPLIT_BINS];
        for (_, b) in part.iter() {
            bins[bin(b)].add(b);
        }
        // `right[i]`: bins i.. together.
        let mut right = [Bin::EMPTY; SPLIT_BINS];
        let mut acc = Bin::EMPTY;
        for i in (0..SPLIT_BINS).rev() {
            acc = acc.merge(&bins[i]);
            right[i] = acc;
        }
        let mut left = Bin::EMPTY;
        for i in 0..SPLIT_BINS - 1 {
            left = left.merge(&bins[i]);
            let r = &right[i + 1];
            if left.n < least || r.n < least {
                continue;
            }
            let cost = left.cost() + r.cost();
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, axis, i));
            }
        }
    }
    let (_, axis, last) = best?;
    let mut k = 0;
    for j in 0..n {
        if bin_of(&part[j].1, axis, cmin[axis], cmax[axis]) <= last {
            part.swap(j, k);
            k += 1;
        }
    }
    Some(k)
}

/// The nodes of [`WIDTH`] children from the binary tree `bin` (root 0): each node's children
/// are its binary descendants two levels down, or the leaves above them, in tree order. Its
/// children are stored together, after it.
pub(super) fn widen(bin: &[BinNode]) -> Vec<Node> {
    let mut out: Vec<Node> = Vec::with_capacity(bin.len());
    if bin.is_empty() {
        return out;
    }
    out.push(bin[0].node);
    let mut todo = vec![(0usize, 0usize)];
    while let Some((b, o)) = todo.pop() {
        // Replace every internal node of the front by its two children, level by level, while
        // the front stays within WIDTH.
        let mut front = vec![b as u32];
        loop {
            let internal = front
                .iter()
                .filter(|&&f| bin[f as usize].left != LEAF)
                .count();
            if internal == 0 || front.len() + internal > WIDTH {
                break;
            }
            front = front
                .iter()
                .flat_map(|&f| match bin[f as usize] {
                    BinNode { left: LEAF, .. } => vec![f],
                    BinNode { left, right, .. } => vec![left, right],
                })
                .collect();
        }
        let len = front.len();
        if len == 1 {
            continue; // a leaf
        }
        let first = out.len();
        for (j, &f) in front.iter().enumerate() {
            out.push(bin[f as usize].node);
            todo.push((f as usize, first + j));
        }
        // At most MAX_LINK nodes: BoxTree::new takes at most MAX_BOXES boxes.
        out[o].link = ((first as u32) << LINK_BITS) | len as u32;
    }
    out
}

// The bake's weighing walk (`bake::occludees`): unused by the runtime alone.
#[cfg_attr(not(feature = "bake"), allow(dead_code))]
impl BoxTree {
    /// The object at tree position `pos` (positions run over the valid boxes, each subtree a
    /// contiguous range).
    pub(crate) fn id_at(&self, pos: u32) -> u32 {
        self.ids[pos as usize]
    }

    /// Number of tree positions (the valid boxes).
    pub(crate) fn positions(&self) -> usize {
        self.ids.len()
    }

    /// Calls `found(start, end, bounds)`, in ascending order of positions, for runs of tree
    /// positions of boxes meeting the rectangle `within = [x0, y0, x1, y1]` that `vo` hides from
    /// `view` (rule 3, [`PreparedVo::cover`]): a whole subtree in one call where its bounds are
    /// hidden and lie within the rectangle (rule 3 is monotone under inclusion; `bounds` are the
    /// subtree's), single boxes otherwise (`bounds` the box); none below bounds outside the
    /// umbra. `boxes` are the boxes by tree position (`boxes[p]` is the input box
    /// [`Self::id_at`]`(p)`): the leaves keep their grown form only ([`Lanes`]), and whether a
    /// box meets `within` is asked of the box itself.
    ///
    /// A subtree that is only partly hidden and looks small ([`Coarse::small`]: its bounds'
    /// larger side over their distance from the cell's centre, radians) is passed over whole:
    /// far away, on the edge of an umbra, where a walk would otherwise visit box after box for
    /// little weight. So the runs found are a subset of the hidden boxes, and exactly them with
    /// [`Coarse::EXACT`].
    ///
    /// # Panics
    /// When `boxes` does not hold one box per position ([`Self::positions`]).
    pub(crate) fn hidden_runs(
        &self,
        view: &crate::runtime::frame::CellView,
        vo: &PreparedVo,
        within: [f64; 4],
        boxes: &[[f64; 6]],
        coarse: Coarse,
        mut found: impl FnMut(u32, u32, &[f64; 6]),
    ) {
        let r = view.rect;
        let (cx, cy) = (0.5 * (r[0] + r[2]), 0.5 * (r[1] + r[3]));
        let small = |b: &[f64; 6]| {
            let size = (b[3] - b[0]).max(b[4] - b[1]);
            let dx = (b[0] - cx).max(cx - b[3]).max(0.0);
            let dy = (b[1] - cy).max(cy - b[4]).max(0.0);
            coarse.small(size, dx.hypot(dy))
        };
        assert_eq!(boxes.len(), self.positions(), "one box per tree position");
        let meets = |b: &[f64; 6]| {
            b[0] <= within[2] && b[3] >= within[0] && b[1] <= within[3] && b[4] >= within[1]
        };
        let inside = |b: &[f64; 6]| {
            b[0] >= within[0] && b[3] <= within[2] && b[1] >= within[1] && b[4] <= within[3]
        };
        let mut stack = [0u32; STACK];
        let mut sp = usize::from(!self.nodes.is_empty());
        while sp > 0 {
            sp -= 1;
            let node = &self.nodes[stack[sp] as usize];
            if !meets(&node.bounds) {
                continue;
            }
            match vo.cover_group(view, &node.bounds, f64::from(node.min_top)) {
                Cover::Outside => continue,
                Cover::Hidden if inside(&node.bounds) => {
                    found(node.start, node.end, &node.bounds);
                    continue;
                }
                _ if small(&node.bounds) => continue,
                _ => {}
            }
            let kids = node.kids();
            if kids.is_empty() {
                let lanes = &self.lanes[node.lanes()];
                let n = (node.end - node.start) as usize;
                let hid = vo.hides_lanes(view, lanes, lanes.apart(view, false), ALL_PLANES);
                for j in 0..n {
                    let p = node.start + j as u32;
                    if hid >> j & 1 == 1 && meets(&boxes[p as usize]) {
                        found(p, p + 1, &boxes[p as usize]);
                    }
                }
                continue;
            }
            // Past the stack's room (the build's depth bound keeps it from happening), a
            // subtree's boxes are left out: fewer positions, never a box that is not hidden.
            if sp + kids.len() > STACK {
                continue;
            }
            // The first child popped first: positions come out ascending.
            for k in kids.rev() {
                stack[sp] = k;
                sp += 1;
            }
        }
    }
}

/// How coarsely [`BoxTree::hidden_runs`] walks the edge of an umbra: a subtree only partly
/// hidden is passed over whole when it looks smaller than `angle` from the cell's centre
/// (its bounds' larger side over their distance, radians), or smaller than `far_angle` once
/// it lies more than `far_m` metres away.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coarse {
    pub angle: f64,
    pub far_m: f64,
    pub far_angle: f64,
}

impl Coarse {
    /// Every hidden box found, none passed over.
    #[cfg(test)]
    pub const EXACT: Coarse = Coarse {
        angle: 0.0,
        far_m: f64::INFINITY,
        far_angle: 0.0,
    };

    /// Whether a subtree `size` metres across, `dist` metres from the cell's centre, is passed
    /// over when it is only partly hidden.
    pub fn small(&self, size: f64, dist: f64) -> bool {
        let angle = if dist > self.far_m {
            self.far_angle
        } else {
            self.angle
        };
        size < angle * dist
    }
}
