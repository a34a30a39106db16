//! `ist occlude`: close body B onto body A under a constant force until it rests (the
//! library's automatic occlusion), and say how far the bite found is from a reference.

use anyhow::Context;
use innersphere::glam::DVec3;
use innersphere::{Pose, SharedTree};
use innersphere_dental::contact_map::Teeth;
use innersphere_dental::{bite, BiteOptions, OcclusionStatus};
use innersphere_eval::haptic::{check_landmarks, crown_centres};
use innersphere_haptic::ContactSource;
use serde_json::json;
use std::path::PathBuf;

/// The exit code of each status (the error exit, 2, is a refusal: bad input, or bodies or
/// poses that cannot bite).
pub fn exit_code(status: OcclusionStatus) -> i32 {
    match status {
        OcclusionStatus::Converged => 0,
        OcclusionStatus::TimeLimit => 1,
        OcclusionStatus::NoContact => 3,
        OcclusionStatus::PassedThrough => 4,
        OcclusionStatus::Escaped => 5,
    }
}

/// Arguments of `ist occlude`. Units: millimetres, newtons, seconds.
#[derive(clap::Args)]
#[command(
    after_help = "Status (JSON `status`, the first word printed) and exit code:\n  converged       0  B rests in contact with A, held by the contact (at rest, the net force below 5 % of the closing force)\n  time_limit      1  still moving when --max-seconds ran out\n  (refused)       2  an error: options outside their limits, arches that do not face each other, a start that cannot bite\n  no_contact      3  at rest without touching A (the joints hold B open)\n  passed_through  4  B ended on the far side of A along the closing axis (through A, or slid off past it); the pose is not a bite\n  escaped         5  B moved away from A; the pose is not a bite\nWith --free the status is the chosen candidate's (converged), or, when no closing converged, the closing from --from's; JSON `closings` counts the closings in each status.\nLimits: --force 0.5–1000 N and at most 2 mm³ × --contact-stiffness (the overlap that carries it at rest); --contact-stiffness up to 1e5 N/mm³; --joint-stiffness 0–1e4 N/mm; --max-seconds up to 60; --starts 1–1000; --spread up to 10 mm; B at --from (and --reference with the joints) at most 30 mm open, turned at most 30°, below A and not beside it."
)]
pub struct Args {
    /// Tree file of body A (fixed, at the identity pose), or its mesh (built with --preset,
    /// cached).
    a: PathBuf,
    /// Tree file or mesh of body B (its tree must hold mass properties: built by this version).
    b: PathBuf,
    /// How a mesh given for A or B becomes its tree.
    #[command(flatten)]
    body: crate::bodies::BodyArgs,
    /// Starting pose of B in A's frame, "tx ty tz qw qx qy qz" (p' = R(q)·p + t).
    #[arg(long, allow_hyphen_values = true)]
    from: String,
    /// Closing direction "x y z" (A's frame; B is pushed along it). Default: the pair's
    /// occlusal "up" (from B towards A), found from the trees' leaf spheres as `ist motion`
    /// finds it from the meshes.
    #[arg(long, num_args = 3, allow_hyphen_values = true)]
    axis: Option<Vec<f64>>,
    /// Closing force (N): 0.5 to 1000, at most 2 mm³ × the contact stiffness (20 N with
    /// the joints' default 10 N/mm³; up to 1000 N needs 500 N/mm³). B closes at 5 mm/s
    /// whatever the force.
    #[arg(long, default_value_t = 5.0)]
    force: f64,
    /// Contact stiffness: penalty force per penetration volume (N/mm³). Default 10 with the
    /// joints, 1000 with --free (stiff, so that the free segment's cusps do not sink into
    /// each other and slide over).
    #[arg(long)]
    contact_stiffness: Option<f64>,
    /// Give up after this much simulated time (s), at most 60.
    #[arg(long, default_value_t = 30.0)]
    max_seconds: f64,
    /// The pose to compare the bite with (default the identity: the scanned bite of a pair
    /// that was scanned in occlusion).
    #[arg(long, default_value = "0 0 0 1 0 0 0", allow_hyphen_values = true)]
    reference: String,
    /// Landmarks of B to compare: a teeth-axes JSON (`{"18": {"c": [x, y, z], …}, …}`,
    /// B's frame and unit, at most 1 MiB), read and checked against B as `ist occlusion-map`
    /// reads teeth; each tooth's crown centre `c` is one landmark, and so is the incisal
    /// point of the pair's frame.
    #[arg(long)]
    landmarks: Option<PathBuf>,
    /// Stiffness of each temporomandibular joint (N/mm): B's two condyles (on the pair's
    /// hinge axis, 50 mm either side of the midline at human scale) are held by springs at
    /// their places in the reference pose.
    #[arg(long, default_value_t = 20.0)]
    joint_stiffness: f64,
    /// B is a free segment (no joints): closed from --starts places around the start
    /// (within --spread mm sideways and forwards and 2 × --spread degrees of yaw), the rest
    /// poses ranked, the best bilateral one chosen (docs/OCCLUSION.md); the JSON lists the
    /// candidates.
    #[arg(long)]
    free: bool,
    /// With --free: closings in all (1 to 1000).
    #[arg(long, default_value_t = 120)]
    starts: usize,
    /// With --free: how far the starts spread sideways and forwards (mm, at most 10; yaw:
    /// twice this in degrees).
    #[arg(long, default_value_t = 2.5)]
    spread: f64,
    /// With --free: the seed of the spread.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Where the contact comes from: `spheres` (the packings' volume) or `mesh` (the meshes'
    /// own exact intersection: B closes on the spheres first, then settles on the meshes;
    /// needs the meshes as `ist query --query mesh-penetration` does). docs/OCCLUSION.md
    /// says what each gives.
    #[arg(long, default_value = "spheres", value_parser = parse_contact)]
    contact: ContactSource,
    /// The meshes of A and B for --contact mesh (default: the bodies' own when given as
    /// meshes, else the meshes their tree files name as their source).
    #[arg(long, num_args = 2, value_names = ["MESH_A", "MESH_B"])]
    meshes: Option<Vec<PathBuf>>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

fn parse_contact(s: &str) -> Result<ContactSource, String> {
    s.parse().map_err(|e: innersphere::Error| e.to_string())
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let from: Pose = args
        .from
        .parse()
        .with_context(|| format!("--from \"{}\"", args.from))?;
    let reference: Pose = args
        .reference
        .parse()
        .with_context(|| format!("--reference \"{}\"", args.reference))?;
    let opts = BiteOptions {
        axis: args.axis.as_ref().map(|v| DVec3::new(v[0], v[1], v[2])),
        force: args.force,
        contact_stiffness: args.contact_stiffness,
        max_seconds: args.max_seconds,
        reference,
        joint_stiffness: args.joint_stiffness,
        free: args.free,
        starts: args.starts,
        spread: args.spread,
        seed: args.seed,
        contact: args.contact,
    };
    anyhow::ensure!(
        args.contact == ContactSource::Mesh || args.meshes.is_none(),
        "--meshes gives the meshes of --contact mesh"
    );
    // Refused before the bodies are built.
    opts.validate()?;
    // Read before the bodies are built, so that a bad file fails at once; checked against B
    // once it is loaded.
    let teeth = args
        .landmarks
        .as_deref()
        .map(|p| Teeth::load_in(p, args.body.unit.unit))
        .transpose()?;
    let (a, mesh_a) = crate::bodies::load_body(&args.a, &args.body)?;
    let (b, mesh_b) = crate::bodies::load_body(&args.b, &args.body)?;
    let teeth = match &teeth {
        Some(t) => {
            let warnings =
                check_landmarks(t, (&b, mesh_b.as_ref()), (&a, mesh_a.as_ref()), &reference)?;
            for w in warnings {
                eprintln!("warning: {w}");
            }
            crown_centres(t)
        }
        None => vec![],
    };
    let (mut a, mut b) = (SharedTree::new(a), SharedTree::new(b));
    if args.contact == ContactSource::Mesh {
        let given = args.meshes.as_deref().unwrap_or(&[]);
        a = crate::bodies::with_mesh(a, given.first(), mesh_a, "A", args.body.unit.unit)?;
        b = crate::bodies::with_mesh(b, given.get(1), mesh_b, "B", args.body.unit.unit)?;
    }
    let t0 = std::time::Instant::now();
    let found = bite(&a, &b, &from, &opts)?;
    let mut landmarks = vec![("incisal".to_string(), found.frame.incisal)];
    landmarks.extend(teeth);
    let o = &found.occlusion;
    let wall = t0.elapsed().as_secs_f64();
    let errors: Vec<(String, f64)> = landmarks
        .iter()
        .map(|(name, p)| {
            let d = (o.pose.transform_point(*p) - reference.transform_point(*p)).length();
            (name.clone(), d)
        })
        .collect();
    let worst = errors.iter().map(|e| e.1).fold(0.0, f64::max);
    if args.json {
        // The library's answer, and what only this door knows: the wall time and the
        // landmarks' errors.
        let error_of = |pose: &Pose| {
            landmarks
                .iter()
                .map(|(_, p)| (pose.transform_point(*p) - reference.transform_point(*p)).length())
                .fold(0.0, f64::max)
        };
        let mut out = found.to_json();
        if let Some(cands) = out["candidates"].as_array_mut() {
            for (c, found) in cands.iter_mut().zip(&found.candidates) {
                c["landmark_error_max"] = json!(error_of(&found.pose));
            }
        }
        out["wall_seconds"] = json!(wall);
        out["landmark_error_max"] = json!(worst);
        out["landmark_errors"] = json!(errors
            .iter()
            .map(|(n, d)| json!({"landmark": n, "error": d}))
            .collect::<Vec<_>>());
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        let p = o.pose.to_array();
        println!(
            "{} after {} steps ({:.3} s simulated, {:.2} s wall): pose {:.4} {:.4} {:.4} {:.6} {:.6} {:.6} {:.6}\n\
             {}.\n\
             volume {:.4} mm³, max depth {:.4} mm, {} patches; landmarks within {:.3} mm of the reference (worst of {})",
            o.status,
            o.steps,
            o.seconds,
            wall,
            p[0], p[1], p[2], p[3], p[4], p[5], p[6],
            o.status.describe(),
            o.volume,
            o.max_depth,
            o.patches.len(),
            worst,
            errors.len()
        );
        if let Some(counts) = &found.closings {
            let total: usize = counts.values().sum();
            let each: Vec<String> = counts
                .iter()
                .filter(|(_, n)| **n > 0)
                .map(|(s, n)| format!("{n} {s}"))
                .collect();
            println!(
                "starts: {total} ({}); candidates: {}",
                each.join(", "),
                found.candidates.len()
            );
        }
    }
    Ok(exit_code(o.status))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_status_has_its_own_exit_code_and_none_is_the_error_code() {
        let codes: Vec<i32> = OcclusionStatus::ALL.iter().map(|s| exit_code(*s)).collect();
        assert_eq!(codes, [0, 3, 1, 4, 5]);
        for (i, c) in codes.iter().enumerate() {
            assert!(*c != 2 && !codes[..i].contains(c), "{codes:?}");
        }
    }
}
