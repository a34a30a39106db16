//! The checks of a splint that every splint test makes, computed from the meshes rather
//! than read from the splint's own report.

use innersphere::glam::DVec3;
use innersphere::mesh::bvh::TriangleBvh;
use innersphere::mesh::winding::FastWinding;
use innersphere::{Mesh, Pose};
use innersphere_dental::splint::{self, SplintOptions};
use std::collections::HashMap;

/// The splint `s` between `a` and `b` (B at `pose`) is a printable wafer that seats, each
/// check computed here from the meshes, not read from the splint's own report:
/// - as read back from its STL bytes (corners with the same `f32` coordinates joined, as
///   every reader joins them): one watertight, consistently wound, outward body with no
///   pinched vertex, and the same vertices as `s.mesh`;
/// - every splint vertex at least clearance − 0.02 from both arches;
/// - no arch vertex inside the splint (generalized winding number, another method than the
///   report's ray parity);
/// - at least 85 % of each arch's occlusal surface within clearance + 0.15 of the splint,
///   the occlusal surface found by rays ([`occlusal`]), not by the splint's columns.
///
/// And the report says it is fit.
pub fn assert_seats(a: &Mesh, b: &Mesh, pose: &Pose, opts: &SplintOptions, s: &splint::Splint) {
    let m = &s.mesh;
    let bytes = innersphere::mesh::io::to_stl_bytes(m).unwrap();
    let read = innersphere::mesh::load_bytes(
        &bytes,
        innersphere::mesh::Format::Stl,
        std::path::Path::new("splint.stl"),
    )
    .unwrap();
    assert_eq!(
        read.vertices.len(),
        m.vertices.len(),
        "vertices joined when read back from the STL"
    );
    let r = read.report();
    assert!(r.watertight && r.winding_consistent, "{r:?}");
    assert_eq!(r.components, 1, "one body");
    assert!(r.volume > 0.0 && r.nonmanifold_edges == 0 && r.boundary_edges == 0);
    assert_eq!(splint::report::pinched_vertices(&read), 0);
    assert!(s.report.watertight && s.report.manifold && s.report.bodies == 1);
    assert!(s.report.fit, "{:?}", s.report.checks);

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
    let up = DVec3::from_array(s.report.insertion_axis);
    let splint_bvh = TriangleBvh::new(m);
    let carried = |pts: &[DVec3], occlusal: &[bool]| -> f64 {
        let near: Vec<&DVec3> = pts
            .iter()
            .zip(occlusal)
            .filter(|p| *p.1)
            .map(|p| p.0)
            .collect();
        assert!(
            near.len() >= 100,
            "an occlusal surface of {} vertices",
            near.len()
        );
        let held = near
            .iter()
            .filter(|p| splint_bvh.distance_sq(***p).sqrt() <= c + 0.15)
            .count();
        held as f64 / near.len() as f64
    };
    let world = Pose::IDENTITY;
    let occ_a = occlusal(a, &world, &bvh_a, pose, &bvh_b, -up, opts.coverage);
    let occ_b = occlusal(b, pose, &bvh_b, &world, &bvh_a, up, opts.coverage);
    let ca = carried(&a.vertices, &occ_a);
    let cb = carried(&b_world, &occ_b);
    assert!(
        ca >= 0.85 && cb >= 0.85,
        "occlusal surface carried: A {ca}, B {cb}"
    );
}

/// Which vertices of `m` (at `pose_m`) form its occlusal surface towards the other arch
/// (its triangle tree `bvh_o`, at `pose_o`), looking along `dir` (world frame, from `m`
/// towards the other arch): a vertex whose ray along `dir` leaves `m` without meeting it
/// again and then meets the other arch, and that lies at most `coverage` behind the
/// foremost such vertex within 15 mm around it along `dir` (the band of the crowns beyond
/// their cusp tips that a wafer climbs, whatever the gap between the arches).
pub fn occlusal(
    m: &Mesh,
    pose_m: &Pose,
    bvh_m: &TriangleBvh,
    pose_o: &Pose,
    bvh_o: &TriangleBvh,
    dir: DVec3,
    coverage: f64,
) -> Vec<bool> {
    let (inv_m, inv_o) = (pose_m.inverse(), pose_o.inverse());
    // Along the ray: past m's own surface (self hits within 1e-3 skipped), to the other.
    let reach: Vec<Option<f64>> = m
        .vertices
        .iter()
        .map(|v| {
            let w = pose_m.transform_point(*v);
            let own = bvh_m.first_hit(
                inv_m.transform_point(w),
                inv_m.transform_vector(dir),
                1e-3,
                f64::INFINITY,
                |_| false,
            );
            let hit = bvh_o.first_hit(
                inv_o.transform_point(w),
                inv_o.transform_vector(dir),
                0.0,
                f64::INFINITY,
                |_| false,
            )?;
            match own {
                Some(o) if o.t < hit.t => None,
                // How far behind: the cusp tips, foremost towards the other arch, least.
                _ => Some(-w.dot(dir)),
            }
        })
        .collect();
    // The foremost per 5 mm cell across the axis (a cell and two rings of neighbours: 10–25 mm).
    let (e1, e2) = {
        let t = if dir.x.abs() < 0.9 {
            DVec3::X
        } else {
            DVec3::Y
        };
        let e1 = dir.cross(t).normalize();
        (e1, dir.cross(e1))
    };
    let cell = |v: DVec3| {
        let w = pose_m.transform_point(v);
        (
            (w.dot(e1) / 5.0).floor() as i64,
            (w.dot(e2) / 5.0).floor() as i64,
        )
    };
    let mut least: HashMap<(i64, i64), f64> = HashMap::new();
    for (v, r) in m.vertices.iter().zip(&reach) {
        if let Some(r) = r {
            let e = least.entry(cell(*v)).or_insert(f64::INFINITY);
            *e = e.min(*r);
        }
    }
    m.vertices
        .iter()
        .zip(&reach)
        .map(|(v, r)| {
            let Some(r) = r else { return false };
            let (i, j) = cell(*v);
            let near = (-2..=2)
                .flat_map(|di| (-2..=2).map(move |dj| (i + di, j + dj)))
                .filter_map(|k| least.get(&k))
                .fold(f64::INFINITY, |x, y| x.min(*y));
            *r <= near + coverage
        })
        .collect()
}
