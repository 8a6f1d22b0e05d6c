//! The scene's fingerprint: one `u64` that a store records (`docs/FORMAT.md`, the scene
//! section) so that vocc can tell whether a store was baked from a given scene.
//!
//! Input: a loaded [`Scene`]. Output: its fingerprint, never 0 (0 means "not recorded" in a
//! store).
//! Invariants: the hash is fixed and documented (FORMAT.md section 5.2): FNV-1a 64 over the
//! little-endian bytes of the origin's three `f64` bit patterns, then, per object in index
//! order, its input feature number (`u32`) and its bounding box's six `f64` bit patterns (min x,
//! y, z, max x, y, z; local frame); a result of 0 is written as 1. It reads nothing else (not
//! the file names, blockers or shapes), so it depends only on what the readers made of the
//! files, in the same way in every build and on every platform. Engines treat it as opaque.

use super::Scene;

/// FNV-1a 64 offset basis.
const FNV_OFFSET: u64 = 0xcbf2_9ce4_8422_2325;
/// FNV-1a 64 prime.
const FNV_PRIME: u64 = 0x0000_0100_0000_01b3;

/// FNV-1a 64, fed in pieces.
struct Fnv1a(u64);

impl Fnv1a {
    fn bytes(&mut self, b: &[u8]) {
        for &x in b {
            self.0 ^= x as u64;
            self.0 = self.0.wrapping_mul(FNV_PRIME);
        }
    }

    fn f64(&mut self, x: f64) {
        self.bytes(&x.to_bits().to_le_bytes());
    }
}

impl Scene {
    /// The scene's fingerprint (module documentation): FNV-1a 64 over the origin and, per object
    /// in index order, its input feature number and bounding box; never 0.
    pub fn fingerprint(&self) -> u64 {
        let mut h = Fnv1a(FNV_OFFSET);
        for x in self.origin.to_array() {
            h.f64(x);
        }
        for o in &self.objects {
            h.bytes(&o.feature.to_le_bytes());
            for x in o
                .bbox
                .min
                .to_array()
                .into_iter()
                .chain(o.bbox.max.to_array())
            {
                h.f64(x);
            }
        }
        if h.0 == 0 {
            1
        } else {
            h.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{load_bytes, ReadOptions};

    #[test]
    fn fnv1a_64_check_values() {
        // The published FNV-1a 64 test vectors.
        for (input, want) in [
            (&b""[..], 0xcbf2_9ce4_8422_2325u64),
            (b"a", 0xaf63_dc4c_8601_ec8c),
            (b"foobar", 0x8594_4171_f739_67e8),
        ] {
            let mut h = Fnv1a(FNV_OFFSET);
            h.bytes(input);
            assert_eq!(h.0, want, "{input:?}");
        }
    }

    fn scene(text: &str) -> Scene {
        let opts = ReadOptions {
            height_attr: Some("h".into()),
            ..ReadOptions::default()
        };
        load_bytes(&[("s.geojson".into(), text.as_bytes())], &opts).unwrap()
    }

    fn square(x: f64, h: f64) -> String {
        format!(
            r#"{{"type":"Feature","properties":{{"h":{h}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},0],[{x1},0],[{x1},10],[{x},10],[{x},0]]]}}}}"#,
            x1 = x + 10.0
        )
    }

    fn collection(features: &[String]) -> String {
        format!(
            r#"{{"type":"FeatureCollection","features":[{}]}}"#,
            features.join(",")
        )
    }

    #[test]
    fn the_fingerprint_is_the_documented_hash_and_follows_the_objects() {
        let a = scene(&collection(&[square(1000.0, 12.0), square(1030.0, 20.0)]));
        // The documented hash, computed here from its definition.
        let mut want = Fnv1a(FNV_OFFSET);
        for x in a.origin.to_array() {
            want.bytes(&x.to_bits().to_le_bytes());
        }
        for o in &a.objects {
            want.bytes(&o.feature.to_le_bytes());
            for x in [
                o.bbox.min.x,
                o.bbox.min.y,
                o.bbox.min.z,
                o.bbox.max.x,
                o.bbox.max.y,
                o.bbox.max.z,
            ] {
                want.bytes(&x.to_bits().to_le_bytes());
            }
        }
        assert_eq!(a.fingerprint(), want.0);
        assert_ne!(a.fingerprint(), 0);
        // The same file again: the same fingerprint.
        let again = scene(&collection(&[square(1000.0, 12.0), square(1030.0, 20.0)]));
        assert_eq!(again.fingerprint(), a.fingerprint());
        // A height, a position, the order or a feature number changed: another one.
        for other in [
            collection(&[square(1000.0, 12.5), square(1030.0, 20.0)]),
            collection(&[square(1000.0, 12.0), square(1031.0, 20.0)]),
            collection(&[square(1030.0, 20.0), square(1000.0, 12.0)]),
            collection(&[
                r#"{"type":"Feature","properties":{},"geometry":null}"#.to_string(),
                square(1000.0, 12.0),
                square(1030.0, 20.0),
            ]),
        ] {
            assert_ne!(scene(&other).fingerprint(), a.fingerprint(), "{other}");
        }
    }
}
