//! Coordinate reference systems: what each file says, longitude/latitude detection, and the
//! projection of geographic input to one metric CRS on load.
//!
//! Input: the CRS text a reader found in its file (a GeoJSON `crs` member, CityJSON
//! `metadata.referenceSystem`, a GeoPackage's `gpkg_spatial_ref_sys` row, a FlatGeobuf header, a
//! Shapefile's `.prj`, a CityGML `srsName`; OpenStreetMap is WGS84 by definition), or nothing.
//! Output: a [`Crs`] per file and one for the scene, and the points projected where needed.
//! Rules (ARCHITECTURE.md, "Coordinate reference systems"; README, "Coordinates"):
//! - a declared CRS is parsed for an EPSG code (`EPSG:3946`, `urn:ogc:def:crs:EPSG::3946`,
//!   `http://www.opengis.net/def/crs/EPSG/0/3946`, the first code of a compound URN, WKT's last
//!   `AUTHORITY["EPSG",...]` or `ID["EPSG",...]`); OGC `CRS84` is longitude/latitude on WGS84;
//!   it is geographic when its definition (crs-definitions) is `+proj=longlat`, or its WKT starts
//!   with `GEOGCS`/`GEOGCRS`;
//! - a footprint file that declares no CRS is *detected* as longitude/latitude (WGS84, the
//!   GeoJSON default of RFC 7946) when every coordinate lies within [-180, 180] x [-90, 90] and
//!   no object spans [`MAX_DEGREES_SPAN`] or more in x or y (a building spans far less than
//!   0.05 degree, about 5 km; in metres, no building is under 5 cm across). Mesh formats
//!   (CityJSON, CityGML, OBJ) are never detected: they carry metric heights with metric x, y;
//! - geographic input is projected on load with proj4rs: to `ReadOptions::crs` when given, else
//!   to the projected CRS of another input, else to the UTM zone (WGS84, EPSG:326NN north,
//!   327NN south) of the centre of the geographic input's extent;
//! - inputs in two different CRSs are projected into one (the first projected CRS, or
//!   `ReadOptions::crs`) when both have an EPSG definition, and refused otherwise with an error
//!   naming both CRSs and files; a file that states no CRS is taken to be in the scene's CRS,
//!   except beside geographic input, where it is refused (its unit is unknown).
//!
//! Invariant: projection happens once, on world f64 coordinates, before the local origin is
//! chosen (ARCHITECTURE.md invariant 3); heights are never changed.

use std::fmt;

use glam::{DVec2, DVec3};
use serde::Serialize;

/// An object spanning this much or more in x or y (in the file's units) is not a building in
/// degrees: the file is not taken for longitude/latitude.
pub const MAX_DEGREES_SPAN: f64 = 0.05;

/// Where a scene's or file's CRS came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CrsSource {
    /// The file says so (or its format does: OpenStreetMap is WGS84).
    File,
    /// The file says nothing; its coordinates are longitude/latitude by the detection rule.
    Detected,
    /// The scene's CRS, into which input in another CRS was projected on load.
    Projected,
    /// Asked for with `ReadOptions::crs` (`--crs`).
    Requested,
}

/// A coordinate reference system as vocc knows it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Crs {
    /// Display name: `EPSG:3946` when the code is known, else the name or text in the file.
    pub name: String,
    /// The EPSG code, when known.
    pub epsg: Option<u32>,
    /// Longitude/latitude (degrees) rather than metres.
    pub geographic: bool,
    pub source: CrsSource,
    /// For a scene: the CRSs of the input projected into it on load (empty when none was).
    pub projected_from: Vec<String>,
}

impl fmt::Display for Crs {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.name)?;
        match self.source {
            CrsSource::File => write!(f, " (from the file)"),
            CrsSource::Detected => write!(
                f,
                " (detected: no CRS stated, every coordinate within longitude/latitude range)"
            ),
            CrsSource::Requested => write!(f, " (requested)"),
            CrsSource::Projected => {
                write!(
                    f,
                    " (projected on load from {})",
                    self.projected_from.join(", ")
                )
            }
        }?;
        if self.source != CrsSource::Projected && !self.projected_from.is_empty() {
            write!(
                f,
                "; projected on load from {}",
                self.projected_from.join(", ")
            )?;
        }
        Ok(())
    }
}

impl Crs {
    /// WGS84 longitude/latitude, as OpenStreetMap and RFC 7946 GeoJSON are.
    pub fn wgs84(source: CrsSource) -> Crs {
        Crs {
            name: "EPSG:4326".into(),
            epsg: Some(4326),
            geographic: true,
            source,
            projected_from: Vec::new(),
        }
    }

    /// A CRS from its EPSG code.
    pub fn from_epsg(code: u32, source: CrsSource) -> Crs {
        Crs {
            name: format!("EPSG:{code}"),
            epsg: Some(code),
            geographic: epsg_is_geographic(code).unwrap_or(false),
            source,
            projected_from: Vec::new(),
        }
    }

    /// Parses what a file declares: a URN, URL, `EPSG:N`, `CRS84`, or WKT. Never fails: text
    /// without a code is kept as the name.
    pub fn parse(text: &str) -> Crs {
        let t = text.trim();
        let upper = t.to_ascii_uppercase();
        if upper.ends_with("CRS84") || upper.ends_with("CRS:84") {
            return Crs::wgs84(CrsSource::File);
        }
        let wkt = upper.starts_with("GEOGCS[")
            || upper.starts_with("GEOGCRS[")
            || upper.starts_with("PROJCS[")
            || upper.starts_with("PROJCRS[")
            || upper.starts_with("GEODCRS[")
            || upper.starts_with("COMPD_CS[")
            || upper.starts_with("COMPOUNDCRS[");
        if wkt {
            let code = wkt_epsg(t);
            let geographic = match code.and_then(epsg_is_geographic) {
                Some(g) => g,
                None => upper.starts_with("GEOG") || upper.starts_with("GEODCRS"),
            };
            let name = match code {
                Some(c) => format!("EPSG:{c}"),
                None => wkt_name(t).unwrap_or_else(|| shorten(t)),
            };
            return Crs {
                name,
                epsg: code,
                geographic,
                source: CrsSource::File,
                projected_from: Vec::new(),
            };
        }
        match text_epsg(t) {
            Some(code) => Crs::from_epsg(code, CrsSource::File),
            None => Crs {
                name: shorten(t),
                epsg: None,
                geographic: false,
                source: CrsSource::File,
                projected_from: Vec::new(),
            },
        }
    }

    /// Whether two CRSs are the same: the same EPSG code, or, without codes, the same name.
    pub fn same_as(&self, other: &Crs) -> bool {
        match (self.epsg, other.epsg) {
            (Some(a), Some(b)) => a == b,
            _ => self.name == other.name,
        }
    }
}

fn shorten(t: &str) -> String {
    let one_line: String = t.split_whitespace().collect::<Vec<_>>().join(" ");
    if one_line.chars().count() > 60 {
        let s: String = one_line.chars().take(57).collect();
        format!("{s}...")
    } else {
        one_line
    }
}

/// `Some(true)` when crs-definitions knows the code as longitude/latitude, `Some(false)` when it
/// knows it otherwise, `None` when it does not know it.
pub fn epsg_is_geographic(code: u32) -> Option<bool> {
    let code = u16::try_from(code).ok()?;
    crs_definitions::from_code(code).map(|d| d.proj4.contains("+proj=longlat"))
}

/// The EPSG code in `EPSG:3946`, `urn:ogc:def:crs:EPSG::3946`, `urn:ogc:def:crs:EPSG:6.6:3946`,
/// `http://www.opengis.net/def/crs/EPSG/0/3946` or a compound URN (its first code).
fn text_epsg(t: &str) -> Option<u32> {
    let upper = t.to_ascii_uppercase();
    let at = upper.find("EPSG")?;
    let rest = &upper[at + 4..];
    // The code is the last number of this component: up to the next ',' (compound URNs).
    let comp = rest.split(',').next().unwrap_or("");
    let digits: Vec<&str> = comp
        .split(|c: char| !c.is_ascii_digit() && c != '.')
        .filter(|s| !s.is_empty())
        .collect();
    let last = digits.last()?;
    if last.contains('.') {
        return None;
    }
    last.parse().ok().filter(|&c| c > 0)
}

/// The code of a WKT's outermost `AUTHORITY["EPSG","N"]` (WKT1) or `ID["EPSG",N]` (WKT2): the
/// last one in the text, at bracket depth 1.
fn wkt_epsg(t: &str) -> Option<u32> {
    let mut depth = 0i32;
    let bytes = t.as_bytes();
    let mut found = None;
    let mut in_str = false;
    for (i, &b) in bytes.iter().enumerate() {
        match b {
            b'"' => in_str = !in_str,
            b'[' | b'(' if !in_str => depth += 1,
            b']' | b')' if !in_str => depth -= 1,
            _ => {}
        }
        if !in_str && depth == 1 && (b == b',') {
            let tail = t[i + 1..].trim_start();
            let tu = tail.to_ascii_uppercase();
            if tu.starts_with("AUTHORITY[") || tu.starts_with("ID[") {
                let inner = &tail[tail.find('[')? + 1..];
                let end = inner.find(']').unwrap_or(inner.len());
                let parts: Vec<&str> = inner[..end]
                    .split(',')
                    .map(|s| s.trim().trim_matches('"'))
                    .collect();
                if parts.len() >= 2 && parts[0].eq_ignore_ascii_case("EPSG") {
                    found = parts[1].parse().ok();
                }
            }
        }
    }
    found
}

/// The first quoted string of a WKT: its name.
fn wkt_name(t: &str) -> Option<String> {
    let a = t.find('"')?;
    let b = t[a + 1..].find('"')?;
    Some(t[a + 1..a + 1 + b].to_string())
}

/// Whether all these xy lie within longitude/latitude range and no object spans
/// [`MAX_DEGREES_SPAN`] or more: see the module header. `objects` yields each object's points.
pub fn looks_geographic<I, J>(objects: I) -> bool
where
    I: IntoIterator<Item = J>,
    J: IntoIterator<Item = DVec2>,
{
    let mut any = false;
    for pts in objects {
        let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
        for p in pts {
            if !(p.x.abs() <= 180.0 && p.y.abs() <= 90.0) {
                return false;
            }
            lo = lo.min(p);
            hi = hi.max(p);
            any = true;
        }
        if lo.x <= hi.x && (hi.x - lo.x >= MAX_DEGREES_SPAN || hi.y - lo.y >= MAX_DEGREES_SPAN) {
            return false;
        }
    }
    any
}

/// The UTM zone (WGS84) of a longitude/latitude point, as an EPSG code: 326NN north of the
/// equator, 327NN south.
pub fn utm_epsg(lon: f64, lat: f64) -> u32 {
    let zone = (((lon + 180.0) / 6.0).floor() as i64).clamp(0, 59) as u32 + 1;
    if lat < 0.0 {
        32700 + zone
    } else {
        32600 + zone
    }
}

/// A projection from one CRS to another, both known by EPSG code.
pub struct Projector {
    src: proj4rs::Proj,
    dst: proj4rs::Proj,
    src_geographic: bool,
    dst_geographic: bool,
}

impl Projector {
    /// Fails with a message when either code has no definition, or the definition does not
    /// parse.
    pub fn new(from: u32, to: u32) -> Result<Projector, String> {
        let proj = |c: u32| -> Result<(proj4rs::Proj, bool), String> {
            let code =
                u16::try_from(c).map_err(|_| format!("EPSG:{c} has no definition in vocc"))?;
            let def = crs_definitions::from_code(code)
                .ok_or_else(|| format!("EPSG:{c} has no definition in vocc"))?;
            let p =
                proj4rs::Proj::from_proj_string(def.proj4).map_err(|e| format!("EPSG:{c}: {e}"))?;
            Ok((p, def.proj4.contains("+proj=longlat")))
        };
        let (src, src_geographic) = proj(from)?;
        let (dst, dst_geographic) = proj(to)?;
        Ok(Projector {
            src,
            dst,
            src_geographic,
            dst_geographic,
        })
    }

    /// Projects one point (degrees for a geographic CRS, as files write them); `None` when the
    /// projection fails or gives a value that is not finite.
    pub fn project(&self, p: DVec2) -> Option<DVec2> {
        let mut pt = if self.src_geographic {
            (p.x.to_radians(), p.y.to_radians(), 0.0)
        } else {
            (p.x, p.y, 0.0)
        };
        proj4rs::transform::transform(&self.src, &self.dst, &mut pt).ok()?;
        let out = if self.dst_geographic {
            DVec2::new(pt.0.to_degrees(), pt.1.to_degrees())
        } else {
            DVec2::new(pt.0, pt.1)
        };
        out.is_finite().then_some(out)
    }

    /// [`Self::project`] for a 3D point; z is kept.
    pub fn project3(&self, p: DVec3) -> Option<DVec3> {
        self.project(DVec2::new(p.x, p.y))
            .map(|q| DVec3::new(q.x, q.y, p.z))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declared_crs_texts() {
        let c = Crs::parse("urn:ogc:def:crs:EPSG::3946");
        assert_eq!(
            (c.name.as_str(), c.epsg, c.geographic),
            ("EPSG:3946", Some(3946), false)
        );
        assert!(Crs::parse("urn:ogc:def:crs:OGC:1.3:CRS84").geographic);
        assert!(Crs::parse("urn:ogc:def:crs:EPSG::4326").geographic);
        assert_eq!(
            Crs::parse("https://www.opengis.net/def/crs/EPSG/0/7415").epsg,
            Some(7415)
        );
        assert_eq!(Crs::parse("EPSG:28992").epsg, Some(28992));
        assert_eq!(
            Crs::parse("urn:ogc:def:crs,crs:EPSG::28992,crs:EPSG::5109").epsg,
            Some(28992)
        );
        let w = Crs::parse(
            r#"PROJCS["RGF93 / CC46",GEOGCS["RGF93",AUTHORITY["EPSG","4171"]],UNIT["metre",1],AUTHORITY["EPSG","3946"]]"#,
        );
        assert_eq!(w.epsg, Some(3946));
        assert!(!w.geographic);
        let esri = Crs::parse(r#"PROJCS["RGF_1993_CC46",GEOGCS["GCS_RGF_1993"]]"#);
        assert_eq!((esri.name.as_str(), esri.epsg), ("RGF_1993_CC46", None));
        let g = Crs::parse(r#"GEOGCS["GCS_WGS_1984",DATUM["D_WGS_1984"]]"#);
        assert!(g.geographic);
    }

    #[test]
    fn detection_and_zones() {
        let b = |x: f64, y: f64, d: f64| {
            vec![DVec2::new(x, y), DVec2::new(x + d, y), DVec2::new(x, y + d)]
        };
        assert!(looks_geographic([
            b(4.83, 45.76, 0.0002),
            b(4.84, 45.77, 0.0003)
        ]));
        // A 1 m square near the origin is metres, not a 100 km building.
        assert!(!looks_geographic([b(0.0, 0.0, 1.0)]));
        assert!(!looks_geographic([b(1_842_000.0, 5_176_000.0, 10.0)]));
        assert!(!looks_geographic(Vec::<Vec<DVec2>>::new()));
        assert_eq!(utm_epsg(4.83, 45.76), 32631);
        assert_eq!(utm_epsg(24.94, 60.17), 32635);
        assert_eq!(utm_epsg(18.47, -33.93), 32734);
        assert_eq!(utm_epsg(180.0, 0.0), 32660);
    }

    #[test]
    fn projection_round_trip_lyon() {
        // A point of Lyon in EPSG:3946 to WGS84 and back.
        let to = Projector::new(3946, 4326).unwrap();
        let back = Projector::new(4326, 3946).unwrap();
        let p = DVec2::new(1_842_000.0, 5_176_050.0);
        let g = to.project(p).unwrap();
        assert!(
            (g.x - 4.83).abs() < 0.02 && (g.y - 45.76).abs() < 0.02,
            "{g}"
        );
        let q = back.project(g).unwrap();
        assert!((q - p).length() < 1e-6, "{q} {p}");
        let utm = Projector::new(4326, 32631).unwrap().project(g).unwrap();
        assert!((utm.x - 643_000.0).abs() < 5_000.0, "{utm}");
    }
}
