//! PLACEHOLDER: filled by the mesh helper.
use super::{FileRead, LoadError, ReadOptions};
use std::path::Path;
pub fn read_cityjson(
    _path: &Path,
    _v: &serde_json::Value,
    _opts: &ReadOptions,
) -> Result<FileRead, LoadError> {
    Ok(FileRead::default())
}
