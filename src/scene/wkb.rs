//! Well-known binary (WKB) polygons, as GeoPackage stores them after its own header.
//!
//! Input: WKB bytes (ISO or extended WKB; 2D, Z, M or ZM; either byte order).
//! Output: the polygons of a Polygon, MultiPolygon or GeometryCollection of them (rings of
//! world xy; z and m are dropped), or `Err(SkipReason)` for a geometry with no area (points,
//! lines), or a message for bytes that break the encoding.
//! Invariants: every length is checked against the bytes left before anything is allocated
//! (a count that cannot fit is an error, not an allocation); nesting is bounded; never panics.

use glam::DVec2;

use super::{Ring, SkipReason};

/// How deep collections may nest.
const MAX_DEPTH: usize = 8;

/// A WKB geometry read for its polygons.
pub enum Read {
    Polygons(Vec<Vec<Ring>>),
    /// No area: the type's name.
    NotAreal(String),
}

/// Reads one WKB geometry (the whole of `b`, trailing bytes allowed).
pub fn polygons(b: &[u8]) -> Result<Read, String> {
    let mut r = Reader { b, at: 0 };
    let mut out = Vec::new();
    match r.geometry(&mut out, 0)? {
        None => Ok(Read::Polygons(out)),
        Some(t) => Ok(Read::NotAreal(t)),
    }
}

/// [`polygons`] as the footprint readers want it.
pub fn footprint(b: &[u8]) -> Result<Result<Vec<Vec<Ring>>, SkipReason>, String> {
    Ok(match polygons(b)? {
        Read::Polygons(p) if p.is_empty() => Err(SkipReason::EmptyGeometry),
        Read::Polygons(p) => Ok(p),
        Read::NotAreal(t) => Err(SkipReason::NotAreal(t)),
    })
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], String> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&e| e <= self.b.len())
            .ok_or_else(|| format!("WKB ends at byte {} (needs {n} more)", self.b.len()))?;
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn u32(&mut self, le: bool) -> Result<u32, String> {
        let s: [u8; 4] = self.take(4)?.try_into().map_err(|_| "short read")?;
        Ok(if le {
            u32::from_le_bytes(s)
        } else {
            u32::from_be_bytes(s)
        })
    }

    fn f64(&mut self, le: bool) -> Result<f64, String> {
        let s: [u8; 8] = self.take(8)?.try_into().map_err(|_| "short read")?;
        Ok(if le {
            f64::from_le_bytes(s)
        } else {
            f64::from_be_bytes(s)
        })
    }

    /// A count of items of at least `each` bytes: it must fit in what is left.
    fn count(&mut self, le: bool, each: usize) -> Result<usize, String> {
        let n = self.u32(le)? as usize;
        let left = self.b.len() - self.at;
        if n.saturating_mul(each) > left {
            return Err(format!(
                "WKB count {n} does not fit in the {left} bytes left"
            ));
        }
        Ok(n)
    }

    /// Reads a geometry, appending its polygons; returns the type name of a geometry with no
    /// area.
    fn geometry(
        &mut self,
        out: &mut Vec<Vec<Ring>>,
        depth: usize,
    ) -> Result<Option<String>, String> {
        if depth > MAX_DEPTH {
            return Err("WKB collections nest too deep".into());
        }
        let order = self.take(1)?[0];
        let le = match order {
            0 => false,
            1 => true,
            o => return Err(format!("WKB byte order {o} (expected 0 or 1)")),
        };
        let code = self.u32(le)?;
        // Extended WKB flags, then ISO's thousands.
        let (mut dims, base) = (
            2 + usize::from(code & 0x8000_0000 != 0) + usize::from(code & 0x4000_0000 != 0),
            code & 0x0fff_ffff,
        );
        if code & 0x2000_0000 != 0 {
            // An SRID follows.
            self.u32(le)?;
        }
        let kind = base % 1000;
        dims += match base / 1000 {
            0 => 0,
            1 | 2 => 1,
            3 => 2,
            t => return Err(format!("WKB geometry type {code} (dimension code {t})")),
        };
        let point = 8 * dims;
        match kind {
            3 => {
                out.push(self.polygon(le, dims)?);
                Ok(None)
            }
            6 | 7 => {
                let n = self.count(le, 5)?;
                let mut not_areal = None;
                for _ in 0..n {
                    if let Some(t) = self.geometry(out, depth + 1)? {
                        not_areal.get_or_insert(t);
                    }
                }
                // A collection with polygons is read for them; one with none has no area.
                Ok(if out.is_empty() { not_areal } else { None })
            }
            1 | 2 | 4 | 5 => {
                // Skip over it (so a collection reads on), and name it.
                match kind {
                    1 => {
                        self.take(point)?;
                    }
                    2 => {
                        let n = self.count(le, point)?;
                        self.take(n * point)?;
                    }
                    _ => {
                        let n = self.count(le, 5)?;
                        for _ in 0..n {
                            let mut ignored = Vec::new();
                            self.geometry(&mut ignored, depth + 1)?;
                        }
                    }
                }
                let name = [
                    "",
                    "Point",
                    "LineString",
                    "",
                    "MultiPoint",
                    "MultiLineString",
                ][kind as usize];
                Ok(Some(name.to_string()))
            }
            15 | 16 => {
                // PolyhedralSurface, TIN: polygons.
                let n = self.count(le, 9)?;
                for _ in 0..n {
                    self.geometry(out, depth + 1)?;
                }
                Ok(None)
            }
            17 => {
                out.push(self.polygon(le, dims)?);
                Ok(None)
            }
            _ => Err(format!("unsupported WKB geometry type {code}")),
        }
    }

    fn polygon(&mut self, le: bool, dims: usize) -> Result<Vec<Ring>, String> {
        let point = 8 * dims;
        let rings = self.count(le, 4)?;
        let mut out = Vec::with_capacity(rings);
        for _ in 0..rings {
            let n = self.count(le, point)?;
            let mut ring = Vec::with_capacity(n);
            for _ in 0..n {
                let x = self.f64(le)?;
                let y = self.f64(le)?;
                for _ in 2..dims {
                    self.f64(le)?;
                }
                ring.push(DVec2::new(x, y));
            }
            out.push(ring);
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn poly_le(z: bool) -> Vec<u8> {
        let mut b = vec![1u8];
        b.extend_from_slice(&(if z { 1003u32 } else { 3 }).to_le_bytes());
        b.extend_from_slice(&1u32.to_le_bytes());
        b.extend_from_slice(&4u32.to_le_bytes());
        for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (0.0, 0.0)] {
            b.extend_from_slice(&f64::to_le_bytes(x));
            b.extend_from_slice(&f64::to_le_bytes(y));
            if z {
                b.extend_from_slice(&f64::to_le_bytes(5.0));
            }
        }
        b
    }

    #[test]
    fn polygons_and_errors() {
        for z in [false, true] {
            let Read::Polygons(p) = polygons(&poly_le(z)).unwrap() else {
                panic!()
            };
            assert_eq!(p[0][0].len(), 4);
            assert_eq!(p[0][0][1], DVec2::new(1.0, 0.0));
        }
        let mut multi = vec![1u8];
        multi.extend_from_slice(&6u32.to_le_bytes());
        multi.extend_from_slice(&2u32.to_le_bytes());
        multi.extend(poly_le(false));
        multi.extend(poly_le(true));
        let Read::Polygons(p) = polygons(&multi).unwrap() else {
            panic!()
        };
        assert_eq!(p.len(), 2);
        // A count that cannot fit is an error, not an allocation.
        let mut huge = vec![1u8];
        huge.extend_from_slice(&3u32.to_le_bytes());
        huge.extend_from_slice(&u32::MAX.to_le_bytes());
        assert!(polygons(&huge).is_err());
        assert!(polygons(&poly_le(false)[..20]).is_err());
        let mut pt = vec![1u8];
        pt.extend_from_slice(&1u32.to_le_bytes());
        pt.extend_from_slice(&[0; 16]);
        assert!(matches!(polygons(&pt).unwrap(), Read::NotAreal(t) if t == "Point"));
    }
}
