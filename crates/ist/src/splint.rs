//! `ist splint`: the occlusal splint (surgical wafer) between two arches at a planned pose,
//! as a watertight binary STL, with its measurements.

use anyhow::Context;
use innersphere::splint::{self, Opening, SplintOptions};
use innersphere::Pose;
use std::path::PathBuf;

/// Arguments of `ist splint`. Lengths in the meshes' units (millimetres for dental scans).
#[derive(clap::Args)]
#[command(
    after_help = "The wafer is made in A's frame and inserted along the pair's occlusal axis: undercuts along it are blocked out, so it goes on and comes off each arch.\nJSON: volume (mm³), triangles, vertices, bodies, watertight, manifold, winding_consistent, min_thickness / thickness_p01 (mm, along inward normals), min_distance_a / _b (mm, exact, over the splint's vertices), a/b_vertices_inside, coverage_a / _b (share of each arch's occlusal surface — within 3.5 mm of the other arch — within clearance + 0.15 mm of the splint), perforated_area (mm²), seconds."
)]
pub struct Args {
    /// Mesh of arch A (upper, fixed): .stl, .obj, .ply or .off, optionally .gz.
    a: PathBuf,
    /// Mesh of arch B (lower).
    b: PathBuf,
    /// Planned pose of B in A's frame, "tx ty tz qw qx qy qz" (p' = R(q)·p + t; mm).
    #[arg(long, default_value = "0 0 0 1 0 0 0", allow_hyphen_values = true)]
    pose: String,
    /// Then open B about the pair's hinge axis by this much at the incisors (mm): the
    /// intermediate splint's vertical opening. `auto`: the least opening that leaves room
    /// for the wafer (perforated over at most 0.5 % of its outline), as a final splint at
    /// the final occlusion needs.
    #[arg(long, default_value = "0", allow_hyphen_values = true)]
    open: String,
    /// Gap between the wafer and each arch (mm), so that it seats.
    #[arg(long, default_value_t = SplintOptions::default().clearance)]
    clearance: f64,
    /// How far the wafer climbs the crowns beyond the cusp tips (mm).
    #[arg(long, default_value_t = SplintOptions::default().coverage)]
    coverage: f64,
    /// Least wafer thickness between the imprints (mm); thinner places are perforated.
    #[arg(long, default_value_t = SplintOptions::default().min_thickness)]
    min_thickness: f64,
    /// How far the buccal and lingual walls stand beyond the teeth (mm).
    #[arg(long, default_value_t = SplintOptions::default().rim)]
    rim: f64,
    /// Grid spacing (mm).
    #[arg(long, default_value_t = SplintOptions::default().voxel)]
    voxel: f64,
    /// Output: the splint in A's frame, as binary STL (`.stl`) or OBJ (`.obj`), gzip-compressed
    /// when the name ends in `.gz`.
    #[arg(short, long)]
    out: PathBuf,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let pose: Pose = args
        .pose
        .parse()
        .with_context(|| format!("--pose \"{}\"", args.pose))?;
    let opening = match args.open.trim() {
        "auto" => Opening::Auto,
        text => match text.parse::<f64>() {
            Ok(o) if o.is_finite() && o.abs() <= 50.0 => Opening::By(o),
            _ => anyhow::bail!(
                "--open must be `auto` or a number of millimetres within ±50, got \"{}\"",
                args.open
            ),
        },
    };
    crate::files::check_outputs(
        &[(args.out.as_path(), innersphere::mesh::SAVED_MESH)],
        &[&args.a, &args.b],
    )?;
    let opts = SplintOptions {
        clearance: args.clearance,
        coverage: args.coverage,
        min_thickness: args.min_thickness,
        rim: args.rim,
        voxel: args.voxel,
    };
    opts.validate()?;
    let a = crate::files::load_mesh(&args.a)?;
    let b = crate::files::load_mesh(&args.b)?;
    let s = splint::make_opened(&a, &b, &pose, opening, &opts)?;
    innersphere::mesh::save(&s.mesh, &args.out)
        .with_context(|| format!("writing {}", args.out.display()))?;
    let r = &s.report;
    if args.json {
        let mut v = serde_json::to_value(r)?;
        v["out"] = args.out.display().to_string().into();
        crate::print::print_json(&v)?;
    } else {
        if r.opened != 0.0 {
            println!("opened {:.2} mm at the incisors about the hinge", r.opened);
        }
        println!(
            "{}: {} triangles, {:.1} mm³, {} bod{}, {}",
            args.out.display(),
            r.triangles,
            r.volume,
            r.bodies,
            if r.bodies == 1 { "y" } else { "ies" },
            if r.watertight && r.manifold && r.winding_consistent {
                "watertight and manifold"
            } else {
                "NOT a clean solid"
            }
        );
        println!(
            "thickness ≥ {:.2} mm; distance to A ≥ {:.3} mm, to B ≥ {:.3} mm; coverage A {:.1} %, B {:.1} %; {:.1} s",
            r.min_thickness,
            r.min_distance_a,
            r.min_distance_b,
            100.0 * r.coverage_a,
            100.0 * r.coverage_b,
            r.seconds
        );
    }
    Ok(0)
}
