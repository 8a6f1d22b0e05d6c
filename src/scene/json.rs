//! JSON scene documents in one streaming pass.
//!
//! Input: the bytes of a `.json`/`.geojson`/`.cityjson` file. Output: a [`FileRead`] and the
//! format name. The top-level object is walked key by key: the members of a GeoJSON
//! `FeatureCollection`'s `features` array are parsed and handed to [`GeoJsonReader`] one at a time,
//! so a file of 10^6 footprints never sits in memory as a JSON tree; every other member is kept as
//! a JSON value (small for GeoJSON; for CityJSON, the document itself), and a CityJSON document
//! goes to [`cityjson::read_cityjson`] whole.
//! Invariants: key order does not matter; malformed JSON fails with its line and column; a
//! problem found in a feature fails with the feature index; nothing panics.

use std::cell::RefCell;
use std::fmt;
use std::path::Path;

use serde::de::{DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
use serde_json::{Map, Value};

use super::cityjson;
use super::error::{LoadError, LoadErrorKind, Location};
use super::geojson::{FeatureIn, GeoJsonReader};
use super::{Crs, FileRead, ReadOptions};

/// Reads a JSON scene document: GeoJSON or CityJSON.
pub fn read_json(
    path: &Path,
    bytes: &[u8],
    opts: &ReadOptions,
) -> Result<(FileRead, &'static str), LoadError> {
    let state = State {
        path,
        opts,
        geojson: RefCell::new(None),
        failure: RefCell::new(None),
        feature: RefCell::new(None),
    };
    let mut de = serde_json::Deserializer::from_slice(bytes);
    let parsed = Top(&state).deserialize(&mut de).and_then(|m| {
        de.end()?;
        Ok(m)
    });
    if let Some(e) = state.failure.borrow_mut().take() {
        return Err(e);
    }
    let mut rest = parsed.map_err(|e| json_error(path, e, *state.feature.borrow()))?;
    let kind = rest.get("type").and_then(Value::as_str).map(str::to_string);
    let crs = geojson_crs(rest.get("crs"));
    match kind.as_deref() {
        Some("FeatureCollection") => {
            let mut reader = match state.geojson.into_inner() {
                Some(r) => r,
                None => {
                    return Err(LoadError::new(
                        path,
                        Location::File,
                        LoadErrorKind::Malformed {
                            format: "GeoJSON",
                            message: "FeatureCollection has no \"features\" array".into(),
                        },
                    ))
                }
            };
            reader.set_crs(crs);
            Ok((reader.finish()?, "GeoJSON"))
        }
        Some("Feature") => {
            let mut reader = GeoJsonReader::new(path, opts)?;
            let f = FeatureIn {
                id: rest.remove("id"),
                properties: rest.remove("properties"),
                geometry: match rest.remove("geometry") {
                    None | Some(Value::Null) => None,
                    Some(g) => Some(serde_json::from_value(g).map_err(|e| {
                        LoadError::new(
                            path,
                            Location::Feature(0),
                            LoadErrorKind::Malformed {
                                format: "GeoJSON",
                                message: e.to_string(),
                            },
                        )
                    })?),
                },
            };
            reader.feature(f)?;
            reader.set_crs(crs);
            Ok((reader.finish()?, "GeoJSON"))
        }
        Some("CityJSON") => Ok((
            cityjson::read_cityjson(path, &Value::Object(rest), opts)?,
            "CityJSON",
        )),
        other => Err(LoadError::new(
            path,
            Location::File,
            LoadErrorKind::Malformed {
                format: "JSON",
                message: format!(
                    "top-level \"type\" is {}, expected \"FeatureCollection\", \"Feature\" or \"CityJSON\"",
                    other.map(|s| format!("{s:?}")).unwrap_or_else(|| "missing".into())
                ),
            },
        )),
    }
}

/// Whether `bytes` are a CityJSONSeq (CityJSON Text Sequence): a first line that is a whole
/// CityJSON object (the header), and more lines after it.
pub fn is_cityjson_seq(bytes: &[u8]) -> bool {
    let mut lines = bytes
        .split(|&b| b == b'\n')
        .filter(|l| !l.iter().all(u8::is_ascii_whitespace));
    let Some(first) = lines.next() else {
        return false;
    };
    // Cheap tests first: a one-line GeoJSON of 10^6 features is never parsed twice.
    let has = |l: &[u8], w: &[u8]| l.windows(w.len()).any(|x| x == w);
    let Some(second) = lines.next() else {
        return false;
    };
    has(second, b"\"CityJSONFeature\"")
        && serde_json::from_slice::<Value>(first)
            .ok()
            .is_some_and(|v| v.get("type").and_then(Value::as_str) == Some("CityJSON"))
}

/// Reads a CityJSONSeq (`.city.jsonl`): line 1 a CityJSON header (version, `transform`,
/// `metadata`; its `vertices` and `CityObjects` empty), then one `CityJSONFeature` per line (its
/// `CityObjects` and its own `vertices`, indexed from 0, under the header's `transform`). Each
/// feature is read as a CityJSON document of its own by [`cityjson::read_cityjson`]; items are
/// numbered across the file in order. Errors name the line, then the place within it.
pub fn read_cityjson_seq(
    path: &Path,
    bytes: &[u8],
    opts: &ReadOptions,
) -> Result<FileRead, LoadError> {
    let malformed = |line: usize, message: String| {
        LoadError::new(
            path,
            Location::Line { line, column: None },
            LoadErrorKind::Malformed {
                format: "CityJSONSeq",
                message,
            },
        )
    };
    let mut out = FileRead::default();
    let mut header: Option<Map<String, Value>> = None;
    for (k, line) in bytes.split(|&b| b == b'\n').enumerate() {
        let ln = k + 1;
        if line.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        let v: Value = serde_json::from_slice(line).map_err(|e| {
            LoadError::new(
                path,
                Location::Line {
                    line: ln,
                    column: Some(e.column()),
                },
                LoadErrorKind::MalformedJson(e.to_string()),
            )
        })?;
        let Value::Object(mut m) = v else {
            return Err(malformed(ln, "a line is not a JSON object".into()));
        };
        let ty = m
            .get("type")
            .and_then(Value::as_str)
            .unwrap_or("")
            .to_string();
        let Some(h) = &header else {
            if ty != "CityJSON" {
                return Err(malformed(
                    ln,
                    format!("the first line must be the CityJSON header (\"type\": \"CityJSON\"), not {ty:?}"),
                ));
            }
            out.crs = cityjson::reference_system(&Value::Object(m.clone()));
            header = Some(m);
            continue;
        };
        if ty != "CityJSONFeature" {
            return Err(malformed(
                ln,
                format!("a line after the header must be a \"CityJSONFeature\", not {ty:?}"),
            ));
        }
        let mut doc = h.clone();
        doc.insert(
            "CityObjects".into(),
            m.remove("CityObjects").unwrap_or(Value::Null),
        );
        doc.insert(
            "vertices".into(),
            m.remove("vertices").unwrap_or(Value::Null),
        );
        let r =
            cityjson::read_cityjson(path, &Value::Object(doc), opts).map_err(|e| LoadError {
                location: Location::InLine {
                    line: ln,
                    inner: Box::new(e.location),
                },
                ..e
            })?;
        let offset = out.items as u32;
        out.objects.extend(r.objects.into_iter().map(|mut o| {
            o.feature += offset;
            o
        }));
        out.skipped.extend(r.skipped.into_iter().map(|mut s| {
            s.feature += offset;
            s
        }));
        for (t, n) in r.other_types {
            *out.other_types.entry(t).or_default() += n;
        }
        out.lods.extend(r.lods);
        out.items += r.items;
    }
    if header.is_none() {
        return Err(malformed(1, "no CityJSON header line".into()));
    }
    Ok(out)
}

/// The CRS of a GeoJSON `crs` member (the 2008 specification's): `{"type": "name",
/// "properties": {"name": URN}}`, or `{"type": "EPSG", "properties": {"code": N}}`. RFC 7946
/// dropped the member (its coordinates are WGS84 longitude/latitude); `None` when there is none.
fn geojson_crs(v: Option<&Value>) -> Option<Crs> {
    let props = v?.get("properties")?;
    if let Some(name) = props.get("name").and_then(Value::as_str) {
        return Some(Crs::parse(name));
    }
    let code = props.get("code")?;
    let code = code
        .as_u64()
        .or_else(|| code.as_str().and_then(|s| s.trim().parse().ok()))?;
    u32::try_from(code)
        .ok()
        .map(|c| Crs::from_epsg(c, crate::scene::CrsSource::File))
}

/// Maps a serde_json error to a located load error: syntax errors are malformed JSON; data errors
/// (a member of the wrong type) are malformed GeoJSON, naming the feature being read.
fn json_error(path: &Path, e: serde_json::Error, feature: Option<usize>) -> LoadError {
    use serde_json::error::Category;
    let location = if e.line() > 0 {
        Location::Line {
            line: e.line(),
            column: Some(e.column()),
        }
    } else {
        Location::File
    };
    let kind = match (e.classify(), feature) {
        (Category::Data, Some(i)) => LoadErrorKind::Malformed {
            format: "GeoJSON",
            message: format!("feature {i}: {e}"),
        },
        _ => LoadErrorKind::MalformedJson(e.to_string()),
    };
    LoadError::new(path, location, kind)
}

struct State<'a> {
    path: &'a Path,
    opts: &'a ReadOptions,
    geojson: RefCell<Option<GeoJsonReader<'a>>>,
    /// The first typed failure from inside the stream; it wins over the serde error used to stop.
    failure: RefCell<Option<LoadError>>,
    /// The feature being parsed, for errors.
    feature: RefCell<Option<usize>>,
}

/// The top-level object: streams `features`, keeps the rest.
struct Top<'s, 'a>(&'s State<'a>);

impl<'de> DeserializeSeed<'de> for Top<'_, '_> {
    type Value = Map<String, Value>;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<Self::Value, D::Error> {
        d.deserialize_map(self)
    }
}

impl<'de> Visitor<'de> for Top<'_, '_> {
    type Value = Map<String, Value>;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a GeoJSON or CityJSON object")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        let mut rest = Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if key == "features" {
                if self.0.geojson.borrow().is_some() {
                    map.next_value::<IgnoredAny>()?;
                    continue;
                }
                match GeoJsonReader::new(self.0.path, self.0.opts) {
                    Ok(r) => *self.0.geojson.borrow_mut() = Some(r),
                    Err(e) => {
                        *self.0.failure.borrow_mut() = Some(e);
                        return Err(serde::de::Error::custom("stopped"));
                    }
                }
                map.next_value_seed(Features(self.0))?;
            } else {
                let v: Value = map.next_value()?;
                rest.insert(key, v);
            }
        }
        Ok(rest)
    }
}

/// The `features` array, one feature at a time.
struct Features<'s, 'a>(&'s State<'a>);

impl<'de> DeserializeSeed<'de> for Features<'_, '_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> Result<(), D::Error> {
        d.deserialize_seq(self)
    }
}

impl<'de> Visitor<'de> for Features<'_, '_> {
    type Value = ();
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("an array of features")
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        loop {
            let next = self.0.geojson.borrow().as_ref().map(|r| r.next_index());
            *self.0.feature.borrow_mut() = next;
            let Some(f) = seq.next_element::<FeatureIn>()? else {
                break;
            };
            let mut g = self.0.geojson.borrow_mut();
            if let Some(reader) = g.as_mut() {
                if let Err(e) = reader.feature(f) {
                    *self.0.failure.borrow_mut() = Some(e);
                    return Err(serde::de::Error::custom("stopped"));
                }
            }
        }
        *self.0.feature.borrow_mut() = None;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str) -> Result<(FileRead, &'static str), LoadError> {
        let opts = ReadOptions {
            height_attr: Some("h".into()),
            ..ReadOptions::default()
        };
        read_json(Path::new("t.geojson"), text.as_bytes(), &opts)
    }

    const SQUARE: &str = r#"{"type":"Polygon","coordinates":[[[0,0],[1,0],[1,1],[0,1],[0,0]]]}"#;

    #[test]
    fn key_order_does_not_matter() {
        let text = format!(
            r#"{{"features":[{{"type":"Feature","properties":{{"h":3}},"geometry":{SQUARE}}}],"type":"FeatureCollection"}}"#
        );
        let (r, fmt) = read(&text).unwrap();
        assert_eq!(fmt, "GeoJSON");
        assert_eq!(r.objects.len(), 1);
    }

    #[test]
    fn single_feature_document() {
        let text =
            format!(r#"{{"type":"Feature","id":"x","properties":{{"h":3}},"geometry":{SQUARE}}}"#);
        let (r, _) = read(&text).unwrap();
        assert_eq!(r.objects[0].name, "x");
    }

    #[test]
    fn features_must_be_an_array() {
        let e = read(r#"{"type":"FeatureCollection","features":{}}"#).unwrap_err();
        assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
    }

    #[test]
    fn trailing_garbage_is_malformed() {
        let e = read(r#"{"type":"FeatureCollection","features":[]} x"#).unwrap_err();
        assert!(matches!(e.kind, LoadErrorKind::MalformedJson(_)), "{e}");
        assert!(matches!(e.location, Location::Line { line: 1, .. }));
    }

    #[test]
    fn a_feature_error_stops_the_stream_with_its_index() {
        let text = format!(
            r#"{{"type":"FeatureCollection","features":[
            {{"type":"Feature","properties":{{"h":3}},"geometry":{SQUARE}}},
            {{"type":"Feature","properties":{{"h":"x"}},"geometry":{SQUARE}}},
            {{"type":"Feature","properties":{{"h":3}},"geometry":{SQUARE}}}]}}"#
        );
        // A height that is not a number is an error under `--on-bad-height error`.
        let opts = ReadOptions {
            height_attr: Some("h".into()),
            on_bad_height: crate::scene::OnBadHeight::Error,
            ..ReadOptions::default()
        };
        let e = read_json(Path::new("t.geojson"), text.as_bytes(), &opts).unwrap_err();
        assert_eq!(e.location, Location::Feature(1));
        // By default it skips that feature and reads on.
        let (r, _) = read(&text).unwrap();
        assert_eq!(r.objects.len(), 2);
        assert_eq!(r.skipped[0].feature, 1);
    }
}
