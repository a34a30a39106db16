//! Builds one mesh and prints the build report (a library-only twin of `ist build --json`,
//! handy while the CLI is being changed).
use innersphere::build::{build_tree, BuildOptions, Resolution};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = std::path::Path::new(&args[1]);
    let h: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.15);
    let refine: u32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0);
    let min_r: f64 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(0.0);
    let t = std::time::Instant::now();
    let mesh = innersphere::mesh::io::load(path).unwrap();
    let mut opts = BuildOptions {
        resolution: Resolution::VoxelSize(h),
        ..Default::default()
    };
    opts.packing.refine_steps = refine;
    opts.packing.min_radius = min_r;
    let (_tree, r) = build_tree(&mesh, &opts, &innersphere::progress::Silent).unwrap();
    println!(
        "spheres {} voxels {} coverage {:.3} stages {:?} total {:.2}s peak {:?}MiB",
        r.spheres,
        r.voxels_inside,
        r.coverage,
        r.stage_seconds,
        t.elapsed().as_secs_f64(),
        innersphere_eval::sysinfo::peak_memory_bytes().map(|b| b >> 20)
    );
}
