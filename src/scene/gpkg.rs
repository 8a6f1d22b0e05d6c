//! GeoPackage footprint reader (through rusqlite's bundled SQLite).
//!
//! Input: the bytes of a `.gpkg` file: a SQLite database whose `gpkg_geometry_columns` names
//! the feature tables and their geometry column. Output: one footprint per row of every feature
//! table (tables in name order, rows in rowid order), with the other columns as attributes read
//! by the footprint reader's rules ([`super::geojson::GeoJsonReader`]: `--height-attr`,
//! `--base-attr`, `--levels-attr`, ...); the CRS from `gpkg_spatial_ref_sys` (its organization
//! code when it is EPSG's, else its WKT).
//! Geometry: the GeoPackage binary header (magic `GP`, flags, SRS id, envelope) then WKB
//! ([`super::wkb`]). An empty geometry is skipped as such.
//! Invariants: the database is opened read-only from memory (nothing is written, nothing else is
//! opened); every SQLite error becomes a [`LoadError`] naming the table and row; never panics.

use std::path::Path;

use rusqlite::types::ValueRef;
use rusqlite::{Connection, MAIN_DB};
use serde_json::{Map, Number, Value};

use super::geojson::FootprintReader;
use super::{
    wkb, Crs, CrsSource, FileRead, LoadError, LoadErrorKind, Location, ReadOptions, SkipReason,
};

const FORMAT: &str = "GeoPackage";

/// Reads a GeoPackage. See the module header.
pub fn read_gpkg(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<FileRead, LoadError> {
    let malformed = |at: Location, message: String| {
        LoadError::new(
            path,
            at,
            LoadErrorKind::Malformed {
                format: FORMAT,
                message,
            },
        )
    };
    if !bytes.starts_with(b"SQLite format 3\0") {
        return Err(malformed(
            Location::File,
            "not a SQLite database (a GeoPackage is one: its first bytes are \"SQLite format 3\")"
                .into(),
        ));
    }
    if bytes.len() > i32::MAX as usize {
        return Err(malformed(
            Location::File,
            format!(
                "{} bytes: larger than vocc reads in memory (2 GiB)",
                bytes.len()
            ),
        ));
    }
    let mut reader = FootprintReader::for_format(path, opts, FORMAT)?;
    let sql = |at: Location| move |e: rusqlite::Error| malformed(at.clone(), e.to_string());
    let mut conn = Connection::open_in_memory().map_err(sql(Location::File))?;
    conn.deserialize_read_exact(MAIN_DB, bytes, bytes.len(), true)
        .map_err(sql(Location::File))?;

    // Only stored tables are read: a view (or a virtual table) could compute rows without end,
    // while a table's rows are bounded by the file.
    let is_table = |name: &str| -> Result<bool, LoadError> {
        conn.query_row(
            "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name = ?1 AND sql NOT LIKE 'CREATE VIRTUAL%'",
            [name],
            |r| r.get::<_, i64>(0),
        )
        .map(|n| n > 0)
        .map_err(sql(Location::File))
    };
    if !is_table("gpkg_geometry_columns")? {
        return Err(malformed(
            Location::File,
            "no gpkg_geometry_columns table, so no feature table".into(),
        ));
    }
    let tables: Vec<(String, String, i64)> = {
        let mut st = conn
            .prepare(
                "SELECT table_name, column_name, srs_id FROM gpkg_geometry_columns ORDER BY table_name",
            )
            .map_err(|e| {
                malformed(
                    Location::File,
                    format!("no gpkg_geometry_columns table, so no feature table ({e})"),
                )
            })?;
        let rows = st
            .query_map([], |r| Ok((r.get(0)?, r.get(1)?, r.get(2)?)))
            .map_err(sql(Location::File))?;
        rows.collect::<Result<_, _>>()
            .map_err(sql(Location::File))?
    };
    let mut crs: Option<Crs> = None;
    for (table, column, srs) in &tables {
        let at_table = Location::Element(format!("table {table:?}"));
        if !is_table(table)? {
            return Err(malformed(
                at_table,
                "not a stored table (a view or virtual table is not read)".into(),
            ));
        }
        if crs.is_none() {
            crs = srs_crs(&conn, *srs).map_err(sql(at_table.clone()))?;
        }
        let quoted = table.replace('"', "\"\"");
        // The column names as values (rusqlite's `column_names` panics on a name that is not
        // UTF-8; found by fuzzing, `tests/fixtures/broken/gpkg_fuzz_*`), in the table's order.
        let names: Vec<String> = {
            let mut st = conn
                .prepare("SELECT name FROM pragma_table_info(?1) ORDER BY cid")
                .map_err(sql(at_table.clone()))?;
            let mut rows = st.query([table]).map_err(sql(at_table.clone()))?;
            let mut names = Vec::new();
            while let Some(r) = rows.next().map_err(sql(at_table.clone()))? {
                names.push(match r.get_ref(0).map_err(sql(at_table.clone()))? {
                    ValueRef::Text(t) | ValueRef::Blob(t) => {
                        String::from_utf8_lossy(t).into_owned()
                    }
                    _ => String::new(),
                });
            }
            names
        };
        let list: Vec<String> = names
            .iter()
            .map(|n| format!("\"{}\"", n.replace('"', "\"\"")))
            .collect();
        if list.is_empty() {
            return Err(malformed(at_table, "the table has no columns".into()));
        }
        let mut st = conn
            .prepare(&format!("SELECT {} FROM \"{quoted}\"", list.join(", ")))
            .map_err(sql(at_table.clone()))?;
        let Some(gcol) = names.iter().position(|n| n.eq_ignore_ascii_case(column)) else {
            return Err(malformed(
                at_table,
                format!("geometry column {column:?} is not a column of the table"),
            ));
        };
        let mut rows = st.query([]).map_err(sql(at_table.clone()))?;
        let mut n = 0usize;
        while let Some(row) = rows.next().map_err(sql(at_table.clone()))? {
            let mut props = Map::new();
            let mut fid = None;
            let mut geom: Option<Vec<u8>> = None;
            for (k, name) in names.iter().enumerate() {
                let v = row.get_ref(k).map_err(sql(at_table.clone()))?;
                if k == gcol {
                    if let ValueRef::Blob(b) = v {
                        geom = Some(b.to_vec());
                    }
                    continue;
                }
                let json = match v {
                    ValueRef::Null => Value::Null,
                    ValueRef::Integer(i) => {
                        if fid.is_none() && name.eq_ignore_ascii_case("fid") {
                            fid = Some(i);
                        }
                        Value::Number(i.into())
                    }
                    ValueRef::Real(f) => Number::from_f64(f).map_or(Value::Null, Value::Number),
                    ValueRef::Text(t) => Value::String(String::from_utf8_lossy(t).into_owned()),
                    ValueRef::Blob(_) => continue,
                };
                props.insert(name.clone(), json);
            }
            let at = Location::Element(match fid {
                Some(f) => format!("table {table:?}, fid {f}"),
                None => format!("table {table:?}, row {n}"),
            });
            n += 1;
            let polygons = match &geom {
                None => Err(SkipReason::EmptyGeometry),
                Some(b) => gpkg_geometry(b).map_err(|m| malformed(at.clone(), m))?,
            };
            reader.item(at, None, &props, polygons)?;
        }
    }
    if tables.is_empty() {
        return Err(malformed(
            Location::File,
            "gpkg_geometry_columns names no feature table".into(),
        ));
    }
    reader.set_crs(crs);
    reader.finish()
}

/// The CRS of an SRS id: EPSG's code when the organization is EPSG, else the WKT definition;
/// `None` for the undefined systems (0 and -1) and for a definition of "undefined".
fn srs_crs(conn: &Connection, srs: i64) -> Result<Option<Crs>, rusqlite::Error> {
    let mut st = conn.prepare(
        "SELECT organization, organization_coordsys_id, definition FROM gpkg_spatial_ref_sys WHERE srs_id = ?1",
    )?;
    let mut rows = st.query([srs])?;
    let Some(row) = rows.next()? else {
        return Ok(None);
    };
    let org: Option<String> = row.get(0).ok();
    let code: Option<i64> = row.get(1).ok();
    let def: Option<String> = row.get(2).ok();
    if let (Some(org), Some(code)) = (&org, code) {
        if org.eq_ignore_ascii_case("EPSG") && code > 0 {
            if let Ok(c) = u32::try_from(code) {
                return Ok(Some(Crs::from_epsg(c, CrsSource::File)));
            }
        }
    }
    Ok(def
        .filter(|d| !d.trim().is_empty() && !d.trim().eq_ignore_ascii_case("undefined"))
        .map(|d| Crs::parse(&d)))
}

/// A GeoPackage geometry blob: its header, then WKB.
fn gpkg_geometry(b: &[u8]) -> Result<Result<Vec<Vec<super::Ring>>, SkipReason>, String> {
    if b.len() < 8 || &b[..2] != b"GP" {
        return Err("geometry blob does not start with the GeoPackage magic \"GP\"".into());
    }
    let flags = b[3];
    if flags & 0x20 != 0 {
        return Err("extended GeoPackage geometry types are not read".into());
    }
    let envelope = match (flags >> 1) & 0x07 {
        0 => 0,
        1 => 32,
        2 | 3 => 48,
        4 => 64,
        e => return Err(format!("envelope indicator {e} is invalid (0 to 4)")),
    };
    if flags & 0x10 != 0 {
        return Ok(Err(SkipReason::EmptyGeometry));
    }
    let start = 8 + envelope;
    let body = b
        .get(start..)
        .ok_or_else(|| format!("geometry blob of {} bytes ends inside its header", b.len()))?;
    wkb::footprint(body)
}
