//! Exact unsigned distance from voxel centres to the mesh surface.
//!
//! Every inside voxel gets the exact minimum over all triangles of the point–triangle
//! distance, found with the [`TriangleBvh`]. Voxels are processed row by row (x fastest),
//! each query's bound seeded with the distances to the closest triangles of the previous
//! voxel in the row and of the neighbour in the previous row, which prunes most of the tree.
//! The pruning is exactly conservative, so the result is bit-identical to brute force and
//! independent of threads and seeds.

use super::inside::classify;
use super::{DistanceField, VoxelGrid};
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;

/// Rows of voxels handled sequentially by one parallel task (fixed, so that seeding does not
/// depend on scheduling).
const ROWS_PER_TASK: usize = 16;
/// Points handled sequentially by one parallel task in [`distance_of_points`].
const POINTS_PER_TASK: usize = 256;

/// Classifies the cells of `grid` ([`classify`]) and gives every inside voxel its exact
/// unsigned distance to the surface.
pub fn compute(
    mesh: &Mesh,
    grid: VoxelGrid,
    progress: &dyn Progress,
) -> crate::error::Result<DistanceField> {
    let (inside, method) = classify(mesh, &grid, progress)?;
    progress.start("triangle tree", 1);
    let bvh = TriangleBvh::new(mesh);
    progress.finish();
    let dist = distances_of_cells(&bvh, &grid, &inside, progress);
    Ok(DistanceField {
        grid,
        inside,
        dist,
        method,
    })
}

/// Exact distance from the centres of `cells` (linear indices, ascending) to the triangles of
/// `bvh`, in the same order (`f64::INFINITY` for an empty tree).
pub fn distances_of_cells(
    bvh: &TriangleBvh,
    grid: &VoxelGrid,
    cells: &[u32],
    progress: &dyn Progress,
) -> Vec<f64> {
    // Start of each run of cells in the same row (same j, k).
    let nx = grid.dims[0].max(1);
    let mut row_starts: Vec<usize> = Vec::new();
    let mut prev_row = u32::MAX;
    for (n, &c) in cells.iter().enumerate() {
        let row = c / nx;
        if row != prev_row {
            row_starts.push(n);
            prev_row = row;
        }
    }
    row_starts.push(cells.len());
    let tasks = (row_starts.len() - 1).div_ceil(ROWS_PER_TASK);
    progress.start("distance field", cells.len() as u64);
    let parts: Vec<Vec<f64>> = (0..tasks)
        .into_par_iter()
        .map(|t| {
            let r0 = t * ROWS_PER_TASK;
            let r1 = (r0 + ROWS_PER_TASK).min(row_starts.len() - 1);
            let span = &cells[row_starts[r0]..row_starts[r1]];
            // Seeds: the previous cell of the row, and the last cell of this task in the same
            // column (the cell of the previous row, when that row was inside too).
            let mut column_seed = vec![u32::MAX; nx as usize];
            let mut hint = u32::MAX;
            let out = span
                .iter()
                .map(|&c| {
                    let p = grid.center_of(c as usize);
                    let i = (c % nx) as usize;
                    let mut bound = bvh.slot_distance_sq(p, hint);
                    if column_seed[i] != hint {
                        bound = bound.min(bvh.slot_distance_sq(p, column_seed[i]));
                    }
                    match bvh.closest_point(p, bound) {
                        Some(cl) => {
                            hint = cl.slot;
                            column_seed[i] = cl.slot;
                            cl.dist_sq.sqrt()
                        }
                        None => f64::INFINITY,
                    }
                })
                .collect();
            progress.advance(span.len() as u64);
            out
        })
        .collect();
    progress.finish();
    parts.concat()
}

/// Exact distance from each point to the triangles of `bvh` (`f64::INFINITY` when empty);
/// fastest when consecutive points are close to each other.
pub fn distance_of_points(bvh: &TriangleBvh, pts: &[DVec3]) -> Vec<f64> {
    pts.par_chunks(POINTS_PER_TASK)
        .flat_map_iter(|chunk| seeded_distances(bvh, chunk.iter().copied()))
        .collect()
}

/// Distances of a sequence of points, each query seeded with the previous answer.
fn seeded_distances(bvh: &TriangleBvh, pts: impl Iterator<Item = DVec3>) -> Vec<f64> {
    let mut hint = u32::MAX;
    pts.map(|p| match bvh.closest_point_from(p, hint) {
        Some(c) => {
            hint = c.slot;
            c.dist_sq.sqrt()
        }
        None => f64::INFINITY,
    })
    .collect()
}
