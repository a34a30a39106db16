//! Signed gaps from the vertices of one mesh to the surface of another: what a contact map
//! colours (an arch by its clearance to the opposing one).

use super::mesh::ExactMesh;
use crate::mesh::union_find::UnionFind;
use crate::pose::Pose;
use glam::DVec3;
use rayon::prelude::*;

/// The signed gap of every vertex of `a` at `pose_a` to the surface of `b` at `pose_b`
/// (world poses): the exact f64 distance to `b`'s nearest triangle, negative where the
/// vertex lies inside `b` (generalized winding number ≥ ½, so `b` should be closed).
///
/// A gap beyond `cap` is reported as `cap` (`f64::INFINITY` for none): the nearest-triangle
/// search then prunes everything farther, which is most of an arch. Gaps below `cap` and
/// every negative gap are exact. A non-finite pose gives NaN gaps.
///
/// Which vertices are inside, without a winding number per vertex (that was two thirds of
/// the time on the jaw pair): an edge of `a` shorter than the sum of its ends' distances to
/// `b`'s surface cannot cross that surface (a crossing point would lie within the edge's
/// length of both ends), so its ends are on the same side. The vertices joined by such edges
/// form groups; one winding number per group, at its vertex farthest from the surface,
/// decides the group. The distances run in parallel (rayon) and the groups are found in
/// order, so the answers are the same on any number of threads.
pub fn vertex_gaps(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    cap: f64,
) -> Vec<f64> {
    // A's vertices into B's frame.
    let to_b = pose_b.inverse().then(pose_a);
    let cap = if cap.is_nan() {
        f64::INFINITY
    } else {
        cap.max(0.0)
    };
    let pts: Vec<DVec3> = a
        .mesh()
        .vertices
        .par_iter()
        .map(|&v| to_b.transform_point(v))
        .collect();
    if pts.iter().any(|p| !p.is_finite()) {
        return vec![f64::NAN; pts.len()];
    }
    // Unsigned distances, capped (a lower bound of the true distance where capped).
    let bvh = b.bvh();
    let mut gaps: Vec<f64> = pts
        .par_iter()
        .map(|&p| match bvh.closest_point(p, cap * cap) {
            Some(c) => c.dist_sq.sqrt().min(cap),
            None => cap,
        })
        .collect();
    // Groups of vertices on one side of B's surface (union-find over the safe edges).
    let n = pts.len();
    let mut sets = UnionFind::new(n);
    for u in 0..n {
        for &v in a.neighbours(u as u32) {
            let v = v as usize;
            if v > u && (pts[u] - pts[v]).length() < gaps[u] + gaps[v] {
                sets.union(u as u32, v as u32);
            }
        }
    }
    // Each group's vertex farthest from the surface (the first such in vertex order).
    let mut far: Vec<u32> = vec![u32::MAX; n];
    let mut roots = Vec::new();
    for v in 0..n {
        let r = sets.find(v as u32) as usize;
        if far[r] == u32::MAX {
            roots.push(r);
            far[r] = v as u32;
        } else if gaps[v] > gaps[far[r] as usize] {
            far[r] = v as u32;
        }
    }
    let (lo, hi) = b.mesh().bbox();
    let inside_root: Vec<bool> = roots
        .par_iter()
        .map(|&r| {
            let p = pts[far[r] as usize];
            p.cmpge(lo).all() && p.cmple(hi).all() && b.contains_point(p)
        })
        .collect();
    let mut inside = vec![false; n];
    for (&r, &i) in roots.iter().zip(&inside_root) {
        inside[r] = i;
    }
    let side: Vec<bool> = (0..n)
        .map(|v| inside[sets.find(v as u32) as usize])
        .collect();
    // Inside: the exact distance, negative (also beyond the cap).
    gaps.par_iter_mut().enumerate().for_each(|(v, g)| {
        if side[v] {
            *g = match bvh.closest_point(pts[v], f64::INFINITY) {
                Some(c) => -c.dist_sq.sqrt(),
                None => f64::NAN,
            };
        }
    });
    gaps
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::closest::point_triangle_distance_sq;
    use crate::shapes;

    /// Against every triangle, on two balls overlapping by a known amount.
    #[test]
    fn gaps_are_the_brute_force_distances_with_the_sign_of_inside() {
        let ball = shapes::icosphere(3);
        let a = ExactMesh::new(&ball).unwrap();
        let b = ExactMesh::new(&ball).unwrap();
        let pose_b = Pose::from_translation(DVec3::new(1.5, 0.2, 0.0));
        let g = vertex_gaps(&a, &Pose::IDENTITY, &b, &pose_b, f64::INFINITY);
        let inv = pose_b.inverse();
        let m = b.mesh();
        let mut inside = 0;
        for (v, &gv) in ball.vertices.iter().zip(&g) {
            let p = inv.transform_point(*v);
            let d = m
                .triangles
                .iter()
                .map(|t| {
                    let [x, y, z] = t.map(|i| m.vertices[i as usize]);
                    point_triangle_distance_sq(p, x, y, z)
                })
                .fold(f64::INFINITY, f64::min)
                .sqrt();
            assert!((gv.abs() - d).abs() <= 1e-12, "{gv} vs {d}");
            // The polyhedral ball is within 1 % of the unit ball.
            let r = p.length();
            if r < 0.98 {
                assert!(gv < 0.0, "{p} at {r}: {gv}");
                inside += 1;
            } else if r > 1.02 {
                assert!(gv > 0.0, "{p} at {r}: {gv}");
            }
        }
        assert!(inside > 10);
        // Capped: the same below the cap, the cap beyond.
        let c = vertex_gaps(&a, &Pose::IDENTITY, &b, &pose_b, 0.5);
        for (&gv, &cv) in g.iter().zip(&c) {
            assert_eq!(cv, gv.min(0.5));
        }
        // A NaN pose gives NaN, never a panic.
        let nan = Pose::from_translation(DVec3::splat(f64::NAN));
        assert!(vertex_gaps(&a, &Pose::IDENTITY, &b, &nan, 1.0)
            .iter()
            .all(|g| g.is_nan()));
    }
}
