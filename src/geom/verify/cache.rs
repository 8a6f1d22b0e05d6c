//! The certificate cache of one verifier: certificates found, listed in 8 m buckets over the
//! piece each certified, newest first, and tried first at later points nearby.
//!
//! Input: a certificate's conditions and blockers, and the piece it held on. Output: of the
//! newest cached where a point lies, one that holds (exactly) at that point and at the probe
//! ahead of it, reaching furthest.
//!
//! Invariant: a cached certificate is checked exactly like a new one, so the cache saves
//! searching and decides nothing. Bucket keys hash with `rustc-hash`'s `FxHasher`: the keys are
//! the verifier's own integers, and the map is only looked up, never iterated, so the hash
//! reaches no output.

use glam::DVec2;

use super::certificate::{reach, Cond};

/// A cached certificate: where its conditions lie in [`CertCache::conds`], and the blockers its
/// chords lie in (shared, not copied, when it is used again).
pub(super) type Cert = (u32, u32, std::rc::Rc<[u32]>);

/// Certificates (their conditions) by where they held: each is listed in the buckets of the
/// bounding box of the piece it certified, grown by [`CACHE_REACH_M`].
#[derive(Default)]
pub(super) struct CertCache {
    /// Each certificate's conditions (a range of `conds`) and the blockers (verifier indices)
    /// its chords lie in.
    pub(super) certs: Vec<Cert>,
    /// The conditions of all the certificates, one after another: one buffer, not an
    /// allocation per certificate.
    pub(super) conds: Vec<Cond>,
    /// Per bucket, its newest entry in `listed`.
    pub(super) buckets: rustc_hash::FxHashMap<(i64, i64), u32>,
    /// The buckets' lists, all in one: a certificate, and the entry listed before it in the
    /// same bucket ([`NO_ENTRY`]: none). One buffer, not a vector per bucket.
    pub(super) listed: Vec<(u32, u32)>,
}

/// The end of a bucket's list in [`CertCache::listed`].
pub(super) const NO_ENTRY: u32 = u32::MAX;

/// A new certificate is first sought among this many blockers nearest the point.
/// Cached certificates tried per point, newest first.
pub const CACHE_TRIES: usize = 16;
/// A cached certificate reaching less far than this is not enough: a new one is sought too,
/// metres.
pub const CACHE_ENOUGH_M: f64 = 2.0;

/// Side of a bucket of the certificate cache, metres.
pub const CACHE_BUCKET_M: f64 = 8.0;
/// A cached certificate is tried within this distance of the piece it certified, metres.
pub const CACHE_REACH_M: f64 = 4.0;

impl CertCache {
    pub(super) fn key(p: DVec2) -> (i64, i64) {
        (
            crate::geom::floor(p.x / CACHE_BUCKET_M) as i64,
            crate::geom::floor(p.y / CACHE_BUCKET_M) as i64,
        )
    }

    /// Caches the certificate of conditions `conds` and blockers `used`, which held from `p0`
    /// to `p1`.
    pub(super) fn add(&mut self, conds: &[Cond], used: std::rc::Rc<[u32]>, p0: DVec2, p1: DVec2) {
        let id = self.certs.len() as u32;
        let start = self.conds.len() as u32;
        self.conds.extend_from_slice(conds);
        self.certs.push((start, self.conds.len() as u32, used));
        let r = DVec2::splat(CACHE_REACH_M);
        let (lo, hi) = (Self::key(p0.min(p1) - r), Self::key(p0.max(p1) + r));
        // Long pieces are listed along their length only (at most 64 buckets).
        let n = ((hi.0 - lo.0 + 1) * (hi.1 - lo.1 + 1)) as usize;
        if n <= 64 {
            for x in lo.0..=hi.0 {
                for y in lo.1..=hi.1 {
                    self.list((x, y), id);
                }
            }
        } else {
            let steps = (p0.distance(p1) / CACHE_BUCKET_M).ceil().max(1.0) as usize;
            for k in 0..=steps.min(64) {
                let q = p0 + (p1 - p0) * (k as f64 / steps.min(64) as f64);
                self.list(Self::key(q), id);
            }
        }
    }

    /// Lists certificate `id` in bucket `key`, newest, unless it is the newest there already.
    pub(super) fn list(&mut self, key: (i64, i64), id: u32) {
        let at = self.listed.len() as u32;
        let head = self.buckets.entry(key).or_insert(NO_ENTRY);
        if *head != NO_ENTRY && self.listed[*head as usize].0 == id {
            return;
        }
        self.listed.push((id, *head));
        *head = at;
    }

    /// The conditions of certificate `id`.
    pub(super) fn conds_of(&self, id: u32) -> &[Cond] {
        let (s, e, _) = self.certs[id as usize];
        &self.conds[s as usize..e as usize]
    }

    /// Of the newest [`CACHE_TRIES`] certificates listed where `q` is, one that holds at `q`
    /// and `p` and reaches furthest towards `b` ([`reach`]), with that reach, if any.
    pub(super) fn find(&self, q: DVec2, p: DVec2, b: DVec2) -> Option<(u32, f64)> {
        let mut at = *self.buckets.get(&Self::key(q))?;
        std::iter::from_fn(|| {
            let &(id, prev) = self.listed.get(at as usize)?;
            at = prev;
            Some(id)
        })
        .take(CACHE_TRIES)
        .filter(|&i| {
            let c = self.conds_of(i);
            [q, p].iter().all(|&x| c.iter().all(|k| k.holds(x)))
        })
        .map(|i| (i, reach(self.conds_of(i), q, b)))
        .max_by(|x, y| x.1.total_cmp(&y.1))
    }
}

#[cfg(test)]
mod tests {
    use super::super::oracle::{brute_hidden, dyadic_points, scene, v};
    use super::super::tests::slices;
    use super::super::Verifier;
    use super::super::MAX_STEP_M;
    use super::*;
    use crate::testutil::Lcg;

    /// A certificate of one condition, `orient(q, (c, -1), (c, 1)) = Ccw`: holding for `q.x < c`.
    fn below(c: f64) -> Vec<Cond> {
        vec![Cond {
            u: v(c, -1.0),
            v: v(c, 1.0),
            strict: true,
        }]
    }

    #[test]
    fn a_hit_is_the_newest_that_holds_and_reaches_furthest() {
        let mut cache = CertCache::default();
        let (q, p, b) = (v(0.0, 0.0), v(0.01, 0.0), v(10.0, 0.0));
        for c in [3.0, 9.0, 0.005, 5.0] {
            cache.add(&below(c), [1].into(), v(0.0, 0.0), v(0.5, 0.0));
        }
        // The one at 0.005 fails at p; of the others 9 reaches furthest, the same as
        // recomputing its reach.
        let (id, t) = cache.find(q, p, b).unwrap();
        assert_eq!(id, 1);
        assert_eq!(t, reach(&below(9.0), q, b));
        assert_eq!(cache.conds_of(id).len(), 1);
        // Far from where they held: nothing is tried.
        assert!(cache.find(v(100.0, 0.0), v(100.01, 0.0), b).is_none());
        // Only the newest CACHE_TRIES are tried.
        for _ in 0..CACHE_TRIES {
            cache.add(&below(1.0), [2].into(), v(0.0, 0.0), v(0.5, 0.0));
        }
        let (id, t) = cache.find(q, p, b).unwrap();
        assert!(id as usize >= 4 && t == 0.1, "{id} {t}");
    }

    #[test]
    fn a_long_piece_is_listed_along_its_length() {
        let mut cache = CertCache::default();
        let (p0, p1) = (v(0.0, 0.0), v(1000.0, 1000.0));
        cache.add(&below(1e9), [0].into(), p0, p1);
        let b = v(2000.0, 0.0);
        // At its ends and at 65 points along it, not in all the 16,000 buckets of its box.
        for k in 0..=64 {
            let q = p0 + (p1 - p0) * (k as f64 / 64.0);
            assert!(cache.find(q, q + v(0.01, 0.0), b).is_some(), "{q:?}");
        }
        assert!(cache.listed.len() <= 65);
        assert!(cache.find(v(1000.0, 0.0), v(1000.01, 0.0), b).is_none());
        // A short piece is listed in every bucket within CACHE_REACH_M of its box.
        let mut cache = CertCache::default();
        cache.add(&below(1e9), [0].into(), v(3.0, 3.0), v(5.0, 3.0));
        for q in [v(-0.5, -0.5), v(8.5, 6.5), v(4.0, 3.0)] {
            assert!(cache.find(q, q + v(0.01, 0.0), b).is_some(), "{q:?}");
        }
        assert!(cache.find(v(17.0, 3.0), v(17.01, 3.0), b).is_none());
    }

    /// The cache saves searching and decides nothing: a verifier whose cache is warm from the
    /// same segment certifies what a fresh one does, to within a step at each end of a piece,
    /// and what it certifies is hidden by the blockers it reports.
    #[test]
    fn a_warm_cache_answers_as_a_recomputation() {
        let mut g = Lcg(19);
        let mut hits = 0;
        for _ in 0..60 {
            let (cell, blockers, (a, b)) = scene(&mut g, 14);
            let warm = Verifier::new(&cell, slices(&blockers));
            let first = warm.hidden_parts_by(a, b);
            let cached = warm.cache.borrow().certs.len();
            let again = warm.hidden_parts_by(a, b);
            hits += cached;
            let fresh = Verifier::new(&cell, slices(&blockers)).hidden_parts_by(a, b);
            // The same search on the same inputs: the same answer.
            assert_eq!(first, fresh);
            // With the cache warm, pieces may end where a cached certificate stops instead of
            // a new one, so their ends may move by a step of the search; what is certified is
            // still hidden by the blockers reported.
            let len = |x: &[(super::super::Hidden, Vec<u32>)]| -> f64 {
                x.iter().map(|(h, _)| h.p0.distance(h.p1)).sum()
            };
            let slack = 2.0 * MAX_STEP_M * (fresh.len() + again.len()) as f64;
            assert!(
                (len(&again) - len(&fresh)).abs() <= slack,
                "{again:?} against {fresh:?}"
            );
            for (h, used) in &again {
                let only: Vec<Vec<DVec2>> =
                    used.iter().map(|&i| blockers[i as usize].clone()).collect();
                for q in dyadic_points(h.p0, h.p1, 3) {
                    assert!(brute_hidden(&cell, &only, q, 300), "{q:?} of {h:?}");
                }
            }
        }
        assert!(hits > 20, "{hits}");
    }
}
