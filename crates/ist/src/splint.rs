//! `ist splint`: the occlusal splint (surgical wafer) between two arches at a planned pose,
//! as a watertight binary STL, with its measurements.

use anyhow::Context;
use innersphere::Pose;
use innersphere_dental::splint::{self, Opening, SplintOptions};
use std::path::PathBuf;

/// Arguments of `ist splint`. Lengths in the meshes' units (millimetres for dental scans).
#[derive(clap::Args)]
#[command(
    after_help = "The wafer is made in A's frame and inserted along the pair's occlusal axis: undercuts along it are blocked out, so it goes on and comes off each arch.\nEvery measurement is made on the mesh as written and read back. Exit codes: 0 a wafer fit to print; 3 a wafer that fails a guarantee (one closed manifold body, the clearance to each arch, no arch vertex inside, the least thickness, 85 % coverage of each arch): it is not written unless --keep-unfit; 2 inputs that cannot make a wafer (another unit, flat arches, arches not facing each other, more than 10 mm apart or passing through each other), with the reason.\nJSON: fit, checks (name, ok, detail), volume (mm³), triangles, vertices, bodies, watertight, manifold, winding_consistent, min_thickness / thickness_p01 (mm, along the insertion axis), min_distance_a / _b (mm, exact, over the splint's vertices), a/b_vertices_inside, coverage_a / _b (share of each arch's occlusal surface — what the other arch sees of it along the insertion axis, up to the coverage cap — within clearance + 0.15 mm of the splint), perforated_area (mm²), out (null when not written), seconds."
)]
pub struct Args {
    /// Mesh of arch A (upper, fixed): .stl, .obj, .ply or .off, optionally .gz.
    a: PathBuf,
    /// Mesh of arch B (lower).
    b: PathBuf,
    #[command(flatten)]
    unit: crate::files::UnitArg,
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
    /// The most triangles the wafer is written with: simplified down to it within a quarter
    /// of --voxel (0: as extracted, a million or more on a full arch).
    #[arg(long, default_value_t = SplintOptions::default().max_triangles)]
    max_triangles: usize,
    /// Output: the splint in A's frame, as binary STL (`.stl`), OBJ (`.obj`; either
    /// gzip-compressed when the name ends in `.gz`) or 3MF (`.3mf`).
    #[arg(short, long)]
    out: PathBuf,
    /// Write the wafer even when it fails one of its guarantees, for inspection (the exit
    /// code is still 3).
    #[arg(long)]
    keep_unfit: bool,
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
            Ok(o) if o.is_finite() => Opening::By(o),
            _ => anyhow::bail!(
                "--open must be `auto` or a number of millimetres, got \"{}\"",
                args.open
            ),
        },
    };
    crate::files::check_outputs(
        &[(args.out.as_path(), splint::threemf::WAFER_FILE)],
        &[&args.a, &args.b],
    )?;
    let opts = SplintOptions {
        clearance: args.clearance,
        coverage: args.coverage,
        min_thickness: args.min_thickness,
        rim: args.rim,
        voxel: args.voxel,
        max_triangles: args.max_triangles,
    };
    opts.validate()?;
    let a = crate::files::load_mesh(&args.a, args.unit.unit)?;
    let b = crate::files::load_mesh(&args.b, args.unit.unit)?;
    let s = splint::make_opened(&a, &b, &pose, opening, &opts)?;
    let r = &s.report;
    let write = r.fit || args.keep_unfit;
    if write {
        splint::threemf::save_wafer(&s.mesh, &args.out)
            .with_context(|| format!("writing {}", args.out.display()))?;
    }
    if !r.fit {
        eprintln!(
            "error: the wafer is NOT fit to print{}:",
            if write {
                format!(
                    " (written to {} for inspection, --keep-unfit)",
                    args.out.display()
                )
            } else {
                format!(
                    "; {} was not written (--keep-unfit writes it for inspection)",
                    args.out.display()
                )
            }
        );
        for c in r.checks.iter().filter(|c| !c.ok) {
            eprintln!("  {}: {}", c.name, c.detail);
        }
    }
    if args.json {
        let mut v = serde_json::to_value(r)?;
        v["out"] = if write {
            args.out.display().to_string().into()
        } else {
            serde_json::Value::Null
        };
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
            if r.checks.iter().any(|c| c.name == "solid" && c.ok) {
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
    Ok(if r.fit { 0 } else { UNFIT })
}

/// The exit code of a wafer that fails one of its guarantees.
pub const UNFIT: i32 = 3;
