//! Exact mesh–mesh distance, intersection and penetration depth: the accuracy reference
//! (the role PQP plays in the Inner Sphere Tree paper) and the baseline a user would
//! otherwise pick.
//!
//! Everything is f64 and works in body A's frame: B's nodes and triangles are transformed
//! into it as a traversal reaches them. [`ExactMesh`] holds one mesh's triangle BVH (the
//! shared [`TriangleBvh`]), per-node bounding shapes, the winding-number hierarchy, its
//! connected components and vertex adjacency; [`ExactScratch`] the per-pair memory.
//!
//! * [`distance`] runs in two phases. First, do the surfaces cross? A depth-first traversal
//!   of the node pairs that may touch tests every pair of triangles whose boxes overlap
//!   with exact predicates ([`tri_tri::triangles_intersect`]) and stops at the first
//!   crossing: distance 0. Otherwise a best-first branch and bound over node pairs, ordered
//!   and pruned by lower bounds that combine the boxes with a slab-and-disc shape per node
//!   (tight for the nearly flat patches near the leaves), finds the minimum of the
//!   triangle–triangle distances (PQP's `TriDist`), filtered per triangle pair by boxes and
//!   planes. The scratch can seed both phases with the last query's pairs (warm start).
//! * [`intersects`]: the first phase alone.
//! * Both count one body lying entirely inside the other (no surface crossing) as
//!   intersecting: for every connected component of one body whose extreme vertices all lie
//!   in the other's bounding box, the generalized winding number of one of its vertices
//!   decides.
//! * [`penetration`] / [`penetration_depth`]: the largest distance to the other surface of a
//!   vertex of one body inside the other (both ways).
//! * [`brute_force_distance`] / [`brute_force_intersects`]: O(n·m) references for tests.
//!
//! No input panics: meshes are validated by [`ExactMesh::new`], degenerate triangles are
//! handled, and a non-finite pose gives a NaN distance, no intersection and depth 0.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x < y)` is deliberate: true for NaN too.

mod bound;
mod penetration;
pub mod tri_tri;

pub use penetration::{penetration, penetration_depth, Body, ExactPenetration};
pub use tri_tri::{
    segment_segment_closest, segment_triangle_intersect, segments_intersect, triangle_distance,
    triangles_intersect, TriDistance,
};

use crate::mesh::bvh::{BvhNode, TriangleBvh, LEAF_SIZE};
use crate::mesh::winding::FastWinding;
use crate::Mesh;
use crate::Pose;
use glam::{DMat3, DVec3};
use tri_tri::triangle_distance_hint;

/// One connected component of a mesh (for the containment test).
#[derive(Debug, Clone, Copy)]
struct Component {
    /// A vertex of the component.
    rep: u32,
    /// Its extreme vertices along 26 directions: `extremes[start..end]`.
    start: u32,
    end: u32,
}

/// A mesh prepared for exact queries: its triangle BVH, winding-number hierarchy, connected
/// components and vertex adjacency. Immutable; share it freely between threads.
#[derive(Debug, Clone)]
pub struct ExactMesh {
    mesh: Mesh,
    winding: FastWinding,
    components: Vec<Component>,
    extremes: Vec<u32>,
    /// Vertex adjacency (CSR): the neighbours of `v` are `adj[adj_start[v]..adj_start[v + 1]]`.
    adj_start: Vec<u32>,
    adj: Vec<u32>,
    /// Bounding shapes of the BVH nodes (same indices).
    shapes: Vec<bound::Shape>,
    /// Unit normal of the triangle in each BVH slot (zero when degenerate).
    normals: Vec<DVec3>,
}

impl ExactMesh {
    /// Prepares `mesh` (which must pass [`Mesh::validate`]: not empty, finite, valid indices).
    pub fn new(mesh: &Mesh) -> crate::Result<Self> {
        mesh.validate()?;
        let winding = FastWinding::new(mesh);
        let (shapes, normals) = bound::shapes(winding.bvh());
        let n = mesh.vertices.len();
        // Union-find over vertices.
        let mut parent: Vec<u32> = (0..n as u32).collect();
        fn find(parent: &mut [u32], mut v: u32) -> u32 {
            while parent[v as usize] != v {
                let g = parent[parent[v as usize] as usize];
                parent[v as usize] = g;
                v = g;
            }
            v
        }
        let mut degree = vec![0u32; n + 1];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                let (ru, rv) = (find(&mut parent, u), find(&mut parent, v));
                if ru != rv {
                    parent[ru.max(rv) as usize] = ru.min(rv);
                }
                degree[u as usize] += 1;
                degree[v as usize] += 1;
            }
        }
        // Adjacency (each undirected edge from both of its triangles, deduplicated).
        let mut adj_start = vec![0u32; n + 1];
        for v in 0..n {
            adj_start[v + 1] = adj_start[v] + degree[v];
        }
        let mut fill = adj_start.clone();
        let mut adj = vec![0u32; adj_start[n] as usize];
        for t in &mesh.triangles {
            for k in 0..3 {
                let (u, v) = (t[k], t[(k + 1) % 3]);
                adj[fill[u as usize] as usize] = v;
                fill[u as usize] += 1;
                adj[fill[v as usize] as usize] = u;
                fill[v as usize] += 1;
            }
        }
        let mut compact = Vec::with_capacity(adj.len() / 2);
        let mut new_start = vec![0u32; n + 1];
        for v in 0..n {
            let s = &mut adj[adj_start[v] as usize..adj_start[v + 1] as usize];
            s.sort_unstable();
            let before = compact.len();
            for &w in s.iter() {
                if (compact.len() == before || compact.last() != Some(&w)) && w as usize != v {
                    compact.push(w);
                }
            }
            new_start[v + 1] = compact.len() as u32;
        }
        // Components: representative and 26 extreme vertices each.
        let dirs: Vec<DVec3> = (0..27)
            .filter(|&i| i != 13)
            .map(|i| {
                DVec3::new(
                    (i % 3) as f64 - 1.0,
                    ((i / 3) % 3) as f64 - 1.0,
                    (i / 9) as f64 - 1.0,
                )
            })
            .collect();
        let mut comp_of_root: std::collections::HashMap<u32, usize> = Default::default();
        let mut best: Vec<(u32, Vec<(f64, u32)>)> = Vec::new();
        let mut used = vec![false; n];
        for t in &mesh.triangles {
            for &v in t {
                used[v as usize] = true;
            }
        }
        for v in 0..n as u32 {
            if !used[v as usize] {
                continue;
            }
            let r = find(&mut parent, v);
            let c = *comp_of_root.entry(r).or_insert_with(|| {
                best.push((v, vec![(f64::NEG_INFINITY, v); dirs.len()]));
                best.len() - 1
            });
            let p = mesh.vertices[v as usize];
            for (slot, d) in best[c].1.iter_mut().zip(&dirs) {
                let s = p.dot(*d);
                if s > slot.0 {
                    *slot = (s, v);
                }
            }
        }
        let mut components = Vec::with_capacity(best.len());
        let mut extremes = Vec::new();
        for (rep, ext) in best {
            let start = extremes.len() as u32;
            let mut e: Vec<u32> = ext.iter().map(|x| x.1).collect();
            e.sort_unstable();
            e.dedup();
            extremes.extend(e);
            components.push(Component {
                rep,
                start,
                end: extremes.len() as u32,
            });
        }
        Ok(ExactMesh {
            mesh: mesh.clone(),
            winding,
            components,
            extremes,
            adj_start: new_start,
            adj: compact,
            shapes,
            normals,
        })
    }

    /// The mesh (local frame).
    pub fn mesh(&self) -> &Mesh {
        &self.mesh
    }

    /// The triangle BVH (shared with the winding-number hierarchy).
    pub fn bvh(&self) -> &TriangleBvh {
        self.winding.bvh()
    }

    /// The winding-number hierarchy.
    pub fn winding(&self) -> &FastWinding {
        &self.winding
    }

    /// Number of connected components (vertex-connected triangle sets).
    pub fn component_count(&self) -> usize {
        self.components.len()
    }

    /// True when the point (local frame) lies inside the solid: winding number ≥ 0.5.
    pub fn contains_point(&self, p: DVec3) -> bool {
        self.winding.winding_number(p).abs() >= 0.5
    }

    /// The neighbours of vertex `v` along mesh edges.
    fn neighbours(&self, v: u32) -> &[u32] {
        let s = self.adj_start.get(v as usize).copied().unwrap_or(0) as usize;
        let e = self.adj_start.get(v as usize + 1).copied().unwrap_or(0) as usize;
        self.adj.get(s..e).unwrap_or(&[])
    }

    /// Vertex indices of the triangle in BVH slot `slot`.
    fn slot_vertices(&self, slot: u32) -> [u32; 3] {
        let t = self.bvh().order[slot as usize];
        self.mesh.triangles[t as usize]
    }

    /// Representatives of the components that may lie inside `outer` (all extreme vertices,
    /// mapped by `to_outer`, inside its bounding box).
    fn maybe_inside<'s>(
        &'s self,
        outer: &'s ExactMesh,
        to_outer: &'s Frame,
    ) -> impl Iterator<Item = u32> + 's {
        let (lo, hi) = outer
            .bvh()
            .bounds()
            .map(|(lo, hi)| (lo - to_outer.pad, hi + to_outer.pad))
            .unwrap_or((DVec3::INFINITY, DVec3::NEG_INFINITY));
        self.components.iter().filter_map(move |c| {
            let all_in = self.extremes[c.start as usize..c.end as usize]
                .iter()
                .all(|&v| {
                    let p = to_outer.point(self.mesh.vertices[v as usize]);
                    p.cmpge(lo).all() && p.cmple(hi).all()
                });
            all_in.then_some(c.rep)
        })
    }

    /// True when a connected component of `self` lies inside `outer` (winding number of one
    /// of its vertices); meaningful when the surfaces do not cross.
    fn component_inside(&self, outer: &ExactMesh, to_outer: &Frame, tests: &mut usize) -> bool {
        self.maybe_inside(outer, to_outer).any(|v| {
            *tests += 1;
            outer.contains_point(to_outer.point(self.mesh.vertices[v as usize]))
        })
    }
}

/// Reusable memory and warm-start state of the exact queries for one pair of meshes (or
/// several: the warm start is only a hint and never changes an answer).
#[derive(Debug, Clone)]
pub struct ExactScratch {
    stack: Vec<(u32, u32, f64)>,
    heap: std::collections::BinaryHeap<HeapItem>,
    /// Closest pair of the last [`distance`] (BVH slots), tried first next time.
    last_pair: Option<(u32, u32)>,
    /// Crossing pair of the last [`intersects`], tried first next time.
    last_hit: Option<(u32, u32)>,
    warm_start: bool,
    stats: ExactStats,
    pub(crate) pen: penetration::PenScratch,
}

/// Work counters of the last query run with an [`ExactScratch`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExactStats {
    /// Node pairs taken from the traversal stack.
    pub node_pairs: usize,
    /// Leaf pairs reached.
    pub leaf_pairs: usize,
    /// Triangle pairs evaluated exactly (after the per-triangle box filter).
    pub triangle_pairs: usize,
    /// Winding-number evaluations of the containment test.
    pub winding_tests: usize,
}

impl Default for ExactScratch {
    fn default() -> Self {
        Self::new()
    }
}

impl ExactScratch {
    /// Scratch with warm start on: each query first evaluates the last answer's triangle
    /// pair, which bounds the search from the start on coherent motions.
    pub fn new() -> Self {
        ExactScratch {
            stack: Vec::new(),
            heap: Default::default(),
            last_pair: None,
            last_hit: None,
            warm_start: true,
            stats: ExactStats::default(),
            pen: Default::default(),
        }
    }

    /// Scratch without warm start: every query starts from nothing (for fair timings).
    pub fn cold() -> Self {
        ExactScratch {
            warm_start: false,
            ..Self::new()
        }
    }

    /// Work counters of the last query.
    pub fn stats(&self) -> ExactStats {
        self.stats
    }

    /// Forgets the last answers.
    pub fn reset(&mut self) {
        self.last_pair = None;
        self.last_hit = None;
    }
}

/// The answer of [`distance`] (points in the world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExactDistance {
    /// Distance between the two solids: the surface distance, or 0 when they intersect.
    pub distance: f64,
    /// Distance between the two surfaces (differs from `distance` only when one body lies
    /// entirely inside the other).
    pub surface_distance: f64,
    /// Closest point on A's surface (a common point when the surfaces cross).
    pub point_a: DVec3,
    /// Closest point on B's surface.
    pub point_b: DVec3,
    /// Index of the triangle of A (in A's mesh) that `point_a` lies on.
    pub tri_a: u32,
    /// Index of the triangle of B that `point_b` lies on.
    pub tri_b: u32,
    /// True when the surfaces cross or touch, or one body lies inside the other.
    pub intersecting: bool,
}

/// B's local frame mapped into A's: `p_A = r · p_B + t`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    r: DMat3,
    abs_r: DMat3,
    t: DVec3,
    /// Absolute slack added to transformed boxes (covers rounding of the transform).
    pad: f64,
}

impl Frame {
    /// The frame of `rel` (B in A), with the padding sized for the two trees' coordinates.
    pub(crate) fn new(rel: &Pose, a: &TriangleBvh, b: &TriangleBvh) -> Frame {
        let r = DMat3::from_quat(rel.rotation);
        let abs_r = DMat3::from_cols(r.x_axis.abs(), r.y_axis.abs(), r.z_axis.abs());
        let mag = |t: &TriangleBvh| {
            t.bounds()
                .map_or(0.0, |(lo, hi)| lo.abs().max(hi.abs()).max_element())
        };
        let scale = mag(a) + mag(b) + rel.translation.abs().max_element();
        Frame {
            r,
            abs_r,
            t: rel.translation,
            pad: 1e-13 * scale,
        }
    }

    /// False for a non-finite pose (the queries then answer "no result").
    pub(crate) fn is_finite(&self) -> bool {
        self.r.is_finite() && self.t.is_finite() && self.pad.is_finite()
    }

    #[inline]
    pub(crate) fn point(&self, p: DVec3) -> DVec3 {
        self.r * p + self.t
    }

    #[inline]
    pub(crate) fn tri(&self, t: &[DVec3; 3]) -> [DVec3; 3] {
        [self.point(t[0]), self.point(t[1]), self.point(t[2])]
    }

    /// A node shape of B mapped into A's frame.
    #[inline]
    fn shape<'s>(&self, s: &'s bound::Shape) -> MappedShape<'s> {
        MappedShape {
            c: self.point(s.c),
            h: self.abs_r * s.h + DVec3::splat(self.pad),
            n: self.r * s.n,
            s,
        }
    }

    /// Squared lower bound on the distance between A's node `a` and B's node `b`.
    #[inline]
    fn lower_bound_sq(&self, a: &bound::Shape, b: &bound::Shape) -> f64 {
        self.shape(b).lower_bound_sq(a, self.pad)
    }
}

/// A node shape of B in A's frame.
struct MappedShape<'s> {
    c: DVec3,
    h: DVec3,
    n: DVec3,
    s: &'s bound::Shape,
}

impl MappedShape<'_> {
    #[inline]
    fn lower_bound_sq(&self, a: &bound::Shape, pad: f64) -> f64 {
        bound::lower_bound_sq(a, self.c, self.h, self.n, self.s, pad)
    }
}

#[inline]
fn tri_box(t: &[DVec3; 3]) -> (DVec3, DVec3) {
    (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
}

#[inline]
fn size_sq(n: &BvhNode) -> f64 {
    (n.hi - n.lo).length_squared()
}

/// Best pair so far (A's frame, BVH slots).
#[derive(Clone, Copy)]
struct Best {
    d2: f64,
    pa: DVec3,
    pb: DVec3,
    sa: u32,
    sb: u32,
    intersecting: bool,
}

impl Best {
    const NONE: Best = Best {
        d2: f64::INFINITY,
        pa: DVec3::ZERO,
        pb: DVec3::ZERO,
        sa: u32::MAX,
        sb: u32::MAX,
        intersecting: false,
    };

    #[inline]
    fn offer(&mut self, r: &TriDistance, sa: u32, sb: u32) {
        if r.dist_sq < self.d2
            || (self.sa == u32::MAX && r.dist_sq <= self.d2)
            || (r.intersecting && !self.intersecting)
        {
            *self = Best {
                d2: r.dist_sq,
                pa: r.point_a,
                pb: r.point_b,
                sa,
                sb,
                intersecting: r.intersecting,
            };
        }
    }
}

/// Distance between every triangle pair of two leaves (known not to cross).
#[inline]
fn leaf_distance(
    a: &ExactMesh,
    b: &ExactMesh,
    na: &BvhNode,
    nb: &BvhNode,
    f: &Frame,
    best: &mut Best,
    stats: &mut ExactStats,
) {
    stats.leaf_pairs += 1;
    let (ta, tb) = (a.bvh(), b.bvh());
    let (sa0, ca) = (na.start as usize, na.count as usize);
    let (sb0, cb) = (nb.start as usize, nb.count as usize);
    let (Some(ta_all), Some(tb_all)) = (ta.tris.get(sa0..sa0 + ca), tb.tris.get(sb0..sb0 + cb))
    else {
        return;
    };
    let (Some(na_all), Some(nb_all)) = (a.normals.get(sa0..sa0 + ca), b.normals.get(sb0..sb0 + cb))
    else {
        return;
    };
    let mut tbuf = [[DVec3::ZERO; 3]; LEAF_SIZE];
    let mut bb = [(DVec3::ZERO, DVec3::ZERO); LEAF_SIZE];
    let mut nbuf = [DVec3::ZERO; LEAF_SIZE];
    for (chunk_i, (chunk, nchunk)) in tb_all
        .chunks(LEAF_SIZE)
        .zip(nb_all.chunks(LEAF_SIZE))
        .enumerate()
    {
        for (j, t) in chunk.iter().enumerate() {
            tbuf[j] = f.tri(t);
            bb[j] = tri_box(&tbuf[j]);
            nbuf[j] = f.r * nchunk[j];
        }
        for (i, (x, &nx)) in ta_all.iter().zip(na_all).enumerate() {
            let (alo, ahi) = tri_box(x);
            for j in 0..chunk.len() {
                let (blo, bhi) = bb[j];
                let gap = (alo - bhi).max(blo - ahi).max(DVec3::ZERO);
                let mut lb = gap.length_squared();
                if !(lb < best.d2) {
                    continue;
                }
                let y = &tbuf[j];
                lb = lb
                    .max(plane_gap_sq(x[0], nx, y))
                    .max(plane_gap_sq(y[0], nbuf[j], x));
                if !(lb < best.d2) {
                    continue;
                }
                stats.triangle_pairs += 1;
                let r = triangle_distance_hint(x, y, false);
                let sb = (sb0 + chunk_i * LEAF_SIZE + j) as u32;
                best.offer(&r, (sa0 + i) as u32, sb);
            }
        }
    }
}

/// Squared distance from the plane through `o` with unit normal `n` to the triangle `t`
/// when `t` lies strictly on one side of it, else 0 (a lower bound on the distance of `t`
/// to anything in the plane).
#[inline]
fn plane_gap_sq(o: DVec3, n: DVec3, t: &[DVec3; 3]) -> f64 {
    let s0 = n.dot(t[0] - o);
    let s1 = n.dot(t[1] - o);
    let s2 = n.dot(t[2] - o);
    let g = s0.min(s1).min(s2).max(-(s0.max(s1).max(s2))).max(0.0);
    // Shrunk by a relative hair so that rounding never prunes the closest pair.
    let g = g * (1.0 - 1e-12);
    g * g
}

/// Exact distance between A and B at their world poses (see the module docs).
///
/// A non-finite pose gives NaN distances and `intersecting = false`.
/// The distance is the exact minimum over all triangle pairs of
/// [`triangle_distance`]; when the surfaces cross it is 0 with a common point, and when one
/// body lies entirely inside the other `distance` is 0 and `intersecting` set while
/// `surface_distance` and the points still give the closest surface pair.
pub fn distance(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    scratch: &mut ExactScratch,
) -> ExactDistance {
    let rel = Pose::relative(pose_a, pose_b);
    let (ta, tb) = (a.bvh(), b.bvh());
    let f = Frame::new(&rel, ta, tb);
    let mut best = Best::NONE;
    if !f.is_finite() {
        return ExactDistance {
            distance: f64::NAN,
            surface_distance: f64::NAN,
            point_a: DVec3::NAN,
            point_b: DVec3::NAN,
            tri_a: u32::MAX,
            tri_b: u32::MAX,
            intersecting: false,
        };
    }
    scratch.stats = ExactStats::default();
    // Phase 1: do the surfaces cross? (Exact predicates on every pair of overlapping
    // triangle boxes, stopping at the first crossing.)
    let first = if scratch.warm_start {
        scratch.last_hit
    } else {
        None
    };
    let mut hit = None;
    overlap_pairs(a, b, &f, &mut scratch.stack, first, |sa, sb, x, y| {
        if let Some(p) = tri_tri::intersection_point(x, y) {
            hit = Some((sa, sb, p));
            true
        } else {
            false
        }
    });
    if let Some((sa, sb, p)) = hit {
        scratch.last_hit = Some((sa, sb));
        best = Best {
            d2: 0.0,
            pa: p,
            pb: p,
            sa,
            sb,
            intersecting: true,
        };
    } else {
        // Phase 2: no triangle pair crosses; branch and bound on floating-point distances.
        if scratch.warm_start {
            if let Some((sa, sb)) = scratch.last_pair {
                if let (Some(x), Some(y)) = (ta.tris.get(sa as usize), tb.tris.get(sb as usize)) {
                    best.offer(&triangle_distance_hint(x, &f.tri(y), false), sa, sb);
                }
            }
        }
        bnb_heap(a, b, &f, &mut best, &mut scratch.heap, &mut scratch.stats);
    }
    if best.sa != u32::MAX {
        scratch.last_pair = Some((best.sa, best.sb));
    }
    finish(
        a,
        pose_a,
        b,
        &rel,
        &f,
        &best,
        &mut scratch.stats.winding_tests,
    )
}

/// A node pair on the best-first queue, smallest lower bound on top.
#[derive(Debug, Clone, Copy, PartialEq)]
struct HeapItem(f64, u32, u32);
impl Eq for HeapItem {}
impl PartialOrd for HeapItem {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for HeapItem {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        o.0.total_cmp(&self.0)
    }
}

/// Best-first branch and bound of [`distance`]: node pairs in the order of their lower
/// bounds ([`bound::lower_bound_sq`]), except that the nearer child pair is taken at once
/// while no queued pair is nearer (which saves most queue operations without changing the
/// order).
fn bnb_heap(
    a: &ExactMesh,
    b: &ExactMesh,
    f: &Frame,
    best: &mut Best,
    heap: &mut std::collections::BinaryHeap<HeapItem>,
    stats: &mut ExactStats,
) {
    let (ta, tb) = (a.bvh(), b.bvh());
    if ta.nodes.is_empty()
        || tb.nodes.is_empty()
        || a.shapes.len() != ta.nodes.len()
        || b.shapes.len() != tb.nodes.len()
    {
        return;
    }
    heap.clear();
    let mut cur = Some(HeapItem(f.lower_bound_sq(&a.shapes[0], &b.shapes[0]), 0, 0));
    loop {
        let HeapItem(lb, ia, ib) = match cur.take() {
            Some(x) => x,
            None => match heap.pop() {
                Some(x) => x,
                None => break,
            },
        };
        if !(lb < best.d2) {
            // Everything still queued is at least as far.
            break;
        }
        stats.node_pairs += 1;
        let na = &ta.nodes[ia as usize];
        let nb = &tb.nodes[ib as usize];
        let (p1, p2, d1, d2) = match (na.is_leaf(), nb.is_leaf()) {
            (true, true) => {
                leaf_distance(a, b, na, nb, f, best, stats);
                continue;
            }
            (la, lb_leaf) => {
                if !la && (lb_leaf || size_sq(na) >= size_sq(nb)) {
                    let sb = f.shape(&b.shapes[ib as usize]);
                    let (x, y) = (ia + 1, na.start);
                    let d1 = sb.lower_bound_sq(&a.shapes[x as usize], f.pad);
                    let d2 = sb.lower_bound_sq(&a.shapes[y as usize], f.pad);
                    ((x, ib), (y, ib), d1, d2)
                } else {
                    let (x, y) = (ib + 1, nb.start);
                    let sa = &a.shapes[ia as usize];
                    let d1 = f.lower_bound_sq(sa, &b.shapes[x as usize]);
                    let d2 = f.lower_bound_sq(sa, &b.shapes[y as usize]);
                    ((ia, x), (ia, y), d1, d2)
                }
            }
        };
        let (near, dn, far, df) = if d1 <= d2 {
            (p1, d1, p2, d2)
        } else {
            (p2, d2, p1, d1)
        };
        if df < best.d2 {
            heap.push(HeapItem(df, far.0, far.1));
        }
        if dn < best.d2 {
            let item = HeapItem(dn, near.0, near.1);
            if heap.peek().is_none_or(|t| dn <= t.0) {
                cur = Some(item);
            } else {
                heap.push(item);
            }
        }
    }
}

/// Converts the best pair to the world-frame answer, with the containment test.
fn finish(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    rel: &Pose,
    f: &Frame,
    best: &Best,
    tests: &mut usize,
) -> ExactDistance {
    let surface = best.d2.sqrt();
    let contained = !best.intersecting && contained(a, b, rel, f, tests);
    let tri = |m: &ExactMesh, s: u32| m.bvh().order.get(s as usize).copied().unwrap_or(u32::MAX);
    ExactDistance {
        distance: if best.intersecting || contained {
            0.0
        } else {
            surface
        },
        surface_distance: surface,
        point_a: pose_a.transform_point(best.pa),
        point_b: pose_a.transform_point(best.pb),
        tri_a: tri(a, best.sa),
        tri_b: tri(b, best.sb),
        intersecting: best.intersecting || contained,
    }
}

/// One body lies entirely inside the other (assuming the surfaces do not cross).
fn contained(a: &ExactMesh, b: &ExactMesh, rel: &Pose, f: &Frame, tests: &mut usize) -> bool {
    if b.component_inside(a, f, tests) {
        return true;
    }
    let g = Frame::new(&rel.inverse(), b.bvh(), a.bvh());
    a.component_inside(b, &g, tests)
}

/// Traverses all pairs of overlapping boxes and calls `leaf(slot_a, slot_b, tri_a, tri_b)`
/// (B's triangle in A's frame) for every triangle pair whose boxes overlap, until it returns
/// true. Tries `first` before anything else. Returns whether it stopped early.
pub(crate) fn overlap_pairs(
    a: &ExactMesh,
    b: &ExactMesh,
    f: &Frame,
    stack: &mut Vec<(u32, u32, f64)>,
    first: Option<(u32, u32)>,
    mut leaf: impl FnMut(u32, u32, &[DVec3; 3], &[DVec3; 3]) -> bool,
) -> bool {
    let (ta, tb) = (a.bvh(), b.bvh());
    if let Some((sa, sb)) = first {
        if let (Some(x), Some(y)) = (ta.tris.get(sa as usize), tb.tris.get(sb as usize)) {
            if leaf(sa, sb, x, &f.tri(y)) {
                return true;
            }
        }
    }
    if ta.nodes.is_empty()
        || tb.nodes.is_empty()
        || a.shapes.len() != ta.nodes.len()
        || b.shapes.len() != tb.nodes.len()
    {
        return false;
    }
    stack.clear();
    if f.lower_bound_sq(&a.shapes[0], &b.shapes[0]) > 0.0 {
        return false;
    }
    stack.push((0, 0, 0.0));
    let mut tb_buf = [[DVec3::ZERO; 3]; LEAF_SIZE];
    let mut bb = [(DVec3::ZERO, DVec3::ZERO); LEAF_SIZE];
    while let Some((ia, ib, _)) = stack.pop() {
        let na = &ta.nodes[ia as usize];
        let nb = &tb.nodes[ib as usize];
        match (na.is_leaf(), nb.is_leaf()) {
            (true, true) => {
                let (sa0, ca) = (na.start as usize, na.count as usize);
                let (sb0, cb) = (nb.start as usize, nb.count as usize);
                let (Some(ta_all), Some(tb_all)) =
                    (ta.tris.get(sa0..sa0 + ca), tb.tris.get(sb0..sb0 + cb))
                else {
                    continue;
                };
                for (ci, chunk) in tb_all.chunks(LEAF_SIZE).enumerate() {
                    for (j, t) in chunk.iter().enumerate() {
                        tb_buf[j] = f.tri(t);
                        bb[j] = tri_box(&tb_buf[j]);
                    }
                    for (i, x) in ta_all.iter().enumerate() {
                        let (alo, ahi) = tri_box(x);
                        for j in 0..chunk.len() {
                            let (blo, bhi) = bb[j];
                            if (alo - bhi).max(blo - ahi).max_element() > 0.0 {
                                continue;
                            }
                            let y = &tb_buf[j];
                            if tri_tri::plane_separates(x, y) || tri_tri::plane_separates(y, x) {
                                continue;
                            }
                            let sb = (sb0 + ci * LEAF_SIZE + j) as u32;
                            if leaf((sa0 + i) as u32, sb, x, y) {
                                stack.clear();
                                return true;
                            }
                        }
                    }
                }
            }
            (la, lb_leaf) => {
                if !la && (lb_leaf || size_sq(na) >= size_sq(nb)) {
                    let sb = f.shape(&b.shapes[ib as usize]);
                    for x in [na.start, ia + 1] {
                        if sb.lower_bound_sq(&a.shapes[x as usize], f.pad) <= 0.0 {
                            stack.push((x, ib, 0.0));
                        }
                    }
                } else {
                    let sa = &a.shapes[ia as usize];
                    for y in [nb.start, ib + 1] {
                        if f.lower_bound_sq(sa, &b.shapes[y as usize]) <= 0.0 {
                            stack.push((ia, y, 0.0));
                        }
                    }
                }
            }
        }
    }
    false
}

/// True when A and B at their world poses intersect: some triangle pair crosses or touches
/// (exact predicates), or one body lies entirely inside the other. False for a non-finite
/// pose.
pub fn intersects(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    scratch: &mut ExactScratch,
) -> bool {
    let rel = Pose::relative(pose_a, pose_b);
    let f = Frame::new(&rel, a.bvh(), b.bvh());
    if !f.is_finite() {
        return false;
    }
    scratch.stats = ExactStats::default();
    let first = if scratch.warm_start {
        scratch.last_hit
    } else {
        None
    };
    let mut hit = None;
    let crossing = overlap_pairs(a, b, &f, &mut scratch.stack, first, |sa, sb, x, y| {
        let h = tri_tri::intersection_point(x, y).is_some();
        if h {
            hit = Some((sa, sb));
        }
        h
    });
    if crossing {
        scratch.last_hit = hit;
        return true;
    }
    contained(a, b, &rel, &f, &mut scratch.stats.winding_tests)
}

/// O(n·m) reference for [`distance`]: every triangle pair, the same containment rule.
pub fn brute_force_distance(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
) -> ExactDistance {
    let rel = Pose::relative(pose_a, pose_b);
    let (ta, tb) = (a.bvh(), b.bvh());
    let f = Frame::new(&rel, ta, tb);
    let mut best = Best::NONE;
    let tbs: Vec<[DVec3; 3]> = tb.tris.iter().map(|t| f.tri(t)).collect();
    'outer: for (i, x) in ta.tris.iter().enumerate() {
        for (j, y) in tbs.iter().enumerate() {
            let r = triangle_distance(x, y);
            best.offer(&r, i as u32, j as u32);
            if r.intersecting {
                break 'outer;
            }
        }
    }
    finish(a, pose_a, b, &rel, &f, &best, &mut 0)
}

/// O(n·m) reference for [`intersects`].
pub fn brute_force_intersects(a: &ExactMesh, pose_a: &Pose, b: &ExactMesh, pose_b: &Pose) -> bool {
    brute_force_distance(a, pose_a, b, pose_b).intersecting
}
