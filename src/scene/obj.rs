//! PLACEHOLDER: filled by the mesh helper.
use super::{FileRead, LoadError, ReadOptions};
use std::path::Path;
pub fn read_obj(_path: &Path, _bytes: &[u8], _opts: &ReadOptions) -> Result<FileRead, LoadError> {
    Ok(FileRead::default())
}
