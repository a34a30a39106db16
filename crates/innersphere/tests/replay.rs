//! Replay statistics on a pair whose answer is known in closed form: two unit balls.

use glam::DVec3;
use innersphere::eval::replay::{replay, QueryKind, ReplayOptions};
use innersphere::exact::ExactMesh;
use innersphere::field::{DistanceField, VoxelGrid};
use innersphere::hierarchy::{self, HierarchyOptions};
use innersphere::motion::{Frame, Motion};
use innersphere::packing::{self, PackingOptions};
use innersphere::progress::Silent;
use innersphere::query::Pose;
use innersphere::tree::TreeMeta;
use innersphere::SphereTree;

/// The tree of a unit ball: the grid has a voxel at the centre, so the packing is one sphere,
/// the ball itself.
fn ball_tree() -> SphereTree {
    let grid = VoxelGrid::covering(DVec3::splat(-1.0), DVec3::splat(1.0), 0.1).unwrap();
    let field = DistanceField::from_signed_distance(grid, |p| 1.0 - p.length());
    let spheres = packing::pack(&field, &PackingOptions::default(), None, &Silent);
    assert!((spheres[0].radius - 1.0).abs() < 1e-9);
    let meta = TreeMeta {
        fanout: 4,
        voxel_size: 0.1,
        min_radius: 0.0,
        mesh_volume: 4.0 / 3.0 * std::f64::consts::PI,
        center_of_mass: [0.0; 3],
        bbox_min: [-1.0; 3],
        bbox_max: [1.0; 3],
        coverage: 1.0,
        mesh_closed: true,
        built_by: None,
    };
    hierarchy::build(&spheres, &HierarchyOptions::default(), meta, &Silent)
        .unwrap()
        .0
}

#[test]
fn replay_of_two_balls_matches_the_closed_form() {
    let a = ball_tree();
    let b = ball_tree();
    // Centre distances: separated from 3.0 down to 2.1, then overlapping from 1.9 to 1.0.
    let centre: Vec<f64> = (0..10)
        .map(|i| 3.0 - 0.1 * i as f64)
        .chain((0..10).map(|i| 1.9 - 0.1 * i as f64))
        .collect();
    let motion = Motion {
        frames: centre
            .iter()
            .enumerate()
            .map(|(i, &d)| Frame {
                t: i as f64 * 1e-3,
                pose: Pose::from_translation(DVec3::new(d, 0.0, 0.0)),
            })
            .collect(),
    };
    let sphere_mesh = innersphere::shapes::icosphere(4);
    let exact = ExactMesh::new(&sphere_mesh).unwrap();
    let report = replay(
        &a,
        &b,
        &motion,
        Some((&exact, &exact)),
        &ReplayOptions::default(),
    );
    assert_eq!(report.frames, 20);
    assert_eq!(report.kinds.len(), QueryKind::ALL.len());
    for k in &report.kinds {
        assert_eq!(k.frames, 20);
        assert!(k.p50_us <= k.p99_us && k.p99_us <= k.max_us, "{k:?}");
    }
    for (row, &d) in report.rows.iter().zip(&centre) {
        // Closed form: the sphere sets are the two balls.
        let expect = (d - 2.0).max(0.0);
        assert!((row.distance - expect).abs() < 1e-5, "{row:?} vs {expect}");
        assert_eq!(row.contact, d < 2.0);
        assert_eq!(row.exact_intersecting, d < 2.0);
    }
    let acc = report.accuracy.unwrap();
    assert_eq!(acc.frames, 20);
    assert_eq!(acc.separated_frames, 10);
    assert_eq!(acc.missed_contacts, 0);
    assert_eq!(acc.false_contacts, 0);
    // The icosphere is inscribed in the ball: the meshes are a little farther apart than the
    // balls, by at most twice the polyhedron's deviation from the sphere.
    assert!(acc.abs_err_max < 0.005, "{acc:?}");
    assert!(acc.abs_err_p50 <= acc.abs_err_p95 && acc.abs_err_p95 <= acc.abs_err_max);
    // The like-for-like speed comparison: our distance p99 over the compared frames (here
    // all 20) is the distance query's own p99, and the speed-up is the ratio of the two p99s.
    let dist = report
        .kinds
        .iter()
        .find(|k| k.kind == QueryKind::Distance)
        .unwrap();
    assert_eq!(acc.distance_p99_us, dist.p99_us);
    assert_eq!(acc.speedup_p99, acc.exact_p99_us / acc.distance_p99_us);

    // More passes time the same work (each from a fresh state): the same answers, every
    // frame's time finite, and the accuracy unchanged.
    let three = replay(
        &a,
        &b,
        &motion,
        Some((&exact, &exact)),
        &ReplayOptions {
            passes: 3,
            ..Default::default()
        },
    );
    assert_eq!((report.passes, three.passes), (1, 3));
    for (r1, r3) in report.rows.iter().zip(&three.rows) {
        assert_eq!((r1.distance, r1.contact), (r3.distance, r3.contact));
        assert!(r3.us.iter().all(|t| t.is_finite() && *t >= 0.0), "{r3:?}");
    }
    let acc3 = three.accuracy.unwrap();
    assert_eq!(acc3.abs_err_max, acc.abs_err_max);
    assert!(acc3.exact_p50_us.is_finite());
}
