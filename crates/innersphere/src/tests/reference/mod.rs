//! An independent f64 reference for every query kind, sharing no code with the queries.
//!
//! It reads only a tree's public arrays (leaf centres, radii, parents, depths, the centre of
//! mass in its meta) and a [`Pose`]'s quaternion and translation, and computes everything
//! itself, in f64 and in the world frame: the rotation matrix from the quaternion, the leaf
//! spheres' world centres, sphere distances and overlaps, the lens volume and centroid (by
//! exact integration of the cross-section area, not the cap formulas the queries use), the
//! force `Σ fᵢ` and the torques `Σ (gᵢ − c) × fᵢ`.
//!
//! The queries transform B's centres in f32, so a leaf pair within rounding distance of
//! touching may be decided either way; [`RefPair::eps`] is that band, and comparisons treat
//! pairs inside it as undecided.
#![allow(dead_code)]

pub(super) mod checks;

use glam::DVec3;
use innersphere::Pose;
use innersphere::SphereTree;

/// A 3-vector as plain numbers.
pub(super) type V3 = [f64; 3];

fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
/// Euclidean length.
pub(super) fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
/// As a glam vector, for comparisons with query results.
pub(super) fn dv(a: V3) -> DVec3 {
    DVec3::new(a[0], a[1], a[2])
}

/// The rotation matrix (rows) of the unit quaternion `w + xi + yj + zk`, normalised here.
pub(super) fn rotation_matrix(w: f64, x: f64, y: f64, z: f64) -> [V3; 3] {
    let n = (w * w + x * x + y * y + z * z).sqrt();
    let (w, x, y, z) = (w / n, x / n, y / n, z / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// A pose as a matrix and a translation: `p' = M·p + t`.
#[derive(Debug, Clone, Copy)]
pub(super) struct RefPose {
    pub m: [V3; 3],
    pub t: V3,
}

impl RefPose {
    /// From the quaternion and translation stored in `p`.
    pub(super) fn of(p: &Pose) -> RefPose {
        let q = p.rotation;
        RefPose {
            m: rotation_matrix(q.w, q.x, q.y, q.z),
            t: [p.translation.x, p.translation.y, p.translation.z],
        }
    }
    /// `M·v`.
    pub(super) fn rotate(&self, v: V3) -> V3 {
        [dot(self.m[0], v), dot(self.m[1], v), dot(self.m[2], v)]
    }
    /// `M·p + t`.
    pub(super) fn apply(&self, p: V3) -> V3 {
        add(self.rotate(p), self.t)
    }
}

/// A leaf sphere in the world frame.
#[derive(Debug, Clone, Copy)]
pub(super) struct Ball {
    /// Node index in its tree.
    pub node: u32,
    pub c: V3,
    pub r: f64,
}

/// The leaf spheres of `t` at `pose`, world frame, ascending node index.
pub(super) fn world_leaves(t: &SphereTree, pose: &Pose) -> Vec<Ball> {
    let p = RefPose::of(pose);
    (0..t.child_count.len())
        .filter(|&n| t.child_count[n] == 0)
        .map(|n| Ball {
            node: n as u32,
            c: p.apply([t.x[n] as f64, t.y[n] as f64, t.z[n] as f64]),
            r: t.r[n] as f64,
        })
        .collect()
}

/// `|cb − ca| − ra − rb`.
pub(super) fn gap(a: &Ball, b: &Ball) -> f64 {
    norm(sub(b.c, a.c)) - a.r - b.r
}

/// Volume of the intersection of two balls of radii `ra`, `rb` whose centres are `d` apart,
/// and the distance of its centroid from A's centre along the line to B's.
///
/// Integrates the cross-section area along that line: on `[lo, hi]` (where both balls are)
/// the section is the smaller of the two discs, `π(ra² − x²)` and `π(rb² − (x − d)²)`,
/// which cross at `x0`; each piece is a quadratic in `x`, so Simpson's rule is exact for
/// both the volume `∫A` and the moment `∫x·A` (a cubic).
pub(super) fn lens(ra: f64, rb: f64, d: f64) -> (f64, f64) {
    let pi = std::f64::consts::PI;
    let lo = (-ra).max(d - rb);
    let hi = ra.min(d + rb);
    if hi <= lo {
        return (0.0, 0.0);
    }
    let area = |x: f64| {
        let sa = ra * ra - x * x;
        let sb = rb * rb - (x - d) * (x - d);
        pi * sa.min(sb).max(0.0)
    };
    // Below x0 B's disc is the smaller one, above it A's (for d > 0).
    let x0 = if d > 0.0 {
        ((d * d + ra * ra - rb * rb) / (2.0 * d)).clamp(lo, hi)
    } else {
        lo
    };
    let simpson = |f: &dyn Fn(f64) -> f64, a: f64, b: f64| {
        (b - a) / 6.0 * (f(a) + 4.0 * f(0.5 * (a + b)) + f(b))
    };
    let (mut v, mut m) = (0.0, 0.0);
    for (s, e) in [(lo, x0), (x0, hi)] {
        if e > s {
            v += simpson(&area, s, e);
            m += simpson(&|x| x * area(x), s, e);
        }
    }
    if v <= 0.0 {
        (0.0, 0.0)
    } else {
        (v, m / v)
    }
}

/// The leaf spheres of both trees at their poses, and the centres of mass, all world frame.
pub(super) struct RefPair {
    pub a: Vec<Ball>,
    pub b: Vec<Ball>,
    pub com_a: V3,
    pub com_b: V3,
    /// Rounding band: pairs with `|gap| < eps` may be decided either way by the queries.
    pub eps: f64,
}

/// Penetration as the reference computes it (world frame).
#[derive(Debug, Clone, Copy)]
pub(super) struct RefPenetration {
    pub volume: f64,
    pub pairs: usize,
    pub max_depth: f64,
    pub normal: V3,
    pub force: V3,
    pub torque_a: V3,
    pub torque_b: V3,
    /// Σ vᵢ·gᵢ, the first moment of the intersection volume.
    pub moment: V3,
    /// Σ |gᵢ − c_a|·|fᵢ| + Σ |gᵢ − c_b|·|fᵢ|: the scale of the torques' rounding.
    pub torque_scale: f64,
    /// |Σ vᵢ·uᵢ|: small when opposing contacts cancel (then the normal is ill-conditioned).
    pub vu_len: f64,
}

impl RefPair {
    /// The pair at world poses `pa`, `pb`.
    pub(super) fn new(a: &SphereTree, pa: &Pose, b: &SphereTree, pb: &Pose) -> RefPair {
        let ca = a.meta.center_of_mass;
        let cb = b.meta.center_of_mass;
        let la = world_leaves(a, pa);
        let lb = world_leaves(b, pb);
        // f32 centres of magnitude up to `extent` carry ~6e-8 relative error per operation.
        let extent = la
            .iter()
            .chain(&lb)
            .map(|s| norm(s.c) + s.r)
            .fold(0.0, f64::max)
            + norm(RefPose::of(pa).t)
            + norm(RefPose::of(pb).t);
        RefPair {
            com_a: RefPose::of(pa).apply(ca),
            com_b: RefPose::of(pb).apply(cb),
            a: la,
            b: lb,
            eps: 2e-6 * (1.0 + extent),
        }
    }

    /// The leaf of A with node index `n`.
    pub(super) fn leaf_a(&self, n: u32) -> &Ball {
        &self.a[self
            .a
            .binary_search_by_key(&n, |s| s.node)
            .expect("a leaf of A")]
    }
    /// The leaf of B with node index `n`.
    pub(super) fn leaf_b(&self, n: u32) -> &Ball {
        &self.b[self
            .b
            .binary_search_by_key(&n, |s| s.node)
            .expect("a leaf of B")]
    }

    /// Every leaf pair as (leaf of A, leaf of B, gap).
    pub(super) fn pairs(&self) -> impl Iterator<Item = (&Ball, &Ball, f64)> + '_ {
        self.a
            .iter()
            .flat_map(move |x| self.b.iter().map(move |y| (x, y, gap(x, y))))
    }

    /// The smallest gap over all leaf pairs and its pair (node indices).
    pub(super) fn min_gap(&self) -> (f64, u32, u32) {
        self.pairs().fold((f64::INFINITY, 0, 0), |best, (x, y, g)| {
            if g < best.0 {
                (g, x.node, y.node)
            } else {
                best
            }
        })
    }

    /// Node pairs with gap below `limit` (`-eps`: surely overlapping; `eps`: possibly).
    pub(super) fn overlapping(&self, limit: f64) -> Vec<(u32, u32)> {
        self.pairs()
            .filter(|p| p.2 < limit)
            .map(|(x, y, _)| (x.node, y.node))
            .collect()
    }

    /// Closest points of a leaf pair on the two spheres: `ca + ra·u`, `cb − rb·u`.
    pub(super) fn closest_points(&self, la: u32, lb: u32) -> (V3, V3) {
        let (x, y) = (self.leaf_a(la), self.leaf_b(lb));
        let d = sub(y.c, x.c);
        let u = scale(d, 1.0 / norm(d));
        (add(x.c, scale(u, x.r)), sub(y.c, scale(u, y.r)))
    }

    /// The contact point of an overlapping leaf pair: on the centre line, in the middle of
    /// the overlap.
    pub(super) fn contact_point(&self, la: u32, lb: u32) -> (V3, f64) {
        let (x, y) = (self.leaf_a(la), self.leaf_b(lb));
        let d = sub(y.c, x.c);
        let len = norm(d);
        let depth = x.r + y.r - len;
        let u = if len > 0.0 {
            scale(d, 1.0 / len)
        } else {
            [0.0; 3]
        };
        (add(x.c, scale(u, x.r - 0.5 * depth)), depth)
    }

    /// Volume, normal, force (`k·V·n`, split into per-pair forces `fᵢ = s·vᵢ·uᵢ` that sum to
    /// it), torques about both centres of mass, over the pairs with gap below `limit`.
    pub(super) fn penetration(&self, k: f64, limit: f64) -> RefPenetration {
        let mut pairs = Vec::new();
        let (mut volume, mut max_depth) = (0.0, 0.0f64);
        let mut vu = [0.0; 3];
        let mut moment = [0.0; 3];
        for (x, y, g) in self.pairs() {
            if g >= limit {
                continue;
            }
            let d = sub(y.c, x.c);
            let len = norm(d);
            let u = if len > 0.0 {
                scale(d, 1.0 / len)
            } else {
                [0.0; 3]
            };
            let (v, along) = lens(x.r, y.r, len);
            let g = add(x.c, scale(u, along));
            volume += v;
            max_depth = max_depth.max(-gap(x, y));
            vu = add(vu, scale(u, v));
            moment = add(moment, scale(g, v));
            pairs.push((v, u, g));
        }
        let len = norm(vu);
        let mut out = RefPenetration {
            volume,
            pairs: pairs.len(),
            max_depth,
            normal: [0.0; 3],
            force: [0.0; 3],
            torque_a: [0.0; 3],
            torque_b: [0.0; 3],
            moment,
            torque_scale: 0.0,
            vu_len: len,
        };
        if len <= 0.0 || volume <= 0.0 {
            return out;
        }
        let s = k * volume / len;
        out.normal = scale(vu, 1.0 / len);
        for (v, u, g) in pairs {
            let f = scale(u, s * v);
            out.force = add(out.force, f);
            out.torque_b = add(out.torque_b, cross(sub(g, self.com_b), f));
            out.torque_a = sub(out.torque_a, cross(sub(g, self.com_a), f));
            out.torque_scale +=
                (norm(sub(g, self.com_a)) + norm(sub(g, self.com_b)) + 1.0) * norm(f);
        }
        out
    }

    /// A bound on how much the queries' volume may differ from [`RefPair::penetration`] with
    /// `limit = 0`: each pair within the rounding band may be in or out, and every pair's
    /// volume moves with its centre distance by at most its section area times `eps`.
    pub(super) fn volume_tolerance(&self) -> f64 {
        let pi = std::f64::consts::PI;
        self.pairs()
            .filter(|p| p.2 < self.eps)
            .map(|(x, y, g)| {
                let r = x.r.min(y.r);
                let band = if g > -self.eps {
                    lens(x.r, y.r, (norm(sub(y.c, x.c)) - self.eps).max(0.0)).0
                } else {
                    0.0
                };
                band + pi * r * r * 2.0 * self.eps
            })
            .sum::<f64>()
            + 1e-12
    }
}

/// The ancestor of node `n` at depth `d` (itself when shallower).
pub(super) fn ancestor_at(t: &SphereTree, mut n: u32, d: u32) -> u32 {
    while t.depth[n as usize] as u32 > d {
        n = t.parent[n as usize];
    }
    n
}

/// A tree made by hand: a root enclosing `leaves` (centre, radius; at most 4) as its
/// children, the centre of mass at `com`.
pub(super) fn hand_tree(leaves: &[(V3, f64)], com: V3) -> SphereTree {
    use innersphere::tree::{TreeMeta, NO_PARENT};
    assert!(!leaves.is_empty() && leaves.len() <= 4);
    let meta = TreeMeta {
        center_of_mass: com,
        ..TreeMeta::unmeasured(4, 0.1, [-10.0; 3], [10.0; 3])
    };
    if leaves.len() == 1 {
        let (c, r) = leaves[0];
        return SphereTree {
            x: vec![c[0] as f32],
            y: vec![c[1] as f32],
            z: vec![c[2] as f32],
            r: vec![r as f32],
            first_child: vec![0],
            child_count: vec![0],
            parent: vec![NO_PARENT],
            depth: vec![0],
            meta,
        };
    }
    // Root: centroid of the centres, radius reaching every leaf (rounded up generously).
    let n = leaves.len() as f64;
    let c = leaves
        .iter()
        .fold([0.0; 3], |s, l| add(s, scale(l.0, 1.0 / n)));
    let r = leaves
        .iter()
        .map(|l| norm(sub(l.0, c)) + l.1)
        .fold(0.0, f64::max)
        * (1.0 + 1e-5);
    let mut t = SphereTree {
        x: vec![c[0] as f32],
        y: vec![c[1] as f32],
        z: vec![c[2] as f32],
        r: vec![r as f32],
        first_child: vec![1],
        child_count: vec![leaves.len() as u8],
        parent: vec![NO_PARENT],
        depth: vec![0],
        meta,
    };
    for &(c, r) in leaves {
        t.x.push(c[0] as f32);
        t.y.push(c[1] as f32);
        t.z.push(c[2] as f32);
        t.r.push(r as f32);
        t.first_child.push(0);
        t.child_count.push(0);
        t.parent.push(0);
        t.depth.push(1);
    }
    t.validate_structure().unwrap();
    t
}
