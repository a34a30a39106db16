//! `ist inspect`: the defect report of a mesh.

use std::path::PathBuf;

/// Arguments of `ist inspect`.
#[derive(clap::Args)]
pub struct Args {
    /// Mesh file: .stl, .obj, .ply or .off, optionally .gz.
    mesh: PathBuf,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let mesh = innersphere::mesh::io::load(&args.mesh)?;
    let report = innersphere::mesh::MeshReport::of(&mesh);
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        let v = serde_json::to_value(&report)?;
        if let Some(map) = v.as_object() {
            for (k, val) in map {
                println!("{k:>22}  {val}");
            }
        }
    }
    Ok(0)
}
