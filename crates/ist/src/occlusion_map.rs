//! `ist occlusion-map`: both arches coloured by their signed gap to each other (exact, in
//! f64 from the meshes), as PLY files, with the contacts per tooth.

use anyhow::Context;
use innersphere::exact::ExactMesh;
use innersphere::Pose;
use innersphere_dental::contact_map::{
    check_pair, save_ply, summarise, ContactMap, Teeth, TeethFit, LEGEND, MAP_FILE, SPOT_GAP,
};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `ist occlusion-map`. Units: the meshes' (millimetres for the jaw scans).
///
/// Each vertex gets `gap`: its exact distance (mm) to the other arch's surface, negative where
/// it lies inside the other arch, and a colour by gap: purple < 0 (inside), red 0–0.05 (tight
/// contact), orange 0.05–0.1 (contact), yellow 0.1–0.2 (near contact), green 0.2–0.3, blue
/// 0.3–0.5, light grey beyond 0.5 mm.
#[derive(clap::Args)]
#[command(
    after_help = "Each vertex's `gap` is its exact distance to the other arch's surface in the meshes' units (mm for the jaw scans), negative where the vertex lies inside the other arch.\nColour scale (signed gap, mm): purple < 0 (inside the other arch), red 0–0.05, orange 0.05–0.1, yellow 0.1–0.2, green 0.2–0.3, blue 0.3–0.5, light grey > 0.5."
)]
pub struct Args {
    /// Mesh of arch A (fixed, at the identity pose): .stl, .obj, .ply or .off, optionally .gz.
    a: PathBuf,
    /// Mesh of arch B.
    b: PathBuf,
    #[command(flatten)]
    unit: crate::files::UnitArg,
    /// Pose of B in A's frame, "tx ty tz qw qx qy qz" (p' = R(q)·p + t; mm).
    #[arg(long, default_value = "0 0 0 1 0 0 0", allow_hyphen_values = true)]
    pose: String,
    /// Output PLY of A with its per-vertex `gap` (mm) and colour (`.ply`, or `.ply.gz`
    /// compressed).
    #[arg(long)]
    out_a: Option<PathBuf>,
    /// Output PLY of B, written at the pose (in A's frame), with its `gap` and colour.
    #[arg(long)]
    out_b: Option<PathBuf>,
    /// Teeth of A: a teeth-axes JSON (`{"3": {"c": [x, y, z], ...}, ...}`, A's frame and
    /// unit, at most 1 MiB); each vertex belongs to the nearest crown centre within 10 mm. A
    /// file that does not fit its arch (the other arch's, another unit, both arches mixed,
    /// a key twice) is refused: docs/OCCLUSION.md.
    #[arg(long)]
    teeth_a: Option<PathBuf>,
    /// Teeth of B (B's own frame, before the pose).
    #[arg(long)]
    teeth_b: Option<PathBuf>,
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
    let outputs: Vec<(&std::path::Path, _)> = [&args.out_a, &args.out_b]
        .into_iter()
        .flatten()
        .map(|p| (p.as_path(), MAP_FILE))
        .collect();
    let mut inputs: Vec<&std::path::Path> = vec![&args.a, &args.b];
    inputs.extend(
        [&args.teeth_a, &args.teeth_b]
            .into_iter()
            .flatten()
            .map(|p| p.as_path()),
    );
    crate::files::check_outputs(&outputs, &inputs)?;
    let unit = args.unit.unit;
    let teeth_a = args
        .teeth_a
        .as_deref()
        .map(|p| Teeth::load_in(p, unit))
        .transpose()?;
    let teeth_b = args
        .teeth_b
        .as_deref()
        .map(|p| Teeth::load_in(p, unit))
        .transpose()?;
    let t0 = Instant::now();
    let (mesh_a, mesh_b) = (
        crate::files::load_mesh(&args.a, args.unit.unit)?,
        crate::files::load_mesh(&args.b, args.unit.unit)?,
    );
    // Before the map: a teeth file that does not fit its arch is refused at once.
    let (fit_a, fit_b) = check_pair(&mesh_a, teeth_a.as_ref(), &mesh_b, teeth_b.as_ref(), &pose)?;
    for w in fit_a.iter().chain(&fit_b).flat_map(|f| &f.warnings) {
        eprintln!("warning: {w}");
    }
    let a = ExactMesh::new(&mesh_a).with_context(|| format!("{}", args.a.display()))?;
    let b = ExactMesh::new(&mesh_b).with_context(|| format!("{}", args.b.display()))?;
    drop((mesh_a, mesh_b));
    let prepared = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let map = ContactMap::new(&a, &Pose::IDENTITY, &b, &pose, f64::INFINITY)?;
    let mapped = t1.elapsed().as_secs_f64();
    for (out, mesh, gaps, at) in [
        (&args.out_a, &a, &map.gaps_a, Pose::IDENTITY),
        (&args.out_b, &b, &map.gaps_b, pose),
    ] {
        if let Some(p) = out {
            save_ply(p, mesh.mesh(), &at, gaps)?;
        }
    }
    let side = |name: &str,
                mesh: &ExactMesh,
                gaps: &[f64],
                teeth: &Option<Teeth>,
                fit: &Option<TeethFit>| {
        let min = gaps.iter().copied().fold(f64::INFINITY, f64::min);
        let inside = gaps.iter().filter(|&&g| g < 0.0).count();
        let within = |t: f64| gaps.iter().filter(|&&g| g <= t).count();
        let teeth = teeth
            .as_ref()
            .zip(fit.as_ref())
            .map(|(t, f)| summarise(mesh.mesh(), gaps, t, &f.regions));
        // Infinite gaps (no vertex, or none within reach) are written as null.
        json!({
            "mesh": name,
            "vertices": gaps.len(),
            "min_gap": min,
            "vertices_inside": inside,
            "vertices_within_0_1": within(0.1),
            "vertices_within_0_2": within(0.2),
            "teeth": teeth,
        })
    };
    let report = json!({
        "pose": [pose.translation.x, pose.translation.y, pose.translation.z,
                 pose.rotation.w, pose.rotation.x, pose.rotation.y, pose.rotation.z],
        "units": "gaps in the meshes' units (mm for the jaw scans); negative: inside the other mesh",
        "spot_gap": SPOT_GAP,
        "a": side(&args.a.display().to_string(), &a, &map.gaps_a, &teeth_a, &fit_a),
        "b": side(&args.b.display().to_string(), &b, &map.gaps_b, &teeth_b, &fit_b),
        "legend": LEGEND.iter().map(|(hi, name, rgb)| json!({"below": hi, "name": name, "rgb": rgb})).collect::<Vec<_>>(),
        "seconds_prepare": prepared,
        "seconds_map": mapped,
    });
    if args.json {
        crate::print::print_json(&report)?;
    } else {
        for k in ["a", "b"] {
            let s = &report[k];
            println!(
                "{}: {} vertices, min gap {} mm, {} inside the other arch, {} within 0.1 mm",
                s["mesh"].as_str().unwrap_or(k),
                s["vertices"],
                num(&s["min_gap"]),
                s["vertices_inside"],
                s["vertices_within_0_1"]
            );
            if let Some(teeth) = s["teeth"].as_array() {
                for t in teeth {
                    println!(
                        "  tooth {:>2}: min gap {} mm, {:.2} mm² within 0.1, {:.2} mm² within 0.2, {} spots",
                        t["tooth"],
                        num(&t["min_gap"]),
                        t["area_within_0_1"].as_f64().unwrap_or(0.0),
                        t["area_within_0_2"].as_f64().unwrap_or(0.0),
                        t["spots"]
                    );
                }
            }
        }
        println!("gaps in {mapped:.2} s (meshes prepared in {prepared:.2} s)");
    }
    Ok(0)
}

/// A JSON number with 3 decimals (gaps in mm: µm), or "none".
fn num(v: &serde_json::Value) -> String {
    v.as_f64().map_or("none".into(), |x| format!("{x:.3}"))
}
