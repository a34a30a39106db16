//! `ist bench`: benchmarks whose numbers go into BENCHMARKS.md.

use crate::build::BuildArgs;
use anyhow::Context;
use std::path::PathBuf;

/// Arguments of `ist bench`.
#[derive(clap::Args)]
pub struct Args {
    #[command(subcommand)]
    what: What,
}

#[derive(clap::Subcommand)]
enum What {
    /// Time the whole build (load, distance field, packing, hierarchy) of each mesh.
    Build(BenchBuild),
    /// Batch queries on several thread counts: poses per second, and whether every thread
    /// count answers the same bits.
    Batch(BenchBatch),
    /// Reproduce the paper's figures on a pair along a motion: CSV files and PNG charts.
    Paper(BenchPaper),
}

#[derive(clap::Args)]
struct BenchBuild {
    /// Mesh files.
    #[arg(required = true)]
    meshes: Vec<PathBuf>,
    #[command(flatten)]
    opts: BuildArgs,
    /// Builds per mesh (medians are reported).
    #[arg(long, default_value_t = 1)]
    repeat: usize,
    /// Print JSON instead of a markdown table.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct BenchBatch {
    /// Tree of body A (fixed).
    a: PathBuf,
    /// Tree of body B.
    b: PathBuf,
    /// Poses of B: random around the identity (for a scanned jaw pair, the bite).
    #[arg(long, default_value_t = 100_000)]
    poses: usize,
    /// Largest shift along each axis, in model units (mm for the jaw scans).
    #[arg(long, default_value_t = 2.0)]
    mm: f64,
    /// Largest rotation, in degrees, about B's centre of mass.
    #[arg(long, default_value_t = 4.0)]
    deg: f64,
    /// Seed of the poses.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Query kind: distance, refined-distance, contact, penetration or mesh-penetration.
    #[arg(long, default_value = "distance")]
    query: String,
    /// Refined distance and mesh penetration: the meshes of A and B (default: the meshes the
    /// trees were built from, where those files still hold them).
    #[arg(long, num_args = 2, value_names = ["MESH_A", "MESH_B"])]
    meshes: Option<Vec<PathBuf>>,
    #[command(flatten)]
    unit: crate::files::UnitArg,
    /// Thread counts to time (0 = all cores).
    #[arg(long, value_delimiter = ',', default_value = "1,0")]
    threads: Vec<usize>,
    /// Poses per fresh-state chunk (1: every pose from a fresh state, right for scattered
    /// poses; a motion gains from long chunks).
    #[arg(long, default_value_t = 1)]
    chunk: usize,
    /// Runs per thread count (the best is reported).
    #[arg(long, default_value_t = 3)]
    repeat: usize,
    /// Print JSON instead of a markdown table.
    #[arg(long)]
    json: bool,
}

#[derive(clap::Args)]
struct BenchPaper {
    /// Mesh of body A (fixed).
    #[arg(long)]
    a: PathBuf,
    /// Mesh of body B (moved by the motion).
    #[arg(long)]
    b: PathBuf,
    /// Motion CSV (`t,tx,ty,tz,qw,qx,qy,qz`: the pose of B in A's frame).
    #[arg(long)]
    motion: PathBuf,
    /// Output folder.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    unit: crate::files::UnitArg,
    /// Build options of the main trees (backtracking, multipoint, ours vs paper);
    /// default: voxel size = longest side / 384.
    #[command(flatten)]
    opts: BuildArgs,
    /// Voxel sizes of the leaf-count sweep (default: longest side / 48 … / 384).
    #[arg(long, value_delimiter = ',')]
    sweep: Vec<f64>,
    /// Compare with the exact mesh distance on every K-th frame; the exact method is timed
    /// on those frames, each warm-started from the previous compared frame (K back).
    #[arg(long, default_value_t = 10)]
    every: usize,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    match args.what {
        What::Paper(a) => paper(a),
        What::Batch(a) => batch(a),
        What::Build(a) => build(a),
    }
}

/// `ist bench paper`.
fn paper(args: BenchPaper) -> anyhow::Result<i32> {
    let BenchPaper {
        a,
        b,
        motion,
        out,
        unit,
        opts,
        sweep,
        every,
        json,
    } = args;
    use innersphere_eval::paper::{run, PaperOptions, FILES};
    // Every file the run may write into --out, checked against the inputs before
    // the minutes of work.
    // The folder is the run's own: made here, so that its check sees it.
    std::fs::create_dir_all(&out)
        .with_context(|| format!("creating the output folder {}", out.display()))?;
    let outputs: Vec<PathBuf> = FILES.iter().map(|f| out.join(f)).collect();
    let outputs: Vec<(&std::path::Path, _)> = outputs
        .iter()
        .map(|p| {
            let png = p.extension().is_some_and(|e| e == "png");
            let kind = if png {
                crate::files::PNG_FILE
            } else {
                crate::files::CSV_FILE
            };
            (p.as_path(), kind)
        })
        .collect();
    crate::files::check_outputs(&outputs, &[&a, &b, &motion])?;
    let ma = crate::files::load_mesh(&a, unit.unit)?;
    let mb = crate::files::load_mesh(&b, unit.unit)?;
    let m = innersphere_eval::motion::Motion::load(&motion)?;
    let size = [ma.bbox(), mb.bbox()]
        .iter()
        .map(|(lo, hi)| (*hi - *lo).max_element())
        .fold(0.0, f64::max);
    let mut po = PaperOptions::for_size(size);
    po.every = every;
    if !sweep.is_empty() {
        po.voxel_sizes = sweep;
    }
    // The given flags override the paper defaults' fields (voxel = longest / 384).
    po.main = opts.apply(po.main);
    innersphere::build::validate_options(&po.main)?;
    let s = run(&ma, &mb, &m, &po, &out, &mut |line| eprintln!("{line}"))?;
    if json {
        crate::print::print_json(&s)?;
    } else {
        println!("machine: {}", innersphere_eval::sysinfo::cpu_description());
        println!("wrote {} files to {}", s.files.len(), out.display());
        println!(
            "main trees {} + {} leaves: proximity p99 (1 pass, all frames) {:.1} µs vs exact mesh distance p99 (1 pass, every {} frames, each warm-started from the previous compared frame) {:.1} µs ({:.1}x); backtracking {:.1}x faster than the full traversal in contact (best of 2); distance error p95 {:.4} units (model units, mm for the jaw scans), refined to the meshes {:.5}",
            s.main_leaves.0,
            s.main_leaves.1,
            s.proximity_p99_us,
            po.every.max(1),
            s.exact_p99_us,
            s.exact_p99_us / s.proximity_p99_us,
            s.backtracking_speedup_in_contact,
            s.main_abs_err_p95,
            s.main_refined_abs_err_p95
        );
    }
    Ok(0)
}

/// `ist bench batch`.
fn batch(args: BenchBatch) -> anyhow::Result<i32> {
    let BenchBatch {
        a,
        b,
        poses,
        mm,
        deg,
        seed,
        query,
        meshes,
        unit,
        threads,
        chunk,
        repeat,
        json,
    } = args;
    if poses > 100_000_000 || !(mm.is_finite() && deg.is_finite()) {
        anyhow::bail!("--poses must be at most 1e8 and --mm, --deg finite numbers");
    }
    let mut ta = innersphere::SharedTree::new(crate::files::load_tree(&a)?);
    let mut tb = innersphere::SharedTree::new(crate::files::load_tree(&b)?);
    if query == "refined-distance" || query == "mesh-penetration" {
        let given = meshes.as_deref().unwrap_or(&[]);
        ta = crate::bodies::with_mesh(ta, given.first(), None, "A", unit.unit)?;
        tb = crate::bodies::with_mesh(tb, given.get(1), None, "B", unit.unit)?;
    }
    let centre = innersphere::glam::DVec3::from_array(tb.meta.center_of_mass);
    let p = innersphere_eval::bench::perturbed_poses(poses, seed, mm, deg, centre);
    let rows = innersphere_eval::bench::bench_batch(&ta, &tb, &p, &query, &threads, chunk, repeat)?;
    if json {
        crate::print::print_json(&rows)?;
    } else {
        println!("machine: {}", innersphere_eval::sysinfo::cpu_description());
        println!("{poses} poses, {query}, chunks of {chunk}, best of {repeat}");
        println!("| threads | s | poses/s | speed-up | same answers |");
        println!("|---|---|---|---|---|");
        for r in &rows {
            println!(
                "| {} | {:.3} | {:.0} | {:.2} | {} |",
                if r.threads == 0 {
                    "all".to_string()
                } else {
                    r.threads.to_string()
                },
                r.seconds,
                r.poses_per_second,
                r.speedup,
                r.same_answers
            );
        }
    }
    Ok(if rows.iter().all(|r| r.same_answers) {
        0
    } else {
        1
    })
}

/// `ist bench build`.
fn build(args: BenchBuild) -> anyhow::Result<i32> {
    let BenchBuild {
        meshes,
        opts,
        repeat,
        json,
    } = args;
    let options = opts.options();
    innersphere::build::validate_options(&options)?;
    let mut rows = Vec::new();
    if !json {
        println!("machine: {}", innersphere_eval::sysinfo::cpu_description());
        println!("{}", crate::print::UNITS);
        println!("| mesh | triangles | voxel (units) | inside voxels | spheres | depth | coverage | load s | field s | packing s | hierarchy s | total s (min–max) | peak MiB |");
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    }
    for m in &meshes {
        let r = innersphere_eval::bench::bench_build(m, &options, repeat)?;
        if !json {
            println!(
                "| {} | {} | {:.4} | {} | {} | {} | {:.3} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} ({:.2}–{:.2}) | {} |",
                r.mesh, r.triangles, r.voxel_size, r.voxels_inside, r.spheres, r.depth,
                r.coverage, r.load_s, r.distance_field_s, r.packing_s, r.hierarchy_s,
                r.total_s, r.total_min_s, r.total_max_s,
                r.peak_memory_bytes.map(|b| (b >> 20).to_string()).unwrap_or_default()
            );
        }
        rows.push(r);
    }
    if json {
        crate::print::print_json(&rows)?;
    }
    Ok(0)
}
