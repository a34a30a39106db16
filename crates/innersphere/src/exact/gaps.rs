//! Signed gaps from the vertices of one mesh to the surface of another: what a contact map
//! colours (an arch by its clearance to the opposing one).

use super::mesh::ExactMesh;
use crate::pose::Pose;
use glam::DVec3;
use rayon::prelude::*;

/// The signed gap of every vertex of `a` at `pose_a` to the surface of `b` at `pose_b`
/// (world poses): the exact f64 distance to `b`'s nearest triangle, negative where the
/// vertex lies inside `b` (generalized winding number ≥ ½, so `b` should be closed).
///
/// A gap beyond `cap` is reported as `cap` (`f64::INFINITY` for none): the nearest-triangle
/// search then prunes everything farther, which is most of an arch. Gaps below `cap` and
/// every negative gap are exact. Vertices run in parallel (rayon); each is computed alone,
/// so the answers are the same on any number of threads. A non-finite pose gives NaN gaps.
pub fn vertex_gaps(
    a: &ExactMesh,
    pose_a: &Pose,
    b: &ExactMesh,
    pose_b: &Pose,
    cap: f64,
) -> Vec<f64> {
    // A's vertices into B's frame.
    let to_b = pose_b.inverse().then(pose_a);
    let (lo, hi) = b.mesh().bbox();
    let cap = if cap.is_nan() {
        f64::INFINITY
    } else {
        cap.max(0.0)
    };
    a.mesh()
        .vertices
        .par_iter()
        .map(|&v| gap(b, to_b.transform_point(v), lo, hi, cap))
        .collect()
}

/// The signed gap of `p` (B's frame) to `b`'s surface, capped at `cap` outside.
fn gap(b: &ExactMesh, p: DVec3, lo: DVec3, hi: DVec3, cap: f64) -> f64 {
    if !p.is_finite() {
        return f64::NAN;
    }
    let in_box = p.cmpge(lo).all() && p.cmple(hi).all();
    if in_box && b.contains_point(p) {
        return match b.bvh().closest_point(p, f64::INFINITY) {
            Some(c) => -c.dist_sq.sqrt(),
            None => f64::NAN,
        };
    }
    match b.bvh().closest_point(p, cap * cap) {
        Some(c) => c.dist_sq.sqrt().min(cap),
        None => cap,
    }
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
