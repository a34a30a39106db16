//! The whole build, mesh → tree: validate and orient the mesh, voxel distance field, sphere
//! packing, BNG hierarchy, flat layout.
//!
//! [`SphereTree::build`] is the short way (tree only); [`SphereTree::build_with_progress`]
//! also reports progress and returns the [`BuildReport`] (warnings included);
//! [`build_tree`] is the same function under its older name (what `ist build` runs).
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
mod verdict;

pub use crate::field::thick::ThickParts;
pub use cache::{BuildCache, CacheOutcome};
pub use options::{validate_options, BuildOptions, Resolution};
pub use pipeline::{build_tree, BuildReport, StageSeconds, MIN_EXTENT};
pub use preset::{
    Preset, CALIBRATED_MIN_RADIUS_PER_VOXEL, CALIBRATED_REFINE_STEPS, FAST_CELLS, FINE_CELLS,
    JAW_PRESET_SIZE_MM, JAW_THICK_LATTICE_MM, JAW_THICK_MARGIN_MM, JAW_THICK_MIN_RADIUS_MM,
    JAW_THICK_RADIUS_MM,
};
pub use verdict::MeshVerdict;

#[cfg(doc)]
use crate::tree::SphereTree;
