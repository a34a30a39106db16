//! # innersphere
//!
//! Collision detection, proximity and penetration volume between highly complex rigid
//! 3D models at haptic rates (1 kHz and more), built on **Inner Sphere Trees** (IST).
//!
//! Build a tree per model once, share the trees, make a [`Pair`] per pair of bodies and ask
//! it every frame, with the world pose of each body:
//!
//! ```
//! use innersphere::{shapes, BuildOptions, Pair, Pose, SphereTree};
//!
//! // Two generated molars whose cusps meet at the identity pose (a mesh file: Mesh::load).
//! let (upper, lower) = shapes::tooth_pair(3);
//! let opts = BuildOptions::default();
//! let mut pair = Pair::new(SphereTree::build(&upper, &opts)?, SphereTree::build(&lower, &opts)?);
//! let apart = Pose::from_translation([0.0, 0.0, -3.0].into());
//! assert!(pair.distance(&Pose::IDENTITY, &apart).distance > 0.0);
//! let bite = pair.penetration(&Pose::IDENTITY, &Pose::IDENTITY);
//! assert!(bite.volume > 0.0 && pair.contact(&Pose::IDENTITY, &Pose::IDENTITY).in_contact());
//! # Ok::<(), innersphere::Error>(())
//! ```
//!
//! Queries allocate nothing and take no lock from the first frame; a [`Pair`] is `Send` and
//! its trees ([`SharedTree`]) are shared read-only between pairs and threads. The module
//! [`query`] lists every query kind; `docs/ARCHITECTURE.md` maps the source.
//!
//! The pipeline, one module per stage:
//!
//! ```text
//! mesh/       load STL/OBJ/PLY/OFF (+ .gz), weld, defect report, triangle BVH, winding number
//! field/      cubic voxel grid, robust inside test, exact distance to the surface
//! packing/    greedy packing of non-overlapping inner spheres
//! hierarchy/  batch neural gas clustering, minimal enclosing spheres, flat layout
//! tree/       the finished tree (structure of arrays) and its file format
//! build/      the whole build: options, presets, mesh verdicts, the pipeline, mass
//!             properties ([`SphereTree::build`])
//! pose.rs     rigid poses: from quaternions, rotation matrices, 4×4 matrices, text
//! query/      the Pair and one file per query kind, over a kernel and the fronts
//! exact/      exact mesh-mesh distance, intersection and penetration depth (also the
//!             accuracy reference of the sphere queries)
//! input.rs    reading the small text inputs (teeth files, motions) within a size limit
//! output.rs   writing outputs: never onto an input, through a temporary file renamed
//!             into place
//! ```
//!
//! Haptic rendering on these queries is the `innersphere-haptic` crate; dental planning (the
//! arches' frame, the bite, the contact map, the wafer) the `innersphere-dental` crate;
//! motion files and generated motions the `innersphere-motion` crate; replay, benchmarks and
//! the paper's figures the `innersphere-eval` crate.

#![deny(missing_docs)]

pub mod build;
pub mod error;
pub mod exact;
// The build's stages; their options are named in `build`.
mod field;
mod hierarchy;
pub mod input;
pub mod mesh;
pub mod output;
mod packing;
pub mod pose;
pub mod progress;
pub mod query;
pub mod shapes;
pub mod tree;

pub use build::{BuildOptions, BuildReport, Resolution};
pub use error::{Error, Result};
pub use glam;
pub use mesh::Mesh;
pub use pose::{MatrixOrder, Pose, PoseError};
pub use query::{
    BudgetedVolume, Contact, ContactResult, ContactStiffness, Distance, DistanceOptions,
    MeshPenetration, Multipoint, MultipointOptions, Pair, Patch, Penetration, PenetrationOptions,
    RefineOptions, RefinedDistance, SharedTree, Tracking,
};
pub use tree::SphereTree;

// The tests that need the internal stages name the crate as its users do.
#[cfg(test)]
extern crate self as innersphere;
#[cfg(test)]
mod tests;

/// The README's examples, compiled as doctests.
#[cfg(doctest)]
#[doc = include_str!("../../../README.md")]
struct ReadmeDoctests;
