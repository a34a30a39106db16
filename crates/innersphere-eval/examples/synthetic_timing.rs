//! Times packing and hierarchy on an analytic field (a wavy slab) with millions of voxels.
use glam::DVec3;
use innersphere::build::pack_signed_distance;
use innersphere::progress::Silent;
use std::time::Instant;

fn main() {
    let h: f64 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(0.01);
    let half = DVec3::new(1.0, 0.7, 0.3);
    let sdf = |p: DVec3| {
        // a box with a wavy top: many small spheres near the waves
        let wave = 0.05 * (p.x * 40.0).sin() * (p.y * 30.0).cos();
        (half - p.abs()).min_element().min(half.z - wave - p.z)
    };
    let t = Instant::now();
    let spheres = pack_signed_distance(-half, half, h, sdf, &Default::default()).unwrap();
    println!(
        "spheres {} packing {:.2}s",
        spheres.len(),
        t.elapsed().as_secs_f64()
    );
    let t = Instant::now();
    let meta = innersphere::tree::TreeMeta::unmeasured(4, h, [0.0; 3], [0.0; 3]);
    let (tree, stats) =
        innersphere::build::tree_of_spheres(&spheres, &Default::default(), meta, &Silent).unwrap();
    println!(
        "nodes {} depth {} hierarchy {:.2}s {:?}",
        tree.len(),
        tree.max_depth(),
        t.elapsed().as_secs_f64(),
        stats
    );
    println!(
        "peak {:?} MB",
        innersphere_eval::sysinfo::peak_memory_bytes().map(|b| b >> 20)
    );
}
