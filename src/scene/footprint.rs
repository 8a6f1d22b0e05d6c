//! PLACEHOLDER
use super::{Ring, RingRejection, RingRepair};
pub struct RepairedPolygon {
    pub repairs: Vec<(usize, RingRepair)>,
    pub result: Result<Vec<Ring>, (usize, RingRejection)>,
}
pub fn repair_polygon(rings: &[Ring]) -> RepairedPolygon {
    RepairedPolygon { repairs: vec![], result: Ok(rings.to_vec()) }
}
