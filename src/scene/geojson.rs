//! PLACEHOLDER
use super::{FileRead, LoadError, ReadOptions};
use std::path::Path;
pub fn read_geojson(_path: &Path, _v: &serde_json::Value, _opts: &ReadOptions) -> Result<FileRead, LoadError> {
    Ok(FileRead::default())
}
