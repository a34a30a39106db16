//! The parts of the intersection's surface grouped into its connected pieces (the contact
//! patches of [`intersection_volume`](super::intersection_volume)), each piece's volume,
//! push direction, centre and mean depth, and the area moments of B's surface inside A that
//! linearise the penalty wrench.
//!
//! A piece of `A ∩ B` is bounded by parts of both surfaces. Two parts belong to the same
//! piece when a crossing segment joins them (A's triangle and B's meet along it) or when they
//! share a vertex that lies inside the other body (the triangles around it are all partly
//! inside, around that vertex). Union–find over the parts, allocation-free once warm.

use crate::mesh::union_find::UnionFind;
use glam::{DMat3, DVec3};

/// One triangle's part inside the other body (A's frame): what the volume, the gradient and
/// the patches read.
#[derive(Debug, Clone, Copy)]
pub(super) struct PartRec {
    /// The triangle's BVH slot in its mesh.
    pub(super) slot: u32,
    /// True for a part of B's surface (inside A).
    pub(super) of_b: bool,
    /// Unit normal of the triangle (outward of its body).
    pub(super) n: DVec3,
    /// First corner of the triangle (the fan's apex).
    pub(super) p0: DVec3,
    /// Area of the part.
    pub(super) area: f64,
    /// First moment `∫ x dS` of the part.
    pub(super) moment: DVec3,
}

/// One connected piece of the intersection (A's frame).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct OverlapPatch {
    /// Centre of B's surface inside A in this piece (area-weighted; of A's inside B when
    /// none of B's bounds it).
    pub point: DVec3,
    /// Unit direction B is pushed out of this piece (`−` the vector area of B's surface in
    /// it); zero when that vanishes (B wholly inside A there).
    pub normal: DVec3,
    /// Mean thickness of the piece along `normal`: its volume over B's surface in it
    /// projected across `normal` (`|∇V|` of the piece). For a flat contact the depth
    /// exactly; for a lens about half its peak. 0 without a normal.
    pub depth: f64,
    /// Volume of the piece.
    pub volume: f64,
    /// Triangle pairs crossing in it.
    pub pairs: u32,
}

/// `Σ a·n nᵀ`, `Σ a·n (r × n)ᵀ`, `Σ a·(r × n)(r × n)ᵀ` over the parts of B's surface inside
/// A (`a` a part's area, `r` from B's centre of mass to the part's centroid): the
/// Gauss–Newton linearisation of the penalty wrench, per unit stiffness (A's frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AreaMoments {
    /// `Σ a·n nᵀ` (force per translation).
    pub linear: DMat3,
    /// `Σ a·n (r × n)ᵀ` (force per rotation; torque per translation transposed).
    pub coupling: DMat3,
    /// `Σ a·(r × n)(r × n)ᵀ` (torque per rotation).
    pub angular: DMat3,
}

impl Default for AreaMoments {
    /// Zero. By hand: glam's default matrix is the identity.
    fn default() -> Self {
        AreaMoments {
            linear: DMat3::ZERO,
            coupling: DMat3::ZERO,
            angular: DMat3::ZERO,
        }
    }
}

impl AreaMoments {
    /// Adds a part of area `a`, unit normal `n`, centroid `x`, about centre `c`.
    #[inline]
    pub(super) fn add(&mut self, a: f64, n: DVec3, x: DVec3, c: DVec3) {
        let s = (x - c).cross(n);
        self.linear += outer(n * a, n);
        self.coupling += outer(n * a, s);
        self.angular += outer(s * a, s);
    }

    /// Rotated into another frame: `R M Rᵀ` block by block.
    pub(crate) fn rotated(&self, r: DMat3) -> AreaMoments {
        let rt = r.transpose();
        AreaMoments {
            linear: r * self.linear * rt,
            coupling: r * self.coupling * rt,
            angular: r * self.angular * rt,
        }
    }
}

/// `u vᵀ`.
#[inline]
fn outer(u: DVec3, v: DVec3) -> DMat3 {
    DMat3::from_cols(u * v.x, u * v.y, u * v.z)
}

/// The patch accumulator of one piece.
#[derive(Debug, Clone, Copy, Default)]
struct Acc {
    origin: DVec3,
    volume: f64,
    grad: DVec3,
    /// Area and first moment of B's parts, of A's parts.
    area: [f64; 2],
    moment: [DVec3; 2],
    pairs: u32,
}

/// The parts of one query and the memory that groups them.
#[derive(Debug, Clone, Default)]
pub(super) struct Grouping {
    pub(super) parts: Vec<PartRec>,
    /// Slot → part index, per mesh (valid where the part it names has that slot and side).
    node_a: Vec<u32>,
    node_b: Vec<u32>,
    sets: UnionFind,
    patch_of: Vec<u32>,
    acc: Vec<Acc>,
    /// The pieces of the last query (A's frame), the largest volume first.
    pub(super) patches: Vec<OverlapPatch>,
}

impl Grouping {
    /// Forgets the last query's parts.
    pub(super) fn clear(&mut self) {
        self.parts.clear();
        self.sets.clear();
    }

    /// Records a part (`tris`: the triangles of its mesh).
    pub(super) fn push(&mut self, rec: PartRec, tris: usize) {
        let i = self.parts.len() as u32;
        let map = if rec.of_b {
            &mut self.node_b
        } else {
            &mut self.node_a
        };
        if map.len() < tris {
            map.resize(tris, u32::MAX);
        }
        map[rec.slot as usize] = i;
        self.parts.push(rec);
        self.sets.push();
    }

    /// The part of triangle `slot` of A (`of_b` false) or B in this query, if it has one.
    #[inline]
    fn node(&self, of_b: bool, slot: u32) -> Option<u32> {
        let map = if of_b { &self.node_b } else { &self.node_a };
        let i = *map.get(slot as usize)?;
        let r = self.parts.get(i as usize)?;
        (r.slot == slot && r.of_b == of_b).then_some(i)
    }

    /// Joins the parts of the triangles in `slots` (all around one inside vertex).
    pub(super) fn join_around(&mut self, of_b: bool, slots: &[u32]) {
        let mut first = None;
        for &t in slots {
            if let Some(i) = self.node(of_b, t) {
                match first {
                    None => first = Some(i),
                    Some(f) => {
                        self.sets.union(f, i);
                    }
                }
            }
        }
    }

    /// Joins A's part of `slot_a` and B's of `slot_b` (they cross).
    pub(super) fn join_crossing(&mut self, slot_a: u32, slot_b: u32) {
        if let (Some(x), Some(y)) = (self.node(false, slot_a), self.node(true, slot_b)) {
            self.sets.union(x, y);
        }
    }

    /// Groups the parts into pieces (after every join): `patches`, the largest first;
    /// `crossings` the crossing pairs' slots. Returns the largest depth.
    pub(super) fn group(&mut self, crossings: impl Iterator<Item = (u32, u32)>) -> f64 {
        self.patches.clear();
        self.acc.clear();
        self.patch_of.clear();
        self.patch_of.resize(self.parts.len(), u32::MAX);
        for i in 0..self.parts.len() as u32 {
            let root = self.sets.find(i) as usize;
            if self.patch_of[root] == u32::MAX {
                self.patch_of[root] = self.acc.len() as u32;
                self.acc.push(Acc {
                    origin: self.parts[i as usize].p0,
                    ..Acc::default()
                });
            }
            let k = self.patch_of[root];
            self.patch_of[i as usize] = k;
            let r = self.parts[i as usize];
            let acc = &mut self.acc[k as usize];
            // About the piece's own origin: a closed piece's sum does not depend on it.
            acc.volume += r.n.dot(r.p0 - acc.origin) * r.area;
            if r.of_b {
                acc.grad += r.n * r.area;
            }
            let side = usize::from(!r.of_b);
            acc.area[side] += r.area;
            acc.moment[side] += r.moment;
        }
        for (sa, _) in crossings {
            if let Some(x) = self.node(false, sa) {
                let k = self.patch_of[x as usize];
                self.acc[k as usize].pairs += 1;
            }
        }
        let mut deepest = 0.0f64;
        for acc in &self.acc {
            let g = acc.grad.length();
            let volume = (acc.volume / 3.0).max(0.0);
            // Without a usable direction (B's surface in the piece closes on itself) the
            // piece has no depth to push out of.
            let (normal, depth) = if g > 1e-12 * acc.area[0] {
                (-acc.grad / g, volume / g)
            } else {
                (DVec3::ZERO, 0.0)
            };
            let side = if acc.area[0] > 0.0 { 0 } else { 1 };
            deepest = deepest.max(depth);
            self.patches.push(OverlapPatch {
                point: acc.moment[side] / acc.area[side].max(f64::MIN_POSITIVE),
                normal,
                depth,
                volume,
                pairs: acc.pairs,
            });
        }
        // Unstable (no allocation), ties broken by the point: the same order every time.
        self.patches.sort_unstable_by(|x, y| {
            y.volume
                .total_cmp(&x.volume)
                .then(x.point.x.total_cmp(&y.point.x))
                .then(x.point.y.total_cmp(&y.point.y))
                .then(x.point.z.total_cmp(&y.point.z))
        });
        deepest
    }
}
