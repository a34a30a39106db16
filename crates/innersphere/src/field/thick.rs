//! Thick parts of a body: where it holds inscribed balls of a given radius (the bone a dental
//! arch stands in, never the teeth), the build keeps only a coarse lattice of its voxels and
//! a larger minimum radius, so that the cost of such a body follows its thin parts and its
//! surface instead of its volume.
//!
//! The thick set is the union of the inscribed balls of radius at least
//! [`ThickParts::radius`], found on two coarse lattices of the voxel grid:
//! - ball centres: every `2·stride` voxels, those inside the mesh whose exact distance to the
//!   surface is at least the radius (made exact only where a triangle within 10 % of the
//!   nearest is that far); each is the centre of a ball of that distance, inside the mesh;
//! - the nodes every `stride` voxels within [`ThickParts::margin`] of some ball (the balls
//!   reach into the thick part's edges and its skin that way): a lower envelope of
//!   paraboloids (the separable exact distance transform with each centre weighted by minus
//!   its ball's radius plus the margin, squared: a node is covered where the envelope is ≤ 0).
//!
//! A voxel is *coarse* when the node nearest to it is covered and it is a node itself; the
//! other voxels of a covered node's neighbourhood are dropped; every other inside voxel is
//! kept as it is. The rule only decides which voxel centres the packing may use and how small
//! a sphere there may be: every sphere is still inside the mesh and disjoint from the others.

use super::grid::VoxelGrid;
use super::inside::classify;
use crate::mesh::bvh::{Near, TriangleBvh};
use crate::mesh::Mesh;
use crate::progress::Progress;
use rayon::prelude::*;

/// How the build treats thick parts (see the module `field::thick`); all lengths in model units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThickParts {
    /// A part is thick where it holds an inscribed ball of at least this radius.
    pub radius: f64,
    /// The thick parts reach this far beyond their balls (into edges and creases too narrow
    /// for a ball, up to the foot of what stands on them).
    pub margin: f64,
    /// There, sphere centres come from every `stride`-th voxel along each axis (at least 2).
    pub stride: u32,
    /// There, no sphere smaller than this is placed.
    pub min_radius: f64,
}

/// Relative margin of the ball centres' distances (the distance field's bounds use the same).
const NEAR_REL: f64 = 0.1;

/// The covered nodes of a grid's `stride` lattice ([`ThickSet::find`]).
#[derive(Debug, Clone)]
pub(crate) struct ThickSet {
    stride: u32,
    /// Nodes along x, y, z; node `(a, b, c)` is voxel `(a, b, c)·stride`.
    dims: [u32; 3],
    /// Whether each node is held by a thick ball (x fastest).
    covered: Vec<bool>,
    /// How many nodes are covered.
    count: usize,
    /// Per axis and voxel coordinate: the nearest node's coordinate and whether the voxel
    /// is on the lattice (tables, so that the per-voxel test divides nothing).
    near: [Vec<(u32, bool)>; 3],
    /// [`ThickParts::min_radius`].
    min_radius: f64,
}

impl ThickSet {
    /// The thick set of `mesh` on `grid` (`bvh` is the mesh's triangle tree), or `None` when
    /// the mesh has no part that thick (then the build is what it is without the rule).
    pub(crate) fn find(
        mesh: &Mesh,
        bvh: &TriangleBvh,
        grid: &VoxelGrid,
        parts: &ThickParts,
        progress: &dyn Progress,
    ) -> crate::error::Result<Option<ThickSet>> {
        let s = parts.stride.max(2);
        let h = grid.h * f64::from(s);
        // Nodes up to the one nearest to the last voxel.
        let dims = grid.dims.map(|d| (d + s / 2) / s + 1);
        // Ball centres: every other node.
        let centres = VoxelGrid {
            origin: grid.origin,
            h: 2.0 * h,
            dims: dims.map(|d| d.div_ceil(2)),
        };
        let (inside, _) = classify(mesh, &centres, progress)?;
        progress.start("thick parts", inside.len() as u64);
        let near = Near {
            abs: 0.0,
            rel: NEAR_REL,
        };
        // Each centre's ball radius in node units, squared and negated (the envelope's
        // weight); none below the thick radius.
        let balls: Vec<(u32, f64)> = inside
            .par_chunks(256)
            .flat_map_iter(|chunk| {
                let mut hint = u32::MAX;
                let out: Vec<(u32, f64)> = chunk
                    .iter()
                    .filter_map(|&c| {
                        let p = centres.center_of(c as usize);
                        let bound = bvh.slot_distance_sq(p, hint);
                        let found = bvh.near_point(p, bound, near);
                        let d = match found {
                            Some(f) => {
                                hint = f.slot;
                                f.dist_sq.sqrt()
                            }
                            None => bound.sqrt(),
                        };
                        // Within 10 % of the nearest: only a candidate is made exact.
                        if !(d.is_finite() && d >= parts.radius) {
                            return None;
                        }
                        let r = bvh
                            .closest_point(p, d * d * (1.0 + 1e-12))
                            .map_or(d, |c| c.dist_sq.sqrt().min(d));
                        (r >= parts.radius).then(|| {
                            let [a, b, cc] = centres.coords(c as usize).map(|x| 2 * x);
                            let node = a + dims[0] * (b + dims[1] * cc);
                            (node, r / h)
                        })
                    })
                    .collect();
                progress.advance(chunk.len() as u64);
                out
            })
            .collect();
        progress.finish();
        if balls.is_empty() {
            return Ok(None);
        }
        let n = dims.iter().map(|&d| d as usize).product();
        // Within the margin of a ball.
        let mut wide = vec![f64::INFINITY; n];
        let m = parts.margin / h;
        for &(node, r) in &balls {
            wide[node as usize] = -(r + m) * (r + m);
        }
        envelope(&mut wide, dims);
        let covered: Vec<bool> = wide.par_iter().map(|&v| v <= 0.0).collect();
        let count = covered.iter().filter(|&&c| c).count();
        Ok(Some(ThickSet {
            stride: s,
            dims,
            covered,
            count,
            near: grid
                .dims
                .map(|d| (0..d).map(|x| ((x + s / 2) / s, x % s == 0)).collect()),
            min_radius: parts.min_radius,
        }))
    }

    /// The voxel `(i, j, k)` (inside the grid): whether its nearest node is covered, and
    /// whether it is a node itself.
    #[inline]
    fn lookup(&self, i: u32, j: u32, k: u32) -> (bool, bool) {
        let (a, on_a) = self.near[0][i as usize];
        let (b, on_b) = self.near[1][j as usize];
        let (c, on_c) = self.near[2][k as usize];
        let covered = self.covered[(a + self.dims[0] * (b + self.dims[1] * c)) as usize];
        (covered, on_a && on_b && on_c)
    }

    #[cfg(test)]
    /// Whether the build keeps inside voxel `(i, j, k)`: outside the thick set, or a node of it.
    #[inline]
    pub(crate) fn keeps(&self, i: u32, j: u32, k: u32) -> bool {
        let (covered, node) = self.lookup(i, j, k);
        !covered || node
    }

    /// The first `k' ≥ k` at which the build may keep a voxel of column `(i, j)`: `k` when it
    /// keeps `(i, j, k)`, else past the voxels of the column it drops for sure (those whose
    /// nearest node is the same covered one, up to the next node on the lattice), so that an
    /// inside test skips them without looking at each.
    #[inline]
    pub(crate) fn next_kept(&self, i: u32, j: u32, k: u32) -> u32 {
        let (covered, node) = self.lookup(i, j, k);
        if !covered || node {
            return k;
        }
        let s = self.stride;
        let c = self.near[2][k as usize].0;
        let on_column = self.near[0][i as usize].1 && self.near[1][j as usize].1;
        if on_column && c * s > k {
            c * s
        } else {
            c * s + s - s / 2
        }
    }

    /// Whether voxel `(i, j, k)` is a coarse one: a covered node.
    #[inline]
    pub(crate) fn is_coarse(&self, i: u32, j: u32, k: u32) -> bool {
        let (covered, node) = self.lookup(i, j, k);
        covered && node
    }

    /// No sphere smaller than this at a coarse voxel ([`ThickParts::min_radius`]).
    pub(crate) fn min_radius(&self) -> f64 {
        self.min_radius
    }

    /// The lattice's stride (voxels).
    pub(crate) fn stride(&self) -> u32 {
        self.stride
    }

    /// The volume the thick set covers, in voxels of the grid.
    pub(crate) fn voxels(&self) -> f64 {
        self.count as f64 * f64::from(self.stride).powi(3)
    }
}

/// `f(m) ← min over n of (|m − n|² + f(n))` over a grid of `dims` (node units; infinite
/// values are no paraboloid): three passes of the one-dimensional lower envelope of
/// parabolas (Felzenszwalb & Huttenlocher 2012), each line on its own thread.
fn envelope(f: &mut [f64], dims: [u32; 3]) {
    let [nx, ny, nz] = dims.map(|d| d as usize);
    // Along x: rows are contiguous.
    f.par_chunks_mut(nx).for_each(|row| {
        let mut scratch = Scratch::new(nx);
        scratch.line(row);
    });
    // Along y and z: gather each line, transform, scatter (a layer per thread for y).
    f.par_chunks_mut(nx * ny).for_each(|layer| {
        let mut scratch = Scratch::new(ny);
        let mut line = vec![0.0; ny];
        for i in 0..nx {
            for (j, v) in line.iter_mut().enumerate() {
                *v = layer[i + nx * j];
            }
            scratch.line(&mut line);
            for (j, v) in line.iter().enumerate() {
                layer[i + nx * j] = *v;
            }
        }
    });
    // Along z: the columns of each row `j` at once (nx·nz values), written back layer by layer.
    let layer = nx * ny;
    let rows: Vec<Vec<f64>> = (0..ny)
        .into_par_iter()
        .map(|j| {
            let mut scratch = Scratch::new(nz);
            let mut line = vec![0.0; nz];
            let mut out = vec![0.0; nx * nz];
            for i in 0..nx {
                for (k, v) in line.iter_mut().enumerate() {
                    *v = f[i + nx * j + layer * k];
                }
                scratch.line(&mut line);
                out[i * nz..(i + 1) * nz].copy_from_slice(&line);
            }
            out
        })
        .collect();
    f.par_chunks_mut(layer).enumerate().for_each(|(k, out)| {
        for (j, row) in rows.iter().enumerate() {
            for i in 0..nx {
                out[i + nx * j] = row[i * nz + k];
            }
        }
    });
}

/// The one-dimensional lower envelope's buffers.
struct Scratch {
    /// Apexes of the envelope's parabolas.
    v: Vec<usize>,
    /// Where each parabola starts to be the lowest.
    z: Vec<f64>,
    out: Vec<f64>,
}

impl Scratch {
    fn new(n: usize) -> Self {
        Scratch {
            v: vec![0; n],
            z: vec![0.0; n + 1],
            out: vec![0.0; n],
        }
    }

    /// `line[q] ← min over p of ((q − p)² + line[p])`.
    fn line(&mut self, line: &mut [f64]) {
        let n = line.len();
        let mut k: isize = -1;
        for q in 0..n {
            if !line[q].is_finite() {
                continue;
            }
            let fq = line[q] + (q * q) as f64;
            loop {
                if k < 0 {
                    k = 0;
                    self.v[0] = q;
                    self.z[0] = f64::NEG_INFINITY;
                    self.z[1] = f64::INFINITY;
                    break;
                }
                let p = self.v[k as usize];
                let s = (fq - (line[p] + (p * p) as f64)) / (2.0 * (q - p) as f64);
                if s <= self.z[k as usize] {
                    k -= 1;
                } else {
                    k += 1;
                    self.v[k as usize] = q;
                    self.z[k as usize] = s;
                    self.z[k as usize + 1] = f64::INFINITY;
                    break;
                }
            }
        }
        if k < 0 {
            return; // no paraboloid on this line
        }
        let mut j = 0usize;
        for q in 0..n {
            while self.z[j + 1] < q as f64 {
                j += 1;
            }
            let p = self.v[j];
            let d = q as f64 - p as f64;
            self.out[q] = d * d + line[p];
        }
        line.copy_from_slice(&self.out[..n]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use proptest::prelude::*;

    proptest! {
        /// The envelope is the brute-force minimum over the weighted nodes.
        #[test]
        fn the_envelope_is_the_brute_force_minimum(
            dims in (1u32..7, 1u32..6, 1u32..5),
            weights in proptest::collection::vec((0usize..210, -30.0f64..5.0), 0..6),
        ) {
            let dims = [dims.0, dims.1, dims.2];
            let n = (dims[0] * dims[1] * dims[2]) as usize;
            let mut f = vec![f64::INFINITY; n];
            for &(at, w) in &weights {
                f[at % n] = w;
            }
            let given = f.clone();
            envelope(&mut f, dims);
            let xyz = |c: usize| {
                let c = c as i64;
                let (nx, ny) = (dims[0] as i64, dims[1] as i64);
                (c % nx, (c / nx) % ny, c / (nx * ny))
            };
            for (m, &got) in f.iter().enumerate() {
                let (x, y, z) = xyz(m);
                let want = (0..n)
                    .filter(|&p| given[p].is_finite())
                    .map(|p| {
                        let (a, b, c) = xyz(p);
                        (((x - a).pow(2) + (y - b).pow(2) + (z - c).pow(2)) as f64) + given[p]
                    })
                    .fold(f64::INFINITY, f64::min);
                prop_assert!(
                    (got - want).abs() < 1e-9 || (got.is_infinite() && want.is_infinite()),
                    "{} {}",
                    got,
                    want
                );
            }
        }
    }

    #[test]
    fn a_slab_is_thick_and_a_rod_is_not() {
        // A 20 × 20 × 8 box: balls of radius 3 fit in it, not in a 4 × 4 × 40 rod.
        for (half, thick) in [
            (DVec3::new(10.0, 10.0, 4.0), true),
            (DVec3::new(2.0, 2.0, 20.0), false),
        ] {
            let mesh = crate::shapes::cuboid(half);
            let bvh = TriangleBvh::new(&mesh);
            let (lo, hi) = mesh.bbox();
            let grid = VoxelGrid::covering(lo, hi, 0.25).unwrap();
            let parts = ThickParts {
                radius: 3.0,
                margin: 0.0,
                stride: 4,
                min_radius: 0.5,
            };
            let set = ThickSet::find(&mesh, &bvh, &grid, &parts, &crate::progress::Silent).unwrap();
            assert_eq!(set.is_some(), thick, "{half}");
            if let Some(set) = set {
                // Thick to the slab's faces but for its edges (the balls of radius up to 4
                // leave them), and the edges too with a margin of 1.
                let frac = |set: &ThickSet| {
                    set.voxels() * 0.25f64.powi(3) / (half.x * half.y * half.z * 8.0)
                };
                assert!(frac(&set) > 0.7 && frac(&set) < 0.9, "{}", frac(&set));
                let wider = ThickParts {
                    margin: 1.0,
                    ..parts
                };
                let all = ThickSet::find(&mesh, &bvh, &grid, &wider, &crate::progress::Silent)
                    .unwrap()
                    .unwrap();
                assert!(frac(&all) > 0.95, "{}", frac(&all));
                // The middle is coarse, a corner is not.
                let mid = grid.dims.map(|d| d / 2 / 4 * 4);
                assert!(set.is_coarse(mid[0], mid[1], mid[2]));
                assert!(!set.keeps(mid[0] + 1, mid[1], mid[2]));
                assert!(set.keeps(1, 1, 1));
            }
        }
    }
}
