//! `ist occlude`: close body B onto body A under a constant force until it rests (the
//! library's automatic occlusion), and say how far the bite found is from a reference.

use anyhow::Context;
use innersphere::contact_map::Teeth;
use innersphere::glam::DVec3;
use innersphere::haptic::{bite, BiteOptions};
use innersphere::{Pose, SharedTree};
use innersphere_eval::haptic::{check_landmarks, crown_centres};
use serde_json::json;
use std::path::PathBuf;

/// Arguments of `ist occlude`. Units: millimetres, newtons, seconds.
#[derive(clap::Args)]
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
    /// Closing force (N).
    #[arg(long, default_value_t = 5.0)]
    force: f64,
    /// Contact stiffness: penalty force per penetration volume (N/mm³). Default 10 with the
    /// joints, 1000 with --free (stiff, so that the free segment's cusps do not sink into
    /// each other and slide over).
    #[arg(long)]
    contact_stiffness: Option<f64>,
    /// Give up after this much simulated time (s).
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
    /// With --free: closings in all.
    #[arg(long, default_value_t = 120)]
    starts: usize,
    /// With --free: how far the starts spread sideways and forwards (mm; yaw: twice this in
    /// degrees).
    #[arg(long, default_value_t = 2.5)]
    spread: f64,
    /// With --free: the seed of the spread.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Print JSON.
    #[arg(long)]
    json: bool,
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
    // Read before the bodies are built, so that a bad file fails at once; checked against B
    // once it is loaded.
    let teeth = args.landmarks.as_deref().map(Teeth::load).transpose()?;
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
    drop((mesh_a, mesh_b));
    let (a, b) = (SharedTree::new(a), SharedTree::new(b));
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
    };
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
             volume {:.4} mm³, max depth {:.4} mm, {} patches; landmarks within {:.3} mm of the reference (worst of {})",
            if o.converged { "converged" } else { "NOT converged" },
            o.steps,
            o.seconds,
            wall,
            p[0], p[1], p[2], p[3], p[4], p[5], p[6],
            o.volume,
            o.max_depth,
            o.patches.len(),
            worst,
            errors.len()
        );
    }
    Ok(if o.converged { 0 } else { 1 })
}
