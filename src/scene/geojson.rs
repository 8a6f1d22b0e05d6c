//! GeoJSON footprint reader.
//!
//! Input: GeoJSON features, one at a time as [`super::json`] streams them out of a
//! `FeatureCollection` (or a single `Feature`), with Polygon or MultiPolygon footprints, 2D or 3D
//! positions (z is ignored), and the attribute names to read.
//! Output: one footprint object per feature, in feature order, in world coordinates:
//! `base` = the base attribute (0 when none is named), `top` = base + height, where height is the
//! height attribute, else the storey attribute times the storey height, else the default height
//! (`ReadOptions::default_height`), each read by [`super::attr`] (units and decimal commas where
//! the meaning is clear). A value that is not a number is passed over and noted, or fails the
//! load (`ReadOptions::on_bad_height`). Features with no height are skipped with their reason
//! and outline, as are features whose geometry is null or has no area; heights from a fallback
//! are reported (`FileRead::fallbacks`).
//! Invariants: every coordinate is range-checked where it enters; errors name the feature index;
//! an unknown geometry type is an error, not a skip; memory holds one feature's JSON at a time.

use std::path::Path;

use glam::DVec2;
use serde::de::{self, Deserializer, SeqAccess, Visitor};
use serde::Deserialize;
use serde_json::{Map, Value};

use super::error::{check_coord, short, LoadError, LoadErrorKind, Location};
use super::{
    attr, FileRead, Footprint, HeightFallback, HeightSource, OnBadHeight, RawObject, ReadOptions,
    Ring, Shape, SkipReason, Skipped, MAX_BASE_M, MAX_HEIGHT_M,
};

/// One feature as parsed; coordinates are kept as a tree of numbers until the geometry type says
/// how deep it must be.
#[derive(Debug, Default, Deserialize)]
pub struct FeatureIn {
    #[serde(default)]
    pub id: Option<Value>,
    #[serde(default)]
    pub properties: Option<Value>,
    #[serde(default)]
    pub geometry: Option<GeometryIn>,
}

#[derive(Debug, Deserialize)]
pub struct GeometryIn {
    #[serde(rename = "type")]
    pub kind: Option<String>,
    #[serde(default)]
    pub coordinates: Option<Tree>,
}

/// Nested arrays of numbers, as GeoJSON coordinates are.
#[derive(Debug, Clone, PartialEq)]
pub enum Tree {
    Num(f64),
    List(Vec<Tree>),
}

impl<'de> Deserialize<'de> for Tree {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Tree, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = Tree;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a number or an array of coordinates")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<Tree, E> {
                Ok(Tree::Num(v))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<Tree, E> {
                Ok(Tree::Num(v as f64))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<Tree, E> {
                Ok(Tree::Num(v as f64))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Tree, A::Error> {
                let mut v = Vec::with_capacity(seq.size_hint().unwrap_or(4).min(4096));
                while let Some(t) = seq.next_element()? {
                    v.push(t);
                }
                Ok(Tree::List(v))
            }
        }
        d.deserialize_any(V)
    }
}

/// The attributes a footprint's heights are read from (ARCHITECTURE.md, "Footprint heights").
#[derive(Clone, Debug, Default)]
pub struct HeightKeys {
    /// The height of the top above the base, metres: the first of these with a value.
    pub height: Vec<String>,
    /// The base elevation, metres (absent: 0).
    pub base: Option<String>,
    /// Storeys, the fallback for a missing height.
    pub levels: Option<String>,
    /// The bottom's height above the base, metres (OpenStreetMap `min_height`).
    pub min_height: Option<String>,
    /// The storey the bottom starts at, the fallback for `min_height`.
    pub min_levels: Option<String>,
    /// The roof's height, taken off a `height` (not off storeys, which count no roof): the solid
    /// part of a building stands to its eaves.
    pub roof_height: Option<String>,
    /// The roof's storeys, the fallback for `roof_height`.
    pub roof_levels: Option<String>,
}

impl HeightKeys {
    /// The keys the reader flags name (`--height-attr`, `--base-attr`, `--levels-attr`, and the
    /// `min_height` and `building:min_level` defaults).
    pub fn from_options(opts: &ReadOptions) -> HeightKeys {
        HeightKeys {
            height: opts.height_attr.iter().cloned().collect(),
            base: opts.base_attr.clone(),
            levels: opts.levels_attr.clone(),
            min_height: opts.min_height_attr.clone(),
            min_levels: opts.min_levels_attr.clone(),
            roof_height: None,
            roof_levels: None,
        }
    }
}

/// Turns features into footprint objects, one at a time: GeoJSON features, and the footprints
/// of the other footprint readers (GeoPackage, FlatGeobuf, Shapefile, OpenStreetMap), whose
/// attributes are handed over as a JSON map so every format reads heights by the same rules.
pub struct GeoJsonReader<'a> {
    path: &'a Path,
    opts: &'a ReadOptions,
    format: &'static str,
    keys: HeightKeys,
    out: FileRead,
    features: usize,
    saw_height: bool,
    first_attributes: Option<Vec<String>>,
    /// Where the item being read sits.
    at: Location,
}

/// The footprint readers' name for it.
pub type FootprintReader<'a> = GeoJsonReader<'a>;

impl<'a> GeoJsonReader<'a> {
    /// Fails at once when no height source is named: GeoJSON footprints carry no height.
    pub fn new(path: &'a Path, opts: &'a ReadOptions) -> Result<Self, LoadError> {
        Self::for_format(path, opts, "GeoJSON")
    }

    /// [`Self::new`] for another footprint format, with the reader flags' keys.
    pub fn for_format(
        path: &'a Path,
        opts: &'a ReadOptions,
        format: &'static str,
    ) -> Result<Self, LoadError> {
        if opts.height_attr.is_none() && opts.levels_attr.is_none() && opts.default_height.is_none()
        {
            return Err(LoadError::new(
                path,
                Location::File,
                LoadErrorKind::NoHeightOption,
            ));
        }
        Ok(Self::with_keys(
            path,
            opts,
            format,
            HeightKeys::from_options(opts),
        ))
    }

    /// A reader with its own keys (OpenStreetMap's tags); never fails.
    pub fn with_keys(
        path: &'a Path,
        opts: &'a ReadOptions,
        format: &'static str,
        keys: HeightKeys,
    ) -> Self {
        GeoJsonReader {
            path,
            opts,
            format,
            keys,
            out: FileRead::default(),
            features: 0,
            saw_height: false,
            first_attributes: None,
            at: Location::File,
        }
    }

    fn err(&self, _i: usize, kind: LoadErrorKind) -> LoadError {
        LoadError::new(self.path, self.at.clone(), kind)
    }

    fn malformed(&self, i: usize, message: String) -> LoadError {
        self.err(
            i,
            LoadErrorKind::Malformed {
                format: self.format,
                message,
            },
        )
    }

    /// [`Self::skip`], keeping the feature's rings for pictures.
    fn skip_with(&mut self, i: usize, name: &str, reason: SkipReason, outline: Vec<Ring>) {
        self.out.skipped.push(Skipped {
            location: self.at.clone(),
            name: name.to_string(),
            reason,
            feature: i as u32,
            outline,
        });
    }

    /// Skips a feature for its geometry. Its height attribute still counts as seen, so a file
    /// whose features all lack usable geometry reports that (no objects), not a missing height.
    fn skip_geometry(&mut self, i: usize, name: &str, props: &Map<String, Value>, why: SkipReason) {
        let numeric = |v: Option<&Value>| matches!(attr::metres(v), attr::Value::Number(_));
        let attrs = self.keys.height.iter().chain(self.keys.levels.iter());
        self.saw_height |= attrs.into_iter().any(|a| numeric(props.get(a)));
        self.skip_with(i, name, why, Vec::new());
    }

    /// Index the next feature will get.
    pub fn next_index(&self) -> usize {
        self.features
    }

    /// The CRS the file states.
    pub fn set_crs(&mut self, crs: Option<super::Crs>) {
        self.out.crs = crs;
    }

    /// Reads the next feature.
    pub fn feature(&mut self, f: FeatureIn) -> Result<(), LoadError> {
        let i = self.features;
        self.features += 1;
        self.at = Location::Feature(i);
        let empty = Map::new();
        let props = match &f.properties {
            None | Some(Value::Null) => &empty,
            Some(Value::Object(m)) => m,
            Some(_) => return Err(self.malformed(i, "\"properties\" is not an object".into())),
        };
        let name = feature_name(f.id.as_ref(), props).unwrap_or_else(|| format!("feature {i}"));
        let Some(geom) = &f.geometry else {
            self.note_attributes(props);
            self.skip_geometry(i, &name, props, SkipReason::EmptyGeometry);
            return Ok(());
        };
        let Some(kind) = geom.kind.as_deref() else {
            return Err(self.malformed(i, "geometry has no \"type\"".into()));
        };
        let coords = geom.coordinates.as_ref();
        let polygons: Vec<Vec<Ring>> = match kind {
            "Polygon" => vec![rings(coords, "Polygon").map_err(|m| self.malformed(i, m))?],
            "MultiPolygon" => match coords {
                Some(Tree::List(parts)) => parts
                    .iter()
                    .map(|p| rings(Some(p), "MultiPolygon part"))
                    .collect::<Result<_, _>>()
                    .map_err(|m| self.malformed(i, m))?,
                _ => {
                    return Err(
                        self.malformed(i, "MultiPolygon coordinates are not an array".into())
                    )
                }
            },
            "Point" | "MultiPoint" | "LineString" | "MultiLineString" | "GeometryCollection" => {
                self.note_attributes(props);
                self.skip_geometry(i, &name, props, SkipReason::NotAreal(kind.to_string()));
                return Ok(());
            }
            other => {
                return Err(self.err(i, LoadErrorKind::UnknownGeometryType(other.to_string())));
            }
        };
        self.footprint_at(i, name, props, polygons)
    }

    fn note_attributes(&mut self, props: &Map<String, Value>) {
        if self.first_attributes.is_none() && !props.is_empty() {
            self.first_attributes = Some(props.keys().take(30).cloned().collect());
        }
    }

    /// Reads one item of another footprint format: its place in the file, its id (else a name
    /// from its attributes, else "feature N"), its attributes, and its polygons (ring 0 the
    /// exterior), or `Err(reason)` when its geometry gives none (empty, not areal).
    pub fn item(
        &mut self,
        at: Location,
        id: Option<String>,
        props: &Map<String, Value>,
        polygons: Result<Vec<Vec<Ring>>, SkipReason>,
    ) -> Result<(), LoadError> {
        let i = self.features;
        self.features += 1;
        self.at = at;
        let id = id.map(Value::String);
        let name = feature_name(id.as_ref(), props).unwrap_or_else(|| format!("feature {i}"));
        match polygons {
            Ok(p) => self.footprint_at(i, name, props, p),
            Err(why) => {
                self.note_attributes(props);
                self.skip_geometry(i, &name, props, why);
                Ok(())
            }
        }
    }

    /// Skips one item whose geometry is not all in the file (an OpenStreetMap way with nodes
    /// outside the extract).
    pub fn skip_item(&mut self, at: Location, name: String, reason: SkipReason) {
        let i = self.features;
        self.features += 1;
        self.at = at;
        self.skip_with(i, &name, reason, Vec::new());
    }

    /// The footprint of item `i`: coordinates checked, heights read by the keys.
    fn footprint_at(
        &mut self,
        i: usize,
        name: String,
        props: &Map<String, Value>,
        polygons: Vec<Vec<Ring>>,
    ) -> Result<(), LoadError> {
        self.note_attributes(props);
        for p in polygons.iter().flatten().flatten() {
            check_coord(p.x, "x")
                .and_then(|_| check_coord(p.y, "y"))
                .map_err(|k| self.err(i, k))?;
        }
        let polygons: Vec<Vec<Ring>> = polygons
            .into_iter()
            .map(|p| p.into_iter().filter(|r| !r.is_empty()).collect::<Vec<_>>())
            .filter(|p| !p.is_empty())
            .collect();
        if polygons.is_empty() {
            self.skip_geometry(i, &name, props, SkipReason::EmptyGeometry);
            return Ok(());
        }

        // A value that is not a number, or a number beyond what a building has: an error, or
        // passed over (noted) under the skip rule.
        let on_bad = self.opts.on_bad_height;
        let at = self.at.clone();
        let path = self.path;
        let bad = |kind: LoadErrorKind| LoadError::new(path, at.clone(), kind);
        let mut passed: Vec<(String, String)> = Vec::new();
        // `limit`: the largest magnitude accepted, and what the value is, for messages.
        let take = |passed: &mut Vec<(String, String)>,
                    attr: &str,
                    v: attr::Value,
                    limit: Option<(f64, &'static str)>|
         -> Result<Option<f64>, LoadError> {
            match v {
                attr::Value::Number(x) => match limit {
                    Some((lim, what)) if x.abs() > lim => match on_bad {
                        OnBadHeight::Error => Err(bad(LoadErrorKind::AbsurdHeight {
                            attr: attr.to_string(),
                            what,
                            value: x,
                            limit: lim,
                        })),
                        OnBadHeight::Skip => {
                            passed.push((
                                attr.to_string(),
                                format!("{} m, beyond the {lim} m a {what} may have", short(x)),
                            ));
                            Ok(None)
                        }
                    },
                    _ => Ok(Some(x)),
                },
                attr::Value::Missing => Ok(None),
                attr::Value::Bad(value) => match on_bad {
                    OnBadHeight::Error => Err(bad(LoadErrorKind::BadAttribute {
                        attr: attr.to_string(),
                        value,
                    })),
                    OnBadHeight::Skip => {
                        passed.push((attr.to_string(), format!("{value}, not a number")));
                        Ok(None)
                    }
                },
            }
        };
        let storey = self.opts.storey_height;
        let height_limit = Some((MAX_HEIGHT_M, "height"));
        let storey_limit = Some((MAX_HEIGHT_M / 3.0, "storey count"));
        // Height: the height attribute, less the roof, else storeys times the storey height,
        // else the default height.
        let mut source = None;
        let mut height = None;
        let mut from_attr = false;
        for a in &self.keys.height {
            if height.is_none() {
                height = take(&mut passed, a, attr::metres(props.get(a)), height_limit)?;
                from_attr = height.is_some();
            }
        }
        if height.is_none() {
            if let Some(a) = &self.keys.levels {
                height = take(&mut passed, a, attr::count(props.get(a)), storey_limit)?
                    .map(|n| n * storey);
                source = height.map(|_| HeightSource::Storeys);
            }
        }
        if height.is_none() {
            height = self.opts.default_height;
            source = height.map(|_| HeightSource::Default);
        }
        if let (Some(h), true) = (height, from_attr) {
            // The solid part stands to the eaves: take the roof off a height (never below 0).
            let mut roof = None;
            if let Some(a) = &self.keys.roof_height {
                roof = take(&mut passed, a, attr::metres(props.get(a)), height_limit)?;
            }
            if roof.is_none() {
                if let Some(a) = &self.keys.roof_levels {
                    roof = take(&mut passed, a, attr::count(props.get(a)), storey_limit)?
                        .map(|n| n * storey);
                }
            }
            if let Some(r) = roof.filter(|r| *r > 0.0 && *r < h) {
                height = Some(h - r);
            }
        }
        let passed_height = passed.clone();
        let base = match &self.keys.base {
            None => Some(0.0),
            Some(a) => take(
                &mut passed,
                a,
                attr::metres(props.get(a)),
                Some((MAX_BASE_M, "base")),
            )?,
        };
        // The bottom above the base: min_height, else the storey it starts at, else 0.
        let mut bottom = Some(0.0);
        let mut bad_bottom = None;
        if let Some(a) = &self.keys.min_height {
            let before = passed.len();
            match take(&mut passed, a, attr::metres(props.get(a)), height_limit)? {
                Some(m) => bottom = Some(m),
                None if passed.len() > before => bad_bottom = Some(a.clone()),
                None => {
                    if let Some(l) = &self.keys.min_levels {
                        let before = passed.len();
                        match take(&mut passed, l, attr::count(props.get(l)), storey_limit)? {
                            Some(n) => bottom = Some(n * storey),
                            None if passed.len() > before => bad_bottom = Some(l.clone()),
                            None => {}
                        }
                    }
                }
            }
        }
        if bad_bottom.is_some() {
            bottom = None;
        }
        let (Some(height), Some(base), Some(bottom)) = (height, base, bottom) else {
            let reason = if height.is_none() {
                match passed_height.into_iter().next() {
                    Some((attr, value)) => SkipReason::BadHeight { attr, value },
                    None => SkipReason::NoHeight,
                }
            } else {
                let a = if base.is_none() {
                    self.keys.base.clone()
                } else {
                    bad_bottom
                };
                match a.and_then(|a| passed.into_iter().find(|(x, _)| *x == a)) {
                    Some((attr, value)) => SkipReason::BadBase { attr, value },
                    None => SkipReason::NoBase,
                }
            };
            self.saw_height |= height.is_some();
            let outline = polygons.into_iter().flatten().collect();
            self.skip_with(i, &name, reason, outline);
            return Ok(());
        };
        if let Some(source) = source {
            self.out.fallbacks.push((
                self.out.objects.len(),
                HeightFallback {
                    source,
                    passed: passed_height,
                },
            ));
        }
        check_coord(height, "height").map_err(|k| self.err(i, k))?;
        check_coord(base, "base").map_err(|k| self.err(i, k))?;
        self.saw_height = true;
        self.out.objects.push(RawObject {
            name,
            location: self.at.clone(),
            feature: i as u32,
            shape: Shape::Footprint(Footprint {
                polygons,
                base: base + bottom,
                top: base + height,
            }),
        });
        Ok(())
    }

    /// Ends the file. Fails when features exist but none had a usable height: the attribute
    /// name is almost certainly wrong.
    pub fn finish(mut self) -> Result<FileRead, LoadError> {
        self.out.items = self.features;
        let for_height = self.out.skipped.iter().any(|s| {
            matches!(
                s.reason,
                SkipReason::NoHeight | SkipReason::BadHeight { .. }
            )
        });
        if !self.saw_height && self.features > 0 && for_height {
            let attr = self
                .keys
                .height
                .first()
                .cloned()
                .or_else(|| self.keys.levels.clone())
                .unwrap_or_default();
            let names = self.first_attributes.unwrap_or_default();
            // The first bad value, when the heights are there but none is usable.
            let bad = self.out.skipped.iter().find_map(|s| match &s.reason {
                SkipReason::BadHeight { attr, value } => {
                    Some(format!(" ({}: {attr:?} is {value})", s.location))
                }
                _ => None,
            });
            return Err(LoadError::new(
                self.path,
                Location::File,
                LoadErrorKind::MissingAttribute {
                    attr,
                    hint: format!(
                        "no feature has a usable height{}; the first feature's attributes are: {}; --default-height M reads them at M metres",
                        bad.unwrap_or_default(),
                        names.join(", ")
                    ),
                },
            ));
        }
        Ok(self.out)
    }
}

/// The feature's id or name: the feature `id`, else a property `id`, `ID`, `name` or `NAME`.
fn feature_name(id: Option<&Value>, props: &Map<String, Value>) -> Option<String> {
    let as_name = |v: &Value| match v {
        Value::String(s) => Some(s.clone()),
        Value::Number(n) => Some(n.to_string()),
        _ => None,
    };
    id.and_then(as_name).or_else(|| {
        ["id", "ID", "name", "NAME"]
            .iter()
            .find_map(|k| props.get(*k).and_then(as_name))
    })
}

/// A Polygon's coordinates: an array of rings, each an array of positions.
fn rings(coords: Option<&Tree>, what: &str) -> Result<Vec<Ring>, String> {
    let Some(Tree::List(rs)) = coords else {
        return Err(format!("{what} coordinates are not an array of rings"));
    };
    rs.iter()
        .enumerate()
        .map(|(ri, r)| {
            let Tree::List(ps) = r else {
                return Err(format!("{what} ring {ri} is not an array of positions"));
            };
            ps.iter()
                .map(|p| {
                    position(p).ok_or_else(|| {
                        format!("{what} ring {ri} has a position that is not 2 to 4 numbers")
                    })
                })
                .collect()
        })
        .collect()
}

fn position(p: &Tree) -> Option<DVec2> {
    let Tree::List(a) = p else { return None };
    match a.as_slice() {
        [Tree::Num(x), Tree::Num(y), rest @ ..]
            if rest.len() <= 2 && rest.iter().all(|t| matches!(t, Tree::Num(_))) =>
        {
            Some(DVec2::new(*x, *y))
        }
        _ => None,
    }
}
