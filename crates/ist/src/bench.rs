//! `ist bench`: benchmarks whose numbers go into BENCHMARKS.md.

use crate::build::BuildArgs;
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
    Build {
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
    },
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    match args.what {
        What::Build {
            meshes,
            opts,
            repeat,
            json,
        } => {
            let options = opts.options();
            innersphere::build::validate_options(&options)?;
            let mut rows = Vec::new();
            if !json {
                println!("machine: {}", innersphere::eval::sysinfo::cpu_description());
                println!("| mesh | triangles | voxel | inside voxels | spheres | depth | coverage | load s | field s | packing s | hierarchy s | total s (min–max) | peak MiB |");
                println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
            }
            for m in &meshes {
                let r = innersphere::eval::bench::bench_build(m, &options, repeat)?;
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
                println!("{}", serde_json::to_string_pretty(&rows)?);
            }
            Ok(0)
        }
    }
}
