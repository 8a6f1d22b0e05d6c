//! The load's localize stage: the CRS of each file (stated, or detected from longitude/latitude
//! ranges) and of the scene, and the projection of every object of a file in another CRS into
//! the scene's ([`crate::scene::crs`]).
//!
//! Input: the files read, in order, and the reader options. Output: the scene's CRS and each
//! file's, with every object projected (coordinates range-checked again); or the conflict or
//! projection error, naming the file.
//! Invariant: files are visited in input order, so the CRS chosen and every error are the same
//! on every run.

use super::*;

/// The CRS of each file (stated or detected) and of the scene, with every object projected into
/// the scene's CRS: the rules of [`super::crs`].
pub(super) fn resolve_crs(
    paths: &[PathBuf],
    reads: &mut [(FileRead, &'static str)],
    opts: &ReadOptions,
) -> Result<(Option<Crs>, Vec<Option<Crs>>), LoadError> {
    let first = paths.first().cloned().unwrap_or_default();
    // Each file's CRS: stated, else longitude/latitude by detection (footprints only).
    let file_crs: Vec<Option<Crs>> = reads
        .iter()
        .map(|(r, _)| {
            r.crs.clone().or_else(|| {
                let all_footprints = !r.objects.is_empty()
                    && r.objects
                        .iter()
                        .all(|o| matches!(o.shape, Shape::Footprint(_)));
                let pts = r.objects.iter().filter_map(|o| match &o.shape {
                    Shape::Footprint(fp) => Some(fp.polygons.iter().flatten().flatten().copied()),
                    Shape::Mesh(_) => None,
                });
                (all_footprints && crs::looks_geographic(pts))
                    .then(|| Crs::wgs84(CrsSource::Detected))
            })
        })
        .collect();
    let requested = match &opts.crs {
        None => None,
        Some(text) => {
            let c = Crs::parse(text);
            let ok = c
                .epsg
                .is_some_and(|e| crs::epsg_is_geographic(e) == Some(false));
            if !ok {
                return Err(LoadError::new(
                    &first,
                    Location::File,
                    LoadErrorKind::Projection {
                        what: format!("the input to {text}"),
                        message: "--crs takes a projected (metric) CRS known by its EPSG code, e.g. EPSG:32631".into(),
                    },
                ));
            }
            Some(Crs {
                source: CrsSource::Requested,
                ..c
            })
        }
    };
    let projected = file_crs
        .iter()
        .enumerate()
        .find_map(|(i, c)| c.as_ref().filter(|c| !c.geographic).map(|c| (i, c.clone())));
    let geographic = file_crs
        .iter()
        .enumerate()
        .find_map(|(i, c)| c.as_ref().filter(|c| c.geographic).map(|c| (i, c.clone())));
    // The scene's CRS, and where it came from (a file index; None: requested or UTM).
    let (mut target, target_file) = match (requested, projected, &geographic) {
        (Some(r), _, _) => (r, None),
        (None, Some((i, c)), _) => (c, Some(i)),
        (None, None, Some(_)) => {
            // The UTM zone of the centre of the geographic input.
            let mut b = Aabb3::EMPTY;
            for (fi, (r, _)) in reads.iter().enumerate() {
                if file_crs[fi].as_ref().is_some_and(|c| c.geographic) {
                    for o in &r.objects {
                        b = b.union(shape_bbox(&o.shape));
                    }
                }
            }
            let (lon, lat) = if b.is_empty() {
                (0.0, 0.0)
            } else {
                (0.5 * (b.min.x + b.max.x), 0.5 * (b.min.y + b.max.y))
            };
            let mut c = Crs::from_epsg(crs::utm_epsg(lon, lat), CrsSource::Projected);
            c.geographic = false;
            (c, None)
        }
        (None, None, None) => return Ok((None, file_crs)),
    };
    let target_name = |t: &Crs| match target_file {
        Some(i) => (paths[i].clone(), t.name.clone()),
        None if t.source == CrsSource::Requested => ("--crs".into(), t.name.clone()),
        None => (
            paths[geographic.as_ref().map(|g| g.0).unwrap_or(0)].clone(),
            format!(
                "{} (projected to {})",
                geographic
                    .as_ref()
                    .map(|g| g.1.name.clone())
                    .unwrap_or_default(),
                t.name
            ),
        ),
    };
    for (fi, (read, _)) in reads.iter_mut().enumerate() {
        let Some(c) = &file_crs[fi] else {
            if target_file.is_none() && target.source != CrsSource::Requested {
                let (a_file, a_crs) = target_name(&target);
                return Err(LoadError::new(
                    &paths[fi],
                    Location::File,
                    LoadErrorKind::MixedCrs(Box::new(CrsConflict {
                        a_file,
                        a_crs,
                        b_file: paths[fi].clone(),
                        b_crs: "no CRS stated".into(),
                        why: "a file that states no CRS cannot be placed beside longitude/latitude input; give both in one CRS, or state it (--crs for the scene)".into(),
                    })),
                ));
            }
            continue;
        };
        if c.same_as(&target) {
            continue;
        }
        let p = match (c.epsg, target.epsg) {
            (Some(a), Some(b)) => Projector::new(a, b),
            _ => Err("a CRS without an EPSG code cannot be projected".to_string()),
        };
        let p = p.map_err(|why| {
            let (a_file, a_crs) = target_name(&target);
            LoadError::new(
                &paths[fi],
                Location::File,
                LoadErrorKind::MixedCrs(Box::new(CrsConflict {
                    a_file,
                    a_crs,
                    b_file: paths[fi].clone(),
                    b_crs: c.name.clone(),
                    why: format!("vocc cannot project one into the other ({why})"),
                })),
            )
        })?;
        project_read(&paths[fi], read, &p, &c.name, &target.name)?;
        if !target.projected_from.contains(&c.name) {
            target.projected_from.push(c.name.clone());
        }
    }
    Ok((Some(target), file_crs))
}

/// Projects every object (and skipped outline) of one file; coordinates are range-checked again.
fn project_read(
    path: &Path,
    read: &mut FileRead,
    p: &Projector,
    from: &str,
    to: &str,
) -> Result<(), LoadError> {
    let fail = |at: &Location, what: String| {
        LoadError::new(
            path,
            at.clone(),
            LoadErrorKind::Projection {
                what: format!("{from} to {to}"),
                message: what,
            },
        )
    };
    let one = |q: DVec2, at: &Location| -> Result<DVec2, LoadError> {
        let r = p
            .project(q)
            .ok_or_else(|| fail(at, format!("point ({}, {}) has no image", q.x, q.y)))?;
        check_coord(r.x, "x")
            .and_then(|_| check_coord(r.y, "y"))
            .map_err(|k| LoadError::new(path, at.clone(), k))?;
        Ok(r)
    };
    read.objects
        .par_iter_mut()
        .try_for_each(|o| -> Result<(), LoadError> {
            let at = o.location.clone();
            match &mut o.shape {
                Shape::Footprint(fp) => {
                    for q in fp.polygons.iter_mut().flatten().flatten() {
                        *q = one(*q, &at)?;
                    }
                }
                Shape::Mesh(m) => {
                    for v in &mut m.vertices {
                        let r = one(DVec2::new(v.x, v.y), &at)?;
                        *v = DVec3::new(r.x, r.y, v.z);
                    }
                }
            }
            Ok(())
        })?;
    for s in &mut read.skipped {
        for q in s.outline.iter_mut().flatten() {
            *q = p.project(*q).unwrap_or(*q);
        }
    }
    Ok(())
}
