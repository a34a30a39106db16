//! Off-grid sphere centres (ProtoSphere-style, Weller & Zachmann 2010): starting at the voxel
//! centre the greedy packing picked, step away from the nearest obstacle — the surface or an
//! already placed sphere — while the free radius grows. Steps are at most half the current free
//! radius, so the centre never leaves the free ball it is in (it stays inside the mesh and
//! outside every sphere), and the popped voxel stays inside the final sphere, so the packing
//! always makes progress. On an open mesh the triangles do not bound the solid everywhere (a
//! free ball may reach through a hole), so there a moved centre must also stay inside by the
//! generalized winding number, with a margin above ½ that no evaluation's error crosses.

use super::Sphere;
use crate::field::VoxelGrid;
use crate::mesh::bvh::TriangleBvh;
use crate::mesh::winding::{FastWinding, DEFAULT_BETA};
use glam::DVec3;

/// What bounds a free radius: a triangle of the surface (its slot in the tree) or a sphere.
#[derive(Clone, Copy)]
enum Obstacle {
    Triangle(u32),
    Sphere(Sphere),
}

/// Placed spheres bucketed in a coarse uniform grid, plus the surface BVH.
pub(super) struct Refiner<'a> {
    bvh: &'a TriangleBvh,
    origin: DVec3,
    cell: f64,
    dims: [i64; 3],
    buckets: Vec<smallvec::SmallVec<[u32; 4]>>,
    steps: u32,
    h: f64,
    /// Spheres too large to bucket cheaply: always checked.
    big: Vec<u32>,
    /// On open meshes: the winding number a moved centre must keep above [`INSIDE_W`].
    winding: Option<FastWinding>,
}

/// The winding number a moved centre keeps on an open mesh: ½ (the inside test's threshold)
/// plus a margin well above the fast evaluation's error (about 1e-3), so that the centre is
/// inside by any evaluation, the check's included.
const INSIDE_W: f64 = 0.55;

impl<'a> Refiner<'a> {
    /// `open`: the mesh's inside was decided by the winding number (see [`INSIDE_W`]).
    pub(super) fn new(grid: &VoxelGrid, bvh: &'a TriangleBvh, steps: u32, open: bool) -> Self {
        let cell = 4.0 * grid.h;
        let dims = grid.dims.map(|d| (d as i64 + 3) / 4 + 1);
        let n = (dims[0] * dims[1] * dims[2]) as usize;
        // About a million cells on the jaw: written on all threads.
        use rayon::prelude::*;
        let buckets = (0..n)
            .into_par_iter()
            .map(|_| smallvec::SmallVec::new())
            .collect();
        Refiner {
            bvh,
            origin: grid.origin - DVec3::splat(grid.h),
            cell,
            dims,
            buckets,
            steps,
            h: grid.h,
            big: Vec::new(),
            winding: open.then(|| FastWinding::from_bvh(bvh.clone(), DEFAULT_BETA)),
        }
    }

    fn cell_of(&self, p: DVec3) -> [i64; 3] {
        let q = ((p - self.origin) / self.cell).floor();
        [
            (q.x as i64).clamp(0, self.dims[0] - 1),
            (q.y as i64).clamp(0, self.dims[1] - 1),
            (q.z as i64).clamp(0, self.dims[2] - 1),
        ]
    }

    /// Whether a sphere of radius `r` is too large to bucket cheaply (kept in `big`).
    fn is_big(&self, r: f64) -> bool {
        r > 8.0 * self.cell
    }

    /// Registers a placed sphere.
    pub(super) fn insert(&mut self, id: u32, c: DVec3, r: f64) {
        if self.is_big(r) {
            self.big.push(id);
            return;
        }
        let a = self.cell_of(c - r);
        let b = self.cell_of(c + r);
        for z in a[2]..=b[2] {
            for y in a[1]..=b[1] {
                for x in a[0]..=b[0] {
                    let i = (x + self.dims[0] * (y + self.dims[1] * z)) as usize;
                    self.buckets[i].push(id);
                }
            }
        }
    }

    /// Registers `new`, the placed spheres with ids `first..`, as [`insert`](Self::insert)
    /// one by one does (every cell lists its ids in ascending order), on all threads when
    /// `parallel`: each thread fills the cells of its own z-slab of the grid.
    pub(super) fn insert_all(&mut self, first: u32, new: &[Sphere], parallel: bool) {
        /// Fewer spheres than this register faster on one thread.
        const MIN_PARALLEL: usize = 512;
        if !parallel || new.len() < MIN_PARALLEL {
            for (id, s) in (first..).zip(new) {
                self.insert(id, s.center, s.radius);
            }
            return;
        }
        use rayon::prelude::*;
        let big: Vec<u32> = (first..)
            .zip(new)
            .filter(|(_, s)| self.is_big(s.radius))
            .map(|(id, _)| id)
            .collect();
        self.big.extend(big);
        // Each sphere's cell box (none for the big ones), computed once for all slabs.
        let boxes: Vec<Option<([i64; 3], [i64; 3])>> = new
            .par_iter()
            .map(|s| {
                (!self.is_big(s.radius)).then(|| {
                    (
                        self.cell_of(s.center - s.radius),
                        self.cell_of(s.center + s.radius),
                    )
                })
            })
            .collect();
        let layer = (self.dims[0] * self.dims[1]) as usize;
        let layers = self.dims[2] as usize;
        let slab = layers.div_ceil(4 * rayon::current_num_threads()).max(1);
        let nx = self.dims[0];
        self.buckets
            .par_chunks_mut(layer * slab)
            .enumerate()
            .for_each(|(n, cells)| {
                let (z0, z1) = ((n * slab) as i64, ((n + 1) * slab) as i64 - 1);
                for (id, b) in (first..).zip(&boxes) {
                    let Some((a, b)) = b else { continue };
                    if b[2] < z0 || a[2] > z1 {
                        continue;
                    }
                    for z in a[2].max(z0)..=b[2].min(z1) {
                        for y in a[1]..=b[1] {
                            for x in a[0]..=b[0] {
                                let i = (x + nx * (y + self.dims[1] * (z - z0))) as usize;
                                cells[i].push(id);
                            }
                        }
                    }
                }
            });
    }

    /// Free radius at `c` (distance to the surface and to every placed sphere) and the nearest
    /// obstacle point, given an upper bound of the free radius (`f64::INFINITY` for none): the
    /// surface is searched within the bound only, which prunes most of the triangle tree. The
    /// answer is the same as without the bound (a bound that turns out too small, by rounding,
    /// falls back to the unbounded search).
    /// `extra` are spheres not registered yet (checked one by one).
    fn free(
        &self,
        c: DVec3,
        spheres: &[Sphere],
        extra: &[Sphere],
        bound: f64,
    ) -> (f64, DVec3, Option<Obstacle>) {
        let b = bound * (1.0 + 1e-9) + 1e-12 * self.h;
        let (mut best, mut at, mut found) = match self.bvh.closest_point(c, b * b) {
            Some(h) => (h.dist_sq.sqrt(), h.point, Some(Obstacle::Triangle(h.slot))),
            None => (b, c, None),
        };
        let consider_sphere =
            |s: Sphere, best: &mut f64, at: &mut DVec3, found: &mut Option<Obstacle>| {
                let d = (c - s.center).length();
                let gap = d - s.radius;
                if gap < *best {
                    *best = gap;
                    *found = Some(Obstacle::Sphere(s));
                    *at = if d > 0.0 {
                        s.center + (c - s.center) * (s.radius / d)
                    } else {
                        c
                    };
                }
            };
        let consider = |id: u32, best: &mut f64, at: &mut DVec3, found: &mut Option<Obstacle>| {
            consider_sphere(spheres[id as usize], best, at, found);
        };
        for &s in extra {
            consider_sphere(s, &mut best, &mut at, &mut found);
        }
        for &id in &self.big {
            consider(id, &mut best, &mut at, &mut found);
        }
        let reach = best.max(0.0);
        let a = self.cell_of(c - reach);
        let bb = self.cell_of(c + reach);
        for z in a[2]..=bb[2] {
            for y in a[1]..=bb[1] {
                for x in a[0]..=bb[0] {
                    let i = (x + self.dims[0] * (y + self.dims[1] * z)) as usize;
                    for &id in &self.buckets[i] {
                        consider(id, &mut best, &mut at, &mut found);
                    }
                }
            }
        }
        if found.is_none() && bound.is_finite() {
            return self.free(c, spheres, extra, f64::INFINITY);
        }
        (best, at, found)
    }

    /// The distance from `c` to `obstacle`, computed as [`free`](Self::free) computes it (so
    /// never below the free radius there).
    fn distance(&self, obstacle: Obstacle, c: DVec3) -> f64 {
        match obstacle {
            Obstacle::Triangle(slot) => self.bvh.slot_distance_sq(c, slot).sqrt(),
            Obstacle::Sphere(s) => (c - s.center).length() - s.radius,
        }
    }

    /// Moves the centre from voxel centre `v` (free radius `rho`) toward a larger free ball,
    /// of radius at most `cap`. `extra`: placed spheres not registered yet.
    pub(super) fn refine(
        &self,
        v: DVec3,
        rho: f64,
        spheres: &[Sphere],
        extra: &[Sphere],
        cap: f64,
    ) -> (DVec3, f64) {
        self.refine_with::<true>(v, rho, spheres, extra, cap)
    }

    /// [`refine`](Self::refine); with `SHORTCUT` a candidate within the free radius of the
    /// obstacle that refused the last one is refused without a search (without, a search
    /// per step: the same centres, which the tests check).
    #[inline(always)]
    fn refine_with<const SHORTCUT: bool>(
        &self,
        v: DVec3,
        rho: f64,
        spheres: &[Sphere],
        extra: &[Sphere],
        cap: f64,
    ) -> (DVec3, f64) {
        // The grid's remaining distance is the free radius at the voxel centre.
        let (mut f, mut q, _) = self.free(v, spheres, extra, rho);
        // The grid value is exact, but never trust a refinement that would shrink the sphere
        // (or a NaN).
        if f.is_nan() || f < rho {
            return (v, rho);
        }
        let mut c = v;
        let mut step = 0.5 * self.h;
        // The obstacle that refused the last candidate: where it is within `f` of the next
        // one, that one is refused too (the free radius is at most its distance), without a
        // search. Halving steps against one wall are most of the refusals.
        let mut wall: Option<Obstacle> = None;
        for _ in 0..self.steps {
            let away = c - q;
            let len = away.length();
            if len <= 0.0 || step < self.h / 64.0 {
                break;
            }
            let cand = c + away * (step.min(0.5 * f) / len);
            if SHORTCUT && wall.is_some_and(|w| self.distance(w, cand) <= f) {
                step *= 0.5;
                continue;
            }
            // The free radius is 1-Lipschitz: at most f plus the distance moved.
            let (fc, qc, obstacle) = self.free(cand, spheres, extra, f + (cand - c).length());
            if fc > f
                && fc <= cap
                && (cand - v).length() <= fc
                && self
                    .winding
                    .as_ref()
                    .is_none_or(|w| w.winding_number(cand).abs() >= INSIDE_W)
            {
                c = cand;
                f = fc;
                q = qc;
            } else {
                wall = obstacle;
                step *= 0.5;
            }
        }
        (c, f)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(8))]
        /// Registering a colour's spheres by z-slab on all threads fills every cell with the
        /// same ids in the same order as registering them one by one, big spheres included.
        #[test]
        fn registering_on_all_threads_equals_one_by_one(
            balls in proptest::collection::vec((-0.9f64..0.9, -0.5f64..0.5, -0.35f64..0.35, 0.001f64..0.12), 512..900),
            big in proptest::collection::vec((-0.5f64..0.5, 1.1f64..1.5), 0..4),
            first in 0u32..1000,
        ) {
            let mesh = crate::shapes::ellipsoid(DVec3::new(1.0, 0.6, 0.4), 3);
            let bvh = TriangleBvh::new(&mesh);
            let (lo, hi) = mesh.bbox();
            let grid = VoxelGrid::with_resolution(lo, hi, 64).unwrap();
            let mut spheres: Vec<Sphere> = balls
                .iter()
                .map(|&(x, y, z, r)| Sphere { center: DVec3::new(x, y, z), radius: r })
                .collect();
            // A few spheres larger than 8 bucket cells (about 1.0 here), kept on the
            // always-checked list.
            for (k, &(x, r)) in big.iter().enumerate() {
                spheres.insert(k * 97 % spheres.len(), Sphere { center: DVec3::new(x, 0.0, 0.0), radius: r });
            }
            let mut one = Refiner::new(&grid, &bvh, 8, false);
            for (id, s) in (first..).zip(&spheres) {
                one.insert(id, s.center, s.radius);
            }
            let mut all = Refiner::new(&grid, &bvh, 8, false);
            all.insert_all(first, &spheres, true);
            prop_assert_eq!(&all.big, &one.big);
            prop_assert!(all.buckets == one.buckets);
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(24))]
        /// Refusing a candidate by the obstacle that refused the last one moves every centre
        /// exactly as a search per step does, among the surface and placed spheres.
        #[test]
        fn the_refused_candidate_shortcut_changes_no_centre(
            balls in proptest::collection::vec((-0.6f64..0.6, -0.4f64..0.4, -0.3f64..0.3, 0.02f64..0.15), 0..40),
            points in proptest::collection::vec((-0.8f64..0.8, -0.5f64..0.5, -0.35f64..0.35), 1..40),
        ) {
            let mesh = crate::shapes::ellipsoid(DVec3::new(1.0, 0.6, 0.4), 3);
            let bvh = TriangleBvh::new(&mesh);
            let (lo, hi) = mesh.bbox();
            let grid = VoxelGrid::with_resolution(lo, hi, 40).unwrap();
            let mut refiner = Refiner::new(&grid, &bvh, 8, false);
            let spheres: Vec<Sphere> = balls
                .iter()
                .map(|&(x, y, z, r)| Sphere { center: DVec3::new(x, y, z), radius: r })
                .collect();
            for (id, s) in spheres.iter().enumerate() {
                refiner.insert(id as u32, s.center, s.radius);
            }
            for &(x, y, z) in &points {
                let v = DVec3::new(x, y, z);
                let (rho, _, _) = refiner.free(v, &spheres, &[], f64::INFINITY);
                if rho.is_nan() || rho <= 0.0 {
                    continue;
                }
                let want = refiner.refine_with::<false>(v, rho, &spheres, &[], f64::INFINITY);
                let got = refiner.refine(v, rho, &spheres, &[], f64::INFINITY);
                prop_assert_eq!(got, want);
            }
        }
    }
}
