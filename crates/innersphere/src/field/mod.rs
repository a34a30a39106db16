//! The voxel distance field: a cubic grid over the mesh ([`grid`]), the robust inside test
//! ([`inside`]) and the exact unsigned distance of every inside voxel to the surface
//! ([`distance`]); in the thick parts of a body only a coarse lattice of voxels ([`thick`]).

pub(crate) mod distance;
pub(crate) mod grid;
pub(crate) mod inside;
pub(crate) mod thick;

pub(crate) use grid::VoxelGrid;

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
pub(crate) struct DistanceField {
    /// The grid the voxels live on.
    pub grid: VoxelGrid,
    /// Linear grid indices (see [`VoxelGrid::index`]) of the inside voxels, ascending.
    pub inside: Vec<u32>,
    /// Exact unsigned distance from each inside voxel centre to the surface (same order).
    pub dist: Vec<f64>,
    /// How inside/outside was decided.
    pub method: InsideMethod,
}

impl DistanceField {
    /// The field of an analytic solid given by its signed distance function `sdf` (positive
    /// inside, the exact distance to the surface there): every cell centre with `sdf > 0` is an
    /// inside voxel. For tests and benchmarks that need packings without a mesh.
    pub(crate) fn from_signed_distance(grid: VoxelGrid, sdf: impl Fn(glam::DVec3) -> f64) -> Self {
        let mut inside = Vec::new();
        let mut dist = Vec::new();
        for idx in 0..grid.len() {
            let d = sdf(grid.center_of(idx));
            if d > 0.0 {
                inside.push(idx as u32);
                dist.push(d);
            }
        }
        DistanceField {
            grid,
            inside,
            dist,
            method: InsideMethod::ClosedExact,
        }
    }
}
