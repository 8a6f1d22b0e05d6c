//! Wavefront OBJ reader.
//!
//! Input: the bytes of an OBJ file (materials, texture coordinates, normals, points and lines
//! are ignored). Output: one [`RawObject`] per `o`/`g` group that has faces, in file order, each
//! a [`Mesh`] of polygon faces (as written, not triangulated) over only the vertices that group
//! uses, in world f64 coordinates as read; groups without faces are reported as
//! [`SkipReason::EmptyGeometry`].
//! Invariants:
//! - parsing is `tobj`'s; this module only adds a cheap line scan that gives each group its
//!   1-based starting line and pins errors to a line (`tobj` reports no line numbers);
//! - every vertex line is checked with [`check_coord`] (after the optional `w` divide): a NaN,
//!   infinite or out-of-range coordinate fails the file at its line;
//! - a file without a single face fails (`MalformedObj("no faces")`);
//! - no input makes this panic (the `tobj` call is additionally guarded by `catch_unwind`).

use std::io::Cursor;
use std::path::Path;

use glam::DVec3;

use super::error::check_coord;
use super::{
    Face, FileRead, LoadError, LoadErrorKind, Location, Mesh, RawObject, ReadOptions, Shape,
    SkipReason, Skipped,
};

/// One group as the line scan sees it, in the order `tobj` emits its models.
struct ScanGroup {
    /// 1-based line of the `o`/`g` statement, `None` for faces before any group statement.
    line: Option<usize>,
    name: String,
}

/// What the line scan found.
struct Scan {
    /// Groups that `tobj` turns into models, in order (the last one is always emitted).
    models: Vec<ScanGroup>,
    /// Groups that had no face statement at all and that `tobj` drops silently.
    empty: Vec<ScanGroup>,
    /// First vertex whose coordinate fails [`check_coord`].
    bad_coord: Option<(usize, LoadErrorKind)>,
    /// First line the scan cannot parse (used only to place a `tobj` error).
    bad_line: Option<(usize, String)>,
}

fn group_name(line: &str) -> String {
    // `o name` / `g name`: the rest of the line after the keyword.
    let t = line.trim_start();
    t.get(1..).unwrap_or("").trim().to_string()
}

/// Parses a face corner `v`, `v/vt`, `v//vn` or `v/vt/vn` and returns the 0-based position index,
/// resolving negative (relative) indices against `n_pos` vertices read so far.
fn corner_index(tok: &str, n_pos: usize) -> Result<usize, String> {
    let v = tok.split('/').next().unwrap_or("");
    let x: i64 = v
        .parse()
        .map_err(|_| format!("face corner {tok:?} is not an index"))?;
    if x == 0 {
        return Err("face index 0 (OBJ indices start at 1)".into());
    }
    if x < 0 {
        let k = n_pos as i64 + x;
        if k < 0 {
            return Err(format!(
                "relative face index {x} reaches before the first vertex"
            ));
        }
        Ok(k as usize)
    } else {
        Ok((x - 1) as usize)
    }
}

fn scan(bytes: &[u8]) -> Scan {
    let mut s = Scan {
        models: Vec::new(),
        empty: Vec::new(),
        bad_coord: None,
        bad_line: None,
    };
    // Faces seen since the last model was emitted (as `tobj` counts: `f` and `l` statements).
    let mut pending_faces = 0usize;
    let mut current = ScanGroup {
        line: None,
        name: String::new(),
    };
    // Whether the current group statement has been followed by a face.
    let mut current_has_faces = false;
    let mut n_pos = 0usize;
    // Positive face indices are resolved at the end of their model by `tobj`; remember the
    // first too-large one and judge it against the final vertex count.
    let mut big_index: Option<(usize, usize)> = None;
    let note = |bad: &mut Option<(usize, String)>, line: usize, msg: String| {
        if bad.is_none() {
            *bad = Some((line, msg));
        }
    };
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let lineno = i + 1;
        let Ok(line) = std::str::from_utf8(raw) else {
            note(&mut s.bad_line, lineno, "line is not valid UTF-8".into());
            continue;
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let toks: Vec<&str> = words.collect();
                let vals: Vec<Option<f64>> = toks.iter().map(|t| t.parse::<f64>().ok()).collect();
                let ok = matches!(toks.len(), 3 | 4 | 6) && vals.iter().all(|v| v.is_some());
                if !ok {
                    note(
                        &mut s.bad_line,
                        lineno,
                        format!(
                            "vertex line needs 3 numbers (plus w or r g b), got {:?}",
                            toks
                        ),
                    );
                } else {
                    let w = if toks.len() == 4 {
                        vals[3].unwrap_or(1.0)
                    } else {
                        1.0
                    };
                    if w == 0.0 {
                        note(&mut s.bad_line, lineno, "vertex w is 0".into());
                    }
                    if s.bad_coord.is_none() {
                        for (k, axis) in ["x", "y", "z"].iter().enumerate() {
                            let c = vals[k].unwrap_or(f64::NAN) / w;
                            if let Err(e) = check_coord(c, axis) {
                                s.bad_coord = Some((lineno, e));
                                break;
                            }
                        }
                    }
                }
                n_pos += 1;
            }
            Some("f" | "l") => {
                for tok in words {
                    match corner_index(tok, n_pos) {
                        Ok(k) if k >= n_pos && big_index.is_none() => {
                            big_index = Some((lineno, k));
                        }
                        Ok(_) => {}
                        Err(m) => note(&mut s.bad_line, lineno, m),
                    }
                }
                pending_faces += 1;
                current_has_faces = true;
            }
            Some("o" | "g") => {
                if pending_faces > 0 {
                    s.models.push(std::mem::replace(
                        &mut current,
                        ScanGroup {
                            line: None,
                            name: String::new(),
                        },
                    ));
                    pending_faces = 0;
                } else if current.line.is_some() && !current_has_faces {
                    // `tobj` renames the pending model: this group disappears.
                    s.empty.push(std::mem::replace(
                        &mut current,
                        ScanGroup {
                            line: None,
                            name: String::new(),
                        },
                    ));
                }
                current = ScanGroup {
                    line: Some(lineno),
                    name: group_name(line),
                };
                current_has_faces = false;
            }
            _ => {}
        }
    }
    s.models.push(current);
    if let Some((line, k)) = big_index {
        if k >= n_pos {
            note(
                &mut s.bad_line,
                line,
                format!(
                    "face index {} is beyond the {} vertices of the file",
                    k + 1,
                    n_pos
                ),
            );
        }
    }
    // Keep the earliest of the problems the scan noted.
    s
}

/// Reads an OBJ file. See the module header.
pub fn read_obj(path: &Path, bytes: &[u8], _opts: &ReadOptions) -> Result<FileRead, LoadError> {
    let err = |location, kind| LoadError::new(path, location, kind);
    let sc = scan(bytes);
    if let Some((line, kind)) = sc.bad_coord.clone() {
        // A parse error earlier in the file takes precedence only if tobj agrees it is one.
        if !matches!(&sc.bad_line, Some((l, _)) if *l < line) || parse_tobj(bytes).is_ok() {
            return Err(err(Location::Line { line, column: None }, kind));
        }
    }
    let models = match parse_tobj(bytes) {
        Ok(m) => m,
        Err(tobj_msg) => {
            return Err(match &sc.bad_line {
                Some((line, msg)) => err(
                    Location::Line {
                        line: *line,
                        column: None,
                    },
                    LoadErrorKind::MalformedObj(format!("{msg} ({tobj_msg})")),
                ),
                None => err(Location::File, LoadErrorKind::MalformedObj(tobj_msg)),
            });
        }
    };
    // The scan mirrors tobj's model splitting; if it ever disagrees, fall back to tobj's names
    // and the file as location rather than mislabel objects.
    let aligned = sc.models.len() == models.len();
    let mut out = FileRead::default();
    // Input feature numbers: the emitted groups (objects and skips) in line order, faces before
    // any group statement first; assigned once all are known (see the end).
    let mut obj_lines: Vec<usize> = Vec::new();
    let mut skip_lines: Vec<usize> = Vec::new();
    for g in &sc.empty {
        skip_lines.push(g.line.unwrap_or(0));
        out.skipped.push(Skipped {
            feature: 0,
            outline: Vec::new(),
            location: g
                .line
                .map_or(Location::File, |line| Location::Line { line, column: None }),
            name: if g.name.is_empty() {
                format!("group at line {}", g.line.unwrap_or(0))
            } else {
                g.name.clone()
            },
            reason: SkipReason::EmptyGeometry,
        });
    }
    let mut any_faces = false;
    for (k, model) in models.into_iter().enumerate() {
        let group_line = if aligned { sc.models[k].line } else { None };
        let (location, mut name) = if aligned {
            let g = &sc.models[k];
            (
                g.line
                    .map_or(Location::File, |line| Location::Line { line, column: None }),
                g.name.clone(),
            )
        } else {
            (Location::File, model.name.clone())
        };
        if name.is_empty() {
            name = format!("object {}", k + 1);
        }
        let m = &model.mesh;
        let mesh = match build_mesh(m) {
            Ok(mesh) => mesh,
            Err(msg) => return Err(err(location, LoadErrorKind::MalformedObj(msg))),
        };
        if mesh.faces.is_empty() {
            // The trailing model tobj always emits is empty when the file ends in a group
            // without faces, or has no faces at all.
            if aligned && sc.models[k].line.is_none() {
                continue;
            }
            skip_lines.push(group_line.unwrap_or(0));
            out.skipped.push(Skipped {
                location,
                name,
                reason: SkipReason::EmptyGeometry,
                feature: 0,
                outline: Vec::new(),
            });
            continue;
        }
        any_faces = true;
        obj_lines.push(if aligned { group_line.unwrap_or(0) } else { k });
        out.objects.push(RawObject {
            name,
            location,
            feature: 0,
            shape: Shape::Mesh(mesh),
        });
    }
    if !any_faces {
        return Err(err(
            Location::File,
            LoadErrorKind::MalformedObj("no faces".into()),
        ));
    }
    // Number the groups by line (when the scan and tobj disagree, objects by tobj's order and
    // skips after them).
    if !aligned {
        skip_lines = vec![usize::MAX; skip_lines.len()];
    }
    let mut all: Vec<usize> = obj_lines.iter().chain(&skip_lines).copied().collect();
    all.sort_unstable();
    let rank = |l: &usize, taken: &mut Vec<bool>| -> u32 {
        // The first untaken position of this line (lines are distinct unless not aligned).
        let start = all.partition_point(|x| x < l);
        let p = (start..all.len()).find(|&p| !taken[p]).unwrap_or(start);
        if let Some(t) = taken.get_mut(p) {
            *t = true;
        }
        p as u32
    };
    let mut taken = vec![false; all.len()];
    for (o, l) in out.objects.iter_mut().zip(&obj_lines) {
        o.feature = rank(l, &mut taken);
    }
    for (s, l) in out.skipped.iter_mut().zip(&skip_lines) {
        s.feature = rank(l, &mut taken);
    }
    out.items = all.len();
    // Objects and skips are each in file order; keep skips sorted by line for reports.
    out.skipped.sort_by_key(|s| match s.location {
        Location::Line { line, .. } => line,
        _ => usize::MAX,
    });
    Ok(out)
}

fn parse_tobj(bytes: &[u8]) -> Result<Vec<tobj::Model>, String> {
    let opts = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let run = || {
        let mut cur = Cursor::new(bytes);
        tobj::load_obj_buf(&mut cur, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
    };
    match std::panic::catch_unwind(run) {
        Ok(Ok((models, _materials))) => Ok(models),
        Ok(Err(e)) => Err(e.to_string()),
        Err(_) => Err("the OBJ parser failed on this input".into()),
    }
}

/// Rebuilds polygon faces from tobj's flat index list and face arities.
fn build_mesh(m: &tobj::Mesh) -> Result<Mesh, String> {
    let n = m.positions.len() / 3;
    let vertices: Vec<DVec3> = (0..n)
        .map(|i| {
            DVec3::new(
                m.positions[3 * i],
                m.positions[3 * i + 1],
                m.positions[3 * i + 2],
            )
        })
        .collect();
    let mut faces = Vec::new();
    let mut at = 0usize;
    let mut push = |len: usize, at: &mut usize| -> Result<(), String> {
        let end = at.checked_add(len).filter(|&e| e <= m.indices.len());
        let Some(end) = end else {
            return Err("face list shorter than its arities".into());
        };
        let ring: Vec<u32> = m.indices[*at..end].to_vec();
        if ring.iter().any(|&i| i as usize >= n) {
            return Err("face index out of range".into());
        }
        *at = end;
        if len >= 3 {
            faces.push(Face { rings: vec![ring] });
        }
        Ok(())
    };
    if m.face_arities.is_empty() {
        if m.indices.len() % 3 != 0 {
            return Err("triangle list length is not a multiple of 3".into());
        }
        while at < m.indices.len() {
            push(3, &mut at)?;
        }
    } else {
        for &a in &m.face_arities {
            push(a as usize, &mut at)?;
        }
    }
    Ok(Mesh { vertices, faces })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(s: &str) -> Result<FileRead, LoadError> {
        read_obj(Path::new("t.obj"), s.as_bytes(), &ReadOptions::default())
    }

    #[test]
    fn groups_become_objects_with_lines() {
        let src = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\no a\nf 1 2 3 4\ng\nf 1 2 3\no empty\no c\nf 2 3 4\n";
        let r = read(src).unwrap();
        assert_eq!(r.objects.len(), 3);
        assert_eq!(r.objects[0].name, "a");
        assert_eq!(
            r.objects[0].location,
            Location::Line {
                line: 5,
                column: None
            }
        );
        assert_eq!(r.objects[1].name, "object 2");
        assert_eq!(r.objects[2].name, "c");
        assert_eq!(
            r.objects[2].location,
            Location::Line {
                line: 10,
                column: None
            }
        );
        let Shape::Mesh(m) = &r.objects[0].shape else {
            panic!()
        };
        assert_eq!(m.faces.len(), 1);
        assert_eq!(m.faces[0].rings[0].len(), 4);
        let Shape::Mesh(m) = &r.objects[2].shape else {
            panic!()
        };
        assert_eq!(m.vertices.len(), 3);
        assert_eq!(r.skipped.len(), 1);
        assert_eq!(r.skipped[0].name, "empty");
        assert_eq!(r.skipped[0].reason, SkipReason::EmptyGeometry);
    }

    #[test]
    fn errors_carry_lines() {
        let e = read("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert_eq!(
            e.location,
            Location::Line {
                line: 2,
                column: None
            }
        );
        assert!(matches!(e.kind, LoadErrorKind::NonFinite(_)));
        let e = read("v 0 0 0\nv 1 0 2e9\nv 0 1 0\nf 1 2 3\n").unwrap_err();
        assert!(matches!(e.kind, LoadErrorKind::OutOfRange { .. }));
        let e = read("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n").unwrap_err();
        assert_eq!(
            e.location,
            Location::Line {
                line: 5,
                column: None
            }
        );
        assert!(matches!(e.kind, LoadErrorKind::MalformedObj(_)));
        let e = read("v 0 0 0\nv 1 x 0\n").unwrap_err();
        assert_eq!(
            e.location,
            Location::Line {
                line: 2,
                column: None
            }
        );
        let e = read("v 0 0 0\n# nothing\n").unwrap_err();
        assert_eq!(e.kind, LoadErrorKind::MalformedObj("no faces".into()));
        for junk in [
            "\u{0}\u{1}\u{2}",
            "f",
            "f 0 0 0",
            "f -5 -6 -7",
            "o\no\no",
            "v 1 2 3 0\nf 1 1 1",
        ] {
            let _ = read(junk);
        }
        assert!(read_obj(
            Path::new("t"),
            &[0xff, 0xfe, b'\n', b'v'],
            &ReadOptions::default()
        )
        .is_err());
    }
}
