//! Exact unsigned distance from voxel centres to the mesh surface.
//!
//! Every inside voxel gets the exact minimum over all triangles of the point–triangle
//! distance, found with the [`TriangleBvh`]. Voxels are processed row by row (x fastest),
//! each query's bound seeded with the distances to the closest triangles of the previous
//! voxel in the row and of the neighbour in the previous row, which prunes most of the tree.
//! The pruning is exactly conservative, so the result is bit-identical to brute force and
//! independent of threads and seeds.

#[cfg(test)]
use super::inside::classify;
use super::inside::classify_where;
use super::thick::ThickSet;
#[cfg(test)]
use super::DistanceField;
use super::VoxelGrid;
use crate::mesh::bvh::{Near, TriangleBvh};
use crate::mesh::Mesh;
use crate::progress::Progress;
use glam::DVec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering::Relaxed};

#[cfg(test)]
/// Rows of voxels handled sequentially by one parallel task (fixed, so that seeding does not
/// depend on scheduling).
const ROWS_PER_TASK: usize = 16;
/// Points handled sequentially by one parallel task in [`distance_of_points`].
const POINTS_PER_TASK: usize = 256;

#[cfg(test)]
/// Classifies the cells of `grid` ([`classify`]) and gives every inside voxel its exact
/// unsigned distance to the surface.
pub(crate) fn compute(
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

#[cfg(test)]
/// Exact distance from the centres of `cells` (linear indices, ascending) to the triangles of
/// `bvh`, in the same order (`f64::INFINITY` for an empty tree).
pub(crate) fn distances_of_cells(
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

/// The inside voxels of a mesh with an upper bound of each one's distance to the surface and
/// the triangle that gives it: what the packing starts from, making a voxel's distance exact
/// only when it needs it ([`crate::packing::pack_bounded`]).
#[derive(Debug, Clone)]
pub(crate) struct DistanceBounds {
    /// The grid the voxels live on.
    pub grid: VoxelGrid,
    /// Linear grid indices of the inside voxels, ascending.
    pub inside: Vec<u32>,
    /// An upper bound of each inside voxel's distance to the surface: its exact distance to
    /// the triangle in `slot` (same order).
    pub bound: Vec<f64>,
    /// The triangle (BVH slot) of each bound.
    pub slot: Vec<u32>,
    /// How inside/outside was decided.
    pub method: super::InsideMethod,
    /// The coarse voxels of thick parts and their minimum radius ([`super::thick`]), when the
    /// body has such parts and the build was asked to treat them so.
    pub coarse: Option<CoarseVoxels>,
}

/// Which inside voxels are coarse ones (lattice nodes of a thick part, [`ThickSet`]) and the
/// smallest sphere the packing may place at them.
#[derive(Debug, Clone)]
pub(crate) struct CoarseVoxels {
    /// One flag per inside voxel (same order).
    pub flags: Vec<bool>,
    /// No sphere below this radius at a coarse voxel.
    pub min_radius: f64,
}

/// Voxels apart of the lattice whose near triangles give the bounds.
const BOUND_STRIDE: u32 = 3;

/// How near a lattice node's triangle must be to its nearest: within a tenth of its distance.
/// The packing's spheres do not depend on the bounds' tightness, only its time: on the jaw
/// arches (2 threads, 6 interleaved rounds, medians) the distance field took 1.31–1.32 s with
/// the nearest triangles and 0.94–0.96 s with this margin, the packing the same to 0.2 s more
/// (looser bounds start its exact searches wider); 20 % saved no more in the field and cost
/// the packing 0.3–0.5 s, 30 % cost it 1 s; half a voxel more (absolute) cost it 0.2 s.
const NEAR_REL: f64 = 0.1;

#[cfg(test)]
/// Classifies the cells of `grid` ([`classify`]) and gives every inside voxel an upper bound
/// of its distance: the distance to a triangle near the nearest node of a lattice
/// `BOUND_STRIDE` (3) voxels apart (within a tenth of the closest triangle's distance, found
/// with the tree `bvh` of `mesh`). The bound is a real triangle's distance, so at least the
/// exact distance, and often equal to it: a 27th of the queries of [`compute`], and cheaper
/// ones, the rest point–triangle distances. (On the jaw, 2 cores: stride 2 spends 0.3–0.5 s
/// more on the nodes; stride 4 saves 0.1–0.2 s there and loses it to the packing's extra
/// exact queries.)
pub(crate) fn bounds(
    mesh: &Mesh,
    bvh: &TriangleBvh,
    grid: VoxelGrid,
    progress: &dyn Progress,
) -> crate::error::Result<DistanceBounds> {
    bounds_where(mesh, bvh, grid, None, progress)
}

/// [`bounds`] of the voxels a [`ThickSet`] keeps (in its thick parts only its lattice's
/// nodes; all inside voxels without one).
// Kept whole (over 120 lines): its passes (the inside cells, the coarse lattice's nodes and
// their nearest triangles, every voxel's bound from its node) share the lattice's indexing
// closures, which a split would hand from function to function.
pub(crate) fn bounds_where(
    mesh: &Mesh,
    bvh: &TriangleBvh,
    grid: VoxelGrid,
    thick: Option<&ThickSet>,
    progress: &dyn Progress,
) -> crate::error::Result<DistanceBounds> {
    let keep = |i, j, k| thick.map_or(k, |t| t.next_kept(i, j, k));
    let (inside, method) = classify_where(mesh, &grid, thick.map(|_| &keep as _), progress)?;
    let s = BOUND_STRIDE;
    let cd = grid.dims.map(|d| (d + s) / s + 1);
    // The coarse voxels of thick parts take their bounds from a lattice as much coarser (deep
    // voxels, whose nearest triangles are the most costly to find, a node each otherwise);
    // its nodes are numbered after the first lattice's.
    let s2 = thick.map_or(s, |t| s * t.stride());
    let cd2 = grid.dims.map(|d| (d + s2) / s2 + 1);
    let first = cd.iter().map(|&d| d as usize).product::<usize>();
    let second = if thick.is_some() {
        cd2.iter().map(|&d| d as usize).product::<usize>()
    } else {
        0
    };
    let lattice = |[i, j, k]: [u32; 3], s: u32, cd: [u32; 3]| -> usize {
        let [a, b, cc] = [i, j, k].map(|x| (x + s / 2) / s);
        a as usize + cd[0] as usize * (b as usize + cd[1] as usize * cc as usize)
    };
    let node_of = |[i, j, k]: [u32; 3]| -> usize {
        if thick.is_some_and(|t| t.is_coarse(i, j, k)) {
            first + lattice([i, j, k], s2, cd2)
        } else {
            lattice([i, j, k], s, cd)
        }
    };
    // The lattice nodes next to an inside voxel, ascending (marked on all threads).
    let cells = first + second;
    let marked: Vec<AtomicBool> = (0..cells).map(|_| AtomicBool::new(false)).collect();
    inside.par_chunks(POINTS_PER_TASK * 16).for_each(|chunk| {
        for (_, ijk) in with_coords(&grid, chunk) {
            marked[node_of(ijk)].store(true, Relaxed);
        }
    });
    let nodes: Vec<u32> = (0..cells as u32)
        .into_par_iter()
        .filter(|&n| marked[n as usize].load(Relaxed))
        .collect();
    drop(marked);
    const UNSET: u32 = u32::MAX;
    progress.start("distance field", (nodes.len() + inside.len()) as u64);
    let near = Near {
        abs: 0.0,
        rel: NEAR_REL,
    };
    let node_point = |n: u32| -> DVec3 {
        let (n, cd, s) = match (n as usize).checked_sub(first) {
            Some(m) => (m, cd2, s2),
            None => (n as usize, cd, s),
        };
        let (cx, cy) = (cd[0] as usize, cd[1] as usize);
        let (i, j, k) = (n % cx, (n / cx) % cy, n / (cx * cy));
        grid.origin + DVec3::new(i as f64, j as f64, k as f64) * (grid.h * s as f64)
    };
    // Near triangles of the nodes, each search bounded by the previous node's triangle (kept
    // when no triangle beats it by the margin).
    let slots: Vec<u32> = nodes
        .par_chunks(POINTS_PER_TASK)
        .flat_map_iter(|chunk| {
            let mut hint = UNSET;
            let out: Vec<u32> = chunk
                .iter()
                .map(|&n| {
                    let p = node_point(n);
                    let bound = bvh.slot_distance_sq(p, hint);
                    match bvh.near_point(p, bound, near) {
                        Some(c) => hint = c.slot,
                        None if bound.is_finite() => {}
                        None => hint = UNSET,
                    }
                    hint
                })
                .collect();
            progress.advance(chunk.len() as u64);
            out
        })
        .collect();
    // The triangle slot of every lattice node, dense (a 27th of the grid's cells at stride
    // 3, 4 bytes each; the second lattice's far fewer).
    let mut node_slot = vec![UNSET; cells];
    for (&n, &slot) in nodes.iter().zip(&slots) {
        node_slot[n as usize] = slot;
    }
    // Written in place chunk by chunk (collecting the chunks' pairs and unzipping them was a
    // serial copy of the whole field).
    let mut bound = vec![0.0; inside.len()];
    let mut slot = vec![UNSET; inside.len()];
    const CHUNK: usize = POINTS_PER_TASK * 16;
    bound
        .par_chunks_mut(CHUNK)
        .zip(slot.par_chunks_mut(CHUNK))
        .zip(inside.par_chunks(CHUNK))
        .for_each(|((bound, slot), chunk)| {
            for ((b, s), (_, [i, j, k])) in bound
                .iter_mut()
                .zip(slot.iter_mut())
                .zip(with_coords(&grid, chunk))
            {
                *s = node_slot[node_of([i, j, k])];
                *b = bvh.slot_distance_sq(grid.center(i, j, k), *s).sqrt();
            }
            progress.advance(chunk.len() as u64);
        });
    progress.finish();
    let coarse = thick.map(|t| CoarseVoxels {
        flags: inside
            .par_iter()
            .map(|&c| {
                let [i, j, k] = grid.coords(c as usize);
                t.is_coarse(i, j, k)
            })
            .collect(),
        min_radius: t.min_radius(),
    });
    Ok(DistanceBounds {
        grid,
        inside,
        bound,
        slot,
        method,
        coarse,
    })
}

/// Each of `cells` (linear indices, ascending) with its coordinates: the next cell of a row
/// steps `i` by one, so only a new row costs the divisions of [`VoxelGrid::coords`] (they were
/// most of the time of a voxel's bound).
fn with_coords<'a>(
    grid: &'a VoxelGrid,
    cells: &'a [u32],
) -> impl Iterator<Item = (u32, [u32; 3])> + 'a {
    let nx = grid.dims[0];
    let mut last: Option<(u32, [u32; 3])> = None;
    cells.iter().map(move |&c| {
        let ijk = match last {
            Some((p, [i, j, k])) if c == p + 1 && i + 1 < nx => [i + 1, j, k],
            _ => grid.coords(c as usize),
        };
        last = Some((c, ijk));
        (c, ijk)
    })
}

#[cfg(test)]
/// Exact distance from each point to the triangles of `bvh` (`f64::INFINITY` when empty);
/// fastest when consecutive points are close to each other.
pub(crate) fn distance_of_points(bvh: &TriangleBvh, pts: &[DVec3]) -> Vec<f64> {
    pts.par_chunks(POINTS_PER_TASK)
        .flat_map_iter(|chunk| seeded_distances(bvh, chunk.iter().copied()))
        .collect()
}

#[cfg(test)]
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
