//! The contact map on the real jaw pair (run with `--ignored`).

use innersphere::exact::ExactMesh;
use innersphere::glam::{DQuat, DVec3};
use innersphere::{Mesh, Pose};
use innersphere_testkit::data as common;

fn load(rel: &str) -> Mesh {
    innersphere::mesh::io::load(&common::data(rel)).expect("load")
}

/// The contact map's gaps on the jaw pair at the scanned bite: on sampled vertices of both
/// arches, the distance to every triangle of the other (brute force) to 1e-9 mm, negative
/// exactly where the vertex is inside by the winding number, and some vertices on each side
/// in contact.
#[test]
#[ignore = "real data: run with --ignored"]
fn contact_map_gaps_are_the_brute_force_distances_on_the_jaws() {
    use innersphere::mesh::closest::point_triangle_distance_sq;
    use innersphere_dental::contact_map::ContactMap;
    let a = ExactMesh::new(&load("jaw/ofj_p26_maxilla_teeth.stl.gz")).unwrap();
    let b = ExactMesh::new(&load("jaw/ofj_p26_mandible_teeth.stl.gz")).unwrap();
    // Slightly open and turned, so that some vertices are inside and most are not.
    let pose = Pose::new(DVec3::new(0.05, -0.1, -0.15), DQuat::from_rotation_z(0.002)).unwrap();
    let map = ContactMap::new(&a, &Pose::IDENTITY, &b, &pose, f64::INFINITY).unwrap();
    for (mine, other, gaps, to_other) in [
        (&a, &b, &map.gaps_a, pose.inverse()),
        (&b, &a, &map.gaps_b, pose),
    ] {
        let n = mine.mesh().vertices.len();
        assert_eq!(gaps.len(), n);
        assert!(gaps.iter().any(|&g| g < 0.0) && gaps.iter().any(|&g| (0.0..0.1).contains(&g)));
        // Every 997th vertex, and the 20 with the smallest gaps.
        let mut idx: Vec<usize> = (0..n).step_by(997).collect();
        let mut by_gap: Vec<usize> = (0..n).collect();
        by_gap.sort_by(|&i, &j| gaps[i].total_cmp(&gaps[j]));
        idx.extend(&by_gap[..20]);
        let m = other.mesh();
        for i in idx {
            let p = to_other.transform_point(mine.mesh().vertices[i]);
            let d = m
                .triangles
                .iter()
                .map(|t| {
                    let [x, y, z] = t.map(|k| m.vertices[k as usize]);
                    point_triangle_distance_sq(p, x, y, z)
                })
                .fold(f64::INFINITY, f64::min)
                .sqrt();
            assert!(
                (gaps[i].abs() - d).abs() <= 1e-9,
                "vertex {i}: {} vs {d}",
                gaps[i]
            );
            assert_eq!(gaps[i] < 0.0, other.contains_point(p), "vertex {i}");
        }
    }
}
