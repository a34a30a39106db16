//! `ist demo`: the main job on a built-in model — no files needed.

use crate::build::BuildArgs;
use crate::progress::Bars;

/// Arguments of `ist demo`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    opts: BuildArgs,
    /// No progress bars.
    #[arg(short, long)]
    quiet: bool,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let opts = args.opts.options();
    let bars = Bars::new(args.quiet || args.json);
    let pair = innersphere::eval::demo::build_pair(&opts, &bars)?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({ "a": pair.a.2, "b": pair.b.2 }))?
        );
        return Ok(0);
    }
    println!("innersphere demo: two generated interlocking tooth-like bodies");
    println!("| body | triangles | inside voxels | spheres | nodes | depth | coverage | build s |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, (_, _, r)) in [("A (upper)", &pair.a), ("B (lower)", &pair.b)] {
        println!(
            "| {name} | {} | {} | {} | {} | {} | {:.3} | {:.2} |",
            r.mesh.triangles, r.voxels_inside, r.spheres, r.nodes, r.depth, r.coverage, r.seconds
        );
    }
    Ok(0)
}
