//! Bounding shapes of BVH nodes for the distance branch and bound.
//!
//! Besides its box, every node gets a "flat disc" description about the box centre `c`:
//! a unit direction `n` (the area-weighted mean normal of its triangles), the half thickness
//! `t = max |n·(x − c)|`, the radius `rho = max |x − c − n n·(x − c)|` across `n` and the
//! ball radius `r = max |x − c|` over its vertices `x`. For the small, nearly flat patches
//! near the bottom of the tree this is almost as tight as the patch itself (like PQP's and
//! FCL's swept rectangles), which is where axis-aligned boxes waste the most.

#![allow(clippy::neg_cmp_op_on_partial_ord)] // `!(x < y)` is deliberate: true for NaN too.

use crate::mesh::bvh::TriangleBvh;
use glam::DVec3;
use rayon::prelude::*;

/// The bounding data of one node (local frame of its mesh).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Shape {
    /// Box centre.
    pub c: DVec3,
    /// Box half extents.
    pub h: DVec3,
    /// Unit direction of the slab.
    pub n: DVec3,
    /// Half thickness of the slab about `c` along `n`.
    pub t: f64,
    /// Radius across `n`.
    pub rho: f64,
    /// Ball radius about `c`.
    pub r: f64,
}

/// The shapes of every node of `bvh` (same indices), and the unit normal of every slot
/// (zero for degenerate triangles).
pub(crate) fn shapes(bvh: &TriangleBvh) -> (Vec<Shape>, Vec<DVec3>) {
    let nodes = &bvh.nodes;
    // Slot range of every node: leaves own theirs, inner nodes span their children.
    let mut range = vec![(0u32, 0u32); nodes.len()];
    for i in (0..nodes.len()).rev() {
        let n = &nodes[i];
        range[i] = if n.is_leaf() {
            (n.start, n.start + n.count)
        } else {
            let l = range.get(i + 1).copied().unwrap_or((0, 0));
            let r = range.get(n.start as usize).copied().unwrap_or((0, 0));
            (l.0.min(r.0), l.1.max(r.1))
        };
    }
    let area_normals: Vec<DVec3> = bvh
        .tris
        .iter()
        .map(|t| (t[1] - t[0]).cross(t[2] - t[0]))
        .collect();
    let unit: Vec<DVec3> = area_normals
        .iter()
        .map(|n| {
            let u = n.normalize_or_zero();
            if u.is_finite() {
                u
            } else {
                DVec3::ZERO
            }
        })
        .collect();
    let shapes = nodes
        .par_iter()
        .zip(range.par_iter())
        .map(|(node, &(s, e))| {
            let c = (node.lo + node.hi) * 0.5;
            let h = (node.hi - node.lo) * 0.5;
            let tris = bvh.tris.get(s as usize..e as usize).unwrap_or(&[]);
            let sum: DVec3 = area_normals
                .get(s as usize..e as usize)
                .unwrap_or(&[])
                .iter()
                .copied()
                .sum();
            let mut n = sum.normalize_or_zero();
            if !(n.length_squared() > 0.5) || !n.is_finite() {
                n = DVec3::Z;
            }
            let (mut t, mut rho2, mut r2) = (0.0f64, 0.0f64, 0.0f64);
            for v in tris.iter().flatten() {
                let d = *v - c;
                let along = n.dot(d);
                let l2 = d.length_squared();
                t = t.max(along.abs());
                r2 = r2.max(l2);
                rho2 = rho2.max((d - n * along).length_squared());
            }
            // A hair of slack for the rounding of the sums above.
            let slack = 1e-12 * (c.abs().max_element() + h.max_element());
            Shape {
                c,
                h,
                n,
                t: t + slack,
                rho: rho2.max(0.0).sqrt() + slack,
                r: r2.sqrt() + slack,
            }
        })
        .collect();
    (shapes, unit)
}

/// Squared lower bound on the distance between node `a` and a node of the other mesh whose
/// shape `b` has centre `bc`, box half extents `bh` (padded) and direction `bn` in `a`'s frame.
///
/// The largest of three bounds: the boxes' gap, and for each node's direction `n` the gap
/// along `n` (its slab against the other's extent along `n`: slab and disc tilted by the
/// angle between the directions) combined in quadrature with the gap across `n` (its disc
/// radius and the other's ball). All three hold for any unit directions, so a poor
/// direction (a closed or curved node) only loosens the bound.
#[inline]
pub(crate) fn lower_bound_sq(
    a: &Shape,
    bc: DVec3,
    bh: DVec3,
    bn: DVec3,
    b: &Shape,
    pad: f64,
) -> f64 {
    let d = bc - a.c;
    let g = (d.abs() - a.h - bh).max(DVec3::ZERO);
    let boxes = g.length_squared();
    // Along a's direction: the slab of a against b's extent along it (b's slab tilted by
    // the angle between the directions); across it: the disc radius of a and b's ball.
    // The sine from the cross product and the across distances as vector rejections stay
    // accurate for nearly parallel directions; the small additions cover their rounding.
    let dn = a.n.dot(d);
    let cos = (a.n.dot(bn).abs() + 1e-15).min(1.0);
    let sin = (a.n.cross(bn).length() + 1e-15).min(1.0);
    let gn = (dn.abs() - a.t - (b.t * cos + b.rho * sin) - pad).max(0.0);
    let across = (d - a.n * dn).length();
    let gp = (across - a.rho - b.r - pad).max(0.0);
    // The same with the roles swapped (b's direction).
    let dm = bn.dot(d);
    let gm = (dm.abs() - b.t - (a.t * cos + a.rho * sin) - pad).max(0.0);
    let across_b = (d - bn * dm).length();
    let gq = (across_b - b.rho - a.r - pad).max(0.0);
    boxes.max(gn * gn + gp * gp).max(gm * gm + gq * gq)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact::tri_tri::triangle_distance;
    use glam::{DMat3, DQuat};
    use proptest::prelude::*;

    fn v3(r: f64) -> impl Strategy<Value = DVec3> {
        (-r..r, -r..r, -r..r).prop_map(|(x, y, z)| DVec3::new(x, y, z))
    }

    /// The slab-and-disc bound never exceeds the true distance between the triangles of
    /// two nodes, for every node pair of two random soups at a random relative pose.
    fn check(ta: &[[DVec3; 3]], tb: &[[DVec3; 3]], q: DQuat, t: DVec3) {
        let a = TriangleBvh::from_triangles(ta);
        let b = TriangleBvh::from_triangles(tb);
        let (sa, _) = shapes(&a);
        let (sb, _) = shapes(&b);
        let r = DMat3::from_quat(q);
        let abs_r = DMat3::from_cols(r.x_axis.abs(), r.y_axis.abs(), r.z_axis.abs());
        let range = |bvh: &TriangleBvh, i: usize| -> Vec<[DVec3; 3]> {
            // Triangles below node i: walk the subtree.
            let mut out = Vec::new();
            let mut stack = vec![i];
            while let Some(j) = stack.pop() {
                let n = &bvh.nodes[j];
                if n.is_leaf() {
                    out.extend_from_slice(
                        &bvh.tris[n.start as usize..(n.start + n.count) as usize],
                    );
                } else {
                    stack.push(j + 1);
                    stack.push(n.start as usize);
                }
            }
            out
        };
        for (i, shape_a) in sa.iter().enumerate() {
            let xa = range(&a, i);
            for (j, s) in sb.iter().enumerate() {
                let xb: Vec<[DVec3; 3]> = range(&b, j)
                    .iter()
                    .map(|tri| tri.map(|v| r * v + t))
                    .collect();
                let lb = lower_bound_sq(shape_a, r * s.c + t, abs_r * s.h, r * s.n, s, 0.0);
                let d = xa
                    .iter()
                    .flat_map(|x| xb.iter().map(move |y| triangle_distance(x, y).dist_sq))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    lb <= d * (1.0 + 1e-12) + 1e-24,
                    "node {i} vs {j}: bound {lb} > {d}"
                );
            }
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(40))]

        #[test]
        fn bound_never_exceeds_distance(
            ta in prop::collection::vec((v3(1.0), v3(0.2), v3(0.2)), 1..24),
            tb in prop::collection::vec((v3(1.0), v3(0.2), v3(0.2)), 1..24),
            q in (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, 0.1..1.0f64),
            t in v3(1.5),
        ) {
            let soup = |v: &Vec<(DVec3, DVec3, DVec3)>| -> Vec<[DVec3; 3]> {
                v.iter().map(|&(p, e, f)| [p, p + e, p + f]).collect()
            };
            let q = DQuat::from_xyzw(q.0, q.1, q.2, q.3).normalize();
            check(&soup(&ta), &soup(&tb), q, t);
        }
    }

    #[test]
    fn flat_parallel_patches_are_tight() {
        // Two parallel grids 1 apart: the bound of the root pair is close to 1 although
        // the boxes (tilted by 45°) overlap.
        let grid = |z: f64| -> Vec<[DVec3; 3]> {
            let mut out = Vec::new();
            for i in 0..4 {
                for j in 0..4 {
                    let p = DVec3::new(i as f64 * 0.1, j as f64 * 0.1, z);
                    out.push([p, p + DVec3::X * 0.1, p + DVec3::Y * 0.1]);
                }
            }
            out
        };
        let q = DQuat::from_axis_angle(DVec3::new(1.0, 1.0, 0.0).normalize(), 0.8);
        let a: Vec<[DVec3; 3]> = grid(0.0).iter().map(|t| t.map(|v| q * v)).collect();
        let b = grid(1.0);
        let ba = TriangleBvh::from_triangles(&a);
        let bb = TriangleBvh::from_triangles(&b);
        let (sa, _) = shapes(&ba);
        let (sb, _) = shapes(&bb);
        // B mapped into A's frame by the same rotation.
        let r = DMat3::from_quat(q);
        let abs_r = DMat3::from_cols(r.x_axis.abs(), r.y_axis.abs(), r.z_axis.abs());
        let s = &sb[0];
        let lb = lower_bound_sq(&sa[0], r * s.c, abs_r * s.h, r * s.n, s, 0.0);
        assert!(lb.sqrt() > 0.99, "{}", lb.sqrt());
        check(
            &a,
            &b.iter().map(|t| t.map(|v| q * v)).collect::<Vec<_>>(),
            DQuat::IDENTITY,
            DVec3::ZERO,
        );
    }
}
