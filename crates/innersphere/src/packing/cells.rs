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
    /// Inside was decided by the generalized winding number (an open mesh): the surface's
    /// triangles do not bound the solid everywhere, so a refined centre must keep |w| ≥ 0.5.
    pub(super) open: bool,
}

/// The remaining distance of every inside voxel (in the order of `Voxels::inside`);
/// negative = covered. Atomic cells with relaxed loads and stores (plain moves on x86) so
/// that the banded packing's blocks, whose writes never meet, share one array.
pub(super) struct Remaining(Vec<AtomicU64>);

impl Remaining {
    pub(super) fn new(values: &[f64]) -> Remaining {
        use rayon::prelude::*;
        Remaining(
            values
                .par_iter()
                .map(|v| AtomicU64::new(v.to_bits()))
                .collect(),
        )
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

/// Where each grid row's inside voxels sit in `Voxels::inside` (ascending), as runs of
/// consecutive cells, so that the voxels of a row segment are found from a few small entries
/// (a row crosses a handful of runs) without touching `inside`, nor a per-cell array over the
/// whole grid. (A binary search in `inside` cost a third of the packing's updates in cache
/// misses.)
pub(super) struct Rows {
    /// `start[r]..start[r + 1]`: the positions of row `r = j + ny·k`.
    start: Vec<u32>,
    /// `run_start[r]..run_start[r + 1]`: the runs of row `r` in `runs`.
    run_start: Vec<u32>,
    /// Each run's first cell `i` and its first position; it lasts until the next run's
    /// position (or the row's end).
    runs: Vec<(u32, u32)>,
}

impl Rows {
    pub(super) fn of(field: Voxels<'_>) -> Rows {
        use rayon::prelude::*;
        const CHUNK: usize = 1 << 16;
        let [nx, ny, nz] = field.grid.dims;
        let rows = ny as usize * nz as usize;
        let inside = field.inside;
        // Where each run of consecutive cells starts (row, first i, position), on all threads.
        let starts: Vec<(u32, u32, u32)> = (0..inside.len().div_ceil(CHUNK))
            .into_par_iter()
            .flat_map_iter(|c| {
                let span = c * CHUNK..((c + 1) * CHUNK).min(inside.len());
                span.filter_map(|pos| {
                    let c = inside[pos];
                    let new_run = pos == 0 || {
                        let prev = inside[pos - 1];
                        c != prev + 1 || c / nx != prev / nx
                    };
                    new_run.then_some((c / nx, c % nx, pos as u32))
                })
                .collect::<Vec<_>>()
            })
            .collect();
        // Rows without voxels start where the next row with voxels does.
        let mut start = vec![inside.len() as u32; rows + 1];
        let mut run_start = vec![starts.len() as u32; rows + 1];
        let mut next_row = 0usize;
        for (n, &(r, _, pos)) in starts.iter().enumerate() {
            let r = r as usize;
            while next_row <= r {
                start[next_row] = pos;
                run_start[next_row] = n as u32;
                next_row += 1;
            }
        }
        let runs = starts.into_iter().map(|(_, i, pos)| (i, pos)).collect();
        Rows {
            start,
            run_start,
            runs,
        }
    }

    /// Calls `f(first position, first i, count)` for each run of row `r` within
    /// `lo ≤ i ≤ hi` (`0 ≤ lo`), in order: the voxels' `i` without reading `inside`.
    #[inline]
    fn for_each_run(&self, r: usize, lo: i64, hi: i64, mut f: impl FnMut(usize, i64, usize)) {
        let end = self.start[r + 1] as usize;
        let runs = &self.runs[self.run_start[r] as usize..self.run_start[r + 1] as usize];
        for (n, &(i0, p0)) in runs.iter().enumerate() {
            let (i0, p0) = (i64::from(i0), p0 as usize);
            if i0 > hi {
                break;
            }
            let len = runs.get(n + 1).map_or(end, |x| x.1 as usize) - p0;
            let a = lo.max(i0);
            let b = hi.min(i0 + len as i64 - 1);
            if a <= b {
                f(p0 + (a - i0) as usize, a, (b - a + 1) as usize);
            }
        }
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
            let r = j as usize + dims[1] as usize * k as usize;
            rows.for_each_run(r, lo, hi, |first, i0, count| {
                for n in 0..count {
                    let pos = first + n;
                    let slot = remaining.get(pos);
                    if slot < 0.0 {
                        continue;
                    }
                    let dx = grid.origin.x + (i0 + n as i64) as f64 * h - center.x;
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
            });
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

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// A row segment's runs hold exactly the inside voxels of the row within it, with
        /// their `i`.
        #[test]
        fn runs_are_the_row_segment(
            cells in proptest::collection::btree_set(0u32..6 * 5 * 4, 0..120),
            lo in 0i64..7,
            width in -1i64..7,
        ) {
            let grid = VoxelGrid { origin: DVec3::ZERO, h: 1.0, dims: [6, 5, 4] };
            let inside: Vec<u32> = cells.into_iter().collect();
            let rows = Rows::of(Voxels { grid: &grid, inside: &inside, open: false });
            let hi = (lo + width).min(5);
            for r in 0..20usize {
                let want: Vec<usize> = (0..inside.len())
                    .filter(|&p| {
                        let c = inside[p];
                        let i = i64::from(c % 6);
                        (c / 6) as usize == r && i >= lo && i <= hi
                    })
                    .collect();
                let mut runs = Vec::new();
                rows.for_each_run(r, lo, hi, |first, i0, count| {
                    runs.extend((0..count).map(|n| (first + n, i0 + n as i64)));
                });
                let with_i: Vec<(usize, i64)> =
                    want.iter().map(|&p| (p, i64::from(inside[p] % 6))).collect();
                prop_assert_eq!(runs, with_i, "runs of row {}", r);
            }
        }
    }
}
