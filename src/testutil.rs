//! A seeded generator for the unit tests (no dependency): Knuth's 64-bit linear congruential
//! sequence, the same numbers on every machine.
//!
//! Input: a seed. Output: the states in turn ([`Lcg::next_u64`]), uniform numbers in `[0, 1)`
//! from their top 53 bits ([`Lcg::next`]) or in `[lo, hi)` ([`Lcg::range`]). With the `bake`
//! feature, also the small scenes of square buildings the bake's unit tests stand on ([`squares`]).

/// The generator; its field is the state, the seed at first.
pub(crate) struct Lcg(pub(crate) u64);

impl Lcg {
    /// The next state.
    pub(crate) fn next_u64(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0
    }

    /// A uniform number in `[0, 1)`.
    pub(crate) fn next(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// A uniform number in `[lo, hi)`.
    pub(crate) fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
}

/// [`Lcg::range`] as a closure.
pub(crate) fn uniform(seed: u64) -> impl FnMut(f64, f64) -> f64 {
    let mut g = Lcg(seed);
    move |lo, hi| g.range(lo, hi)
}

/// A scene of square buildings read from GeoJSON, each `([x, y, side], base, height)` in metres
/// (its `h` and `b` attributes).
#[cfg(feature = "bake")]
pub(crate) fn squares(items: &[([f64; 3], f64, f64)]) -> crate::scene::Scene {
    let feats: Vec<String> = items
        .iter()
        .map(|&([x, y, d], base, h)| {
            format!(
                r#"{{"type":"Feature","properties":{{"h":{h},"b":{base}}},"geometry":{{"type":"Polygon","coordinates":[[[{x},{y}],[{},{y}],[{},{}],[{x},{}],[{x},{y}]]]}}}}"#,
                x + d,
                x + d,
                y + d,
                y + d
            )
        })
        .collect();
    let text = format!(
        r#"{{"type":"FeatureCollection","features":[{}]}}"#,
        feats.join(",")
    );
    let opts = crate::scene::ReadOptions {
        height_attr: Some("h".into()),
        base_attr: Some("b".into()),
        ..Default::default()
    };
    crate::scene::load_bytes(&[("squares.geojson".into(), text.as_bytes())], &opts).unwrap()
}
