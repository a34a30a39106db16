//! Where the edges of one mesh's triangle cross another triangle: the edge (its vertex ids),
//! how far along it, and in which direction, from the exact segment–triangle test. What the
//! penetration depth's flood fill and the intersection volume's boundary both read.

use super::tri_tri::{PlaneSides, SidesOf};
use glam::DVec3;

/// An edge's key: its vertex ids, the smaller first.
#[inline]
pub(super) fn edge_key(u: u32, v: u32) -> u64 {
    let (lo, hi) = if u < v { (u, v) } else { (v, u) };
    ((lo as u64) << 32) | hi as u64
}

/// A crossing of edge `key` (`lo < hi`) with the other mesh's triangle in slot `other`, at
/// `t` from `lo` to `hi`; `dir` is the sign of `(p_hi − p_lo) · n` there (`n` the crossed
/// face's outward normal): negative when walking from `lo` to `hi` enters the other body.
#[derive(Debug, Clone, Copy)]
pub(super) struct EdgeCrossing {
    pub(super) key: u64,
    pub(super) other: u32,
    pub(super) t: f64,
    pub(super) dir: f64,
}

/// The barrier edges of a flood fill from crossings sorted by edge and along it: per edge,
/// its key and `dir` at the crossing nearest each end, into `out`.
pub(super) fn barriers(cross: &[EdgeCrossing], out: &mut Vec<(u64, f64, f64)>) {
    out.clear();
    for run in cross.chunk_by(|x, y| x.key == y.key) {
        out.push((run[0].key, run[0].dir, run[run.len() - 1].dir));
    }
}

/// Where each edge's crossings lie in a list sorted by edge ([`EdgeCrossing::key`]): a hash
/// map from the edge's key to its run. A triangle's part looks up each of its three edges,
/// mostly finding none; a binary search over thousands of crossings cost a dozen dependent
/// loads each. Its memory is kept from query to query (no allocation once warm).
#[derive(Debug, Clone, Default)]
pub(super) struct EdgeRuns {
    runs: std::collections::HashMap<u64, (u32, u32), ahash::RandomState>,
}

impl EdgeRuns {
    /// Indexes `cross` (sorted by key).
    pub(super) fn index(&mut self, cross: &[EdgeCrossing]) {
        self.runs.clear();
        let mut start = 0;
        for run in cross.chunk_by(|x, y| x.key == y.key) {
            self.runs
                .insert(run[0].key, (start as u32, run.len() as u32));
            start += run.len();
        }
    }

    /// The crossings of edge `key` in the indexed list `cross` (sorted along the edge).
    #[inline]
    pub(super) fn of<'c>(&self, cross: &'c [EdgeCrossing], key: u64) -> &'c [EdgeCrossing] {
        match self.runs.get(&key) {
            Some(&(start, len)) => cross
                .get(start as usize..(start + len) as usize)
                .unwrap_or(&[]),
            None => &[],
        }
    }
}

/// Marks over a mesh's vertices or triangles, cleared in O(1) per use: a mark is the current
/// generation's number.
#[derive(Debug, Clone, Default)]
pub(super) struct Stamps {
    stamp: Vec<u32>,
    generation: u32,
}

impl Stamps {
    /// Clears every mark, for `n` items.
    pub(super) fn begin(&mut self, n: usize) {
        if self.stamp.len() < n {
            self.stamp.resize(n, 0);
        }
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.iter_mut().for_each(|x| *x = 0);
            self.generation = 1;
        }
    }

    /// True when item `i` is marked.
    #[inline]
    pub(super) fn is_marked(&self, i: u32) -> bool {
        self.stamp[i as usize] == self.generation
    }

    /// Marks item `i`; true when it was not marked yet.
    #[inline]
    pub(super) fn mark(&mut self, i: u32) -> bool {
        let s = &mut self.stamp[i as usize];
        let new = *s != self.generation;
        *s = self.generation;
        new
    }
}

/// Records where the edges of `t_in` (vertex ids `ids`, points in the common frame) cross
/// the triangle `t_other` (slot `other`, outward normal from its winding), and the crossing
/// points in `points`; `sides`: `t_in`'s corners against `t_other`'s plane. Returns whether a crossing was decided at a coincidence
/// ([`SidesOf::segment_or_coincident`]).
pub(super) fn edge_crossings(
    ids: [u32; 3],
    t_in: &[DVec3; 3],
    other: u32,
    t_other: &[DVec3; 3],
    sides: &PlaneSides,
    out: &mut Vec<EdgeCrossing>,
    points: &mut Vec<DVec3>,
) -> bool {
    // The corners' sides of the other plane, once for the three edges (the exact segment
    // test of each edge reads them).
    let Some(sides) = SidesOf::with(t_other, t_in, sides) else {
        return false;
    };
    let mut coincident = false;
    let n = (t_other[1] - t_other[0]).cross(t_other[2] - t_other[0]);
    for k in 0..3 {
        let (mut u, mut v) = (ids[k], ids[(k + 1) % 3]);
        let (mut pu, mut pv) = (t_in[k], t_in[(k + 1) % 3]);
        let (mut ku, mut kv) = (k, (k + 1) % 3);
        if u == v {
            continue;
        }
        if u > v {
            std::mem::swap(&mut u, &mut v);
            std::mem::swap(&mut pu, &mut pv);
            std::mem::swap(&mut ku, &mut kv);
        }
        let (meets, at_coincidence) = sides.segment_or_coincident(pu, pv, ku, kv);
        coincident |= at_coincidence;
        if !meets {
            continue;
        }
        let du = n.dot(pu - t_other[0]);
        let dv = n.dot(pv - t_other[0]);
        let t = du / (du - dv);
        let t = if t.is_finite() {
            t.clamp(0.0, 1.0)
        } else {
            0.5
        };
        points.push(pu + (pv - pu) * t);
        out.push(EdgeCrossing {
            key: edge_key(u, v),
            other,
            t,
            dir: dv - du,
        });
    }
    coincident
}
