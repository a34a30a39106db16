//! `ist query`: one query between two trees, B posed in A's frame (A at identity).

use anyhow::Context;
use innersphere::{DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose};
use serde_json::json;
use std::path::PathBuf;

/// Which query to run.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Exact distance of the sphere packings, closest points.
    Distance,
    /// First contact (the same answer as the paper's distance traversal).
    Contact,
    /// Up to --k contacts, one per split-depth pair (the paper's multipoint traversal).
    Multipoint,
    /// Penetration volume, force, torque and contact patches.
    Penetration,
}

/// Arguments of `ist query`.
#[derive(clap::Args)]
pub struct Args {
    /// Tree file of body A (at the identity pose).
    a: PathBuf,
    /// Tree file of body B.
    b: PathBuf,
    /// Pose of B in A's frame, "tx ty tz qw qx qy qz" (p' = R(q)·p + t; q is normalized).
    #[arg(long, default_value = "0 0 0 1 0 0 0", allow_hyphen_values = true)]
    pose_b: String,
    /// The query.
    #[arg(long, value_enum, default_value_t = Kind::Distance)]
    query: Kind,
    /// Multipoint: most contacts to report.
    #[arg(long, default_value_t = 4)]
    k: usize,
    /// Multipoint: at most one contact below each pair of nodes at this depth.
    #[arg(long, default_value_t = 4)]
    split_depth: u32,
    /// Penetration: force per unit of penetration volume.
    #[arg(long, default_value_t = 1.0)]
    stiffness: f64,
    /// Distance: report minus the deepest leaf overlap instead of 0 when overlapping.
    #[arg(long)]
    signed: bool,
    /// Distance: absolute error tolerance.
    #[arg(long, default_value_t = 0.0)]
    abs_tol: f64,
    /// Distance: relative error tolerance.
    #[arg(long, default_value_t = 0.0)]
    rel_tol: f64,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

fn v3(v: innersphere::glam::DVec3) -> [f64; 3] {
    v.to_array()
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let pose_b: Pose = args
        .pose_b
        .parse()
        .with_context(|| format!("--pose-b \"{}\"", args.pose_b))?;
    if !(args.stiffness.is_finite() && args.stiffness >= 0.0) {
        anyhow::bail!("--stiffness must be a finite number ≥ 0");
    }
    if !(args.abs_tol >= 0.0 && args.rel_tol >= 0.0) {
        anyhow::bail!("--abs-tol and --rel-tol must be ≥ 0");
    }
    let a = innersphere::tree::file::load(&args.a)
        .with_context(|| format!("loading {}", args.a.display()))?;
    let b = innersphere::tree::file::load(&args.b)
        .with_context(|| format!("loading {}", args.b.display()))?;
    crate::warn_if_stale(&args.a, &a);
    crate::warn_if_stale(&args.b, &b);
    let pose_a = Pose::IDENTITY;
    let mut pair = Pair::new(a, b);
    let t0 = std::time::Instant::now();
    let (out, summary) = match args.query {
        Kind::Distance => {
            let opts = DistanceOptions {
                abs_tolerance: args.abs_tol,
                rel_tolerance: args.rel_tol,
                signed: args.signed,
                coherence: false,
                best_first: false,
            };
            let p = pair.distance_with(&pose_a, &pose_b, &opts);
            let secs = t0.elapsed().as_secs_f64();
            (
                json!({
                    "query": "distance",
                    "distance": p.distance,
                    "contact": p.overlapping,
                    "lower_bound": p.lower_bound,
                    "point_a": v3(p.point_a),
                    "point_b": v3(p.point_b),
                    "normal": v3(p.normal),
                    "leaf_a": p.leaf_a,
                    "leaf_b": p.leaf_b,
                    "visits": p.visits,
                    "seconds": secs,
                }),
                format!(
                    "distance {:.6} ({}), closest points A {:?} B {:?}, leaves {}/{}, {} node pairs",
                    p.distance,
                    if p.overlapping { "overlapping" } else { "separated" },
                    v3(p.point_a),
                    v3(p.point_b),
                    p.leaf_a,
                    p.leaf_b,
                    p.visits
                ),
            )
        }
        Kind::Contact => {
            let q = pair.contact(&pose_a, &pose_b);
            let secs = t0.elapsed().as_secs_f64();
            (
                json!({
                    "query": "contact",
                    "contact": q.in_contact(),
                    "distance": q.distance,
                    "point": q.contact.map(|c| v3(c.point)),
                    "normal": q.contact.map(|c| v3(c.normal)),
                    "depth": q.contact.map(|c| c.depth),
                    "leaf_a": q.contact.map(|c| c.leaf_a),
                    "leaf_b": q.contact.map(|c| c.leaf_b),
                    "visits": q.visits,
                    "seconds": secs,
                }),
                match q.contact {
                    Some(c) => format!(
                        "contact at {:?} (depth {:.6}, leaves {}/{}), {} node pairs",
                        v3(c.point),
                        c.depth,
                        c.leaf_a,
                        c.leaf_b,
                        q.visits
                    ),
                    None => format!(
                        "no contact, separated by at least {:.6}, {} node pairs",
                        q.distance, q.visits
                    ),
                },
            )
        }
        Kind::Multipoint => {
            let opts = MultipointOptions {
                k: args.k,
                split_depth: args.split_depth,
                reuse: false,
                safe_motion: false,
                tracking: false,
            };
            let m = pair.multipoint(&pose_a, &pose_b, &opts);
            let secs = t0.elapsed().as_secs_f64();
            let contacts = pair.contacts();
            let mut s = format!("{} contacts", m.count);
            for c in contacts {
                s += &format!("\n  {:?} depth {:.6}", v3(c.point), c.depth);
            }
            if contacts.is_empty() {
                s += &format!(", separated by at least {:.6}", m.distance);
            }
            (
                json!({
                    "query": "multipoint",
                    "contact": !contacts.is_empty(),
                    "distance": m.distance,
                    "contacts": contacts,
                    "visits": m.visits,
                    "seconds": secs,
                }),
                s,
            )
        }
        Kind::Penetration => {
            let opts = PenetrationOptions {
                stiffness: args.stiffness,
                safe_motion: false,
                ..Default::default()
            };
            let p = pair.penetration_with(&pose_a, &pose_b, &opts);
            let patches = pair.patches();
            let secs = t0.elapsed().as_secs_f64();
            let mut s = format!(
                "volume {:.6e} over {} leaf pairs (deepest {:.6}), force on B {:?}, torque on B {:?}, on A {:?}",
                p.volume,
                p.pairs,
                p.max_depth,
                v3(p.force),
                v3(p.torque_b),
                v3(p.torque_a)
            );
            for q in patches {
                s += &format!(
                    "\n  patch at {:?} normal {:?} depth {:.6} volume {:.6e}",
                    v3(q.point),
                    v3(q.normal),
                    q.depth,
                    q.volume
                );
            }
            if p.pairs == 0 {
                s += &format!("\nno contact, separated by at least {:.6}", p.distance);
            }
            (
                json!({
                    "query": "penetration",
                    "contact": p.pairs > 0,
                    "distance": p.distance,
                    "volume": p.volume,
                    "pairs": p.pairs,
                    "max_depth": p.max_depth,
                    "normal": v3(p.normal),
                    "force": v3(p.force),
                    "torque": v3(p.torque_b),
                    "torque_a": v3(p.torque_a),
                    "torque_b": v3(p.torque_b),
                    "patches": patches,
                    "visits": p.visits,
                    "seconds": secs,
                }),
                s,
            )
        }
    };
    if args.json {
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else {
        println!("{summary}");
    }
    Ok(0)
}
