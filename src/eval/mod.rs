//! Evaluation: the ground-truth visible set, metrics, reports and pictures.
//!
//! Input: a loaded [`crate::scene::Scene`] and, for the metrics, a store baked from it.
//! Output: [`raycast::Caster`], a ray caster over footprint prisms and mesh faces;
//! [`truth::visible_set`], the objects first hit by rays from sampled eye points of a cell;
//! [`metrics`] (PVS against VS per cell), [`report`] (`vocc eval`, `docs/RESULTS.md`),
//! [`plot`] and [`picture`] (SVG); [`bound`], sampled estimates of what any occluders from the
//! blockers outside a cell could cull in 2D, and of what 10 ideal VOs could (what limits
//! tightness).
//! Invariant: [`raycast`] and [`truth`] read no blockers, virtual occluders, verifier or culler;
//! the only code they share with the pipeline is the scene model and its readers. The metrics
//! build the PVS with the runtime culler, from the store's bytes, as an engine does.

pub mod bound;
pub mod ground;
pub mod metrics;
pub mod picture;
pub mod plot;
pub mod raycast;
pub mod report;
pub mod truth;
