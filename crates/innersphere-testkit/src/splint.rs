//! The checks of a splint that every splint test makes, computed from the meshes rather
//! than read from the splint's own report.

use innersphere::glam::DVec3;
use innersphere::mesh::bvh::TriangleBvh;
use innersphere::mesh::winding::FastWinding;
use innersphere::splint::{self, SplintOptions};
use innersphere::{Mesh, Pose};

/// The splint `s` between `a` and `b` (B at `pose`) is a printable wafer that seats, each check computed here from the meshes, not read from the
/// splint's own report: one watertight, consistently wound, outward body; every splint
/// vertex at least clearance − 0.02 from both arches; no arch vertex inside the splint
/// (generalized winding number, another method than the report's ray parity); at least
/// 85 % of each arch's occlusal surface within clearance + 0.15 of the splint.
pub fn assert_seats(a: &Mesh, b: &Mesh, pose: &Pose, opts: &SplintOptions, s: &splint::Splint) {
    let m = &s.mesh;
    let r = m.report();
    assert!(r.watertight && r.winding_consistent, "{r:?}");
    assert_eq!(r.components, 1, "one body");
    assert!(r.volume > 0.0 && r.nonmanifold_edges == 0 && r.boundary_edges == 0);
    assert_eq!(splint::report::pinched_vertices(m), 0);
    assert!(s.report.watertight && s.report.manifold && s.report.bodies == 1);

    let bvh_a = TriangleBvh::new(a);
    let bvh_b = TriangleBvh::new(b);
    let inv = pose.inverse();
    let c = opts.clearance;
    for v in &m.vertices {
        let da = bvh_a.distance_sq(*v).sqrt();
        let db = bvh_b.distance_sq(inv.transform_point(*v)).sqrt();
        assert!(
            da >= c - 0.02 && db >= c - 0.02,
            "vertex {v}: {da} from A, {db} from B"
        );
    }
    let wind = FastWinding::new(m);
    let b_world: Vec<DVec3> = b
        .vertices
        .iter()
        .map(|v| pose.transform_point(*v))
        .collect();
    for p in a.vertices.iter().chain(&b_world) {
        assert!(
            wind.winding_number(*p) < 0.5,
            "arch vertex {p} inside the splint"
        );
    }
    let splint_bvh = TriangleBvh::new(m);
    let carried = |pts: &[DVec3], other: &dyn Fn(DVec3) -> f64| -> f64 {
        let near: Vec<&DVec3> = pts.iter().filter(|p| other(**p) <= 3.5).collect();
        let held = near
            .iter()
            .filter(|p| splint_bvh.distance_sq(***p).sqrt() <= c + 0.15)
            .count();
        held as f64 / near.len().max(1) as f64
    };
    let ca = carried(&a.vertices, &|p| {
        bvh_b.distance_sq(inv.transform_point(p)).sqrt()
    });
    let cb = carried(&b_world, &|p| bvh_a.distance_sq(p).sqrt());
    assert!(
        ca >= 0.85 && cb >= 0.85,
        "occlusal surface carried: A {ca}, B {cb}"
    );
}
