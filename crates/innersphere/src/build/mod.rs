//! The whole build, mesh → tree, as named stages (`stages.rs`, timed in [`StageSeconds`]):
//! prepare (validate and orient the mesh, choose the grid), field (voxel distance bounds),
//! packing (the inner spheres), hierarchy (BNG clustering and flat layout), tree (the
//! [`SphereTree`] with its meta), report ([`BuildReport`]).
//!
//! [`SphereTree::build`] is the short way (tree only); [`SphereTree::build_with_progress`]
//! also reports progress and returns the [`BuildReport`] (warnings included; what `ist build`
//! runs); [`build_tree`] is the same function under its older name (what [`BuildCache`] and
//! the tests call). [`pack_signed_distance`] packs an analytic solid without a mesh, and
//! [`tree_of_spheres`] makes the tree of a sphere set that no mesh was packed into.
//!
//! Lengths are in **model units**: the library never assumes a unit. [`BuildOptions`] says
//! how fine the packing is, either as numbers or from a named [`Preset`]
//! ([`BuildOptions::preset`], [`BuildOptions::recommended_for`]), which are functions of the
//! mesh because a fixed voxel size only makes sense for a known unit and scale.

pub mod cache;
mod mass;
mod options;
mod pipeline;
mod preset;
mod stages;
mod verdict;

pub use crate::field::thick::ThickParts;
pub use crate::hierarchy::{HierarchyOptions, HierarchyStats};
pub use crate::packing::{PackingOptions, Sphere};
pub use cache::{BuildCache, CacheOutcome};
pub use options::{validate_options, BuildOptions, Resolution};
pub use pipeline::{
    build_tree, pack_signed_distance, tree_of_spheres, BuildReport, StageSeconds, MIN_EXTENT,
};
pub use preset::Preset;
pub use verdict::MeshVerdict;

#[cfg(doc)]
use crate::tree::SphereTree;
