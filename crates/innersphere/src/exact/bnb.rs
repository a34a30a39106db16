//! The best-first branch and bound over node pairs of [`distance`](fn@super::distance): the
//! best pair so far, the queue, and the triangle pairs of two leaves.

use super::frame::{size_sq, tri_box, Frame};
use super::mesh::ExactMesh;
use super::scratch::{ExactStats, HeapItem};
use super::tri_tri::{triangle_distance_hint, TriDistance};
use crate::mesh::bvh::{BvhNode, LEAF_SIZE};
use glam::DVec3;

/// Best pair so far (A's frame, BVH slots).
#[derive(Clone, Copy)]
pub(super) struct Best {
    pub(super) d2: f64,
    pub(super) pa: DVec3,
    pub(super) pb: DVec3,
    pub(super) sa: u32,
    pub(super) sb: u32,
    pub(super) intersecting: bool,
}

impl Best {
    pub(super) const NONE: Best = Best {
        d2: f64::INFINITY,
        pa: DVec3::ZERO,
        pb: DVec3::ZERO,
        sa: u32::MAX,
        sb: u32::MAX,
        intersecting: false,
    };

    #[inline]
    pub(super) fn offer(&mut self, r: &TriDistance, sa: u32, sb: u32) {
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

/// Distance between every triangle pair of two leaves that may beat `best` by more than
/// the fraction `1 − √keep` of it (`keep` = 1: any improvement), filtered by their boxes
/// and planes. With `crossings` the pairs whose boxes meet are tested for crossing first
/// (else the leaves are known not to cross).
#[inline]
#[allow(clippy::too_many_arguments)]
pub(super) fn leaf_distance(
    a: &ExactMesh,
    b: &ExactMesh,
    na: &BvhNode,
    nb: &BvhNode,
    f: &Frame,
    best: &mut Best,
    stats: &mut ExactStats,
    keep: f64,
    crossings: bool,
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
                let g2 = gap.length_squared();
                if !(g2 < best.d2 * keep) {
                    continue;
                }
                let y = &tbuf[j];
                let lb = g2
                    .max(plane_gap_sq(x[0], nx, y))
                    .max(plane_gap_sq(y[0], nbuf[j], x));
                if !(lb < best.d2 * keep) {
                    continue;
                }
                stats.triangle_pairs += 1;
                let r = triangle_distance_hint(x, y, crossings && g2 == 0.0);
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

/// Best-first branch and bound of [`distance`](fn@super::distance): node pairs in the order of
/// their lower bounds ([`bound::lower_bound_sq`](super::bound::lower_bound_sq)), except that
/// the nearer child pair is taken at once while no queued pair is nearer (which saves most
/// queue operations without changing the order).
pub(super) fn bnb_heap(
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
                leaf_distance(a, b, na, nb, f, best, stats, 1.0, false);
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
