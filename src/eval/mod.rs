//! Evaluation: the ground-truth visible set, independent of the occlusion pipeline.
//!
//! Input: a loaded [`crate::scene::Scene`] (original geometry only).
//! Output: [`raycast::Caster`], a ray caster over footprint prisms and mesh faces, and
//! [`truth::visible_set`], the objects first hit by rays from sampled eye points of a cell.
//! Invariant: nothing here reads blockers, virtual occluders, the verifier or the culler; the
//! only shared code is the scene model and its readers.

pub mod raycast;
pub mod truth;
