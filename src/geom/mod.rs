//! Geometry: the exact predicates and the checks built only from them.
//!
//! All exact tests live in [`predicates`]; nothing else in the crate computes a sign from
//! floating-point arithmetic to decide topology or occlusion.

pub mod predicates;
pub mod verify;

pub use predicates::{Containment, Orientation, SegmentIntersection};

use glam::DVec2;

/// A pseudo-angle of direction `d`, monotone in the true angle, in `[0, 4)`: floating point, for
/// ordering and bucketing directions only (the hidden map's bins, the verifier's choice of
/// what to try); it decides nothing.
#[inline]
pub fn pseudo_angle(d: DVec2) -> f64 {
    let s = d.x.abs() + d.y.abs();
    if s == 0.0 {
        return 0.0;
    }
    let t = d.y / s;
    if d.x >= 0.0 {
        if t >= 0.0 {
            t
        } else {
            4.0 + t
        }
    } else {
        2.0 - t
    }
}

/// `x.floor()`, bit for bit, without a library call: the baseline x86-64 target has no rounding
/// instruction (it came with SSE4.1), so `f64::floor` calls libm, and the bake's hidden maps
/// and verifier bucket points in hot loops. Every float of magnitude `2^52` or more is an
/// integer (or not finite, or NaN): itself.
#[inline]
pub fn floor(x: f64) -> f64 {
    if x.abs() < 4_503_599_627_370_496.0 {
        let i = x as i64 as f64;
        if i > x {
            i - 1.0
        } else {
            // The sign of a zero kept (`floor(-0.0)` is `-0.0`).
            i.copysign(x)
        }
    } else {
        x
    }
}

/// `x.ceil()`, bit for bit, without a library call ([`floor`]).
#[inline]
pub fn ceil(x: f64) -> f64 {
    -floor(-x)
}

#[cfg(test)]
mod tests {
    #[test]
    fn floor_and_ceil_are_the_library_ones_bit_for_bit() {
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            0.9999999999999999,
            -0.9999999999999999,
            4_503_599_627_370_495.5,
            -4_503_599_627_370_495.5,
            4_503_599_627_370_496.0,
            9.3e18,
            -9.3e18,
            1e300,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
        ];
        let mut g = crate::testutil::Lcg(3);
        for _ in 0..100_000 {
            let seed = g.next_u64();
            xs.push(f64::from_bits(seed));
            xs.push((seed >> 11) as f64 / (1u64 << 40) as f64 - 4096.0);
        }
        for x in xs {
            assert_eq!(
                super::floor(x).to_bits(),
                x.floor().to_bits(),
                "floor {x:e}"
            );
            assert_eq!(super::ceil(x).to_bits(), x.ceil().to_bits(), "ceil {x:e}");
        }
    }
}
