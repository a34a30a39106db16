//! Greedy packing of non-overlapping inner spheres into the voxel distance field.
//!
//! Repeatedly the voxel with the largest remaining distance becomes the centre of a sphere of
//! that radius; voxels it covers are discarded, and every other voxel's remaining distance
//! shrinks to its distance from the new sphere where that is smaller (paper, section II-B).
//! Unlike the paper's code, which rescans every voxel per sphere (O(spheres × voxels)), only
//! the voxels within twice the new radius are visited: a voxel farther away has a remaining
//! distance ≤ the new radius < its distance to the new sphere, so it cannot change.

mod queue;
mod refine;

use crate::field::distance::DistanceBounds;
use crate::field::{DistanceField, VoxelGrid};
use crate::mesh::bvh::TriangleBvh;
use glam::DVec3;
use queue::{Entry, MaxQueue};

/// One inner sphere, in f64 model units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sphere {
    /// Centre.
    pub center: DVec3,
    /// Radius.
    pub radius: f64,
}

/// Options of the packing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackingOptions {
    /// No sphere smaller than this is placed (model units; 0 = down to 1e-4 voxel).
    pub min_radius: f64,
    /// Stop after this many spheres.
    pub max_spheres: usize,
    /// Let each sphere's centre move off the voxel centre toward the local maximum of the free
    /// radius (ProtoSphere-style: step away from the nearest obstacle while the sphere grows),
    /// at most this many steps; 0 keeps centres on voxel centres (the paper's packing).
    pub refine_steps: u32,
}

impl Default for PackingOptions {
    fn default() -> Self {
        PackingOptions {
            min_radius: 0.0,
            max_spheres: usize::MAX,
            refine_steps: 0,
        }
    }
}

/// Packs inner spheres into `field`. Every sphere's radius is at most the exact distance of its
/// centre to the surface and to every earlier sphere, so the spheres lie inside the mesh and do
/// not overlap. Deterministic.
///
/// With `opts.refine_steps > 0` the surface BVH `surface` is needed to measure the exact
/// distance to the surface at off-grid centres; without it refinement is skipped.
pub fn pack(
    field: &DistanceField,
    opts: &PackingOptions,
    surface: Option<&TriangleBvh>,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    let voxels = Voxels {
        grid: &field.grid,
        inside: &field.inside,
    };
    pack_voxels(voxels, &field.dist, None, opts, surface, progress)
}

/// [`pack`] from upper bounds of the voxels' distances ([`DistanceBounds`]): a voxel's
/// distance is made exact (a query of `bvh`, the mesh's tree, pruned by its bound) only when
/// it comes to the top of the queue uncovered, and is put back when it shrinks. Every other
/// entry's value is at least its exact one, so the voxel on top with an exact value is the
/// one [`pack`] would take: the same spheres, bit for bit, for about a third of the exact
/// distance queries on the jaw (two of three voxels are covered before they come up).
pub fn pack_bounded(
    field: &DistanceBounds,
    bvh: &TriangleBvh,
    opts: &PackingOptions,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    let voxels = Voxels {
        grid: &field.grid,
        inside: &field.inside,
    };
    let surface = (opts.refine_steps > 0).then_some(bvh);
    pack_voxels(
        voxels,
        &field.bound,
        Some((bvh, &field.slot)),
        opts,
        surface,
        progress,
    )
}

/// The inside voxels: the grid and their linear indices, ascending.
#[derive(Clone, Copy)]
struct Voxels<'a> {
    grid: &'a VoxelGrid,
    inside: &'a [u32],
}

/// The packing over voxels with distances `dist` (exact, or upper bounds with `lazy`: the
/// tree and each bound's triangle slot).
fn pack_voxels(
    field: Voxels<'_>,
    dist: &[f64],
    lazy: Option<(&TriangleBvh, &[u32])>,
    opts: &PackingOptions,
    surface: Option<&TriangleBvh>,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    let grid = field.grid;
    // Remaining distance of every inside voxel, in the order of `field.inside` (the queue's
    // `cell` is that position: the same order as the grid index); negative = covered. Only
    // the inside voxels are held (on the jaw 8M of a 64M-cell grid), found row by row.
    let mut remaining = dist.to_vec();
    // With bounds: whether the voxel's distance to the surface is exact yet.
    let mut exact = vec![false; if lazy.is_some() { dist.len() } else { 0 }];
    let rows = Rows::of(field);
    // Spheres below 1e-4 voxel are useless and would vanish when rounded to f32.
    let floor = opts.min_radius.max(1e-4 * grid.h);
    let mut heap = MaxQueue::with(|emit| {
        for (pos, &d) in dist.iter().enumerate() {
            if d > 0.0 && d >= floor {
                emit(Entry {
                    value: d,
                    cell: pos as u32,
                });
            }
        }
    });
    progress.start("packing spheres", field.inside.len() as u64);
    let mut spheres = Vec::new();
    let h = grid.h;
    let dims = grid.dims;
    let mut covered_since_report = 0u64;
    let mut refiner = match surface {
        Some(bvh) if opts.refine_steps > 0 => {
            Some(refine::Refiner::new(grid, bvh, opts.refine_steps))
        }
        _ => None,
    };
    while let Some(Entry { value, cell }) = heap.pop() {
        if spheres.len() >= opts.max_spheres {
            break;
        }
        let current = remaining[cell as usize];
        if current != value {
            // Stale entry: the voxel shrank (or was covered) after it was pushed.
            if current > 0.0 && current >= floor {
                heap.push(Entry {
                    value: current,
                    cell,
                });
            }
            continue;
        }
        let [ci, cj, ck] = grid.coords(field.inside[cell as usize] as usize);
        let voxel = grid.center(ci, cj, ck);
        if let Some((bvh, slots)) = lazy {
            let pos = cell as usize;
            if !exact[pos] {
                exact[pos] = true;
                // value = min(bound, gaps) and the exact distance is at most the bound.
                let e = bvh
                    .closest_point(voxel, bvh.slot_distance_sq(voxel, slots[pos]))
                    .map_or(value, |c| c.dist_sq.sqrt());
                let now = value.min(e);
                if now != value {
                    remaining[pos] = now;
                    if now > 0.0 && now >= floor {
                        heap.push(Entry { value: now, cell });
                    }
                    continue;
                }
            }
        }
        let (center, radius) = match refiner.as_mut() {
            Some(r) => r.refine(voxel, value, &spheres),
            None => (voxel, value),
        };
        if let Some(r) = refiner.as_mut() {
            r.insert(spheres.len() as u32, center, radius);
        }
        spheres.push(Sphere { center, radius });
        // The sphere may sit off the voxel grid: measure from its real centre. The popped
        // voxel is always covered (refinement keeps it inside the sphere).
        let fc = (center - grid.origin) / h;
        let (ci, cj, ck) = (
            fc.x.round() as u32,
            fc.y.round() as u32,
            fc.z.round() as u32,
        );

        // Visit the cells within 2·radius of the centre, row by row.
        let reach = 2.0 * radius;
        let reach_cells = (reach / h).floor() as i64;
        let reach_sq = reach * reach;
        let r_sq = radius * radius;
        // One extra cell of reach covers the rounding of an off-grid centre.
        let pad = i64::from(refiner.is_some());
        let reach_cells = reach_cells + pad;
        let (ci, cj, ck) = (ci as i64, cj as i64, ck as i64);
        for k in (ck - reach_cells).max(0)..=(ck + reach_cells).min(dims[2] as i64 - 1) {
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
                for pos in rows.span(
                    field,
                    j as usize + dims[1] as usize * k as usize,
                    row,
                    lo,
                    hi,
                ) {
                    let slot = &mut remaining[pos];
                    if *slot < 0.0 {
                        continue;
                    }
                    let i = field.inside[pos] - row;
                    let dx = grid.origin.x + i as f64 * h - center.x;
                    let d_sq = dx * dx + dyz;
                    if d_sq <= r_sq {
                        *slot = -1.0;
                        covered_since_report += 1;
                    } else {
                        let gap = d_sq.sqrt() - radius;
                        if gap < *slot {
                            *slot = gap;
                        }
                    }
                }
            }
        }
        if covered_since_report >= 65_536 {
            progress.advance(covered_since_report);
            covered_since_report = 0;
        }
    }
    progress.advance(covered_since_report);
    progress.finish();
    spheres
}

/// Where each grid row's inside voxels sit in `field.inside` (ascending), so that the
/// voxels of a row segment are found without a per-cell array over the whole grid.
struct Rows {
    /// `start[r]..start[r + 1]`: the positions of row `r = j + ny·k`.
    start: Vec<u32>,
}

impl Rows {
    fn of(field: Voxels<'_>) -> Rows {
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

/// Total volume of a set of spheres.
pub fn total_volume(spheres: &[Sphere]) -> f64 {
    spheres
        .iter()
        .map(|s| 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3))
        .sum()
}
