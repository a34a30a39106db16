//! Mass properties of closed meshes against closed forms, and their place in the tree's meta.

use glam::{DMat3, DQuat, DVec3};
use innersphere::{shapes, BuildOptions, Mesh, Resolution, SphereTree};
use proptest::prelude::*;

fn moved(mesh: &Mesh, rot: DQuat, t: DVec3) -> Mesh {
    let mut m = mesh.clone();
    for v in &mut m.vertices {
        *v = rot * *v + t;
    }
    m
}

fn close(a: DMat3, b: DMat3, tol: f64) -> bool {
    (a - b).to_cols_array().iter().all(|x| x.abs() <= tol)
}

proptest! {
    /// A box of sides 2a × 2b × 2c, turned and moved anywhere: volume 8abc, centre at the
    /// translation, inertia R·diag(V(b²+c²)/3, …)·Rᵀ about it.
    #[test]
    fn a_box_anywhere_has_the_closed_form(
        h in (0.01f64..10.0, 0.01f64..10.0, 0.01f64..10.0),
        axis in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
        angle in -3.2f64..3.2,
        t in (-1e3f64..1e3, -1e3f64..1e3, -1e3f64..1e3),
        inward in any::<bool>(),
    ) {
        let half = DVec3::new(h.0, h.1, h.2);
        let axis = DVec3::new(axis.0, axis.1, axis.2);
        prop_assume!(axis.length() > 1e-3);
        let rot = DQuat::from_axis_angle(axis.normalize(), angle);
        let t = DVec3::new(t.0, t.1, t.2);
        let mut mesh = moved(&shapes::cuboid(half), rot, t);
        if inward {
            mesh.flip();
        }
        let m = mesh.mass_properties().unwrap();
        let v = 8.0 * half.x * half.y * half.z;
        prop_assert!((m.volume - v).abs() <= 1e-9 * v.max(1.0), "{} vs {v}", m.volume);
        let scale = half.max_element() + t.abs().max_element();
        prop_assert!((m.center_of_mass - t).length() <= 1e-9 * scale, "{:?}", m.center_of_mass);
        let sq = half * half;
        let diag = DVec3::new(sq.y + sq.z, sq.x + sq.z, sq.x + sq.y) * (v / 3.0);
        let r = DMat3::from_quat(rot);
        let want = r * DMat3::from_diagonal(diag) * r.transpose();
        let tol = 1e-7 * v * (scale * scale).max(1.0);
        prop_assert!(close(m.inertia, want, tol), "{:?} vs {:?}", m.inertia, want);
    }
}

#[test]
fn a_fine_sphere_has_the_ball_inertia() {
    let m = shapes::icosphere(6).mass_properties().unwrap();
    let v = 4.0 / 3.0 * std::f64::consts::PI;
    assert!((m.volume / v - 1.0).abs() < 2e-3, "{}", m.volume);
    let i = 0.4 * v;
    for d in [m.inertia.x_axis.x, m.inertia.y_axis.y, m.inertia.z_axis.z] {
        assert!((d / i - 1.0).abs() < 5e-3, "{d} vs {i}");
    }
    assert!(m.inertia.x_axis.y.abs() < 1e-3 * i);
}

#[test]
fn a_flat_mesh_has_none() {
    let mut m = shapes::cuboid(DVec3::ONE);
    for v in &mut m.vertices {
        v.z = 0.0;
    }
    assert!(m.mass_properties().is_none());
}

#[test]
fn a_build_stores_the_inertia_and_a_file_keeps_it() {
    let mesh = shapes::cuboid(DVec3::new(1.0, 2.0, 3.0));
    let tree = SphereTree::build(
        &mesh,
        &BuildOptions {
            resolution: Resolution::Cells(16),
            ..Default::default()
        },
    )
    .unwrap();
    let want = mesh.mass_properties().unwrap().inertia_entries();
    assert_eq!(tree.meta.inertia, Some(want));
    let bytes = innersphere::tree::file::to_checked_bytes(&tree).unwrap();
    let back = innersphere::tree::file::from_bytes(&bytes).unwrap();
    assert_eq!(back.meta.inertia, Some(want));
}

#[test]
fn a_tree_written_before_the_inertia_reads_as_none() {
    let mesh = shapes::cuboid(DVec3::ONE);
    let mut tree = SphereTree::build(
        &mesh,
        &BuildOptions {
            resolution: Resolution::Cells(8),
            ..Default::default()
        },
    )
    .unwrap();
    tree.meta.inertia = None;
    let bytes = innersphere::tree::file::to_checked_bytes(&tree).unwrap();
    assert!(!String::from_utf8_lossy(&bytes).contains("inertia"));
    let back = innersphere::tree::file::from_bytes(&bytes).unwrap();
    assert_eq!(back.meta.inertia, None);
}
