//! PLACEHOLDER: filled by the mesh helper.
use super::{Mesh, NoBlocker};
use glam::DVec2;

/// A convex prism proven to lie inside a closed mesh.
#[derive(Clone, Debug, PartialEq)]
pub struct SolidPiece {
    pub polygon: Vec<DVec2>,
    pub base: f64,
    pub top: f64,
}

pub fn solid_pieces(_mesh: &Mesh) -> Result<Vec<SolidPiece>, NoBlocker> {
    Err(NoBlocker::NoProvableInterior)
}
