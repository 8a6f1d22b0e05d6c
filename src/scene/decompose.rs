//! PLACEHOLDER
use super::Ring;
use glam::DVec2;
#[derive(Debug, thiserror::Error)]
#[error("x")]
pub struct DecomposeError;
pub fn convex_pieces(_rings: &[Ring]) -> Result<Vec<Vec<DVec2>>, DecomposeError> { Ok(vec![]) }
