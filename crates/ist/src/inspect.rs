//! `ist inspect`: the defect report of a mesh, and what `ist build` will do with it.

use innersphere::build::MeshVerdict;
use innersphere::mesh::MeshReport;
use std::path::PathBuf;

/// Arguments of `ist inspect`.
#[derive(clap::Args)]
pub struct Args {
    /// Mesh file: .stl, .obj, .ply or .off, optionally .gz.
    mesh: PathBuf,
    #[command(flatten)]
    unit: crate::files::UnitArg,
    /// Print JSON (the report's fields, plus "verdict": closed, closed_inward, open or soup,
    /// and "verdict_text", the sentence of the last line of the plain output).
    #[arg(long)]
    json: bool,
}

/// The unit of a report field in the plain output (lengths in model units).
fn unit(field: &str) -> &'static str {
    match field {
        "volume" => " units³",
        "area" => " units²",
        "bbox_min" | "bbox_max" => " units",
        _ => "",
    }
}

/// One sentence: what kind of mesh this is and what `ist build` will do with it (the same
/// decision [`innersphere::build::build_tree`] makes, from the same [`MeshVerdict`]).
pub fn verdict_text(r: &MeshReport) -> String {
    let mut s = match MeshVerdict::of(r) {
        MeshVerdict::Closed => format!(
            "closed and consistently oriented{}: build uses the exact inside test (signed ray crossings with exact predicates) and measures coverage against the mesh volume",
            if r.nonmanifold_edges > 0 {
                format!(" (non-manifold at {} edges, which the exact test handles)", r.nonmanifold_edges)
            } else {
                String::new()
            }
        ),
        MeshVerdict::ClosedInward => format!(
            "closed but facing inward (volume {:.6} units³): build flips every triangle, warns, then uses the exact inside test",
            r.volume
        ),
        MeshVerdict::Open => format!(
            "{}: build decides inside/outside by the generalized winding number (≥ 0.5, which closes small holes), warns, and measures coverage against the inside-voxel volume; a repaired (closed, consistently oriented) mesh gets the exact test",
            if r.boundary_edges == 0 {
                format!(
                    "closed but not consistently oriented ({} non-manifold edges{})",
                    r.nonmanifold_edges,
                    if r.winding_consistent { "" } else { "; some edges are used twice in the same direction" }
                )
            } else {
                format!(
                    "open ({} boundary edges, {} non-manifold edges{})",
                    r.boundary_edges,
                    r.nonmanifold_edges,
                    if r.winding_consistent { "" } else { ", inconsistently oriented" }
                )
            }
        ),
        MeshVerdict::Soup => format!(
            "a triangle soup ({} of {} edges open, {} pieces): it encloses no volume, and build refuses it",
            r.boundary_edges, r.edges, r.components
        ),
    };
    if r.degenerate_triangles > 0 {
        s += &format!(
            "; {} degenerate (zero-area) triangles, which build tolerates with a warning",
            r.degenerate_triangles
        );
    }
    s
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let mesh = crate::files::load_mesh(&args.mesh, args.unit.unit)?;
    let report = MeshReport::of(&mesh);
    let verdict = MeshVerdict::of(&report);
    let text = verdict_text(&report);
    let mut v = serde_json::to_value(&report)?;
    if args.json {
        v["verdict"] = serde_json::to_value(verdict)?;
        v["verdict_text"] = text.into();
        crate::print::print_json(&v)?;
    } else {
        println!("{:>22}  {}", "units", crate::print::UNITS);
        if let Some(map) = v.as_object() {
            for (k, val) in map {
                println!("{k:>22}  {val}{}", unit(k));
            }
        }
        println!("verdict: {text}");
    }
    Ok(0)
}
