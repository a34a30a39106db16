//! Exact mesh–mesh distance, intersection and penetration depth: the accuracy reference
//! (the role PQP plays in the Inner Sphere Tree paper) and the baseline a user would
//! otherwise pick.
//!
//! Everything is f64 and works in body A's frame: B's nodes and triangles are transformed
//! into it as a traversal reaches them. [`ExactMesh`] holds one mesh's triangle BVH (the
//! shared [`TriangleBvh`]), per-node bounding shapes, the winding-number hierarchy, its
//! connected components and vertex adjacency; [`ExactScratch`] the per-pair memory.
//!
//! * [`distance`] runs in two phases. First, do the surfaces cross? A depth-first traversal
//!   of the node pairs that may touch tests every pair of triangles whose boxes overlap
//!   with exact predicates (`tri_tri::triangles_intersect`) and stops at the first
//!   crossing: distance 0. Otherwise a best-first branch and bound over node pairs, ordered
//!   and pruned by lower bounds that combine the boxes with a slab-and-disc shape per node
//!   (tight for the nearly flat patches near the leaves), finds the minimum of the
//!   triangle–triangle distances (PQP's `TriDist`), filtered per triangle pair by boxes and
//!   planes. The scratch can seed both phases with the last query's pairs (warm start).
//! * [`intersects`]: the first phase alone.
//! * Both count one body lying entirely inside the other (no surface crossing) as
//!   intersecting: for every connected component of one body whose extreme vertices all lie
//!   in the other's bounding box, the generalized winding number of one of its vertices
//!   decides.
//! * [`penetration`] / [`penetration_depth`]: the largest distance to the other surface of a
//!   vertex of one body inside the other (both ways).
//! * [`vertex_gaps`]: the signed distance of every vertex of one body to the other's
//!   surface (negative inside), what a contact map colours.
//! * [`self_intersections`]: the triangle pairs of one mesh that meet away from a shared
//!   corner (a printable solid has none).
//! * `brute_force_distance` / `brute_force_intersects` (tests only): O(n·m) references.
//!
//! The files: `mesh` ([`ExactMesh`]), `scratch` ([`ExactScratch`]), `frame` (B's frame in
//! A's), `overlap` (the traversal of overlapping node pairs), `bnb` (the branch and bound),
//! `containment`, `distance`, `gaps`, `intersects`, `self_intersections`, `penetration`, `overlap_volume` (the
//! meshes' intersection volume and its gradient), `overlap_patches` (its connected pieces),
//! `front` (the node-pair front it carries), `crossings` (edge–triangle crossings), `bound`
//! (node shapes) and `tri_tri` (triangle pairs).
//!
//! No input panics: meshes are validated by [`ExactMesh::new`], degenerate triangles are
//! handled, and a non-finite pose gives a NaN distance, no intersection and depth 0.
//!
//! [`distance`]: fn@distance
//! [`intersects`]: fn@intersects
//! [`penetration`]: fn@penetration

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x < y)` is deliberate: true for NaN too.

mod bnb;
mod bound;
mod containment;
mod crossings;
mod distance;
mod frame;
mod front;
mod gaps;
mod intersects;
pub(crate) mod local;
mod mesh;
mod overlap;
mod overlap_patches;
mod overlap_volume;
mod penetration;
mod scratch;
mod self_intersections;
// Triangle–triangle primitives: the kernels of the exact queries.
pub(crate) mod tri_tri;

#[cfg(test)]
pub(crate) use distance::brute_force_distance;
pub use distance::{distance, ExactDistance};
pub use gaps::vertex_gaps;
#[cfg(test)]
pub(crate) use intersects::brute_force_intersects;
pub use intersects::intersects;
pub use mesh::ExactMesh;
pub use overlap_patches::{AreaMoments, OverlapPatch};
pub use overlap_volume::{intersection_volume, MeshOverlap, NUDGE};
pub use penetration::{penetration, penetration_depth, Body, ExactPenetration};
pub use scratch::{ExactScratch, ExactStats};
pub use self_intersections::{mesh_self_intersections, self_intersections};
#[cfg(test)]
pub(crate) use tri_tri::{
    segment_segment_closest, segment_triangle_intersect, triangle_distance, triangles_intersect,
};

#[cfg(doc)]
use crate::mesh::bvh::TriangleBvh;
