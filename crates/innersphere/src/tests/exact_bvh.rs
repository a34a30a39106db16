//! BVH-vs-BVH exact distance, intersection and penetration depth against brute force over
//! all triangle pairs on small meshes at random poses.

use innersphere::exact::{
    brute_force_distance, brute_force_intersects, distance, intersects, penetration,
    penetration_depth, triangle_distance, Body, ExactMesh, ExactScratch,
};
use innersphere::glam::{DQuat, DVec3};
use innersphere::mesh::winding::exact_winding_number;
use innersphere::Pose;
use innersphere::{shapes, Mesh};
use proptest::prelude::*;

/// A perturbed icosphere or box: `kind` 0..=2.
fn body(kind: u8, sub: u32, noise: &[f64], scale: DVec3) -> Mesh {
    let mut m = match kind {
        0 => shapes::icosphere(sub),
        1 => shapes::cuboid(DVec3::ONE),
        _ => shapes::torus(1.0, 0.35, 10, 6),
    };
    for (i, v) in m.vertices.iter_mut().enumerate() {
        let k = noise[i % noise.len()];
        *v = *v * scale * (1.0 + 0.15 * k);
    }
    m
}

fn pose() -> impl Strategy<Value = Pose> {
    (
        (-2.5..2.5f64, -2.5..2.5f64, -2.5..2.5f64),
        (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64),
    )
        .prop_map(|((x, y, z), (w, i, j, k))| {
            Pose::new(DVec3::new(x, y, z), DQuat::from_xyzw(i, j, k, w + 1e-3))
                .unwrap_or(Pose::IDENTITY)
        })
}

fn mesh_strategy() -> impl Strategy<Value = Mesh> {
    (
        0u8..3,
        0u32..3,
        prop::collection::vec(-1.0..1.0f64, 1..40),
        (0.3..1.5f64, 0.3..1.5f64, 0.3..1.5f64),
    )
        .prop_map(|(kind, sub, noise, (x, y, z))| body(kind, sub, &noise, DVec3::new(x, y, z)))
}

fn close(x: f64, y: f64) -> bool {
    (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-300) || (x - y).abs() <= 1e-14
}

/// Brute-force penetration depth: every vertex of one body with exact winding number ≥ 0.5
/// against the other, its distance to the other's surface over all triangles.
fn brute_depth(inner: &Mesh, to_outer: &Pose, outer: &Mesh) -> (f64, usize) {
    let mut used = vec![false; inner.vertices.len()];
    for t in &inner.triangles {
        for &v in t {
            used[v as usize] = true;
        }
    }
    let mut depth = 0.0f64;
    let mut n = 0;
    for (v, &u) in inner.vertices.iter().zip(&used) {
        if !u {
            continue;
        }
        let p = to_outer.transform_point(*v);
        let w = exact_winding_number(outer, p);
        if w.abs() >= 0.5 {
            n += 1;
            let d = (0..outer.triangles.len())
                .map(|t| {
                    let [a, b, c] = outer.triangle(t);
                    innersphere::mesh::closest::point_triangle_distance_sq(p, a, b, c)
                })
                .fold(f64::INFINITY, f64::min);
            depth = depth.max(d.sqrt());
        }
    }
    (depth, n)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    #[test]
    fn bvh_equals_brute_force(ma in mesh_strategy(), mb in mesh_strategy(), pa in pose(), pbs in prop::collection::vec(pose(), 1..4)) {
        let a = ExactMesh::new(&ma).unwrap();
        let b = ExactMesh::new(&mb).unwrap();
        // One scratch over several poses: the warm start must never change an answer.
        let mut warm = ExactScratch::new();
        let mut cold = ExactScratch::cold();
        for pb in &pbs {
            let r = distance(&a, &pa, &b, pb, &mut warm);
            let c = distance(&a, &pa, &b, pb, &mut cold);
            let bf = brute_force_distance(&a, &pa, &b, pb);
            prop_assert_eq!(r.intersecting, bf.intersecting);
            prop_assert_eq!(c.intersecting, bf.intersecting);
            prop_assert!(close(r.distance, bf.distance), "bvh {} brute {}", r.distance, bf.distance);
            prop_assert!(close(c.distance, bf.distance), "cold {} brute {}", c.distance, bf.distance);
            prop_assert!(r.distance == 0.0 || !r.intersecting);
            let crossing = bf.surface_distance == 0.0;
            if !crossing {
                prop_assert!(close(r.surface_distance, bf.surface_distance));
            }
            // The reported triangles and points realise the distance (world frame).
            let ta = ma.triangle(r.tri_a as usize).map(|v| pa.transform_point(v));
            let tb = mb.triangle(r.tri_b as usize).map(|v| pb.transform_point(v));
            let tt = triangle_distance(&ta, &tb);
            prop_assert!((tt.dist_sq.sqrt() - r.surface_distance).abs() <= 1e-9);
            prop_assert!(((r.point_a - r.point_b).length() - r.surface_distance).abs() <= 1e-9);
            // intersects agrees, warm and cold.
            prop_assert_eq!(intersects(&a, &pa, &b, pb, &mut warm), bf.intersecting);
            prop_assert_eq!(intersects(&a, &pa, &b, pb, &mut cold), brute_force_intersects(&a, &pa, &b, pb));
            // Containment rule against exact winding numbers of every vertex.
            if !crossing {
                let rel = Pose::relative(&pa, pb);
                let b_in_a = mb.vertices.iter().any(|v| exact_winding_number(&ma, rel.transform_point(*v)).abs() >= 0.5);
                let a_in_b = ma.vertices.iter().any(|v| exact_winding_number(&mb, rel.inverse().transform_point(*v)).abs() >= 0.5);
                prop_assert_eq!(bf.intersecting, b_in_a || a_in_b);
            }
        }
    }

    #[test]
    fn penetration_equals_brute_force(ma in mesh_strategy(), mb in mesh_strategy(), pa in pose(), pb in pose()) {
        let a = ExactMesh::new(&ma).unwrap();
        let b = ExactMesh::new(&mb).unwrap();
        let mut s = ExactScratch::new();
        let p = penetration(&a, &pa, &b, &pb, &mut s);
        let rel = Pose::relative(&pa, &pb);
        let (db, nb) = brute_depth(&mb, &rel, &ma);
        let (da, na) = brute_depth(&ma, &rel.inverse(), &mb);
        let want = da.max(db);
        // The fast winding number may classify a vertex within rounding of the surface
        // differently; such a vertex is too shallow to matter unless everything is.
        prop_assert!((p.depth - want).abs() <= 1e-9 * (1.0 + want) || want.max(p.depth) < 1e-6,
            "depth {} brute {} (b in a {} / {}, a in b {} / {})", p.depth, want, p.b_vertices_in_a, nb, p.a_vertices_in_b, na);
        prop_assert!(p.b_vertices_in_a.abs_diff(nb) <= 1 && p.a_vertices_in_b.abs_diff(na) <= 1,
            "counts {} {} vs {} {}", p.b_vertices_in_a, p.a_vertices_in_b, nb, na);
        prop_assert_eq!(penetration_depth(&a, &pa, &b, &pb, &mut s), p.depth);
        if p.depth > 0.0 {
            prop_assert!(((p.vertex - p.surface_point).length() - p.depth).abs() <= 1e-9);
            prop_assert!(distance(&a, &pa, &b, &pb, &mut s).intersecting);
        }
    }
}

#[test]
fn nested_bodies_and_far_apart() {
    let big = ExactMesh::new(&shapes::icosphere(3)).unwrap();
    let small = ExactMesh::new(&shapes::ellipsoid(DVec3::new(0.3, 0.2, 0.25), 2)).unwrap();
    let mut s = ExactScratch::new();
    let at = |x: f64| Pose::from_translation(DVec3::new(x, 0.0, 0.0));
    // Small one inside the big one: no surface crossing, still intersecting.
    let r = distance(&big, &Pose::IDENTITY, &small, &at(0.1), &mut s);
    assert!(r.intersecting && r.distance == 0.0);
    assert!(
        (r.surface_distance - 0.6).abs() < 0.02,
        "{}",
        r.surface_distance
    );
    assert!(intersects(&big, &Pose::IDENTITY, &small, &at(0.1), &mut s));
    assert!(intersects(&small, &at(0.1), &big, &Pose::IDENTITY, &mut s));
    let p = penetration(&big, &Pose::IDENTITY, &small, &at(0.1), &mut s);
    assert_eq!(p.vertex_of, Some(Body::B));
    assert_eq!(p.b_vertices_in_a, small.mesh().vertices.len());
    assert_eq!(p.a_vertices_in_b, 0);
    let want = small
        .mesh()
        .vertices
        .iter()
        .map(|v| 1.0 - (*v + DVec3::new(0.1, 0.0, 0.0)).length())
        .fold(0.0, f64::max);
    assert!((p.depth - want).abs() < 0.01, "{} vs {}", p.depth, want);
    // Crossing.
    let r = distance(&big, &Pose::IDENTITY, &small, &at(1.0), &mut s);
    assert!(r.intersecting && r.distance == 0.0 && r.surface_distance == 0.0);
    // Apart.
    let r = distance(&big, &Pose::IDENTITY, &small, &at(3.0), &mut s);
    assert!(!r.intersecting);
    assert!((r.distance - 1.7).abs() < 1e-3, "{}", r.distance);
    assert_eq!(
        penetration_depth(&big, &Pose::IDENTITY, &small, &at(3.0), &mut s),
        0.0
    );
    // Two unit spheres overlapping by 0.3: depth about 0.3.
    let p = penetration(&big, &Pose::IDENTITY, &big, &at(1.7), &mut s);
    assert!((p.depth - 0.3).abs() < 0.01, "{}", p.depth);
    // Non-finite poses: no panic.
    let bad = Pose {
        rotation: DQuat::from_xyzw(f64::NAN, 0.0, 0.0, 1.0),
        translation: DVec3::ZERO,
    };
    let _ = distance(&big, &Pose::IDENTITY, &small, &bad, &mut s);
    let _ = intersects(&big, &Pose::IDENTITY, &small, &bad, &mut s);
    let _ = penetration(&big, &Pose::IDENTITY, &small, &bad, &mut s);
    // Invalid meshes are rejected, not panicked on.
    assert!(ExactMesh::new(&Mesh::default()).is_err());
    let broken = Mesh {
        vertices: vec![DVec3::ZERO],
        triangles: vec![[0, 1, 2]],
    };
    assert!(ExactMesh::new(&broken).is_err());
}

#[test]
fn degenerate_mesh_triangles() {
    // A mesh full of zero-area and needle triangles against a box.
    let mut soup = Vec::new();
    for i in 0..50 {
        let x = i as f64 * 0.05 - 1.2;
        soup.push([
            DVec3::new(x, 0.0, 0.0),
            DVec3::new(x, 0.0, 0.0),
            DVec3::new(x, 0.0, 0.0),
        ]);
        soup.push([
            DVec3::new(x, 0.5, 0.0),
            DVec3::new(x + 0.3, 0.5, 0.0),
            DVec3::new(x + 0.15, 0.5, 0.0),
        ]);
        soup.push([
            DVec3::new(x, 0.0, 1.5),
            DVec3::new(x, 0.2, 1.5),
            DVec3::new(x, 0.1, 1.5 + 1e-300),
        ]);
    }
    let needles = ExactMesh::new(&Mesh::from_soup(&soup)).unwrap();
    let cube = ExactMesh::new(&shapes::cuboid(DVec3::splat(0.4))).unwrap();
    let mut s = ExactScratch::new();
    for k in 0..20 {
        let pb = Pose::new(
            DVec3::new(0.1 * k as f64 - 1.0, 0.3, 0.2 * k as f64 - 1.0),
            DQuat::from_rotation_y(0.3 * k as f64),
        )
        .unwrap();
        let r = distance(&needles, &Pose::IDENTITY, &cube, &pb, &mut s);
        let bf = brute_force_distance(&needles, &Pose::IDENTITY, &cube, &pb);
        assert!(r.distance.is_finite());
        assert_eq!(r.intersecting, bf.intersecting);
        assert!(
            close(r.distance, bf.distance),
            "{} {}",
            r.distance,
            bf.distance
        );
        let _ = penetration(&needles, &Pose::IDENTITY, &cube, &pb, &mut s);
    }
}

#[test]
fn near_contact_equals_brute_force() {
    // Bodies brought within a hair of touching (found by bisection), where rounding and
    // the pruning bounds matter most; then nudged to exactly around the contact.
    let ma = body(
        0,
        3,
        &[0.3, -0.2, 0.5, 0.0, -0.7],
        DVec3::new(1.0, 0.8, 1.2),
    );
    let mb = shapes::torus(0.9, 0.3, 24, 12);
    let a = ExactMesh::new(&ma).unwrap();
    let b = ExactMesh::new(&mb).unwrap();
    let mut warm = ExactScratch::new();
    let mut cold = ExactScratch::cold();
    for k in 0..8 {
        let ang = k as f64 * 1.3;
        let dir = DVec3::new(ang.cos(), ang.sin(), 0.3 * (k as f64 - 6.0) / 6.0).normalize();
        let rot = DQuat::from_axis_angle(
            DVec3::new(0.2, 1.0, 0.1 * k as f64).normalize(),
            0.4 * k as f64,
        );
        let at = |s: f64| Pose::new(dir * s, rot).unwrap();
        // Bisection on the crossing state: inside at 0, apart at 5.
        let (mut lo, mut hi) = (0.0, 5.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if intersects(&a, &Pose::IDENTITY, &b, &at(mid), &mut cold) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        for s in [hi, lo, hi + 1e-9, hi + 1e-6, hi + 1e-3] {
            let pb = at(s);
            let r = distance(&a, &Pose::IDENTITY, &b, &pb, &mut warm);
            let c = distance(&a, &Pose::IDENTITY, &b, &pb, &mut cold);
            let bf = brute_force_distance(&a, &Pose::IDENTITY, &b, &pb);
            assert_eq!(r.intersecting, bf.intersecting, "k {k} s {s}");
            assert_eq!(c.intersecting, bf.intersecting, "k {k} s {s}");
            assert!(
                close(r.distance, bf.distance),
                "k {k} s {s}: {} vs {}",
                r.distance,
                bf.distance
            );
            assert!(
                close(c.distance, bf.distance),
                "k {k} s {s}: {} vs {}",
                c.distance,
                bf.distance
            );
            assert_eq!(
                intersects(&a, &Pose::IDENTITY, &b, &pb, &mut warm),
                bf.intersecting
            );
        }
    }
}
