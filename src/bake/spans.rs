//! Sets of occludees as runs of positions, and what they cost: the weights both generators
//! pick VOs by.
//!
//! Input: occludee positions in the runtime's box hierarchy (each subtree a contiguous range of
//! positions, [`crate::runtime::culler::BoxTree`]), as ranges found whole subtrees at a time, and
//! the occludees' costs by position.
//! Output: [`Spans`] (sorted, disjoint, non-touching half-open ranges), their union, and the cost
//! of one set less another ([`Costs`], by prefix sums).
//! Why: a VO far from its cell, or one whose umbra opens onto the far field, hides thousands of
//! objects, most of them in whole subtrees of the hierarchy. As ranges a hidden set costs what
//! the subtrees it takes do, not what its objects do, and the greedy's overlap arithmetic runs
//! over ranges; so weighing a VO against every object of a city costs about as much as weighing
//! it against a neighbourhood.
//! Invariants: ranges are ascending, non-empty, and separated by at least one position (touching
//! ranges are merged); every operation keeps that, so equal sets are equal values.

/// A set of positions as sorted, disjoint, non-touching half-open ranges `start..end`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Spans(Vec<(u32, u32)>);

impl Spans {
    /// The empty set.
    pub const fn new() -> Spans {
        Spans(Vec::new())
    }

    /// The set of `ids` (any order, repeats allowed).
    pub fn from_ids(ids: &[u32]) -> Spans {
        let mut v = ids.to_vec();
        v.sort_unstable();
        let mut s = Spans::new();
        for i in v {
            s.push(i, i + 1);
        }
        s
    }

    /// Adds `start..end`, which must not begin before the last range's start: what a walk of the
    /// hierarchy in position order finds. Touching or overlapping the last range merges with it.
    pub fn push(&mut self, start: u32, end: u32) {
        if start >= end {
            return;
        }
        match self.0.last_mut() {
            Some(last) if start <= last.1 => {
                debug_assert!(start >= last.0, "ranges pushed out of order");
                last.1 = last.1.max(end);
            }
            _ => self.0.push((start, end)),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The ranges, ascending.
    pub fn ranges(&self) -> &[(u32, u32)] {
        &self.0
    }

    /// How many positions the set holds.
    pub fn count(&self) -> u64 {
        self.0.iter().map(|&(s, e)| (e - s) as u64).sum()
    }

    /// The positions, ascending.
    pub fn positions(&self) -> impl Iterator<Item = u32> + '_ {
        self.0.iter().flat_map(|&(s, e)| s..e)
    }

    /// The union of both sets.
    pub fn union(&self, other: &Spans) -> Spans {
        let mut out = Spans(Vec::with_capacity(self.0.len() + other.0.len()));
        let (mut i, mut j) = (0, 0);
        while i < self.0.len() || j < other.0.len() {
            let take_self = j == other.0.len() || (i < self.0.len() && self.0[i].0 <= other.0[j].0);
            let r = if take_self {
                i += 1;
                self.0[i - 1]
            } else {
                j += 1;
                other.0[j - 1]
            };
            out.push(r.0, r.1);
        }
        out
    }
}

/// The occludees' costs by position, as prefix sums: the cost of a range in one subtraction.
#[derive(Clone, Debug, Default)]
pub struct Costs {
    prefix: Vec<u64>,
}

impl Costs {
    /// `cost[p]` of the occludee at position `p`.
    pub fn new(cost: &[u64]) -> Costs {
        let mut prefix = Vec::with_capacity(cost.len() + 1);
        let mut sum = 0u64;
        prefix.push(0);
        for &c in cost {
            sum += c;
            prefix.push(sum);
        }
        Costs { prefix }
    }

    /// The summed cost of `start..end` (positions past the end cost nothing).
    fn range(&self, start: u32, end: u32) -> u64 {
        let at = |p: u32| self.prefix[(p as usize).min(self.prefix.len() - 1)];
        at(end) - at(start)
    }

    /// The summed cost of `s`.
    pub fn of(&self, s: &Spans) -> u64 {
        s.0.iter().map(|&(a, b)| self.range(a, b)).sum()
    }

    /// The summed cost of what `s` holds and `covered` does not: the gain of picking a VO that
    /// hides `s` after VOs that hide `covered`. One merge of both range lists.
    pub fn gain(&self, s: &Spans, covered: &Spans) -> u64 {
        let mut g = 0;
        let mut k = 0;
        let c = &covered.0;
        for &(a, b) in &s.0 {
            let mut at = a;
            while k < c.len() && c[k].1 <= at {
                k += 1;
            }
            let mut j = k;
            while at < b {
                match c.get(j) {
                    Some(&(cs, ce)) if cs < b => {
                        if cs > at {
                            g += self.range(at, cs);
                        }
                        at = at.max(ce);
                        j += 1;
                    }
                    _ => {
                        g += self.range(at, b);
                        at = b;
                    }
                }
            }
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sets of small positions against their plain forms (boolean arrays).
    #[test]
    fn union_and_gain_match_the_plain_set_arithmetic() {
        let mut next = crate::testutil::uniform(11);
        for round in 0..400 {
            let n = 1 + (next(0.0, 60.0) as usize);
            let pick = |next: &mut dyn FnMut(f64, f64) -> f64, p: f64| -> Vec<u32> {
                (0..n as u32).filter(|_| next(0.0, 1.0) < p).collect()
            };
            let (pa, pb) = (next(0.0, 1.0), next(0.0, 1.0));
            let a_ids = pick(&mut next, pa);
            let b_ids = pick(&mut next, pb);
            let cost: Vec<u64> = (0..n).map(|_| 1 + next(0.0, 9.0) as u64).collect();
            let (a, b) = (Spans::from_ids(&a_ids), Spans::from_ids(&b_ids));
            // Canonical: no empty and no touching ranges.
            for s in [&a, &b] {
                for w in s.ranges().windows(2) {
                    assert!(w[0].1 < w[1].0, "round {round}: {s:?}");
                }
                assert!(s.ranges().iter().all(|&(x, y)| x < y));
            }
            assert_eq!(a.positions().collect::<Vec<_>>(), a_ids);
            let mut u_ids = a_ids.clone();
            u_ids.extend(&b_ids);
            assert_eq!(a.union(&b), Spans::from_ids(&u_ids), "round {round}");
            let costs = Costs::new(&cost);
            let plain: u64 = a_ids
                .iter()
                .filter(|i| !b_ids.contains(i))
                .map(|&i| cost[i as usize])
                .sum();
            assert_eq!(costs.gain(&a, &b), plain, "round {round}: {a:?} less {b:?}");
            assert_eq!(
                costs.of(&a),
                a_ids.iter().map(|&i| cost[i as usize]).sum::<u64>()
            );
            assert_eq!(a.count(), a_ids.len() as u64);
        }
    }

    #[test]
    fn pushes_merge_touching_and_overlapping_ranges() {
        let mut s = Spans::new();
        s.push(0, 4);
        s.push(4, 6);
        s.push(5, 9);
        s.push(3, 3);
        s.push(12, 13);
        assert_eq!(s.ranges(), &[(0, 9), (12, 13)]);
        assert_eq!(s.count(), 10);
    }
}
