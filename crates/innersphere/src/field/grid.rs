//! The cubic voxel grid laid over a mesh.

use crate::error::num;
use glam::DVec3;

/// The most cells a grid may have (per-cell arrays must fit in memory).
pub(crate) const MAX_CELLS: u64 = 600_000_000;

/// A cubic voxel grid: `dims` cells of edge `h`, cell `(i, j, k)` centred at
/// `origin + h * (i, j, k)`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct VoxelGrid {
    /// Centre of cell (0, 0, 0).
    pub origin: DVec3,
    /// Edge length of a (cubic) cell, in model units.
    pub h: f64,
    /// Number of cells along x, y and z.
    pub dims: [u32; 3],
}

impl VoxelGrid {
    /// A grid of cell size `h` covering the box `[lo, hi]` with the box centred in the grid.
    pub(crate) fn covering(lo: DVec3, hi: DVec3, h: f64) -> crate::error::Result<Self> {
        if !(h.is_finite() && h > 0.0) {
            return Err(crate::error::Error::InvalidOption(format!(
                "voxel size must be a positive number, got {h}"
            )));
        }
        if !(lo.is_finite() && hi.is_finite()) || hi.cmplt(lo).any() {
            return Err(crate::error::Error::InvalidMesh(
                "empty or non-finite bounding box".into(),
            ));
        }
        let ext = hi - lo;
        let mut dims = [0u32; 3];
        let mut cells: u64 = 1;
        for a in 0..3 {
            let n = (ext[a] / h).floor() + 1.0;
            if n > (MAX_CELLS as f64) {
                return Err(Self::too_large(h, ext));
            }
            dims[a] = n as u32;
            cells = cells.saturating_mul(dims[a] as u64);
        }
        if cells > MAX_CELLS {
            return Err(Self::too_large(h, ext));
        }
        let span = DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64) - 1.0;
        let origin = (lo + hi) * 0.5 - span * h * 0.5;
        Ok(VoxelGrid { origin, h, dims })
    }

    /// A grid with `n` cells along the longest side of the box `[lo, hi]`.
    pub(crate) fn with_resolution(lo: DVec3, hi: DVec3, n: u32) -> crate::error::Result<Self> {
        if n < 2 {
            return Err(crate::error::Error::InvalidOption(format!(
                "resolution must be at least 2 cells, got {n}"
            )));
        }
        let longest = (hi - lo).max_element();
        if !(longest.is_finite() && longest > 0.0) {
            return Err(crate::error::Error::InvalidMesh(
                "the mesh has no extent".into(),
            ));
        }
        // Said in the caller's terms: cells, not the voxel size they come to.
        Self::covering(lo, hi, longest / n as f64).map_err(|_| {
            let ext = hi - lo;
            let most = (MAX_CELLS as f64 * longest.powi(3) / (ext.x * ext.y * ext.z)).cbrt();
            crate::error::Error::InvalidOption(format!(
                "a resolution of {n} cells along the longest side gives a grid of more than \
                 {MAX_CELLS} cells over this mesh's {} × {} × {} box; at most about {} cells \
                 along its longest side fit",
                num(ext.x),
                num(ext.y),
                num(ext.z),
                most.floor()
            ))
        })
    }

    fn too_large(h: f64, ext: DVec3) -> crate::error::Error {
        crate::error::Error::InvalidOption(format!(
            "a voxel size of {} gives a grid of more than {MAX_CELLS} cells over this mesh's \
             {} × {} × {} box; use a larger voxel size",
            num(h),
            num(ext.x),
            num(ext.y),
            num(ext.z)
        ))
    }

    /// Total number of cells.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.dims[0] as usize * self.dims[1] as usize * self.dims[2] as usize
    }

    /// True when the grid has no cells.
    #[inline]
    pub(crate) fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Linear index of cell `(i, j, k)`: x fastest, then y, then z.
    #[inline]
    pub(crate) fn index(&self, i: u32, j: u32, k: u32) -> usize {
        i as usize + self.dims[0] as usize * (j as usize + self.dims[1] as usize * k as usize)
    }

    /// Cell coordinates of a linear index.
    #[inline]
    pub(crate) fn coords(&self, idx: usize) -> [u32; 3] {
        let nx = self.dims[0] as usize;
        let ny = self.dims[1] as usize;
        [
            (idx % nx) as u32,
            ((idx / nx) % ny) as u32,
            (idx / (nx * ny)) as u32,
        ]
    }

    /// Centre of cell `(i, j, k)`.
    #[inline]
    pub(crate) fn center(&self, i: u32, j: u32, k: u32) -> DVec3 {
        self.origin + DVec3::new(i as f64, j as f64, k as f64) * self.h
    }

    /// Centre of the cell with linear index `idx`.
    #[inline]
    pub(crate) fn center_of(&self, idx: usize) -> DVec3 {
        let [i, j, k] = self.coords(idx);
        self.center(i, j, k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covering_centres_the_box_and_indexes_round_trip() {
        let g = VoxelGrid::covering(DVec3::ZERO, DVec3::new(1.0, 0.5, 0.25), 0.1).unwrap();
        assert_eq!(g.dims, [11, 6, 3]);
        let c0 = g.center(0, 0, 0);
        let c1 = g.center(10, 5, 2);
        assert!(((c0 + c1) * 0.5 - DVec3::new(0.5, 0.25, 0.125)).length() < 1e-12);
        for idx in [0, 7, 65, g.len() - 1] {
            let [i, j, k] = g.coords(idx);
            assert_eq!(g.index(i, j, k), idx);
        }
    }

    #[test]
    fn absurd_sizes_are_errors() {
        assert!(VoxelGrid::covering(DVec3::ZERO, DVec3::ONE, 0.0).is_err());
        assert!(VoxelGrid::covering(DVec3::ZERO, DVec3::ONE, f64::NAN).is_err());
        assert!(VoxelGrid::covering(DVec3::ZERO, DVec3::ONE, 1e-6).is_err());
        assert!(VoxelGrid::with_resolution(DVec3::ZERO, DVec3::ONE, 1).is_err());
    }
}
