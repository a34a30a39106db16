//! Greedy packing of non-overlapping inner spheres into the voxel distance field.
//!
//! Repeatedly the voxel with the largest remaining distance becomes the centre of a sphere of
//! that radius; voxels it covers are discarded, and every other voxel's remaining distance
//! shrinks to its distance from the new sphere where that is smaller (paper, section II-B).
//! Unlike the paper's code, which rescans every voxel per sphere (O(spheres × voxels)), only
//! the voxels within twice the new radius are visited: a voxel farther away has a remaining
//! distance ≤ the new radius < its distance to the new sphere, so it cannot change.

mod banded;
mod cells;
mod queue;
mod refine;

use crate::field::distance::DistanceBounds;
use crate::field::{DistanceField, VoxelGrid};
use crate::mesh::bvh::TriangleBvh;
use cells::{cover, Remaining, Rows, Voxels};
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
pub(crate) fn pack(
    field: &DistanceField,
    opts: &PackingOptions,
    surface: Option<&TriangleBvh>,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    let voxels = Voxels {
        grid: &field.grid,
        inside: &field.inside,
        open: field.method == crate::field::InsideMethod::WindingNumber,
    };
    let floors = Floors {
        floor: floor(opts, &field.grid),
        coarse: None,
    };
    pack_voxels(voxels, &field.dist, None, floors, opts, surface, progress)
}

/// [`pack`] from upper bounds of the voxels' distances ([`DistanceBounds`]): a voxel's
/// distance is made exact (a query of `bvh`, the mesh's tree, pruned by its bound) only when
/// it comes to the top of the queue uncovered, and is put back when it shrinks. Every other
/// entry's value is at least its exact one, so the voxel on top with an exact value is the
/// one [`pack`] would take: the same spheres, bit for bit, for about a third of the exact
/// distance queries on the jaw (two of three voxels are covered before they come up).
pub(crate) fn pack_bounded(
    field: &DistanceBounds,
    bvh: &TriangleBvh,
    opts: &PackingOptions,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    let voxels = Voxels {
        grid: &field.grid,
        inside: &field.inside,
        open: field.method == crate::field::InsideMethod::WindingNumber,
    };
    let surface = (opts.refine_steps > 0).then_some(bvh);
    pack_voxels(
        voxels,
        &field.bound,
        Some((bvh, &field.slot)),
        Floors::of(field, opts),
        opts,
        surface,
        progress,
    )
}

/// The spheres of [`pack_bounded`] packed on all of rayon's threads: the greedy order is
/// kept within bands of remaining distance (each band's lower end 0.9 of its upper end) and,
/// within a band, within independent blocks of the grid that are packed at the same time
/// (`banded` module). The same guarantees (inside the mesh, disjoint, deterministic and the
/// same for any number of threads), not the same spheres as the global order: a band's
/// spheres come block by block. With a finite `max_spheres` this is [`pack_bounded`], whose
/// global order makes "the largest N" meaningful.
pub(crate) fn pack_parallel(
    field: &DistanceBounds,
    bvh: &TriangleBvh,
    opts: &PackingOptions,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    if opts.max_spheres != usize::MAX {
        return pack_bounded(field, bvh, opts, progress);
    }
    let voxels = Voxels {
        grid: &field.grid,
        inside: &field.inside,
        open: field.method == crate::field::InsideMethod::WindingNumber,
    };
    let floors = Floors::of(field, opts);
    banded::pack(
        voxels,
        &field.bound,
        bvh,
        &field.slot,
        floors,
        opts,
        progress,
    )
}

/// The packing over voxels with distances `dist` (exact, or upper bounds with `lazy`: the
/// tree and each bound's triangle slot), in the global greedy order.
fn pack_voxels(
    field: Voxels<'_>,
    dist: &[f64],
    lazy: Option<(&TriangleBvh, &[u32])>,
    floors: Floors<'_>,
    opts: &PackingOptions,
    surface: Option<&TriangleBvh>,
    progress: &dyn crate::progress::Progress,
) -> Vec<Sphere> {
    let grid = field.grid;
    let open = field.open;
    // Only the inside voxels are held (on the jaw 8M of a 64M-cell grid), found row by row.
    let remaining = Remaining::new(dist);
    // With bounds: whether the voxel's distance to the surface is exact yet.
    let mut exact = vec![false; if lazy.is_some() { dist.len() } else { 0 }];
    let rows = Rows::of(field);
    let floor = floors.floor;
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
    let mut covered_since_report = 0u64;
    let mut refiner = match surface {
        Some(bvh) if opts.refine_steps > 0 => {
            Some(refine::Refiner::new(grid, bvh, opts.refine_steps, open))
        }
        _ => None,
    };
    // One extra cell of reach covers the rounding of an off-grid centre.
    let pad = i64::from(refiner.is_some());
    while let Some(Entry { value, cell }) = heap.pop() {
        if spheres.len() >= opts.max_spheres {
            break;
        }
        let current = remaining.get(cell as usize);
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
                let now = exact_distance(bvh, voxel, slots[pos], value);
                if now != value {
                    remaining.set(pos, now);
                    if now > 0.0 && now >= floor {
                        heap.push(Entry { value: now, cell });
                    }
                    continue;
                }
            }
        }
        if floors.below(cell, value) {
            continue;
        }
        let (center, radius) = match refiner.as_ref() {
            Some(r) => r.refine(voxel, value, &spheres, &[], f64::INFINITY),
            None => (voxel, value),
        };
        if let Some(r) = refiner.as_mut() {
            r.insert(spheres.len() as u32, center, radius);
        }
        spheres.push(Sphere { center, radius });
        // The sphere may sit off the voxel grid: measure from its real centre. The popped
        // voxel is always covered (refinement keeps it inside the sphere). Every other
        // voxel's remaining distance is at most `value` ≤ radius, so none beyond 2·radius
        // changes.
        covered_since_report += cover(field, &rows, &remaining, center, radius, 2.0 * radius, pad);
        if covered_since_report >= 65_536 {
            progress.advance(covered_since_report);
            covered_since_report = 0;
        }
    }
    progress.advance(covered_since_report);
    progress.finish();
    spheres
}

/// The smallest radius placed at each voxel: [`floor`], and at the coarse voxels of thick
/// parts their own minimum radius when larger.
#[derive(Clone, Copy)]
struct Floors<'a> {
    floor: f64,
    coarse: Option<(&'a [bool], f64)>,
}

impl<'a> Floors<'a> {
    fn of(field: &'a DistanceBounds, opts: &PackingOptions) -> Floors<'a> {
        let floor = floor(opts, &field.grid);
        Floors {
            floor,
            coarse: field
                .coarse
                .as_ref()
                .map(|c| (&c.flags[..], c.min_radius.max(floor))),
        }
    }

    /// Whether `value` at voxel `pos` (a position in the inside list) is below its floor.
    #[inline]
    fn below(&self, pos: u32, value: f64) -> bool {
        value < self.floor
            || self
                .coarse
                .is_some_and(|(flags, f)| value < f && flags[pos as usize])
    }
}

/// The smallest radius placed: the larger of the option and 1e-4 voxel (smaller spheres are
/// useless and would vanish when rounded to f32).
fn floor(opts: &PackingOptions, grid: &VoxelGrid) -> f64 {
    opts.min_radius.max(1e-4 * grid.h)
}

/// The exact distance of `voxel` to the surface, given `value` = min(its bound, gaps to the
/// spheres) and the bound's triangle `slot`: min(value, exact) (the exact distance is at most
/// the bound). Only triangles nearer than `value` can change it: the search is pruned by it
/// (with a slack for rounding) where it is below the slot's distance.
#[inline]
fn exact_distance(bvh: &TriangleBvh, voxel: DVec3, slot: u32, value: f64) -> f64 {
    let reach = bvh
        .slot_distance_sq(voxel, slot)
        .min(value * value * (1.0 + 1e-12));
    let e = bvh
        .closest_point(voxel, reach)
        .map_or(value, |c| c.dist_sq.sqrt());
    value.min(e)
}

/// Total volume of a set of spheres.
pub(crate) fn total_volume(spheres: &[Sphere]) -> f64 {
    spheres
        .iter()
        .map(|s| 4.0 / 3.0 * std::f64::consts::PI * s.radius.powi(3))
        .sum()
}
