//! The viewer page (`vocc view`): a scene's geometry as binary buffers, and one self-contained
//! HTML page that shows the city in 3D with a store's cells, VOs and PVS.
//!
//! Input: a store's bytes and a loaded [`Scene`]. Output: [`SceneGeometry`] (what a renderer
//! needs of each object, in the store's local frame, as flat typed arrays), and the page
//! ([`page`]): the template `js/viewer/page.html` with the bundled viewer `js/dist/viewer.js`
//! (three.js and the JavaScript runtime of `js/src/`, built by `js/viewer/build.mjs` and
//! committed), and the data as one base64 block of little-endian typed arrays described by a
//! JSON directory.
//! Invariants:
//! - the page builds its PVS with the JavaScript runtime from the store's own bytes and the
//!   objects' world boxes, which are the very `f64` boxes `vocc pvs` culls (`bbox + origin`), in
//!   object index order, with their input feature numbers;
//! - geometry is shipped as polygons, not triangles: footprints as rings extruded from base to
//!   top, mesh faces as rings of 3D points; the page triangulates them (one pass, earcut);
//! - the page needs nothing from the network: everything is inline.

use crate::scene::{Scene, Shape};

/// The bundled viewer script (`js/dist/viewer.js`, built by `node js/viewer/build.mjs`).
const BUNDLE: &str = include_str!("../../js/dist/viewer.js");
/// The page's HTML and CSS, with the placeholders `{{TITLE}}`, `{{META}}`, `{{DATA}}` and
/// `{{SCRIPT}}`.
const TEMPLATE: &str = include_str!("../../js/viewer/page.html");

/// A scene's objects as a renderer needs them, in the store's local frame (`local = world -
/// origin`, rounded to `f32`), in object index order. Footprint polygons and mesh faces both
/// list their rings: ring `r` has `ring_len[r]` points; footprint rings are 2D (`fp_xy`), face
/// rings 3D (`face_xyz`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneGeometry {
    /// World boxes `xmin, ymin, zmin, xmax, ymax, zmax` per object: what `vocc pvs` culls.
    pub boxes: Vec<f64>,
    /// Input feature number per object (`vocc pvs` prints these).
    pub features: Vec<u32>,
    /// Per footprint polygon: its object, bottom and top (local), and its number of rings
    /// (the first the exterior, the others holes).
    pub fp_object: Vec<u32>,
    pub fp_base: Vec<f32>,
    pub fp_top: Vec<f32>,
    pub fp_rings: Vec<u32>,
    /// Points per footprint ring, and the points, `x, y`.
    pub fp_ring_len: Vec<u32>,
    pub fp_xy: Vec<f32>,
    /// Per mesh face: its object and its number of rings.
    pub face_object: Vec<u32>,
    pub face_rings: Vec<u32>,
    /// Points per face ring, and the points, `x, y, z`.
    pub face_ring_len: Vec<u32>,
    pub face_xyz: Vec<f32>,
}

impl SceneGeometry {
    /// The geometry of `scene` in the frame of `origin` (the store's origin, world metres).
    pub fn new(scene: &Scene, origin: [f64; 3]) -> SceneGeometry {
        let so = scene.origin;
        // Scene-local to store-local, in f64 before the rounding to f32.
        let shift = [so.x - origin[0], so.y - origin[1], so.z - origin[2]];
        let mut g = SceneGeometry::default();
        for ob in &scene.objects {
            let (a, b) = (ob.bbox.min + so, ob.bbox.max + so);
            g.boxes.extend_from_slice(&[a.x, a.y, a.z, b.x, b.y, b.z]);
            g.features.push(ob.feature);
            match &ob.shape {
                Shape::Footprint(fp) => {
                    for poly in &fp.polygons {
                        let rings: Vec<&[glam::DVec2]> = poly
                            .iter()
                            .map(|r| open_ring(r))
                            .filter(|r| r.len() >= 3)
                            .collect();
                        if rings.is_empty() {
                            continue;
                        }
                        g.fp_object.push(ob.index);
                        g.fp_base.push((fp.base + shift[2]) as f32);
                        g.fp_top.push((fp.top + shift[2]) as f32);
                        g.fp_rings.push(rings.len() as u32);
                        for r in rings {
                            g.fp_ring_len.push(r.len() as u32);
                            for p in r {
                                g.fp_xy.push((p.x + shift[0]) as f32);
                                g.fp_xy.push((p.y + shift[1]) as f32);
                            }
                        }
                    }
                }
                Shape::Mesh(m) => {
                    for face in &m.faces {
                        let rings: Vec<&Vec<u32>> =
                            face.rings.iter().filter(|r| r.len() >= 3).collect();
                        if rings.is_empty() {
                            continue;
                        }
                        g.face_object.push(ob.index);
                        g.face_rings.push(rings.len() as u32);
                        for r in rings {
                            g.face_ring_len.push(r.len() as u32);
                            for &i in r {
                                let p = m.vertices.get(i as usize).copied().unwrap_or_default();
                                g.face_xyz.push((p.x + shift[0]) as f32);
                                g.face_xyz.push((p.y + shift[1]) as f32);
                                g.face_xyz.push((p.z + shift[2]) as f32);
                            }
                        }
                    }
                }
            }
        }
        g
    }

    /// Number of objects.
    pub fn len(&self) -> usize {
        self.features.len()
    }

    pub fn is_empty(&self) -> bool {
        self.features.is_empty()
    }
}

/// A ring without its closing point (GeoJSON repeats the first point at the end).
fn open_ring(r: &[glam::DVec2]) -> &[glam::DVec2] {
    match r {
        [first, .., last] if first == last => &r[..r.len() - 1],
        _ => r,
    }
}

/// The element type of a section of the data block, as the page names it.
#[derive(Clone, Copy)]
enum Kind {
    U8,
    U32,
    F32,
    F64,
}

/// Appends the sections as one buffer (each section aligned to 8 bytes, little-endian) and
/// returns the buffer and its JSON directory `{name: [offset, count, type]}`.
fn pack(sections: &[(&str, Kind, Vec<u8>)]) -> (Vec<u8>, serde_json::Value) {
    let mut buf = Vec::new();
    let mut dir = serde_json::Map::new();
    for (name, kind, bytes) in sections {
        while buf.len() % 8 != 0 {
            buf.push(0);
        }
        let (ty, size) = match kind {
            Kind::U8 => ("u8", 1),
            Kind::U32 => ("u32", 4),
            Kind::F32 => ("f32", 4),
            Kind::F64 => ("f64", 8),
        };
        dir.insert(
            name.to_string(),
            serde_json::json!([buf.len(), bytes.len() / size, ty]),
        );
        buf.extend_from_slice(bytes);
    }
    (buf, serde_json::Value::Object(dir))
}

fn le_u32(v: &[u32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn le_f32(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn le_f64(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// Standard base64 with padding.
pub fn base64(bytes: &[u8]) -> String {
    const ABC: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(ABC[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// What the page says about its inputs (shown in its panel).
#[derive(Clone, Debug, Default)]
pub struct PageInfo {
    /// The page's title (the store's file name).
    pub title: String,
    /// The store's file name and the scene files' names, as given.
    pub store: String,
    pub scene: Vec<String>,
}

/// JSON text that is safe inside a `<script>` element (no `</` sequence closes it).
fn script_safe(s: &str) -> String {
    s.replace("</", "<\\/")
}

/// The viewer page for `store_bytes` (a store file, 2.0 or 1.0, which the page decodes itself)
/// and `geometry` (in the store's frame).
pub fn page(store_bytes: &[u8], geometry: &SceneGeometry, info: &PageInfo) -> String {
    let g = geometry;
    let (data, dir) = pack(&[
        ("store", Kind::U8, store_bytes.to_vec()),
        ("boxes", Kind::F64, le_f64(&g.boxes)),
        ("features", Kind::U32, le_u32(&g.features)),
        ("fpObject", Kind::U32, le_u32(&g.fp_object)),
        ("fpBase", Kind::F32, le_f32(&g.fp_base)),
        ("fpTop", Kind::F32, le_f32(&g.fp_top)),
        ("fpRings", Kind::U32, le_u32(&g.fp_rings)),
        ("fpRingLen", Kind::U32, le_u32(&g.fp_ring_len)),
        ("fpXy", Kind::F32, le_f32(&g.fp_xy)),
        ("faceObject", Kind::U32, le_u32(&g.face_object)),
        ("faceRings", Kind::U32, le_u32(&g.face_rings)),
        ("faceRingLen", Kind::U32, le_u32(&g.face_ring_len)),
        ("faceXyz", Kind::F32, le_f32(&g.face_xyz)),
    ]);
    let meta = serde_json::json!({
        "title": info.title,
        "store": info.store,
        "scene": info.scene,
        "objects": g.len(),
        "bytes": data.len(),
        "sections": dir,
    });
    let escape = |s: &str| {
        s.replace('&', "&amp;")
            .replace('<', "&lt;")
            .replace('>', "&gt;")
    };
    TEMPLATE
        .replacen("{{TITLE}}", &escape(&info.title), 1)
        .replacen("{{META}}", &script_safe(&meta.to_string()), 1)
        .replacen("{{DATA}}", &base64(&data), 1)
        .replacen("{{SCRIPT}}", &script_safe(BUNDLE), 1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_of_the_rfc_4648_examples() {
        for (i, want) in [
            "", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy",
        ]
        .iter()
        .enumerate()
        {
            assert_eq!(base64(&b"foobar"[..i]), *want);
        }
    }

    #[test]
    fn sections_are_aligned_and_described() {
        let (buf, dir) = pack(&[
            ("a", Kind::U8, vec![1, 2, 3]),
            ("b", Kind::F64, le_f64(&[1.5, -2.0])),
        ]);
        assert_eq!(buf.len(), 8 + 16);
        assert_eq!(dir["a"], serde_json::json!([0, 3, "u8"]));
        assert_eq!(dir["b"], serde_json::json!([8, 2, "f64"]));
        assert_eq!(&buf[8..16], &1.5f64.to_le_bytes());
    }

    #[test]
    fn the_page_holds_no_closing_script_tag_but_its_own() {
        let p = page(&[1, 2, 3], &SceneGeometry::default(), &PageInfo::default());
        let closes = p.matches("</script>").count();
        let opens = p.matches("<script").count();
        assert_eq!(closes, opens);
    }
}
