//! A bounding-volume hierarchy over the triangles of a mesh.
//!
//! A flat f64 AABB tree: nodes in one `Vec` in depth-first order (the first child of an inner
//! node directly follows it), triangles reordered so that every leaf owns a contiguous range,
//! and the triangle corners copied in that order so that queries never chase indices.
//! Every node also carries a slab (the mean normal of its triangles and their extent along
//! it), a far tighter distance bound than the box for the nearly flat patches below low
//! nodes. Built with a binned surface-area heuristic, in parallel for the top levels; the
//! result depends only on the input, never on thread scheduling.

use super::closest::closest_point_on_triangle;
use crate::mesh::Mesh;
use glam::DVec3;

/// Most triangles in a leaf of [`TriangleBvh::new`]'s trees (the exact mesh queries' buffers
/// are this long).
pub(crate) const LEAF_SIZE: usize = 4;
/// Most triangles in a leaf of any tree ([`TriangleBvh::with_leaf_size`]).
pub(crate) const MAX_LEAF_SIZE: usize = 16;
/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Subtrees with more triangles than this are built in parallel.
const PAR_THRESHOLD: usize = 8192;
/// Below this depth splits follow the SAH; deeper ones split at the median, which bounds the
/// depth by `MEDIAN_DEPTH + log2(n)`.
const MEDIAN_DEPTH: u32 = 40;
/// Nodes with at most this many triangles get slabs fitted to their corners; bigger ones take
/// the slab through their box corners (keeps the build O(n log SLAB_EXACT)).
const SLAB_EXACT: usize = 1024;
/// Upper bound of the tree depth (sizes the traversal stacks).
pub(crate) const MAX_DEPTH: usize = MEDIAN_DEPTH as usize + 34;

/// One node of a [`TriangleBvh`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct BvhNode {
    /// Minimum corner of the box around every triangle below this node.
    pub lo: DVec3,
    /// Maximum corner of the box.
    pub hi: DVec3,
    /// Leaf: first slot of its triangles in [`TriangleBvh::tris`] / [`TriangleBvh::order`].
    /// Inner node: index of its second child (the first child is the next node).
    pub start: u32,
    /// Leaf: number of triangles (≥ 1). Inner node: 0.
    pub count: u32,
}

impl BvhNode {
    /// True when the node holds triangles rather than children.
    #[inline]
    pub(crate) fn is_leaf(&self) -> bool {
        self.count > 0
    }

    /// Squared distance from `p` to the node's box (0 inside).
    #[inline]
    pub(crate) fn dist_sq(&self, p: DVec3) -> f64 {
        (self.lo - p)
            .max(p - self.hi)
            .max(DVec3::ZERO)
            .length_squared()
    }
}

/// A flat AABB tree over triangles. Node 0 is the root (no nodes for an empty mesh).
#[derive(Debug, Clone, Default)]
pub struct TriangleBvh {
    /// Nodes in depth-first order: an inner node `i` has children `i + 1` and `nodes[i].start`.
    pub(crate) nodes: Vec<BvhNode>,
    /// The original triangle index of each slot.
    pub order: Vec<u32>,
    /// The corners of the triangle in each slot (BVH order).
    pub tris: Vec<[DVec3; 3]>,
    /// One slab per node (same index): a second, orientation-aware bound that is much
    /// tighter than the box for the nearly flat surface patches below low nodes.
    pub(crate) slabs: Vec<NodeSlab>,
}

/// The slab `lo ≤ normal · x ≤ hi` that holds every triangle below a node; `normal` is the
/// unit area-weighted mean normal of those triangles (or +x when they cancel out).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct NodeSlab {
    /// Unit slab normal.
    pub normal: DVec3,
    /// Lowest `normal · x` over the node's triangle corners.
    pub lo: f64,
    /// Highest `normal · x` over the node's triangle corners.
    pub hi: f64,
}

impl NodeSlab {
    /// A lower bound of the distance from `p` to the slab (0 inside), with a relative slack
    /// of 1e-9 that absorbs every rounding error: never above the computed distance from `p`
    /// to any triangle in the slab.
    #[inline]
    pub(crate) fn lower_bound(&self, p: DVec3) -> f64 {
        let d = self.normal.dot(p);
        let gap = (d - self.hi).max(self.lo - d);
        (gap - 1e-9 * (d.abs() + self.lo.abs() + self.hi.abs())).max(0.0)
    }
}

/// How near the nearest triangle `TriangleBvh::near_point` must come: a triangle at
/// distance `d` will do when `d·(1 − rel) − abs` is at most the nearest triangle's distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Near {
    /// Absolute margin (model units, ≥ 0).
    pub abs: f64,
    /// Relative margin (0 ≤ rel < 1).
    pub rel: f64,
}

impl Near {
    /// No margin: the nearest triangle's distance.
    pub(crate) const EXACT: Near = Near { abs: 0.0, rel: 0.0 };

    /// The squared distance below which something must lie to beat a triangle at squared
    /// distance `best` by the margin.
    #[inline]
    fn cut(self, best: f64) -> f64 {
        let s = (best.sqrt() * (1.0 - self.rel) - self.abs).max(0.0);
        s * s
    }
}

/// The answer of [`TriangleBvh::closest_point`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// Squared distance from the query point to `point`.
    pub dist_sq: f64,
    /// The closest point on the surface.
    pub point: DVec3,
    /// Index of the triangle it lies on, in the original mesh.
    pub triangle: u32,
    /// The triangle's slot in the tree ([`TriangleBvh::tris`]); handy as a seed for the
    /// next, nearby query.
    pub slot: u32,
}

#[derive(Clone, Copy)]
struct Prim {
    lo: DVec3,
    hi: DVec3,
    c: DVec3,
    idx: u32,
}

#[derive(Clone, Copy)]
struct Bin {
    lo: DVec3,
    hi: DVec3,
    n: usize,
}

impl Bin {
    const EMPTY: Bin = Bin {
        lo: DVec3::splat(f64::INFINITY),
        hi: DVec3::splat(f64::NEG_INFINITY),
        n: 0,
    };
}

#[inline]
fn half_area(lo: DVec3, hi: DVec3) -> f64 {
    let e = (hi - lo).max(DVec3::ZERO);
    e.x * e.y + e.y * e.z + e.z * e.x
}

impl TriangleBvh {
    /// Builds the tree over all triangles of `mesh` (whose indices must be valid).
    pub fn new(mesh: &Mesh) -> Self {
        Self::with_leaf_size(mesh, LEAF_SIZE)
    }

    /// [`new`](Self::new) with up to `leaf` triangles per leaf (clamped to
    /// 1..=[`MAX_LEAF_SIZE`]): fewer, larger leaves suit many point queries far from the
    /// surface (the build's distance bounds and exact distances), small ones the mesh–mesh
    /// queries (leaves of 8 there: exact jaw distance p99 1.02–1.03×, worst frame
    /// 1.07–1.11×).
    pub(crate) fn with_leaf_size(mesh: &Mesh, leaf: usize) -> Self {
        use rayon::prelude::*;
        let tris: Vec<[DVec3; 3]> = (0..mesh.triangles.len())
            .into_par_iter()
            .map(|t| mesh.triangle(t))
            .collect();
        Self::from_triangles_with(&tris, leaf)
    }

    #[cfg(test)]
    /// Builds the tree over a triangle soup; triangle `i` of the answers is `tris[i]`.
    pub(crate) fn from_triangles(tris: &[[DVec3; 3]]) -> Self {
        Self::from_triangles_with(tris, LEAF_SIZE)
    }

    /// [`from_triangles`](Self::from_triangles) with up to `leaf` triangles per leaf.
    fn from_triangles_with(tris: &[[DVec3; 3]], leaf: usize) -> Self {
        use rayon::prelude::*;
        let leaf = leaf.clamp(1, MAX_LEAF_SIZE);
        let mut prims: Vec<Prim> = tris
            .par_iter()
            .enumerate()
            .map(|(i, t)| {
                let lo = t[0].min(t[1]).min(t[2]);
                let hi = t[0].max(t[1]).max(t[2]);
                Prim {
                    lo,
                    hi,
                    c: (lo + hi) * 0.5,
                    idx: i as u32,
                }
            })
            .collect();
        let mut nodes = Vec::with_capacity((2 * prims.len()).saturating_sub(1));
        if !prims.is_empty() {
            build(&mut prims, 0, 0, leaf, &mut nodes);
        }
        let order: Vec<u32> = prims.par_iter().map(|p| p.idx).collect();
        let tris: Vec<[DVec3; 3]> = order.par_iter().map(|&i| tris[i as usize]).collect();
        let slabs = slabs(&nodes, &tris);
        TriangleBvh {
            nodes,
            order,
            tris,
            slabs,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// True when the tree holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Bounding box `(lo, hi)` of all triangles (`None` when empty).
    pub fn bounds(&self) -> Option<(DVec3, DVec3)> {
        self.nodes.first().map(|n| (n.lo, n.hi))
    }

    /// The nearest surface point to `p` whose squared distance is at most `upper_bound_sq`
    /// (`f64::INFINITY` for no bound), or `None` when no triangle is that close.
    ///
    /// Ordered depth-first descent (nearer child first) that prunes the nodes whose box or
    /// slab lies farther than the best triangle found so far. Both bounds are exactly
    /// conservative, so the distance is the exact minimum over all triangles of
    /// [`closest_point_on_triangle`], bit for bit, whatever the bound; ties keep the first
    /// triangle found.
    pub fn closest_point(&self, p: DVec3, upper_bound_sq: f64) -> Option<Closest> {
        self.search::<false, false>(p, upper_bound_sq, Near::EXACT)
            .ok()
    }

    /// [`closest_point`](Self::closest_point), but when no triangle is within the bound it
    /// returns a lower bound of the squared distance instead: at least `upper_bound_sq`, and
    /// often more (the nearest box, slab or triangle that the search pruned). The same
    /// search; only the pruned bounds are kept.
    pub fn closest_point_or_bound(&self, p: DVec3, upper_bound_sq: f64) -> Result<Closest, f64> {
        self.search::<true, false>(p, upper_bound_sq, Near::EXACT)
    }

    /// The search of [`closest_point`](Self::closest_point). With `BOUND` a miss returns the
    /// smallest squared distance that was pruned (at least `upper_bound_sq`); without, the
    /// pruned distances are not tracked. With `NEAR` a triangle `near` of the nearest will
    /// do: the search prunes what cannot come nearer than `near.cut` of the best so far.
    #[inline(always)]
    fn search<const BOUND: bool, const NEAR: bool>(
        &self,
        p: DVec3,
        upper_bound_sq: f64,
        near: Near,
    ) -> Result<Closest, f64> {
        let mut best = upper_bound_sq;
        // What a node or triangle must be below to be looked at.
        let cut_of = |best: f64| if NEAR { near.cut(best) } else { best };
        let mut cut = cut_of(best);
        let mut found: Option<(usize, DVec3)> = None;
        // The smallest squared distance that was pruned (kept only with `BOUND`).
        let mut pruned = f64::INFINITY;
        let Some(root) = self.nodes.first() else {
            return Err(f64::INFINITY);
        };
        let d = root.dist_sq(p);
        if d.is_nan() || d > cut {
            return Err(if d.is_nan() { upper_bound_sq } else { d });
        }
        let mut stack = [(0u32, 0.0f64); MAX_DEPTH + 2];
        let mut sp = 0usize;
        let mut node = 0usize;
        loop {
            let n = &self.nodes[node];
            let mut next = None;
            if n.is_leaf() {
                let s = n.start as usize;
                for (slot, &[a, b, c]) in self.tris[s..s + n.count as usize].iter().enumerate() {
                    // The triangle's own box first: a cheap, exactly conservative bound.
                    let lo = a.min(b).min(c);
                    let hi = a.max(b).max(c);
                    let bd = (lo - p).max(p - hi).max(DVec3::ZERO).length_squared();
                    if bd > cut {
                        if BOUND {
                            pruned = pruned.min(bd);
                        }
                        continue;
                    }
                    let q = closest_point_on_triangle(p, a, b, c);
                    let d = (p - q).length_squared();
                    if d < best || (found.is_none() && d <= best) {
                        best = d;
                        cut = cut_of(best);
                        found = Some((s + slot, q));
                    } else if BOUND {
                        pruned = pruned.min(d);
                    }
                }
            } else {
                let (l, r) = (node + 1, n.start as usize);
                // Without a bound to return, a child its box already prunes needs no slab.
                let bound =
                    |i: usize| self.bound_above(i, p, if BOUND { f64::INFINITY } else { cut });
                let dl = bound(l);
                let dr = bound(r);
                let (near, dn, far, df) = if dl <= dr {
                    (l, dl, r, dr)
                } else {
                    (r, dr, l, dl)
                };
                if df <= cut {
                    stack[sp] = (far as u32, df);
                    sp += 1;
                } else if BOUND {
                    pruned = pruned.min(df);
                }
                if dn <= cut {
                    next = Some(near);
                } else if BOUND {
                    pruned = pruned.min(dn);
                }
            }
            match next {
                Some(nx) => node = nx,
                None => loop {
                    if sp == 0 {
                        return match found {
                            Some((slot, point)) => Ok(Closest {
                                dist_sq: best,
                                point,
                                triangle: self.order[slot],
                                slot: slot as u32,
                            }),
                            None => Err(pruned.max(upper_bound_sq)),
                        };
                    }
                    sp -= 1;
                    let (idx, d) = stack[sp];
                    if d <= cut {
                        node = idx as usize;
                        break;
                    }
                },
            }
        }
    }

    /// A lower bound of the squared distance from `p` to the triangles below node `i` (the
    /// larger of the box and slab bounds), or only the box's bound where that is
    /// already above `cut` (the node is pruned either way; the slab is not read).
    #[inline]
    fn bound_above(&self, i: usize, p: DVec3, cut: f64) -> f64 {
        let b = self.nodes[i].dist_sq(p);
        if b > cut {
            return b;
        }
        let s = self.slabs[i].lower_bound(p);
        b.max(s * s)
    }

    /// Squared distance from `p` to the triangle in slot `slot` (`f64::INFINITY` for a slot
    /// that does not exist, e.g. `u32::MAX`): an upper bound for [`closest_point`](Self::closest_point).
    #[inline]
    pub fn slot_distance_sq(&self, p: DVec3, slot: u32) -> f64 {
        match self.tris.get(slot as usize) {
            Some(&[a, b, c]) => (p - closest_point_on_triangle(p, a, b, c)).length_squared(),
            None => f64::INFINITY,
        }
    }

    /// Like [`closest_point`](Self::closest_point) with the bound taken from the triangle in
    /// `hint_slot` (typically the answer for a nearby point): always finds the nearest triangle,
    /// but prunes most of the tree from the start.
    pub(crate) fn closest_point_from(&self, p: DVec3, hint_slot: u32) -> Option<Closest> {
        self.closest_point(p, self.slot_distance_sq(p, hint_slot))
    }

    /// A triangle `near` of the nearest one to `p` (among those within the squared bound
    /// `upper_bound_sq`; `None` when none is, or when none beats the bound by `near`'s
    /// margin): for upper bounds of distances, where the nearest triangle is not needed and
    /// a near one is much cheaper to find far from the surface (the search prunes what
    /// cannot beat the best so far by the margin).
    pub(crate) fn near_point(&self, p: DVec3, upper_bound_sq: f64, near: Near) -> Option<Closest> {
        self.search::<false, true>(p, upper_bound_sq, near).ok()
    }

    /// Squared distance from `p` to the nearest triangle (`f64::INFINITY` when empty).
    pub fn distance_sq(&self, p: DVec3) -> f64 {
        self.closest_point(p, f64::INFINITY)
            .map_or(f64::INFINITY, |c| c.dist_sq)
    }
}

/// The slab of every node: normals summed bottom-up, extents over each node's slot range.
fn slabs(nodes: &[BvhNode], tris: &[[DVec3; 3]]) -> Vec<NodeSlab> {
    use rayon::prelude::*;
    let n = nodes.len();
    let mut range = vec![(0usize, 0usize); n];
    // The leaves' area-weighted normals on all threads, then the inner nodes' sums.
    let mut normal: Vec<DVec3> = nodes
        .par_iter()
        .map(|node| {
            if node.is_leaf() {
                let r = node.start as usize..(node.start + node.count) as usize;
                tris[r].iter().map(|&[a, b, c]| (b - a).cross(c - a)).sum()
            } else {
                DVec3::ZERO
            }
        })
        .collect();
    for i in (0..n).rev() {
        let node = &nodes[i];
        if node.is_leaf() {
            range[i] = (node.start as usize, (node.start + node.count) as usize);
        } else {
            let (l, r) = (i + 1, node.start as usize);
            normal[i] = normal[l] + normal[r];
            range[i] = (range[l].0, range[r].1);
        }
    }
    (0..n)
        .into_par_iter()
        .map(|i| {
            let len = normal[i].length();
            let unit = normal[i] / len;
            let normal = if len > 0.0 && unit.is_finite() {
                unit
            } else {
                DVec3::X
            };
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            if range[i].1 - range[i].0 <= SLAB_EXACT {
                for t in &tris[range[i].0..range[i].1] {
                    for v in t {
                        let d = normal.dot(*v);
                        lo = lo.min(d);
                        hi = hi.max(d);
                    }
                }
            } else {
                // Big, curved regions: their slabs rarely prune; the box corners suffice.
                let (a, b) = (nodes[i].lo, nodes[i].hi);
                for k in 0..8 {
                    let c = DVec3::new(
                        if k & 1 == 0 { a.x } else { b.x },
                        if k & 2 == 0 { a.y } else { b.y },
                        if k & 4 == 0 { a.z } else { b.z },
                    );
                    let d = normal.dot(c);
                    lo = lo.min(d);
                    hi = hi.max(d);
                }
            }
            NodeSlab { normal, lo, hi }
        })
        .collect()
}

/// Builds the subtree over `prims` (whose first slot is `first`) and appends it to `out`.
fn build(prims: &mut [Prim], first: u32, depth: u32, leaf: usize, out: &mut Vec<BvhNode>) {
    let [lo, hi, clo, chi] = if prims.len() > 4 * PAR_THRESHOLD {
        // Min and max merge exactly: the same box whatever the scheduling.
        use rayon::prelude::*;
        prims.par_chunks(PAR_THRESHOLD).map(extent).reduce(
            || extent(&[]),
            |a, b| {
                [
                    a[0].min(b[0]),
                    a[1].max(b[1]),
                    a[2].min(b[2]),
                    a[3].max(b[3]),
                ]
            },
        )
    } else {
        extent(prims)
    };
    let n = prims.len();
    if n <= leaf {
        out.push(BvhNode {
            lo,
            hi,
            start: first,
            count: n as u32,
        });
        return;
    }
    let mid = split(prims, clo, chi, depth);
    let me = out.len();
    out.push(BvhNode {
        lo,
        hi,
        start: 0,
        count: 0,
    });
    let (left, right) = prims.split_at_mut(mid);
    let rfirst = first + mid as u32;
    if n > PAR_THRESHOLD {
        let (ln, rn) = rayon::join(
            || {
                let mut v = Vec::with_capacity(2 * left.len());
                build(left, first, depth + 1, leaf, &mut v);
                v
            },
            || {
                let mut v = Vec::with_capacity(2 * right.len());
                build(right, rfirst, depth + 1, leaf, &mut v);
                v
            },
        );
        append_shifted(out, &ln);
        out[me].start = out.len() as u32;
        append_shifted(out, &rn);
    } else {
        build(left, first, depth + 1, leaf, out);
        out[me].start = out.len() as u32;
        build(right, rfirst, depth + 1, leaf, out);
    }
}

/// The box of `prims` and the box of their centroids: `[lo, hi, centroid lo, centroid hi]`.
fn extent(prims: &[Prim]) -> [DVec3; 4] {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    let mut clo = lo;
    let mut chi = hi;
    for p in prims {
        lo = lo.min(p.lo);
        hi = hi.max(p.hi);
        clo = clo.min(p.c);
        chi = chi.max(p.c);
    }
    [lo, hi, clo, chi]
}

/// Appends a subtree built in its own vector, shifting its child links.
fn append_shifted(out: &mut Vec<BvhNode>, sub: &[BvhNode]) {
    let base = out.len() as u32;
    out.extend(sub.iter().map(|n| {
        let mut n = *n;
        if !n.is_leaf() {
            n.start += base;
        }
        n
    }));
}

/// Reorders `prims` into two non-empty halves and returns the size of the first.
fn split(prims: &mut [Prim], clo: DVec3, chi: DVec3, depth: u32) -> usize {
    let n = prims.len();
    let ext = chi - clo;
    let axis = if ext.x >= ext.y && ext.x >= ext.z {
        0
    } else if ext.y >= ext.z {
        1
    } else {
        2
    };
    if ext[axis].is_nan() || ext[axis] <= 0.0 {
        // All centroids coincide (or are not finite): split by position in the list.
        return n / 2;
    }
    if depth < MEDIAN_DEPTH {
        if let Some(m) = sah_split(prims, clo, ext) {
            return m;
        }
    }
    // Median split along the longest axis (total order, so deterministic).
    let mid = n / 2;
    prims.select_nth_unstable_by(mid, |a, b| {
        a.c[axis].total_cmp(&b.c[axis]).then(a.idx.cmp(&b.idx))
    });
    mid
}

/// Binned SAH over the three axes; `None` when no bin boundary separates the centroids.
fn sah_split(prims: &mut [Prim], clo: DVec3, ext: DVec3) -> Option<usize> {
    let mut bins = [[Bin::EMPTY; BINS]; 3];
    let scale = DVec3::new(
        if ext.x > 0.0 {
            BINS as f64 / ext.x
        } else {
            0.0
        },
        if ext.y > 0.0 {
            BINS as f64 / ext.y
        } else {
            0.0
        },
        if ext.z > 0.0 {
            BINS as f64 / ext.z
        } else {
            0.0
        },
    );
    let bin_of = |c: f64, a: usize| -> usize {
        // NaN casts to 0; the `min` keeps the maximum centroid in the last bin.
        (((c - clo[a]) * scale[a]) as usize).min(BINS - 1)
    };
    let fill = |bins: &mut [[Bin; BINS]; 3], chunk: &[Prim]| {
        for p in chunk {
            for (a, axis_bins) in bins.iter_mut().enumerate() {
                let b = &mut axis_bins[bin_of(p.c[a], a)];
                b.lo = b.lo.min(p.lo);
                b.hi = b.hi.max(p.hi);
                b.n += 1;
            }
        }
    };
    if prims.len() > 4 * PAR_THRESHOLD {
        // Min, max and counts merge exactly: the same bins whatever the scheduling.
        use rayon::prelude::*;
        bins = prims
            .par_chunks(PAR_THRESHOLD)
            .map(|chunk| {
                let mut b = [[Bin::EMPTY; BINS]; 3];
                fill(&mut b, chunk);
                b
            })
            .reduce(
                || [[Bin::EMPTY; BINS]; 3],
                |mut x, y| {
                    for (xa, ya) in x.iter_mut().zip(&y) {
                        for (xb, yb) in xa.iter_mut().zip(ya) {
                            xb.lo = xb.lo.min(yb.lo);
                            xb.hi = xb.hi.max(yb.hi);
                            xb.n += yb.n;
                        }
                    }
                    x
                },
            );
    } else {
        fill(&mut bins, prims);
    }
    let mut best: Option<(f64, usize, usize)> = None; // (cost, axis, bins on the left)
    for (a, axis_bins) in bins.iter().enumerate() {
        if ext[a].is_nan() || ext[a] <= 0.0 {
            continue;
        }
        // Sweep from the right to get suffix areas and counts.
        let mut right_cost = [0.0f64; BINS];
        let (mut lo, mut hi, mut cnt) = (
            DVec3::splat(f64::INFINITY),
            DVec3::splat(f64::NEG_INFINITY),
            0,
        );
        for i in (1..BINS).rev() {
            let b = &axis_bins[i];
            lo = lo.min(b.lo);
            hi = hi.max(b.hi);
            cnt += b.n;
            right_cost[i] = if cnt > 0 {
                half_area(lo, hi) * cnt as f64
            } else {
                0.0
            };
        }
        let (mut lo, mut hi, mut cnt) = (
            DVec3::splat(f64::INFINITY),
            DVec3::splat(f64::NEG_INFINITY),
            0,
        );
        for i in 0..BINS - 1 {
            let b = &axis_bins[i];
            lo = lo.min(b.lo);
            hi = hi.max(b.hi);
            cnt += b.n;
            if cnt == 0 || cnt == prims.len() {
                continue;
            }
            let cost = half_area(lo, hi) * cnt as f64 + right_cost[i + 1];
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, a, i + 1));
            }
        }
    }
    let (_, axis, nl) = best?;
    // In-place partition: bins < nl to the front.
    let mut i = 0;
    let mut j = prims.len();
    while i < j {
        if bin_of(prims[i].c[axis], axis) < nl {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
    (i > 0 && i < prims.len()).then_some(i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::closest::point_triangle_distance_sq;
    use proptest::prelude::*;

    fn brute(tris: &[[DVec3; 3]], p: DVec3) -> f64 {
        tris.iter()
            .map(|t| point_triangle_distance_sq(p, t[0], t[1], t[2]))
            .fold(f64::INFINITY, f64::min)
    }

    fn check_structure(bvh: &TriangleBvh, n: usize) {
        check_structure_with(bvh, n, LEAF_SIZE);
    }

    fn check_structure_with(bvh: &TriangleBvh, n: usize, leaf: usize) {
        assert_eq!(bvh.len(), n);
        let mut seen = vec![false; n];
        for &o in &bvh.order {
            assert!(!seen[o as usize]);
            seen[o as usize] = true;
        }
        let mut covered = 0;
        for (i, node) in bvh.nodes.iter().enumerate() {
            if node.is_leaf() {
                assert!(node.count as usize <= leaf);
                covered += node.count as usize;
                let slab = &bvh.slabs[i];
                for t in &bvh.tris[node.start as usize..(node.start + node.count) as usize] {
                    for v in t {
                        assert!(v.cmpge(node.lo).all() && v.cmple(node.hi).all());
                        let d = slab.normal.dot(*v);
                        assert!(d >= slab.lo && d <= slab.hi);
                        assert_eq!(slab.lower_bound(*v), 0.0);
                    }
                }
            } else {
                for c in [i + 1, node.start as usize] {
                    assert!(c > i && c < bvh.nodes.len());
                    let ch = &bvh.nodes[c];
                    assert!(ch.lo.cmpge(node.lo).all() && ch.hi.cmple(node.hi).all());
                }
            }
        }
        assert_eq!(covered, n);
        assert_eq!(bvh.slabs.len(), bvh.nodes.len());
    }

    fn v3(r: f64) -> impl Strategy<Value = DVec3> {
        (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    proptest! {
        #[test]
        fn closest_equals_brute_force(
            tris in prop::collection::vec((v3(1.0), v3(0.3), v3(0.3)), 1..120),
            pts in prop::collection::vec(v3(1.5), 1..20),
            bound in prop::sample::select(vec![f64::INFINITY, 0.01, 0.1, 0.5]),
            leaf in 1..=MAX_LEAF_SIZE,
        ) {
            let tris: Vec<[DVec3; 3]> = tris.iter().map(|&(a, b, c)| [a, a + b, a + c]).collect();
            let bvh = TriangleBvh::from_triangles_with(&tris, leaf);
            check_structure_with(&bvh, tris.len(), leaf);
            for &p in &pts {
                let r = brute(&tris, p);
                // The bound-returning search finds the same, or a lower bound on a miss.
                match bvh.closest_point_or_bound(p, bound) {
                    Ok(c) => prop_assert_eq!(Some(c), bvh.closest_point(p, bound)),
                    Err(lower) => {
                        prop_assert!(bvh.closest_point(p, bound).is_none());
                        prop_assert!(
                            lower >= bound && lower <= r.max(bound) * (1.0 + 1e-12),
                            "{} vs {}",
                            lower,
                            r
                        );
                    }
                }
                match bvh.closest_point(p, bound) {
                    Some(c) => {
                        prop_assert!(c.dist_sq <= bound);
                        prop_assert!((c.dist_sq - r).abs() <= 1e-12 * (1.0 + r), "{} vs {}", c.dist_sq, r);
                        let t = tris[c.triangle as usize];
                        prop_assert_eq!(point_triangle_distance_sq(p, t[0], t[1], t[2]), c.dist_sq);
                        prop_assert!(((c.point - p).length_squared() - c.dist_sq).abs() <= 1e-12);
                        prop_assert_eq!(bvh.order[c.slot as usize], c.triangle);
                        // Seeding with any triangle gives the same distance.
                        for hint in [0, c.slot, (tris.len() / 2) as u32, u32::MAX] {
                            let s = bvh.closest_point_from(p, hint).unwrap();
                            prop_assert_eq!(s.dist_sq, bvh.distance_sq(p));
                        }
                    }
                    None => prop_assert!(r > bound * (1.0 - 1e-12), "missed {} <= {}", r, bound),
                }
            }
        }
    }

    proptest! {
        /// A near triangle is a real triangle within the margin of the nearest; with no
        /// margin it is the nearest; a miss means the bound was not beaten by the margin.
        #[test]
        fn near_point_is_within_its_margin(
            tris in prop::collection::vec((v3(1.0), v3(0.3), v3(0.3)), 1..120),
            pts in prop::collection::vec(v3(1.5), 1..20),
            abs in prop::sample::select(vec![0.0, 0.01, 0.1]),
            rel in prop::sample::select(vec![0.0, 0.1, 0.5]),
            bound in prop::sample::select(vec![f64::INFINITY, 0.01, 0.5]),
        ) {
            let tris: Vec<[DVec3; 3]> = tris.iter().map(|&(a, b, c)| [a, a + b, a + c]).collect();
            let bvh = TriangleBvh::from_triangles(&tris);
            let near = Near { abs, rel };
            for &p in &pts {
                let r = brute(&tris, p).sqrt();
                let slack = 1e-9 * (1.0 + r);
                match bvh.near_point(p, bound, near) {
                    Some(c) => {
                        let t = tris[c.triangle as usize];
                        prop_assert_eq!(point_triangle_distance_sq(p, t[0], t[1], t[2]), c.dist_sq);
                        prop_assert!(c.dist_sq <= bound);
                        let d = c.dist_sq.sqrt();
                        prop_assert!(d >= r - slack);
                        prop_assert!(d * (1.0 - rel) - abs <= r + slack, "{} vs {}", d, r);
                        if abs == 0.0 && rel == 0.0 {
                            prop_assert_eq!(Some(c), bvh.closest_point(p, bound));
                        }
                    }
                    None => {
                        let b = bound.sqrt();
                        prop_assert!(b * (1.0 - rel) - abs <= r + slack, "missed {} < {}", r, b);
                    }
                }
            }
        }
    }

    #[test]
    fn degenerate_inputs() {
        assert!(TriangleBvh::from_triangles(&[])
            .closest_point(DVec3::ZERO, f64::INFINITY)
            .is_none());
        // Many identical triangles and point triangles: no panic, a valid tree.
        let t = [DVec3::ZERO, DVec3::X, DVec3::Y];
        let mut tris = vec![t; 1000];
        tris.extend(std::iter::repeat_n([DVec3::ONE; 3], 500));
        let bvh = TriangleBvh::from_triangles(&tris);
        check_structure(&bvh, tris.len());
        let c = bvh
            .closest_point(DVec3::new(0.2, 0.2, 1.0), f64::INFINITY)
            .unwrap();
        assert!((c.dist_sq - 1.0).abs() < 1e-15);
        // Exponentially spaced triangles (a bad case for SAH depth).
        let tris: Vec<[DVec3; 3]> = (0..2000)
            .map(|i| {
                let x = 1.01f64.powi(i);
                [
                    DVec3::new(x, 0.0, 0.0),
                    DVec3::new(x, 1.0, 0.0),
                    DVec3::new(x, 0.0, 1.0),
                ]
            })
            .collect();
        let bvh = TriangleBvh::from_triangles(&tris);
        check_structure(&bvh, tris.len());
        let p = DVec3::new(3.3, 0.1, 0.1);
        assert_eq!(bvh.distance_sq(p), brute(&tris, p));
    }

    #[test]
    fn deterministic_parallel_build() {
        // 81920 triangles: parallel subtrees and parallel binning.
        let m = crate::shapes::icosphere(6);
        let a = TriangleBvh::new(&m);
        let b = TriangleBvh::new(&m);
        assert_eq!(a.nodes, b.nodes);
        assert_eq!(a.order, b.order);
        assert_eq!(a.slabs, b.slabs);
        check_structure(&a, m.triangles.len());
    }
}
