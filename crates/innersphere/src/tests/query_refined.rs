//! The refined distance ([`Pair::refined_distance`]) on a generated tooth pair against the
//! exact mesh distance: never below it, never above the sphere distance, equal to it when
//! the balls cover the meshes; contacts the spheres miss are found; bad input is an error.

use glam::{DQuat, DVec3};
use innersphere::exact::{self, ExactMesh, ExactScratch};
use innersphere::query::batch::{self, BatchOptions};
use innersphere::{
    shapes, BuildOptions, Mesh, Pair, PenetrationOptions, Pose, RefineOptions, Resolution,
    SharedTree, SphereTree,
};
use proptest::prelude::*;
use std::sync::{Arc, OnceLock};

/// The demo's tooth pair (upper = A, lower = B) with coarse trees (few, large spheres: the
/// sphere distance is far from the meshes', so the refinement has work to do) and meshes.
struct Teeth {
    a: SharedTree,
    b: SharedTree,
    ma: Arc<ExactMesh>,
    mb: Arc<ExactMesh>,
}

fn teeth() -> &'static Teeth {
    static T: OnceLock<Teeth> = OnceLock::new();
    T.get_or_init(|| {
        let (upper, lower) = shapes::tooth_pair(3);
        let opts = BuildOptions {
            resolution: Resolution::Cells(24),
            ..Default::default()
        };
        let tree = |m: &Mesh| SharedTree::new(SphereTree::build(m, &opts).unwrap());
        let (ma, mb) = (
            Arc::new(ExactMesh::new(&upper).unwrap()),
            Arc::new(ExactMesh::new(&lower).unwrap()),
        );
        Teeth {
            a: tree(&upper).with_exact_mesh(ma.clone()).unwrap(),
            b: tree(&lower).with_exact_mesh(mb.clone()).unwrap(),
            ma,
            mb,
        }
    })
}

/// B (the lower tooth) lowered by `lift` (mm) along z, shifted sideways and turned a little.
fn pose_b(lift: f64, side: [f64; 2], turn: [f64; 3]) -> Pose {
    Pose::new(
        DVec3::new(side[0], side[1], -lift),
        DQuat::from_scaled_axis(DVec3::from_array(turn)),
    )
    .unwrap()
}

fn exact_distance(t: &Teeth, pa: &Pose, pb: &Pose) -> exact::ExactDistance {
    exact::distance(&t.ma, pa, &t.mb, pb, &mut ExactScratch::cold())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// exact ≤ refined ≤ spheres on every pose; a refined answer's points lie on its
    /// triangles at its distance; touching meshes are never reported apart by more than the
    /// spheres' own error.
    #[test]
    fn refined_lies_between_the_exact_and_the_sphere_distance(
        lift in -1.0f64..1.5,
        side in prop::array::uniform2(-1.5f64..1.5),
        turn in prop::array::uniform3(-0.3f64..0.3),
        scale in 0.0f64..2.0,
    ) {
        let t = teeth();
        let (pa, pb) = (Pose::IDENTITY, pose_b(lift, side, turn));
        let mut pair = Pair::new(&t.a, &t.b);
        let opts = RefineOptions { radius_scale: scale, rel_tolerance: 0.0, ..Default::default() };
        let r = pair.refined_distance_with(&pa, &pb, &opts).unwrap();
        let e = exact_distance(t, &pa, &pb);
        prop_assert_eq!(r.spheres.distance, Pair::new(&t.a, &t.b).distance(&pa, &pb).distance);
        prop_assert!(r.distance <= r.spheres.distance.max(0.0));
        prop_assert!(r.distance >= e.distance - 1e-12, "{} < exact {}", r.distance, e.distance);
        prop_assert!(r.complete);
        if r.intersecting {
            prop_assert!(e.intersecting, "the refined distance says touching, the meshes do not");
            prop_assert_eq!(r.distance, 0.0);
        }
        if r.refined && !r.intersecting {
            let tri = |m: &Mesh, i: u32, p: &Pose| m.triangles[i as usize].map(|v| p.transform_point(m.vertices[v as usize]));
            let (x, y) = (tri(t.ma.mesh(), r.tri_a, &pa), tri(t.mb.mesh(), r.tri_b, &pb));
            let d = exact::triangle_distance(&x, &y).dist_sq.sqrt();
            prop_assert!((d - r.distance).abs() <= 1e-9, "{d} vs {}", r.distance);
            prop_assert!(((r.point_b - r.point_a).length() - r.distance).abs() <= 1e-9);
        }
    }
}

/// Balls that cover both meshes make the refinement the exact mesh distance.
#[test]
fn balls_over_the_whole_meshes_give_the_exact_distance() {
    let t = teeth();
    let opts = RefineOptions {
        radius_scale: 100.0,
        rel_tolerance: 0.0,
        max_node_pairs: u64::MAX,
        ..Default::default()
    };
    let mut pair = Pair::new(&t.a, &t.b);
    let mut separated = 0;
    for i in 0..24 {
        let s = i as f64 / 24.0 * std::f64::consts::TAU;
        let pb = pose_b(
            0.3 + 0.9 * s.sin(),
            [1.2 * s.cos(), 0.8 * (2.0 * s).sin()],
            [0.1 * s.sin(), 0.05, 0.2 * s.cos()],
        );
        let r = pair
            .refined_distance_with(&Pose::IDENTITY, &pb, &opts)
            .unwrap();
        let e = exact_distance(t, &Pose::IDENTITY, &pb);
        assert!(r.complete);
        if e.intersecting {
            assert!(r.intersecting || r.spheres.overlapping, "frame {i}");
        } else {
            separated += 1;
            assert!(
                (r.distance - e.distance).abs() <= 1e-12,
                "frame {i}: refined {} exact {} spheres {}",
                r.distance,
                e.distance,
                r.spheres.distance
            );
        }
    }
    assert!(separated >= 8, "{separated} separated frames");
}

/// The default balls already take most of the spheres' error away on these coarse trees.
#[test]
fn the_default_refinement_is_much_nearer_than_the_spheres() {
    let t = teeth();
    let mut pair = Pair::new(&t.a, &t.b);
    let (mut sphere_err, mut refined_err) = (0.0, 0.0);
    for i in 0..40 {
        let s = i as f64 / 40.0 * std::f64::consts::TAU;
        let pb = pose_b(
            0.6 + 0.4 * s.sin(),
            [0.5 * s.cos(), 0.3],
            [0.0, 0.1 * s.sin(), 0.0],
        );
        let r = pair.refined_distance(&Pose::IDENTITY, &pb).unwrap();
        let e = exact_distance(t, &Pose::IDENTITY, &pb);
        if !e.intersecting && !r.spheres.overlapping {
            sphere_err += r.spheres.distance - e.distance;
            refined_err += r.distance - e.distance;
        }
    }
    assert!(sphere_err > 0.0);
    assert!(
        refined_err <= 0.1 * sphere_err,
        "refined error {refined_err} against the spheres' {sphere_err}"
    );
}

/// A reset pair answers as a fresh one (the last answer's triangle pair, which bounds the
/// next search, is forgotten).
#[test]
fn a_reset_pair_answers_as_a_fresh_one() {
    let t = teeth();
    let poses: Vec<Pose> = (0..30)
        .map(|i| {
            pose_b(
                0.4 + 0.02 * i as f64,
                [0.03 * i as f64, 0.1],
                [0.0, 0.0, 0.01 * i as f64],
            )
        })
        .collect();
    let mut warm = Pair::new(&t.a, &t.b);
    for p in &poses {
        warm.refined_distance(&Pose::IDENTITY, p).unwrap();
    }
    let target = pose_b(1.2, [-0.8, 0.5], [0.05, 0.0, 0.2]);
    warm.reset();
    let got = warm.refined_distance(&Pose::IDENTITY, &target).unwrap();
    let want = Pair::new(&t.a, &t.b)
        .refined_distance(&Pose::IDENTITY, &target)
        .unwrap();
    assert_eq!(got, want);
}

/// A budget too small for the search: an upper bound still, and marked incomplete.
#[test]
fn a_spent_budget_still_gives_an_upper_bound() {
    let t = teeth();
    let pb = pose_b(0.8, [0.3, -0.2], [0.0, 0.05, 0.1]);
    let opts = RefineOptions {
        max_node_pairs: 3,
        ..Default::default()
    };
    let r = Pair::new(&t.a, &t.b)
        .refined_distance_with(&Pose::IDENTITY, &pb, &opts)
        .unwrap();
    let e = exact_distance(t, &Pose::IDENTITY, &pb);
    assert!(!r.complete);
    assert!(r.node_pairs <= 3);
    assert!(e.distance <= r.distance && r.distance <= r.spheres.distance);
}

/// Overlapping spheres lie inside both bodies: touching, distance 0, nothing searched.
#[test]
fn overlapping_spheres_are_a_contact() {
    let t = teeth();
    let r = Pair::new(&t.a, &t.b)
        .refined_distance(&Pose::IDENTITY, &pose_b(-0.8, [0.0, 0.0], [0.0; 3]))
        .unwrap();
    assert!(r.spheres.overlapping && r.intersecting);
    assert_eq!((r.distance, r.node_pairs, r.refined), (0.0, 0, false));
}

/// Far, non-finite and huge poses: answers or NaN, never a panic or a hang.
#[test]
fn far_and_non_finite_poses_answer() {
    let t = teeth();
    let mut pair = Pair::new(&t.a, &t.b);
    for p in [
        Pose::from_translation(DVec3::new(1e6, 0.0, 0.0)),
        Pose::from_translation(DVec3::new(0.0, 3e30, 0.0)),
    ] {
        let r = pair.refined_distance(&Pose::IDENTITY, &p).unwrap();
        assert!(
            r.distance > 0.0 && r.distance <= r.spheres.distance,
            "{r:?}"
        );
    }
    let nan = Pose::from_translation(DVec3::new(f64::NAN, 0.0, 0.0));
    let r = pair.refined_distance(&Pose::IDENTITY, &nan).unwrap();
    assert!(!r.intersecting && !r.refined);
}

/// Trees without their meshes, a mesh that is not the tree's, and bad options: errors that
/// say what is wrong.
#[test]
fn missing_or_foreign_meshes_and_bad_options_are_errors() {
    let t = teeth();
    let bare = SharedTree::new(t.a.tree().clone());
    let err = Pair::new(&bare, &t.b)
        .refined_distance(&Pose::IDENTITY, &Pose::IDENTITY)
        .unwrap_err();
    assert!(err.to_string().contains("with_mesh"), "{err}");
    let err = bare.clone().with_mesh(t.mb.mesh()).unwrap_err();
    assert!(err.to_string().contains("not the mesh"), "{err}");
    let mut pair = Pair::new(&t.a, &t.b);
    for bad in [
        RefineOptions {
            radius_scale: f64::NAN,
            ..Default::default()
        },
        RefineOptions {
            radius_scale: -1.0,
            ..Default::default()
        },
        RefineOptions {
            margin: f64::INFINITY,
            ..Default::default()
        },
        RefineOptions {
            max_node_pairs: 0,
            ..Default::default()
        },
        RefineOptions {
            rel_tolerance: 1.5,
            ..Default::default()
        },
        RefineOptions {
            rel_tolerance: f64::NAN,
            ..Default::default()
        },
    ] {
        let err = pair
            .refined_distance_with(&Pose::IDENTITY, &Pose::IDENTITY, &bad)
            .unwrap_err();
        assert!(err.to_string().contains("refine"), "{err}");
    }
}

/// The batch door: on any number of threads the same bits in input order, each chunk one
/// pair carried from a fresh state; trees without meshes and bad options are refused before
/// any query.
#[test]
fn refined_distance_many_is_a_pair_per_chunk_on_any_thread_count() {
    let t = teeth();
    let poses: Vec<Pose> = (0..40)
        .map(|i| {
            let s = i as f64 / 39.0;
            pose_b(
                0.6 - 0.62 * s,
                [0.3 * s, -0.2 * s],
                [0.02 * s, 0.0, 0.05 * s],
            )
        })
        .collect();
    let (pa, q, chunk) = ([Pose::IDENTITY], RefineOptions::default(), 16);
    let at = |threads| BatchOptions { threads, chunk };
    let bits = |r: &innersphere::RefinedDistance| {
        let mut v = vec![r.distance.to_bits(), r.spheres.distance.to_bits()];
        v.extend(r.point_a.to_array().map(f64::to_bits));
        v.extend(r.point_b.to_array().map(f64::to_bits));
        v.extend([
            r.tri_a as u64,
            r.tri_b as u64,
            r.intersecting as u64,
            r.complete as u64,
        ]);
        v
    };
    let one = batch::refined_distance_many(&t.a, &t.b, &pa, &poses, &q, &at(1)).unwrap();
    assert_eq!(one.len(), poses.len());
    assert!(one.iter().any(|r| r.intersecting) && one.iter().any(|r| !r.intersecting));
    let mut pair = Pair::new(t.a.clone(), t.b.clone());
    for (i, pb) in poses.iter().enumerate() {
        if i % chunk == 0 {
            pair.reset();
        }
        let r = pair.refined_distance_with(&Pose::IDENTITY, pb, &q).unwrap();
        assert_eq!(bits(&one[i]), bits(&r), "pose {i}");
    }
    for threads in [2, 3, 0] {
        let got = batch::refined_distance_many(&t.a, &t.b, &pa, &poses, &q, &at(threads)).unwrap();
        let same = got.iter().zip(&one).all(|(x, y)| bits(x) == bits(y));
        assert!(same, "{threads} threads");
    }
    let bare = SharedTree::new(t.a.tree().clone());
    let err = batch::refined_distance_many(&bare, &t.b, &pa, &poses, &q, &at(2)).unwrap_err();
    assert!(err.to_string().contains("meshes"), "{err}");
    let nan = RefineOptions {
        radius_scale: f64::NAN,
        ..q
    };
    let err = batch::refined_distance_many(&t.a, &t.b, &pa, &poses, &nan, &at(2)).unwrap_err();
    assert!(err.to_string().contains("radius_scale"), "{err}");
}

/// The meshes' penetration's batch door, as the refined distance's: the same bits on any
/// number of threads in input order, each chunk one pair carried from a fresh state; trees
/// without meshes and a bad stiffness refused before any query.
#[test]
fn mesh_penetration_many_is_a_pair_per_chunk_on_any_thread_count() {
    let t = teeth();
    let poses: Vec<Pose> = (0..40)
        .map(|i| {
            let s = i as f64 / 39.0;
            pose_b(
                0.3 - 0.7 * s,
                [0.3 * s, -0.2 * s],
                [0.02 * s, 0.0, 0.05 * s],
            )
        })
        .collect();
    let (pa, q, chunk) = ([Pose::IDENTITY], PenetrationOptions::default(), 16);
    let at = |threads| BatchOptions { threads, chunk };
    let bits = |m: &innersphere::MeshPenetration| {
        let mut v = vec![m.volume.to_bits(), m.max_depth.to_bits()];
        for x in [m.force, m.torque_a, m.torque_b, m.gradient] {
            v.extend(x.to_array().map(f64::to_bits));
        }
        v.extend([m.patch_count as u64, m.crossing_pairs as u64]);
        v
    };
    let one = batch::mesh_penetration_many(&t.a, &t.b, &pa, &poses, &q, &at(1)).unwrap();
    assert_eq!(one.len(), poses.len());
    assert!(one.iter().any(|m| m.contact) && one.iter().any(|m| !m.contact));
    let mut pair = Pair::new(t.a.clone(), t.b.clone());
    for (i, pb) in poses.iter().enumerate() {
        if i % chunk == 0 {
            pair.reset();
        }
        let m = pair.mesh_penetration_with(&Pose::IDENTITY, pb, &q).unwrap();
        assert_eq!(bits(&one[i]), bits(&m), "pose {i}");
    }
    for threads in [2, 3, 0] {
        let got = batch::mesh_penetration_many(&t.a, &t.b, &pa, &poses, &q, &at(threads)).unwrap();
        let same = got.iter().zip(&one).all(|(x, y)| bits(x) == bits(y));
        assert!(same, "{threads} threads");
    }
    let bare = SharedTree::new(t.a.tree().clone());
    let err = batch::mesh_penetration_many(&bare, &t.b, &pa, &poses, &q, &at(2)).unwrap_err();
    assert!(err.to_string().contains("meshes"), "{err}");
    let nan = PenetrationOptions {
        stiffness: f64::NAN,
        ..q
    };
    let err = batch::mesh_penetration_many(&t.a, &t.b, &pa, &poses, &nan, &at(2)).unwrap_err();
    assert!(err.to_string().contains("stiffness"), "{err}");
}
