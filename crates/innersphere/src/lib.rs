//! # innersphere
//!
//! Collision detection, proximity and penetration volume between highly complex rigid
//! 3D models at haptic rates (1 kHz and more), built on **Inner Sphere Trees** (IST).
//!
//! The pipeline, one module per stage:
//!
//! ```text
//! mesh/       load STL/OBJ/PLY/OFF (+ .gz), weld, defect report, triangle BVH, winding number
//! field/      cubic voxel grid, robust inside test, exact distance to the surface
//! packing/    greedy packing of non-overlapping inner spheres
//! hierarchy/  batch neural gas clustering, minimal enclosing spheres, flat layout
//! tree/       the finished tree (structure of arrays) and its file format
//! pose.rs     rigid poses: from quaternions, rotation matrices, 4×4 matrices, text
//! query/      per-pair state and one file per query kind
//! exact/      exact mesh-mesh distance, intersection and penetration depth (also the
//!             accuracy reference of the sphere queries)
//! ```
//!
//! [`build::build_tree`] runs the whole build; [`tree::SphereTree`] is what queries use.
//! Motion files, replay, benchmarks and the paper's figures are the `innersphere-eval` crate.

#![deny(missing_docs)]

pub mod build;
pub mod error;
pub mod exact;
pub mod field;
pub mod hierarchy;
pub mod mesh;
pub mod packing;
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
    BudgetedVolume, Contact, ContactResult, Distance, DistanceOptions, Multipoint,
    MultipointOptions, Pair, Patch, Penetration, PenetrationOptions, SharedTree, Tracking,
};
pub use tree::SphereTree;
