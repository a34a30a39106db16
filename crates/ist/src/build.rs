//! `ist build`: mesh → Inner Sphere Tree file.

use crate::progress::Bars;
use anyhow::Context;
use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::hierarchy::HierarchyOptions;
use innersphere::packing::PackingOptions;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `ist build`.
#[derive(clap::Args)]
pub struct Args {
    /// Mesh file: .stl, .obj, .ply or .off, optionally .gz.
    mesh: PathBuf,
    /// Output tree file.
    #[arg(short, long)]
    output: PathBuf,
    #[command(flatten)]
    opts: BuildArgs,
    /// Print the build report as JSON (no progress bars).
    #[arg(long)]
    json: bool,
    /// No progress bars.
    #[arg(short, long)]
    quiet: bool,
}

/// Build options shared by every subcommand that builds trees.
#[derive(clap::Args, Clone)]
pub struct BuildArgs {
    /// Voxel edge length in model units.
    #[arg(long, conflicts_with = "resolution")]
    pub voxel_size: Option<f64>,
    /// Cells along the longest side of the bounding box (default 128).
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Smallest inner-sphere radius to place (model units).
    #[arg(long, default_value_t = 0.0)]
    pub min_radius: f64,
    /// Stop after this many inner spheres.
    #[arg(long)]
    pub max_spheres: Option<usize>,
    /// Off-grid refinement steps per sphere (0 = centres on voxel centres, as in the paper).
    #[arg(long, default_value_t = 0)]
    pub refine_steps: u32,
    /// Children per inner node.
    #[arg(long, default_value_t = 4)]
    pub fanout: u32,
}

impl BuildArgs {
    /// The library's options from the command line.
    pub fn options(&self) -> BuildOptions {
        BuildOptions {
            resolution: match (self.voxel_size, self.resolution) {
                (Some(h), _) => Resolution::VoxelSize(h),
                (None, Some(n)) => Resolution::Cells(n),
                (None, None) => Resolution::Cells(128),
            },
            packing: PackingOptions {
                min_radius: self.min_radius,
                max_spheres: self.max_spheres.unwrap_or(usize::MAX),
                refine_steps: self.refine_steps,
            },
            hierarchy: HierarchyOptions {
                fanout: self.fanout,
                ..Default::default()
            },
        }
    }
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let t0 = Instant::now();
    let opts = args.opts.options();
    innersphere::build::validate_options(&opts)?;
    let mesh = innersphere::mesh::io::load(&args.mesh)?;
    let t_load = t0.elapsed().as_secs_f64();
    let bars = Bars::new(args.quiet || args.json);
    let (tree, report) = build_tree(&mesh, &opts, &bars)?;
    let t1 = Instant::now();
    innersphere::tree::file::save(&tree, &args.output)
        .with_context(|| format!("writing {}", args.output.display()))?;
    let t_write = t1.elapsed().as_secs_f64();
    let total = t0.elapsed().as_secs_f64();
    if args.json {
        let mut v = serde_json::to_value(&report)?;
        v["seconds"] = total.into();
        v["build_seconds"] = report.seconds.into();
        v["stage_seconds"]["load"] = t_load.into();
        v["stage_seconds"]["write"] = t_write.into();
        v["output"] = args.output.display().to_string().into();
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        for w in &report.warnings {
            eprintln!("warning: {w}");
        }
        let s = &report.stage_seconds;
        println!("{} -> {}", args.mesh.display(), args.output.display());
        println!(
            "  mesh        {} vertices, {} triangles, volume {:.6}",
            report.mesh.vertices, report.mesh.triangles, report.mesh_volume
        );
        println!(
            "  grid        {} x {} x {} cells of {:.6}, {} inside",
            report.grid_dims[0],
            report.grid_dims[1],
            report.grid_dims[2],
            report.voxel_size,
            report.voxels_inside
        );
        println!(
            "  spheres     {} (radius {:.6} .. {:.6}), coverage {:.3}",
            report.spheres, report.min_sphere_radius, report.max_sphere_radius, report.coverage
        );
        println!(
            "  tree        {} nodes, depth {}, fan-out {}, enclosing ratio {:.4}",
            report.nodes, report.depth, report.fanout, report.enclosing_ratio_mean
        );
        println!(
            "  seconds     {total:.2} total: load {t_load:.2}, prepare {:.2}, distance field {:.2}, packing {:.2}, hierarchy {:.2}, write {t_write:.2}",
            s.prepare, s.distance_field, s.packing, s.hierarchy
        );
    }
    Ok(0)
}
