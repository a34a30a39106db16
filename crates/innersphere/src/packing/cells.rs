//! The packing's voxels: which are inside, where each grid row's voxels sit, their remaining
//! distances, and the update that a new sphere makes to them ([`cover`]).

use crate::field::VoxelGrid;
use glam::DVec3;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// The inside voxels: the grid and their linear indices, ascending.
#[derive(Clone, Copy)]
pub(super) struct Voxels<'a> {
    pub(super) grid: &'a VoxelGrid,
    pub(super) inside: &'a [u32],
}

/// The remaining distance of every inside voxel (in the order of `Voxels::inside`);
/// negative = covered. Atomic cells with relaxed loads and stores (plain moves on x86) so
/// that the banded packing's blocks, whose writes never meet, share one array.
pub(super) struct Remaining(Vec<AtomicU64>);

impl Remaining {
    pub(super) fn new(values: &[f64]) -> Remaining {
        Remaining(values.iter().map(|v| AtomicU64::new(v.to_bits())).collect())
    }
    #[inline]
    pub(super) fn get(&self, pos: usize) -> f64 {
        f64::from_bits(self.0[pos].load(Relaxed))
    }
    #[inline]
    pub(super) fn set(&self, pos: usize, v: f64) {
        self.0[pos].store(v.to_bits(), Relaxed);
    }
}

/// Where each grid row's inside voxels sit in `Voxels::inside` (ascending), so that the
/// voxels of a row segment are found without a per-cell array over the whole grid.
pub(super) struct Rows {
    /// `start[r]..start[r + 1]`: the positions of row `r = j + ny·k`.
    start: Vec<u32>,
}

impl Rows {
    pub(super) fn of(field: Voxels<'_>) -> Rows {
        let [nx, ny, nz] = field.grid.dims;
        let rows = ny as usize * nz as usize;
        let mut start = vec![0u32; rows + 1];
        for &c in field.inside {
            start[(c / nx) as usize + 1] += 1;
        }
        for r in 0..rows {
            start[r + 1] += start[r];
        }
        Rows { start }
    }

    /// The positions of the inside voxels of row `r` (first cell index `base`) with
    /// `lo ≤ i ≤ hi`.
    #[inline]
    fn span(
        &self,
        field: Voxels<'_>,
        r: usize,
        base: u32,
        lo: i64,
        hi: i64,
    ) -> std::ops::Range<usize> {
        let (a, b) = (self.start[r] as usize, self.start[r + 1] as usize);
        let cells = &field.inside[a..b];
        let first = cells.partition_point(|&c| ((c - base) as i64) < lo);
        let last = cells.partition_point(|&c| ((c - base) as i64) <= hi);
        a + first..a + last
    }
}

/// Cells of reach beyond which [`cover`] splits its slices over threads.
const PARALLEL_REACH_CELLS: i64 = 24;

/// Applies a new sphere to the voxels within `reach` of its centre: those inside it are
/// covered, the others' remaining distance shrinks to their gap to it where that is smaller.
/// `pad` extra cells of reach cover the rounding of an off-grid centre. A voxel farther than
/// `reach` must not be able to change (the caller's bound). Returns the voxels covered. A
/// large sphere's z-slices are updated on several threads (they hold distinct voxels).
pub(super) fn cover(
    field: Voxels<'_>,
    rows: &Rows,
    remaining: &Remaining,
    center: DVec3,
    radius: f64,
    reach: f64,
    pad: i64,
) -> u64 {
    let grid = field.grid;
    let h = grid.h;
    let dims = grid.dims;
    let fc = (center - grid.origin) / h;
    let (ci, cj, ck) = (
        fc.x.round() as i64,
        fc.y.round() as i64,
        fc.z.round() as i64,
    );
    let reach_cells = (reach / h).floor() as i64 + pad;
    let reach_sq = reach * reach;
    let r_sq = radius * radius;
    let slice = |k: i64| -> u64 {
        let mut covered = 0u64;
        let dz = grid.origin.z + k as f64 * h - center.z;
        for j in (cj - reach_cells).max(0)..=(cj + reach_cells).min(dims[1] as i64 - 1) {
            let dy = grid.origin.y + j as f64 * h - center.y;
            let dyz = dy * dy + dz * dz;
            if dyz > reach_sq {
                continue;
            }
            let span = ((reach_sq - dyz).sqrt() / h).floor() as i64 + pad;
            let (lo, hi) = ((ci - span).max(0), (ci + span).min(dims[0] as i64 - 1));
            let row = grid.index(0, j as u32, k as u32) as u32;
            let r = j as usize + dims[1] as usize * k as usize;
            for pos in rows.span(field, r, row, lo, hi) {
                let slot = remaining.get(pos);
                if slot < 0.0 {
                    continue;
                }
                let i = field.inside[pos] - row;
                let dx = grid.origin.x + i as f64 * h - center.x;
                let d_sq = dx * dx + dyz;
                if d_sq <= r_sq {
                    remaining.set(pos, -1.0);
                    covered += 1;
                } else {
                    let gap = d_sq.sqrt() - radius;
                    if gap < slot {
                        remaining.set(pos, gap);
                    }
                }
            }
        }
        covered
    };
    let ks = (ck - reach_cells).max(0)..=(ck + reach_cells).min(dims[2] as i64 - 1);
    if reach_cells >= PARALLEL_REACH_CELLS {
        use rayon::prelude::*;
        ks.into_par_iter().map(slice).sum()
    } else {
        ks.map(slice).sum()
    }
}
