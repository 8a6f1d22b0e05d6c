//! The runtime culler: a cell's potentially visible set (PVS) from its VOs and the engine's
//! object boxes.
//!
//! Input: the engine's object boxes `[xmin, ymin, zmin, xmax, ymax, zmax]` in the store's local
//! frame (or in world coordinates with the frame's origin, [`BoxTree::from_world`]), indexed by
//! their position in the input slice; per query, a [`Frame`], a cell id and its [`CellRecord`].
//! Output: [`BoxTree`], a bounding volume hierarchy built once per scene (nodes of up to 4
//! children, leaves of up to 8 boxes; `tree.rs`), and per cell entry the ascending indices of
//! the objects that may be visible ([`pvs`], [`pvs_with_stats`]; this file).
//! Invariants:
//! - the PVS is the set of objects that no VO of the cell hides by rule 3
//!   ([`PreparedVo::cover`] `== Hidden`); the hierarchy only saves work. A subtree is culled when
//!   its bounds are `Hidden` (rule 3 is monotone under inclusion, so every box inside is hidden
//!   too), and a VO is dropped for a subtree when its bounds are `Outside` that VO's umbra (then
//!   no box inside can be hidden by it). Property tests check the result against the box-by-box
//!   rule. The VOs are tried in any order (the one that last hid something first), which
//!   changes how many are tried, not the answer; a leaf's boxes are tested for `Hidden` alone,
//!   side by side (`PreparedVo::hides_lanes`, the same arithmetic as `cover` lane by lane).
//!   Only the rounding of rule 3's orientation signs (relative 1e-16, against boxes that rule 3
//!   grows by 1 mm) could tell the two apart, at a box lying within about 1e-12 m of an umbra
//!   edge; even then the hierarchy stays sound: a subtree is culled only when its bounds are
//!   hidden, which, by rule 3's margin, every box inside really is, and dropping a VO can only
//!   keep more objects;
//! - each VO carries down the walk the half-planes of its umbra that the bounds above were not
//!   found strictly inside; the others are not tested again below, with the same answer bit
//!   for bit (a form's least value over a footprint, rounded as computed, only grows as the
//!   footprint shrinks: `PreparedVo::cover_group_planes`); so does the finding that the
//!   bounds are apart from the cell, which holds for every box inside
//!   (`Probe::within` of the occlusion module);
//! - never culled: boxes that touch the cell (rule 3 refuses them), invalid boxes (a NaN or
//!   infinite coordinate, or `min > max` on an axis; kept out of the hierarchy and always
//!   returned), every object of a skipped cell, of a cell without VOs and of a cell id outside
//!   the frame's grid;
//! - a query allocates nothing beyond growing `out` (which also holds a bitmap of the visible
//!   objects while the query runs, so no sort is needed); the traversal stack is a fixed array
//!   (the build bounds the depth, `STACK`; past the array, a subtree would be returned whole,
//!   which is conservative).

use crate::runtime::format::CellRecord;
use crate::runtime::frame::{Frame, MAX_VOS_PER_CELL};
use crate::runtime::grid::CellId;
use crate::runtime::occlusion::{Cover, GroupProbe, Lanes, PreparedVo, ALL_PLANES};

#[cfg(test)]
mod tests;
mod tree;

#[cfg(feature = "bake")]
pub(crate) use tree::Coarse;
use tree::STACK;
pub use tree::{BoxTree, MAX_BOXES};

/// What one query did (for tests and profiling).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PvsStats {
    /// VOs prepared for the query.
    pub vos: usize,
    /// Nodes whose bounds were tested.
    pub nodes_tested: usize,
    /// Subtrees (internal or leaf) culled whole.
    pub subtrees_culled: usize,
    /// Subtrees returned whole because no VO was left for them.
    pub subtrees_kept: usize,
    /// Single boxes tested in leaves.
    pub boxes_tested: usize,
    /// Objects in the PVS.
    pub visible: usize,
}

/// The half-planes still to test of VO `i` in `planes` (three bits per VO, see [`test`]).
#[inline(always)]
fn planes_of(planes: u32, i: usize) -> u8 {
    (planes >> (3 * i)) as u8 & ALL_PLANES
}

/// Set while the subtree has not been found apart from the cell
/// ([`Probe::within`](crate::runtime::occlusion::Probe::within)): the last bit of the word that
/// carries the half-planes still to test down the walk.
const APART_TODO: u32 = 1 << 31;

/// Every half-plane of every VO still to test, and the cell's apartness: where the walk starts.
const ALL_VO_PLANES: u32 = ((1 << (3 * MAX_VOS_PER_CELL)) - 1) | APART_TODO;
const _: () = assert!(3 * MAX_VOS_PER_CELL < 31);

/// `None` when a VO of `mask` (not empty) hides `bx`, else the VOs of `mask` whose umbra `bx`
/// meets, and for each of them the half-planes of its umbra that `bx` is not strictly inside
/// (bits `3i..3i + 3` for VO `i`), which are all that the boxes below must test
/// ([`PreparedVo::cover_group_planes`]), and [`APART_TODO`] unless `bx` was found apart from
/// the cell; `planes` holds those of the parent. VO `*last` is
/// tried first, and becomes the VO that hid `bx` (see [`hidden`]).
#[inline]
fn test(
    prepared: &[PreparedVo; MAX_VOS_PER_CELL],
    view: &crate::runtime::frame::CellView,
    (mask, planes): (u16, u32),
    last: &mut usize,
    bx: &[f64; 6],
    min_top: f64,
) -> Option<(u16, u32)> {
    let g = GroupProbe::within(view, bx, min_top, planes & APART_TODO == 0);
    let mut left = mask;
    let mut keep = mask;
    let mut below = if g.probe.is_apart() { 0 } else { APART_TODO };
    let mut i = *last;
    if mask & (1 << i) == 0 {
        i = left.trailing_zeros() as usize;
    }
    loop {
        left &= !(1 << i);
        match prepared[i].cover_group_planes(view, &g, planes_of(planes, i)) {
            (Cover::Hidden, _) => {
                *last = i;
                return None;
            }
            (Cover::Outside, _) => keep &= !(1 << i),
            (Cover::Partial, todo) => below |= u32::from(todo) << (3 * i),
        }
        if left == 0 {
            return Some((keep, below));
        }
        i = left.trailing_zeros() as usize;
    }
}

/// The boxes of leaf `l` that a VO of `mask` (not empty) hides, as bits of `live` (bit `j`:
/// box `j`): whether each box is apart from the cell once ([`Lanes::apart`]), then each VO's
/// test of every box at once, of the half-planes `planes` leaves it ([`test`]), until every box
/// of `live` is hidden. VO `*last` is tried first, and becomes the last VO that hid a box: a VO
/// that hid boxes of a leaf tends to hide the next leaves of the depth-first walk too, which
/// are their neighbours. The order changes no answer, only how many VOs are tried.
#[inline]
fn hidden_lanes(
    prepared: &[PreparedVo; MAX_VOS_PER_CELL],
    view: &crate::runtime::frame::CellView,
    (mask, planes): (u16, u32),
    last: &mut usize,
    l: &Lanes,
    live: u32,
) -> u32 {
    let apart = l.apart(view, planes & APART_TODO == 0);
    let mut left = mask;
    let mut i = *last;
    if mask & (1 << i) == 0 {
        i = left.trailing_zeros() as usize;
    }
    let mut hid = 0;
    loop {
        left &= !(1 << i);
        let h = prepared[i].hides_lanes(view, l, apart, planes_of(planes, i)) & live;
        if h & !hid != 0 {
            *last = i;
            hid |= h;
            if hid == live {
                return hid;
            }
        }
        if left == 0 {
            return hid;
        }
        i = left.trailing_zeros() as usize;
    }
}

/// Marks object `id` visible in the bitmap `out` ([`pvs_with_stats`]).
#[inline(always)]
fn keep(out: &mut [u32], id: u32) {
    out[(id >> 5) as usize] |= 1 << (id & 31);
}

/// One query's walk down the tree ([`pvs_with_stats`]).
struct Walk<'a> {
    tree: &'a BoxTree,
    prepared: &'a [PreparedVo; MAX_VOS_PER_CELL],
    view: &'a crate::runtime::frame::CellView,
    /// The VO that last hid something ([`test`]).
    last: usize,
    /// Inner nodes that passed their test, with what they left for below.
    stack: [(u32, (u16, u32)); STACK],
    sp: usize,
    st: PvsStats,
}

impl Walk<'_> {
    /// Tests node `ni` with what its parent left, `vos`: culls it, keeps it whole, tests its
    /// boxes (a leaf), or stacks it with what it leaves for its children. `out` is the bitmap
    /// of the visible objects.
    #[inline(always)]
    fn visit(&mut self, out: &mut [u32], ni: u32, vos: (u16, u32)) {
        let node = &self.tree.nodes[ni as usize];
        self.st.nodes_tested += 1;
        let Some(vos) = test(
            self.prepared,
            self.view,
            vos,
            &mut self.last,
            &node.bounds,
            f64::from(node.min_top),
        ) else {
            self.st.subtrees_culled += 1;
            return;
        };
        let range = node.start as usize..node.end as usize;
        let kids = node.kids();
        // Past the stack's room (the build's depth bound keeps it from happening), a subtree
        // is kept whole, which is conservative.
        if vos.0 == 0 || (!kids.is_empty() && self.sp == STACK) {
            self.st.subtrees_kept += 1;
            for &id in &self.tree.ids[range] {
                keep(out, id);
            }
            return;
        }
        if kids.is_empty() {
            let n = range.len();
            self.st.boxes_tested += n;
            let lanes = &self.tree.lanes[node.lanes()];
            let live = (1u32 << n) - 1;
            let hid = hidden_lanes(self.prepared, self.view, vos, &mut self.last, lanes, live);
            let mut visible = live & !hid;
            let ids = &self.tree.ids[range];
            while visible != 0 {
                keep(out, ids[visible.trailing_zeros() as usize]);
                visible &= visible - 1;
            }
            return;
        }
        self.stack[self.sp] = (ni, vos);
        self.sp += 1;
    }
}

/// The PVS of cell `id` with record `rec`: `out` is cleared, then holds the ascending indices
/// of every object of `tree` that no VO of the cell hides.
pub fn pvs(frame: &Frame, id: CellId, rec: &CellRecord, tree: &BoxTree, out: &mut Vec<u32>) {
    pvs_with_stats(frame, id, rec, tree, out);
}

/// [`pvs`], and what the query did.
pub fn pvs_with_stats(
    frame: &Frame,
    id: CellId,
    rec: &CellRecord,
    tree: &BoxTree,
    out: &mut Vec<u32>,
) -> PvsStats {
    out.clear();
    let mut st = PvsStats::default();
    let all = |out: &mut Vec<u32>, mut st: PvsStats| {
        out.extend(0..tree.len as u32);
        st.visible = out.len();
        st
    };
    // Where the cell stands: its ground level and, in 2.1, its rise (the top eye).
    let (ground, vos) = match rec {
        CellRecord::Skipped => return all(out, st),
        CellRecord::Vos { vos, .. } => (rec.stand(), vos.as_slice()),
    };
    let Some(view) = frame.cell_view(id, ground) else {
        return all(out, st);
    };
    // The VOs that can hide something, first to last; `full` has a bit for each. A VO whose
    // umbra is empty ([`PreparedVo::is_usable`]) would be dropped at the root as `Outside`.
    let mut prepared = [PreparedVo::UNUSABLE; MAX_VOS_PER_CELL];
    let mut full: u16 = 0;
    for (i, (slot, q)) in prepared.iter_mut().zip(vos).enumerate() {
        if let Some(g) = frame.dequantize(id, ground, q) {
            *slot = PreparedVo::new(&view, &g);
            st.vos += 1;
            if slot.is_usable() {
                full |= 1 << i;
            }
        }
    }
    if full == 0 {
        return all(out, st);
    }

    // `out` first serves as a bitmap of the visible objects (one bit per object, in u32 words),
    // then holds their ids after it; the bitmap is drained at the end. No other memory, and no
    // sort: ids come out ascending from the bitmap. Marking the visible objects rather than the
    // culled ones writes the smaller set when the VOs do their job.
    let n = tree.len;
    let words = n.div_ceil(32);
    out.resize(words, 0);
    for &id in &tree.invalid {
        keep(out, id);
    }

    // The walk tests a node before it goes on the stack: a stacked node passed its test, with
    // the VOs and half-planes it left for below, and popping it tests its children. A leaf's
    // boxes are tested as soon as the leaf passes, so only inner nodes wait on the stack.
    let mut walk = Walk {
        tree,
        prepared: &prepared,
        view: &view,
        last: 0,
        stack: [(0u32, (0u16, 0u32)); STACK],
        sp: 0,
        st,
    };
    // The nodes to visit next, and what their parent left them: the root first.
    let (mut next, mut vos) = if tree.nodes.is_empty() {
        (0..0, (0, 0))
    } else {
        (0..1, (full, ALL_VO_PLANES))
    };
    loop {
        for k in next {
            walk.visit(out, k, vos);
        }
        if walk.sp == 0 {
            break;
        }
        walk.sp -= 1;
        let ni;
        (ni, vos) = walk.stack[walk.sp];
        next = tree.nodes[ni as usize].kids();
    }
    let mut st = walk.st;
    for w in 0..words {
        let mut visible = out[w];
        while visible != 0 {
            let b = visible.trailing_zeros();
            visible &= visible - 1;
            out.push((w as u32) << 5 | b);
        }
    }
    out.drain(..words);
    st.visible = out.len();
    st
}
