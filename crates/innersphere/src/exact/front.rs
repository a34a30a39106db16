//! The front of node pairs that the meshes' penetration carries from one query to the next:
//! where the last traversal stopped, each pair found apart with the lower bound of its gap,
//! each leaf pair to be tested again. The next query re-tests only the pairs that the motion
//! since could have closed (a running bound on how far any point of B moved relative to A),
//! so a haptic frame touches the nodes near the contact instead of the two trees from the
//! root: the traversal of two scans' BVHs is bound by memory, not by its tests.

use super::frame::Frame;
use super::mesh::ExactMesh;
use super::overlap::{leaf_pair, split_pair, PairSides};
use crate::pose::Pose;
use glam::{DMat3, DVec3};

/// A node pair of the front: apart by at least `gap` when the odometer read `at` (a leaf pair
/// that may touch has `gap` 0 and is tested every time).
#[derive(Debug, Clone, Copy)]
struct Entry {
    ia: u32,
    ib: u32,
    gap: f64,
    at: f64,
}

/// The front of one pair of meshes (see the module docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct PairFront {
    entries: Vec<Entry>,
    next: Vec<Entry>,
    stack: Vec<(u32, u32)>,
    /// Sum of the motion bounds of the queries so far.
    odometer: f64,
    /// The last query's relative pose (B in A) and the meshes it was for.
    last: Option<(DMat3, DVec3, usize, usize)>,
    /// Entries after the last traversal from the root: the front restarts from the root when
    /// it has grown well beyond that (contact that moved on leaves fine pairs behind).
    fresh: usize,
    /// Queries still to start from the root after a carried front that the motion had mostly
    /// expired (steps too long for the front to pay).
    cooldown: u32,
    /// Queries run from a carried front (for the tests).
    carried_total: u64,
}

/// After a carried query that had to re-test more than half its entries, this many queries
/// start from the root.
const COOLDOWN: u32 = 8;

impl PairFront {
    /// Queries run from a carried front so far.
    #[cfg(test)]
    pub(crate) fn carried(&self) -> u64 {
        self.carried_total
    }

    /// Forgets the front: the next query starts from the roots.
    pub(crate) fn reset(&mut self) {
        self.last = None;
    }

    /// Calls `leaf` for every triangle pair of `a` and `b` (B's at `rel` in A's frame, `f`)
    /// whose boxes overlap and whose planes do not separate them, as
    /// [`overlap_pairs`](super::overlap::overlap_pairs) does, from the front of the last
    /// query on the same meshes (from the roots when `warm` is false or nothing is carried).
    pub(crate) fn overlap_pairs(
        &mut self,
        a: &ExactMesh,
        b: &ExactMesh,
        rel: &Pose,
        f: &Frame,
        warm: bool,
        mut leaf: impl FnMut(u32, u32, &[DVec3; 3], &[DVec3; 3], &PairSides),
    ) {
        let (ta, tb) = (a.bvh(), b.bvh());
        if ta.nodes.is_empty()
            || tb.nodes.is_empty()
            || a.shapes.len() != ta.nodes.len()
            || b.shapes.len() != tb.nodes.len()
        {
            self.last = None;
            return;
        }
        let r = DMat3::from_quat(rel.rotation);
        let ids = (
            a as *const ExactMesh as usize,
            b as *const ExactMesh as usize,
        );
        let carried = match self.last {
            Some((r0, t0, ia, ib)) if warm && (ia, ib) == ids => {
                self.odometer += motion_bound(b, &r0, t0, &r, rel.translation, f.pad);
                // A front grown to twice a fresh one's size (the contact moved on and left
                // fine pairs behind) restarts from the roots.
                self.cooldown == 0 && self.entries.len() <= 2 * self.fresh.max(128)
            }
            _ => false,
        };
        if carried {
            self.carried_total += 1;
        } else {
            self.cooldown = self.cooldown.saturating_sub(1);
        }
        let mut expired = 0usize;
        self.last = Some((r, rel.translation, ids.0, ids.1));
        if !carried {
            self.entries.clear();
            self.entries.push(Entry {
                ia: 0,
                ib: 0,
                gap: -1.0,
                at: self.odometer,
            });
        }
        let odo = self.odometer;
        self.next.clear();
        let mut touched = false;
        for e in &self.entries {
            // Still apart: it moved less than its gap since.
            if e.gap > odo - e.at {
                self.next.push(*e);
                continue;
            }
            expired += 1;
            // The pair's own bound first: it may still be apart, by a new gap.
            let lb = f.lower_bound_sq(&a.shapes[e.ia as usize], &b.shapes[e.ib as usize]);
            if lb > 0.0 {
                self.next.push(Entry {
                    gap: shrink(lb),
                    at: odo,
                    ..*e
                });
                continue;
            }
            self.stack.clear();
            self.stack.push((e.ia, e.ib));
            while let Some((ia, ib)) = self.stack.pop() {
                let (na, nb) = (&ta.nodes[ia as usize], &tb.nodes[ib as usize]);
                if na.is_leaf() && nb.is_leaf() {
                    touched = true;
                    leaf_pair(a, b, f, ia, ib, &mut |sa, sb, x, y, sides| {
                        leaf(sa, sb, x, y, sides);
                        false
                    });
                    self.next.push(Entry {
                        ia,
                        ib,
                        gap: 0.0,
                        at: odo,
                    });
                    continue;
                }
                let (stack, next) = (&mut self.stack, &mut self.next);
                split_pair(a, b, f, ia, ib, |x, y, lb| {
                    if lb > 0.0 {
                        next.push(Entry {
                            ia: x,
                            ib: y,
                            gap: shrink(lb),
                            at: odo,
                        });
                    } else {
                        stack.push((x, y));
                    }
                });
            }
        }
        if carried && 2 * expired > self.entries.len() {
            self.cooldown = COOLDOWN;
        }
        std::mem::swap(&mut self.entries, &mut self.next);
        if !carried {
            self.fresh = self.entries.len();
        }
        // Nothing near: the next query starts from the roots (one bound, and a compact front).
        if !touched {
            self.last = None;
        }
    }
}

/// A gap from a squared lower bound, rounded down (the bound carries its own padding).
#[inline]
fn shrink(lb_sq: f64) -> f64 {
    lb_sq.sqrt() * (1.0 - 1e-12)
}

/// How far any point of `b` may have moved, relative to A, from the frame `(r0, t0)` to
/// `(r1, t1)`: the move of the centre `c` of its box plus the rotation's change (its Frobenius
/// norm, at least the spectral one) times the box's half diagonal, padded for rounding.
fn motion_bound(b: &ExactMesh, r0: &DMat3, t0: DVec3, r1: &DMat3, t1: DVec3, pad: f64) -> f64 {
    let Some((lo, hi)) = b.bvh().bounds() else {
        return f64::INFINITY;
    };
    let (c, rho) = ((lo + hi) * 0.5, (hi - lo).length() * 0.5);
    let dr = *r1 - *r0;
    let frob =
        (dr.x_axis.length_squared() + dr.y_axis.length_squared() + dr.z_axis.length_squared())
            .sqrt();
    let d = ((*r1 * c + t1) - (*r0 * c + t0)).length() + frob * rho;
    let d = d * (1.0 + 1e-9) + 4.0 * pad;
    if d.is_finite() {
        d
    } else {
        f64::INFINITY
    }
}
