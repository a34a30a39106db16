//! Packing and hierarchy invariants on analytic distance fields (boxes and balls), so that
//! they are tested independently of the mesh pipeline.

use glam::DVec3;
use innersphere::build::tree_of_spheres;
use innersphere::field::{DistanceField, VoxelGrid};
use innersphere::hierarchy::HierarchyOptions;
use innersphere::packing::{self, PackingOptions, Sphere};
use innersphere::progress::Silent;
use innersphere::tree::{file, SphereTree, TreeMeta};
use proptest::prelude::*;

/// The distance field of an analytic solid given by its signed distance (positive inside).
fn analytic_field(lo: DVec3, hi: DVec3, h: f64, sdf: impl Fn(DVec3) -> f64) -> DistanceField {
    let grid = VoxelGrid::covering(lo, hi, h).unwrap();
    DistanceField::from_signed_distance(grid, sdf)
}

fn box_sdf(half: DVec3) -> impl Fn(DVec3) -> f64 {
    move |p: DVec3| (half - p.abs()).min_element()
}

fn ball_sdf(r: f64) -> impl Fn(DVec3) -> f64 {
    move |p: DVec3| r - p.length()
}

fn meta() -> TreeMeta {
    TreeMeta::unmeasured(4, 0.1, [0.0; 3], [0.0; 3])
}

fn assert_packing_invariants(spheres: &[Sphere], sdf: &dyn Fn(DVec3) -> f64) {
    for s in spheres {
        assert!(s.radius > 0.0);
        assert!(
            s.radius <= sdf(s.center) + 1e-12,
            "sphere {s:?} pokes out: distance {}",
            sdf(s.center)
        );
    }
    for (i, a) in spheres.iter().enumerate() {
        for b in &spheres[i + 1..] {
            let gap = (a.center - b.center).length() - a.radius - b.radius;
            assert!(gap >= -1e-12, "overlap {gap} between {a:?} and {b:?}");
        }
    }
}

/// `f` on a rayon pool of `threads` threads.
fn on(threads: usize, f: &(dyn Fn() -> Vec<Sphere> + Sync)) -> Vec<Sphere> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
        .install(f)
}

fn assert_tree_invariants(tree: &SphereTree, spheres: &[Sphere]) {
    tree.validate_structure().unwrap();
    assert_eq!(
        tree.leaf_count(),
        spheres.len(),
        "every leaf holds exactly one sphere"
    );
    // Every node encloses every leaf sphere below it (in f32 as stored, no tolerance).
    for leaf in tree.leaves() {
        let (cl, rl) = tree.sphere(leaf);
        let mut n = tree.parent[leaf];
        while n != innersphere::tree::NO_PARENT {
            let (cp, rp) = tree.sphere(n as usize);
            let need = (cl.as_dvec3() - cp.as_dvec3()).length() + rl as f64;
            assert!(need <= rp as f64, "node {n} does not enclose leaf {leaf}");
            n = tree.parent[n as usize];
        }
    }
    // Each packed sphere is exactly one leaf: its centre rounded to the nearest f32, and the
    // largest f32 radius that keeps the leaf inside the packed sphere.
    let key = |c: [f32; 3], r: f32| [c[0].to_bits(), c[1].to_bits(), c[2].to_bits(), r.to_bits()];
    let mut want: Vec<[u32; 4]> = spheres
        .iter()
        .map(|s| {
            let c32 = s.center.as_vec3();
            let room = s.radius - (c32.as_dvec3() - s.center).length();
            key(c32.to_array(), largest_f32_not_above(room))
        })
        .collect();
    let mut got: Vec<[u32; 4]> = tree
        .leaves()
        .map(|n| {
            let (c, r) = tree.sphere(n);
            key(c.to_array(), r)
        })
        .collect();
    want.sort_unstable();
    got.sort_unstable();
    assert!(
        want.windows(2).all(|w| w[0] != w[1]),
        "two packed spheres round to the same leaf"
    );
    assert!(
        want == got,
        "the leaves are not the packed spheres rounded to f32"
    );
    // The stored leaves are pairwise disjoint. Each lies inside its packed sphere, so they
    // overlap no more than the packed spheres may (1e-12, see `assert_packing_invariants`);
    // computing the gap from the f32 values in f64 adds at most a few 1e-16.
    let leaves: Vec<(DVec3, f64)> = tree
        .leaves()
        .map(|n| {
            let (c, r) = tree.sphere(n);
            (c.as_dvec3(), r as f64)
        })
        .collect();
    for (i, a) in leaves.iter().enumerate() {
        for b in &leaves[i + 1..] {
            let gap = (a.0 - b.0).length() - a.1 - b.1;
            assert!(gap >= -1e-12, "leaves {a:?} and {b:?} overlap by {}", -gap);
        }
    }
}

/// The largest f32 not above `x` (0 for `x` ≤ 0).
fn largest_f32_not_above(x: f64) -> f32 {
    if x <= 0.0 {
        return 0.0;
    }
    let r = x as f32;
    let r = if r as f64 > x {
        f32::from_bits(r.to_bits() - 1)
    } else {
        r
    };
    assert!(r as f64 <= x && f32::from_bits(r.to_bits() + 1) as f64 > x);
    r
}

#[test]
fn box_packing_and_tree() {
    let half = DVec3::new(1.0, 0.6, 0.4);
    let sdf = box_sdf(half);
    let field = analytic_field(-half, half, 0.05, &sdf);
    let spheres = packing::pack(&field, &PackingOptions::default(), None, &Silent);
    assert!(spheres.len() > 100);
    assert_packing_invariants(&spheres, &sdf);
    // The first sphere is the largest possible one.
    assert!((spheres[0].radius - 0.4).abs() < 0.05);
    let (tree, stats) =
        tree_of_spheres(&spheres, &HierarchyOptions::default(), meta(), &Silent).unwrap();
    assert_tree_invariants(&tree, &spheres);
    assert!(stats.enclosing_ratio_mean < 1.0 + 1e-6, "{stats:?}");
    // Coverage of a box is substantial.
    let cov = packing::total_volume(&spheres) / (8.0 * half.x * half.y * half.z);
    assert!(cov > 0.5 && cov < 1.0, "coverage {cov}");
}

#[test]
fn min_radius_and_max_count_are_respected() {
    let half = DVec3::new(1.0, 0.7, 0.5);
    let sdf = box_sdf(half);
    let field = analytic_field(-half, half, 0.05, &sdf);
    let opts = PackingOptions {
        min_radius: 0.1,
        ..Default::default()
    };
    let spheres = packing::pack(&field, &opts, None, &Silent);
    assert!(spheres.len() > 5);
    assert!(spheres.iter().all(|s| s.radius >= 0.1));
    let capped = packing::pack(
        &field,
        &PackingOptions {
            max_spheres: 7,
            ..Default::default()
        },
        None,
        &Silent,
    );
    assert_eq!(capped.len(), 7);
}

#[test]
fn hierarchy_is_deterministic_and_round_trips_through_the_file_format() {
    let half = DVec3::new(1.0, 0.7, 0.5);
    let sdf = box_sdf(half);
    let field = analytic_field(-half, half, 0.04, &sdf);
    let spheres = packing::pack(&field, &PackingOptions::default(), None, &Silent);
    for fanout in [2, 4, 8] {
        let opts = HierarchyOptions {
            fanout,
            ..Default::default()
        };
        let (a, _) = tree_of_spheres(&spheres, &opts, meta(), &Silent).unwrap();
        let (b, _) = tree_of_spheres(&spheres, &opts, meta(), &Silent).unwrap();
        let bytes = file::to_bytes(&a);
        assert_eq!(
            bytes,
            file::to_bytes(&b),
            "fanout {fanout}: not deterministic"
        );
        assert!(a.child_count.iter().all(|&c| c as u32 <= fanout));
        assert_tree_invariants(&a, &spheres);
        let back = file::from_bytes(&bytes).unwrap();
        assert!(back == a, "the tree changed in a file round trip");
    }
}

#[test]
fn corrupt_tree_files_are_errors() {
    let half = DVec3::new(1.0, 0.7, 0.5);
    let sdf = box_sdf(half);
    let field = analytic_field(-half, half, 0.1, &sdf);
    let spheres = packing::pack(&field, &PackingOptions::default(), None, &Silent);
    let (tree, _) =
        tree_of_spheres(&spheres, &HierarchyOptions::default(), meta(), &Silent).unwrap();
    let bytes = file::to_bytes(&tree);
    // Every truncation.
    for len in (0..bytes.len()).step_by(7) {
        assert!(
            file::from_bytes(&bytes[..len]).is_err(),
            "truncated to {len}"
        );
    }
    // Every single-byte flip is caught (checksum, magic or size).
    for pos in (0..bytes.len()).step_by(5) {
        let mut b = bytes.clone();
        b[pos] ^= 0x5a;
        assert!(file::from_bytes(&b).is_err(), "flip at {pos} undetected");
    }
    // A lying node count does not allocate: it is rejected by size.
    let mut b = bytes.clone();
    b[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
    assert!(file::from_bytes(&b).is_err());
    // A valid checksum over a broken structure is still rejected.
    let mut broken = tree.clone();
    broken.first_child[0] = 0;
    assert!(file::from_bytes(&file::to_bytes(&broken)).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]
    #[test]
    fn packing_invariants_on_random_boxes_and_balls(
        hx in 0.2..1.0f64, hy in 0.2..1.0f64, hz in 0.2..1.0f64,
        h in 0.04..0.15f64, min_r in 0.0..0.1f64, ball in any::<bool>(),
        fanout in 2u32..9,
    ) {
        let half = DVec3::new(hx, hy, hz);
        let sdf: Box<dyn Fn(DVec3) -> f64> = if ball {
            Box::new(ball_sdf(hx))
        } else {
            Box::new(box_sdf(half))
        };
        let ext = if ball { DVec3::splat(hx) } else { half };
        let field = analytic_field(-ext, ext, h, &sdf);
        prop_assume!(!field.inside.is_empty());
        let opts = PackingOptions { min_radius: min_r, ..Default::default() };
        let spheres = packing::pack(&field, &opts, None, &Silent);
        assert_packing_invariants(&spheres, &sdf);
        prop_assume!(!spheres.is_empty());
        let hopts = HierarchyOptions { fanout, ..Default::default() };
        let (tree, _) = tree_of_spheres(&spheres, &hopts, meta(), &Silent).unwrap();
        assert_tree_invariants(&tree, &spheres);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    /// Off-grid refinement keeps every invariant: spheres inside, disjoint, tree valid.
    #[test]
    fn refined_packing_keeps_the_invariants(
        hx in 0.3..1.0f64, hy in 0.3..1.0f64, hz in 0.3..1.0f64,
        h in 0.05..0.15f64, min_r in 0.0..0.05f64, steps in 1u32..10,
    ) {
        let half = DVec3::new(hx, hy, hz);
        let sdf = box_sdf(half);
        let field = analytic_field(-half, half, h, &sdf);
        let bvh = innersphere::mesh::bvh::TriangleBvh::new(&innersphere::shapes::cuboid(half));
        let opts = PackingOptions { min_radius: min_r, refine_steps: steps, ..Default::default() };
        let spheres = packing::pack(&field, &opts, Some(&bvh), &Silent);
        prop_assume!(!spheres.is_empty());
        assert_packing_invariants(&spheres, &sdf);
        let plain = packing::pack(&field, &PackingOptions { min_radius: min_r, ..Default::default() }, None, &Silent);
        let (vr, vp) = (packing::total_volume(&spheres), packing::total_volume(&plain));
        prop_assert!(vr >= 0.9 * vp, "refined coverage {} much below plain {}", vr, vp);
        let (tree, _) = tree_of_spheres(&spheres, &HierarchyOptions::default(), meta(), &Silent).unwrap();
        assert_tree_invariants(&tree, &spheres);
    }
}

/// The packing from distance bounds (what the build runs) places the same spheres, bit for
/// bit, as the packing from exact distances, with and without off-grid refinement and a
/// minimum radius, on generated meshes of several shapes.
#[test]
fn packing_from_bounds_equals_packing_from_exact_distances() {
    use innersphere::field::distance;
    use innersphere::mesh::bvh::TriangleBvh;
    use innersphere::shapes;
    let meshes = [
        shapes::molar(3, 0.2),
        shapes::torus(1.0, 0.35, 48, 24),
        shapes::ellipsoid(DVec3::new(1.0, 0.6, 0.4), 3),
    ];
    for mesh in &meshes {
        let (lo, hi) = mesh.bbox();
        let grid = VoxelGrid::with_resolution(lo, hi, 40).unwrap();
        let bvh = TriangleBvh::new(mesh);
        let exact = distance::compute(mesh, grid, &Silent).unwrap();
        let bounds = distance::bounds(mesh, &bvh, grid, &Silent).unwrap();
        assert_eq!(exact.inside, bounds.inside);
        assert!(exact.dist.iter().zip(&bounds.bound).all(|(e, b)| e <= b));
        assert!(
            exact.dist.iter().zip(&bounds.bound).any(|(e, b)| e < b),
            "loose somewhere"
        );
        for opts in [
            PackingOptions::default(),
            PackingOptions {
                min_radius: 0.5 * grid.h,
                refine_steps: 8,
                ..Default::default()
            },
        ] {
            let want = packing::pack(&exact, &opts, Some(&bvh), &Silent);
            let got = packing::pack_bounded(&bounds, &bvh, &opts, &Silent);
            assert_eq!(want, got, "{opts:?}");
        }
    }
}

/// The parallel packing on generated meshes, with and without refinement: every sphere lies
/// within the surface's distance of its centre and none overlap, the spheres are the same on
/// 1, 4 and 16 threads, and they fill at least 97 % of the volume the global greedy order fills.
#[test]
fn parallel_packing_is_valid_thread_independent_and_as_full_as_the_global_order() {
    use innersphere::field::distance;
    use innersphere::mesh::bvh::TriangleBvh;
    use innersphere::shapes;
    let meshes = [
        shapes::molar(3, 0.2),
        shapes::torus(1.0, 0.35, 48, 24),
        shapes::ellipsoid(DVec3::new(1.0, 0.6, 0.4), 3),
    ];
    for mesh in &meshes {
        let (lo, hi) = mesh.bbox();
        let grid = VoxelGrid::with_resolution(lo, hi, 48).unwrap();
        let bvh = TriangleBvh::new(mesh);
        let bounds = distance::bounds(mesh, &bvh, grid, &Silent).unwrap();
        let exact = distance::compute(mesh, grid, &Silent).unwrap();
        assert!(exact.dist.iter().zip(&bounds.bound).any(|(e, b)| e < b));
        let surface = |p: DVec3| bvh.closest_point(p, f64::INFINITY).unwrap().dist_sq.sqrt();
        for opts in [
            PackingOptions::default(),
            PackingOptions {
                min_radius: 0.5 * grid.h,
                refine_steps: 8,
                ..Default::default()
            },
        ] {
            let one = on(1, &|| packing::pack_parallel(&bounds, &bvh, &opts, &Silent));
            let four = on(4, &|| packing::pack_parallel(&bounds, &bvh, &opts, &Silent));
            assert_eq!(one, four, "{opts:?}");
            // Many threads on few blocks: each block makes up to 16 voxels exact at once.
            let many = on(16, &|| {
                packing::pack_parallel(&bounds, &bvh, &opts, &Silent)
            });
            assert_eq!(one, many, "{opts:?}");
            // The bounds' tightness changes nothing: exact distances as bounds, same spheres.
            let tight = distance::DistanceBounds {
                bound: exact.dist.clone(),
                ..bounds.clone()
            };
            let from_exact = packing::pack_parallel(&tight, &bvh, &opts, &Silent);
            assert_eq!(one, from_exact, "{opts:?}");
            assert_packing_invariants(&one, &surface);
            let global = packing::pack_bounded(&bounds, &bvh, &opts, &Silent);
            let (v, g) = (packing::total_volume(&one), packing::total_volume(&global));
            assert!(v >= 0.97 * g, "{opts:?}: volume {v} against {g}");
        }
    }
}

/// With a finite sphere budget the parallel packing is the global order's (the largest N).
#[test]
fn parallel_packing_with_a_budget_is_the_global_order() {
    use innersphere::field::distance;
    use innersphere::mesh::bvh::TriangleBvh;
    let mesh = innersphere::shapes::molar(3, 0.2);
    let (lo, hi) = mesh.bbox();
    let grid = VoxelGrid::with_resolution(lo, hi, 32).unwrap();
    let bvh = TriangleBvh::new(&mesh);
    let bounds = distance::bounds(&mesh, &bvh, grid, &Silent).unwrap();
    let opts = PackingOptions {
        max_spheres: 50,
        ..Default::default()
    };
    let got = packing::pack_parallel(&bounds, &bvh, &opts, &Silent);
    assert_eq!(got.len(), 50);
    assert_eq!(got, packing::pack_bounded(&bounds, &bvh, &opts, &Silent));
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(12))]
    /// The parallel packing on random ellipsoids and grids: spheres within the surface's
    /// distance of their centres, disjoint, and the same on 1 and 3 threads.
    #[test]
    fn parallel_packing_invariants_on_random_ellipsoids(
        rx in 0.3..1.2f64, ry in 0.3..1.2f64, rz in 0.3..1.2f64,
        cells in 16u32..40, refine in any::<bool>(), min_r in 0.0..0.6f64,
    ) {
        use innersphere::field::distance;
        use innersphere::mesh::bvh::TriangleBvh;
        let mesh = innersphere::shapes::ellipsoid(DVec3::new(rx, ry, rz), 3);
        let (lo, hi) = mesh.bbox();
        let grid = VoxelGrid::with_resolution(lo, hi, cells).unwrap();
        let bvh = TriangleBvh::new(&mesh);
        let bounds = distance::bounds(&mesh, &bvh, grid, &Silent).unwrap();
        let opts = PackingOptions {
            min_radius: min_r * grid.h,
            refine_steps: if refine { 8 } else { 0 },
            ..Default::default()
        };
        let run = || packing::pack_parallel(&bounds, &bvh, &opts, &Silent);
        let one = on(1, &run);
        prop_assert_eq!(&one, &on(3, &run));
        prop_assert!(!one.is_empty());
        assert_packing_invariants(&one, &|p| bvh.closest_point(p, f64::INFINITY).unwrap().dist_sq.sqrt());
    }
}
