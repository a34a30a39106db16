//! The voxel distance field: a cubic grid over the mesh ([`grid`]), the robust inside test
//! ([`inside`]) and the exact unsigned distance of every inside voxel to the surface
//! ([`distance`]).

pub mod distance;
pub mod grid;
pub mod inside;

pub use grid::VoxelGrid;

/// How inside/outside was decided.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum InsideMethod {
    /// The mesh is closed (every edge is used equally often in both directions): exact
    /// signed ray-crossing count along grid columns with exact predicates.
    ClosedExact,
    /// The mesh is open, holed or non-manifold: generalized winding number ≥ 0.5.
    WindingNumber,
}

/// The inside voxels of a mesh and their exact distance to its surface.
#[derive(Debug, Clone)]
pub struct DistanceField {
    /// The grid the voxels live on.
    pub grid: VoxelGrid,
    /// Linear grid indices (see [`VoxelGrid::index`]) of the inside voxels, ascending.
    pub inside: Vec<u32>,
    /// Exact unsigned distance from each inside voxel centre to the surface (same order).
    pub dist: Vec<f64>,
    /// How inside/outside was decided.
    pub method: InsideMethod,
}
