//! GeoTIFF DEMs: a raster of ground heights, georeferenced, as terrain triangles.
//!
//! Input: the bytes of a single-band GeoTIFF (any sample type the `tiff` crate decodes; strips
//! or tiles; uncompressed, Deflate or LZW, with the floating-point predictor), and the world
//! window to keep. The georeferencing is read from the GeoTIFF tags here: `ModelPixelScale`
//! with `ModelTiepoint`, or an axis-aligned `ModelTransformation`; `GTRasterTypeGeoKey`
//! (pixel is area, the default, or point) from the `GeoKeyDirectory`, and the EPSG code of
//! `ProjectedCSTypeGeoKey`; `GDAL_NODATA` marks pixels with no data (NaN too).
//! Output: [`Dem`]: two triangles per square of four valid pixel centres that meets the window
//! (the diagonal from the lower-left to the upper-right centre), world coordinates; and what
//! `vocc info` reports. A square with a pixel of no data gives nothing: the terrain has a hole.
//! Invariants: never panics on any input (a fuzz target runs it); every refusal is a
//! [`LoadError`] naming the file, the tag or pixel and the rule; memory is bounded by the
//! image's declared size, refused above [`MAX_PIXELS`].

use std::io::Cursor;
use std::path::Path;

use glam::{DVec2, DVec3};
use tiff::decoder::{Decoder, DecodingResult, Limits};
use tiff::tags::Tag;

use super::error::check_coord;
use super::{LoadError, LoadErrorKind, Location};

/// The most pixels a DEM may have.
pub const MAX_PIXELS: u64 = 32_000_000;
const FORMAT: &str = "GeoTIFF";

/// A DEM read: its triangles in the window, and what it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Dem {
    pub triangles: Vec<[DVec3; 3]>,
    pub width: u32,
    pub height: u32,
    /// Pixel size, metres (x, y).
    pub pixel: (f64, f64),
    /// World position of pixel (0, 0)'s centre.
    pub first_centre: DVec2,
    /// `ProjectedCSTypeGeoKey`, when given.
    pub epsg: Option<u32>,
    pub nodata_value: Option<f64>,
    /// Pixels of no data within the window.
    pub nodata: usize,
}

fn malformed(path: &Path, location: Location, message: impl Into<String>) -> LoadError {
    LoadError::new(
        path,
        location,
        LoadErrorKind::Malformed {
            format: FORMAT,
            message: message.into(),
        },
    )
}

fn tag_loc(name: &str) -> Location {
    Location::Element(format!("tag {name}"))
}

/// Reads a GeoTIFF DEM, keeping the squares of pixel centres that meet the world window
/// `[lo, hi]` (all of them when `None`).
pub fn read_dem(
    path: &Path,
    bytes: &[u8],
    window: Option<(DVec2, DVec2)>,
) -> Result<Dem, LoadError> {
    let tiff_err =
        |what: &str, e: tiff::TiffError| malformed(path, Location::File, format!("{what}: {e}"));
    let mut limits = Limits::default();
    limits.decoding_buffer_size = 1 << 28;
    limits.ifd_value_size = 1 << 20;
    let mut d = Decoder::new(Cursor::new(bytes))
        .map_err(|e| tiff_err("not a TIFF file", e))?
        .with_limits(limits);
    let (w, h) = d.dimensions().map_err(|e| tiff_err("image size", e))?;
    if w < 2 || h < 2 {
        return Err(malformed(
            path,
            Location::File,
            format!("a DEM needs at least 2 x 2 pixels, this one has {w} x {h}"),
        ));
    }
    if w as u64 * h as u64 > MAX_PIXELS {
        return Err(malformed(
            path,
            Location::File,
            format!("{w} x {h} pixels is more than the {MAX_PIXELS} a DEM may have"),
        ));
    }
    let spp = d
        .find_tag_unsigned::<u16>(Tag::SamplesPerPixel)
        .ok()
        .flatten()
        .unwrap_or(1);
    if spp != 1 {
        return Err(malformed(
            path,
            tag_loc("SamplesPerPixel"),
            format!("a DEM has one band, this file has {spp}"),
        ));
    }
    // Georeferencing.
    let f64s = |d: &mut Decoder<Cursor<&[u8]>>, tag: u16| -> Result<Option<Vec<f64>>, LoadError> {
        match d.find_tag(Tag::Unknown(tag)) {
            Ok(None) => Ok(None),
            Ok(Some(v)) => v
                .into_f64_vec()
                .map(Some)
                .map_err(|e| tiff_err("a georeferencing tag", e)),
            Err(e) => Err(tiff_err("a georeferencing tag", e)),
        }
    };
    let scale = f64s(&mut d, 33550)?;
    let tie = f64s(&mut d, 33922)?;
    let transform = f64s(&mut d, 34264)?;
    let keys: Vec<u64> = match d.find_tag(Tag::Unknown(34735)) {
        Ok(Some(v)) => v
            .into_u64_vec()
            .map_err(|e| tiff_err("GeoKeyDirectory", e))?,
        _ => Vec::new(),
    };
    let key = |id: u64| -> Option<u64> {
        // Header of 4 shorts, then 4 shorts a key: id, location (0: the value itself), count, value.
        keys.get(4..)?
            .chunks_exact(4)
            .find(|k| k[0] == id && k[1] == 0)
            .map(|k| k[3])
    };
    let pixel_is_point = key(1025) == Some(2);
    let epsg = key(3072).filter(|&c| c > 0 && c < 32767).map(|c| c as u32);
    // x = ax * i + cx, y = ay * j + cy, raster coordinates (i, j) of pixel corners.
    let (ax, cx, ay, cy) = if let (Some(s), Some(t)) = (&scale, &tie) {
        if s.len() < 2 || t.len() < 6 {
            return Err(malformed(
                path,
                tag_loc("ModelPixelScale"),
                "ModelPixelScale needs 3 values and ModelTiepoint 6",
            ));
        }
        let (sx, sy) = (s[0], s[1]);
        if !(sx.is_finite() && sy.is_finite() && sx > 0.0 && sy > 0.0) {
            return Err(malformed(
                path,
                tag_loc("ModelPixelScale"),
                format!("pixel size {sx} x {sy} is not positive"),
            ));
        }
        // Tiepoint: raster (i, j) -> world (x, y).
        (sx, t[3] - t[0] * sx, -sy, t[4] + t[1] * sy)
    } else if let Some(m) = &transform {
        if m.len() < 16 {
            return Err(malformed(
                path,
                tag_loc("ModelTransformation"),
                "ModelTransformation needs 16 values",
            ));
        }
        if m[1] != 0.0 || m[4] != 0.0 {
            return Err(malformed(path, tag_loc("ModelTransformation"), "a rotated or sheared raster is not supported (warp it north up first, e.g. with gdalwarp)"));
        }
        if !(m[0] != 0.0 && m[5] != 0.0) {
            return Err(malformed(
                path,
                tag_loc("ModelTransformation"),
                "a pixel of zero size",
            ));
        }
        (m[0], m[3], m[5], m[7])
    } else {
        return Err(malformed(path, Location::File, "no georeferencing: a GeoTIFF DEM needs ModelPixelScale and ModelTiepoint, or ModelTransformation"));
    };
    for (v, what) in [
        (ax, "pixel size x"),
        (ay, "pixel size y"),
        (cx, "origin x"),
        (cy, "origin y"),
    ] {
        check_coord(v, what).map_err(|k| LoadError::new(path, tag_loc("ModelTiepoint"), k))?;
    }
    let off = if pixel_is_point { 0.0 } else { 0.5 };
    let centre =
        |i: u32, j: u32| DVec2::new(ax * (i as f64 + off) + cx, ay * (j as f64 + off) + cy);
    let nodata_value = match d.find_tag(Tag::GdalNodata) {
        Ok(Some(v)) => {
            let s = v.into_string().map_err(|e| tiff_err("GDAL_NODATA", e))?;
            let t = s.trim_matches(char::from(0)).trim();
            Some(t.parse::<f64>().map_err(|_| {
                malformed(
                    path,
                    tag_loc("GDAL_NODATA"),
                    format!("{t:?} is not a number"),
                )
            })?)
        }
        _ => None,
    };
    let img = d.read_image().map_err(|e| tiff_err("pixel data", e))?;
    let n = w as usize * h as usize;
    let (values, f32_data): (Vec<f64>, bool) = match img {
        DecodingResult::F32(v) => (v.into_iter().map(f64::from).collect(), true),
        DecodingResult::F64(v) => (v, false),
        DecodingResult::U8(v) => (v.into_iter().map(f64::from).collect(), false),
        DecodingResult::U16(v) => (v.into_iter().map(f64::from).collect(), false),
        DecodingResult::U32(v) => (v.into_iter().map(f64::from).collect(), false),
        DecodingResult::I8(v) => (v.into_iter().map(f64::from).collect(), false),
        DecodingResult::I16(v) => (v.into_iter().map(f64::from).collect(), false),
        DecodingResult::I32(v) => (v.into_iter().map(f64::from).collect(), false),
        _ => {
            return Err(malformed(
                path,
                Location::File,
                "unsupported sample type (use 8 to 32-bit integers or 32/64-bit floats)",
            ))
        }
    };
    if values.len() < n {
        return Err(malformed(
            path,
            Location::File,
            format!("{} samples for {w} x {h} pixels", values.len()),
        ));
    }
    let nd = nodata_value.map(|v| if f32_data { v as f32 as f64 } else { v });
    let valid = |z: f64| z.is_finite() && Some(z) != nd && z.abs() <= super::MAX_BASE_M;
    // Squares (i, j)..(i + 1, j + 1) of pixel centres that meet the window.
    let (i0, i1, j0, j1) = match window {
        None => (0u32, w - 1, 0u32, h - 1),
        Some((lo, hi)) => {
            let range = |a: f64, c: f64, lo: f64, hi: f64, n: u32| -> Option<(u32, u32)> {
                // Raster coordinate of a world value, as a pixel-centre index.
                let (r0, r1) = ((lo - c) / a - off, (hi - c) / a - off);
                let (r0, r1) = (r0.min(r1).floor() - 1.0, r0.max(r1).ceil() + 1.0);
                let (r0, r1) = (r0.max(0.0), r1.min((n - 1) as f64));
                (r0 < r1).then_some((r0 as u32, r1 as u32))
            };
            let (Some((i0, i1)), Some((j0, j1))) =
                (range(ax, cx, lo.x, hi.x, w), range(ay, cy, lo.y, hi.y, h))
            else {
                return Ok(Dem {
                    triangles: Vec::new(),
                    width: w,
                    height: h,
                    pixel: (ax.abs(), ay.abs()),
                    first_centre: centre(0, 0),
                    epsg,
                    nodata_value,
                    nodata: 0,
                });
            };
            (i0, i1, j0, j1)
        }
    };
    let z = |i: u32, j: u32| values[j as usize * w as usize + i as usize];
    let mut nodata = 0;
    for j in j0..=j1 {
        for i in i0..=i1 {
            if !valid(z(i, j)) {
                nodata += 1;
            }
        }
    }
    let mut triangles = Vec::new();
    for j in j0..j1 {
        for i in i0..i1 {
            let q = [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)];
            if !q.iter().all(|&(a, b)| valid(z(a, b))) {
                continue;
            }
            let p = q.map(|(a, b)| centre(a, b).extend(z(a, b)));
            if !p.iter().all(|v| v.is_finite()) {
                return Err(malformed(
                    path,
                    Location::Element(format!("pixel {i}, {j}")),
                    "a pixel centre is not finite",
                ));
            }
            // Rows run down (ay < 0): (i, j + 1) is the lower left; split along (i, j+1)-(i+1, j).
            triangles.push([p[3], p[1], p[0]]);
            triangles.push([p[3], p[2], p[1]]);
        }
    }
    Ok(Dem {
        triangles,
        width: w,
        height: h,
        pixel: (ax.abs(), ay.abs()),
        first_centre: centre(0, 0),
        epsg,
        nodata_value,
        nodata,
    })
}
