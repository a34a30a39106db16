//! Exact distance and penetration depth on the real tooth data (run with `--ignored`).

use super::data as common;

use innersphere::exact::{
    distance, intersects, penetration, triangle_distance, ExactMesh, ExactScratch,
};
use innersphere::glam::{DQuat, DVec3};
use innersphere::mesh::bvh::TriangleBvh;
use innersphere::Mesh;
use innersphere::Pose;

fn load(rel: &str) -> Mesh {
    innersphere::mesh::io::load(&common::data(rel)).expect("load")
}

/// The true minimum distance when it is at most `bound`: only triangles that come within
/// `bound` of the other surface (decided by point queries on a plain triangle BVH, another
/// code path than the BVH-vs-BVH traversal) can realise it; all pairs among those.
fn shell_brute_force(a: &Mesh, b: &Mesh, rel: &Pose, bound: f64) -> f64 {
    let ta: Vec<[DVec3; 3]> = (0..a.triangles.len()).map(|t| a.triangle(t)).collect();
    let tb: Vec<[DVec3; 3]> = (0..b.triangles.len())
        .map(|t| b.triangle(t).map(|v| rel.transform_point(v)))
        .collect();
    let bvh_a = TriangleBvh::from_triangles(&ta);
    let bvh_b = TriangleBvh::from_triangles(&tb);
    let near = |tris: &[[DVec3; 3]], other: &TriangleBvh| -> Vec<[DVec3; 3]> {
        tris.iter()
            .filter(|t| {
                let c = (t[0] + t[1] + t[2]) / 3.0;
                let r = t.iter().map(|v| (*v - c).length()).fold(0.0, f64::max);
                other.closest_point(c, (bound + r + 1e-9).powi(2)).is_some()
            })
            .copied()
            .collect()
    };
    let na = near(&ta, &bvh_b);
    let nb = near(&tb, &bvh_a);
    assert!(!na.is_empty() && !nb.is_empty());
    println!(
        "shell within {bound}: {} x {} triangles",
        na.len(),
        nb.len()
    );
    assert!(
        na.len() * nb.len() < 50_000_000,
        "shell too thick: {} x {}",
        na.len(),
        nb.len()
    );
    let mut best = f64::INFINITY;
    for x in &na {
        let (xl, xh) = (x[0].min(x[1]).min(x[2]), x[0].max(x[1]).max(x[2]));
        for y in &nb {
            let (yl, yh) = (y[0].min(y[1]).min(y[2]), y[0].max(y[1]).max(y[2]));
            let gap = (xl - yh).max(yl - xh).max(DVec3::ZERO).length_squared();
            if gap >= best {
                continue;
            }
            best = best.min(triangle_distance(x, y).dist_sq);
        }
    }
    best.sqrt()
}

#[test]
#[ignore = "real data: run with --ignored"]
fn molars_distance_equals_brute_force() {
    let ma = load("jaw/ofj_p26_tooth03_upper_first_molar.stl");
    let mb = load("jaw/ofj_p26_tooth30_lower_first_molar.stl");
    let a = ExactMesh::new(&ma).unwrap();
    let b = ExactMesh::new(&mb).unwrap();
    let mut s = ExactScratch::new();
    // In the bite they touch (and overlap a little).
    assert!(distance(&a, &Pose::IDENTITY, &b, &Pose::IDENTITY, &mut s).intersecting);
    assert!(intersects(&a, &Pose::IDENTITY, &b, &Pose::IDENTITY, &mut s));
    let p = penetration(&a, &Pose::IDENTITY, &b, &Pose::IDENTITY, &mut s);
    println!("molars in the bite: penetration {p:?}");
    assert!(p.depth > 0.1 && p.depth < 0.3, "{}", p.depth);
    // Open the bite: the lower molar moves down (and a little sideways, turned).
    let up = DVec3::new(0.036, -0.059, 0.998).normalize();
    let centre = mb.bbox().0 * 0.5 + mb.bbox().1 * 0.5;
    let mut separated = 0;
    for (k, (drop, side, angle)) in [
        (0.4, 0.0, 0.0),
        (0.8, 0.3, 0.02),
        (1.5, -0.5, -0.05),
        (3.0, 1.0, 0.1),
        (0.3, 0.2, 0.03),
    ]
    .into_iter()
    .enumerate()
    {
        let rot = DQuat::from_axis_angle(DVec3::new(1.0, 0.3, -0.2).normalize(), angle);
        // Rotate about the molar's centre, then translate.
        let t = centre - rot * centre - up * drop + DVec3::X * side;
        let pb = Pose::new(t, rot).unwrap();
        let pa = Pose::new(
            DVec3::new(3.0, -2.0, 1.0) * k as f64,
            DQuat::from_rotation_z(0.1 * k as f64),
        )
        .unwrap();
        let pb_world = pa.then(&pb);
        let r = distance(&a, &pa, &b, &pb_world, &mut s);
        let cold = distance(&a, &pa, &b, &pb_world, &mut ExactScratch::cold());
        assert_eq!(r.distance, cold.distance);
        println!("drop {drop} side {side} angle {angle}: {r:?}");
        if r.intersecting {
            assert_eq!(r.distance, 0.0);
            continue;
        }
        separated += 1;
        let want = shell_brute_force(&ma, &mb, &pb, r.distance);
        assert!(
            (r.distance - want).abs() <= 1e-9 * want,
            "bvh {} brute {}",
            r.distance,
            want
        );
        assert!(!intersects(&a, &pa, &b, &pb_world, &mut s));
        assert_eq!(penetration(&a, &pa, &b, &pb_world, &mut s).depth, 0.0);
    }
    assert!(separated >= 3);
}

#[test]
#[ignore = "real data: run with --ignored"]
fn jaw_bite_penetration() {
    let ma = load("jaw/ofj_p26_maxilla_teeth.stl.gz");
    let mb = load("jaw/ofj_p26_mandible_teeth.stl.gz");
    let a = ExactMesh::new(&ma).unwrap();
    let b = ExactMesh::new(&mb).unwrap();
    assert_eq!(a.component_count(), 15);
    assert_eq!(b.component_count(), 16);
    let mut s = ExactScratch::new();
    let t = std::time::Instant::now();
    let p = penetration(&a, &Pose::IDENTITY, &b, &Pose::IDENTITY, &mut s);
    println!("jaw bite: {p:?} in {:?}", t.elapsed());
    // The data's README: 911 lower-tooth vertices inside upper teeth, deepest tooth pair 0.30 mm.
    assert!(
        p.b_vertices_in_a.abs_diff(911) <= 20,
        "{}",
        p.b_vertices_in_a
    );
    assert!(p.depth > 0.25 && p.depth < 0.4, "{}", p.depth);
    let r = distance(&a, &Pose::IDENTITY, &b, &Pose::IDENTITY, &mut s);
    assert!(r.intersecting && r.distance == 0.0);
    // The lower arch 10 mm down: separated, at the brute-force minimum over every pair of
    // triangles that come that close to the other arch.
    let open = Pose::from_translation(DVec3::new(0.0, 0.0, -10.0));
    let r = distance(&a, &Pose::IDENTITY, &b, &open, &mut s);
    assert!(!r.intersecting && r.distance < 10.0, "{r:?}");
    let want = shell_brute_force(&ma, &mb, &open, r.distance);
    println!("jaw opened 10 mm: {r:?}, brute force {want}");
    assert!(
        (r.distance - want).abs() <= 1e-9 * want,
        "bvh {} brute {want}",
        r.distance
    );
    assert_eq!(
        penetration(&a, &Pose::IDENTITY, &b, &open, &mut s).depth,
        0.0
    );
}
