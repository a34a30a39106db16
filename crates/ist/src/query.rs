//! `ist query`: one query between two trees, B posed in A's frame (A at identity).

use anyhow::Context;
use innersphere::query::TraversalOptions;
use innersphere::{
    DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose, RefineOptions, SharedTree,
};
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
    /// Time-critical penetration volume: the overlap found within --budget node-pair tests
    /// and a proved upper bound on the rest (the haptic loop's fallback).
    PenetrationWithin,
    /// The paper's distance traversal: first contact from the roots (the baseline of
    /// `contact`).
    DistanceTraversal,
    /// The paper's backtracking traversal (on a fresh pair: the distance traversal).
    Backtracking,
    /// The distance between the meshes: the sphere distance refined by the exact distance
    /// of the triangles near its closest points (needs the meshes: a body given as a mesh,
    /// --meshes, or the mesh a tree file names as its source).
    RefinedDistance,
    /// The penetration of the meshes themselves: the exact volume of the intersection of the
    /// two solids, the force and torques from its exact gradient (--stiffness as for
    /// `penetration`); needs the meshes as `refined-distance` does.
    MeshPenetration,
}

/// Arguments of `ist query`.
#[derive(clap::Args)]
pub struct Args {
    /// Tree file of body A (at the identity pose), or its mesh (built with --preset, cached).
    a: PathBuf,
    /// Tree file or mesh of body B.
    b: PathBuf,
    /// How a mesh given for A or B becomes its tree.
    #[command(flatten)]
    body: crate::bodies::BodyArgs,
    /// Pose of B in A's frame, "tx ty tz qw qx qy qz" (p' = R(q)·p + t; t in model units,
    /// mm for the jaw scans; q is normalized).
    #[arg(long, default_value = "0 0 0 1 0 0 0", allow_hyphen_values = true)]
    pose_b: String,
    /// The query.
    #[arg(long, value_enum, default_value_t = Kind::Distance)]
    query: Kind,
    /// Multipoint: most contacts to report, at least 1 (the same default as `ist replay
    /// --k`: the k = 16 of the benchmarks and of multipoint's speed bar, p99 ≤ 100 µs).
    #[arg(long, default_value_t = 16)]
    k: usize,
    /// Multipoint: at most one contact below each pair of nodes at this depth.
    #[arg(long, default_value_t = 4)]
    split_depth: u32,
    /// Penetration: force per unit of penetration volume, in your force unit per model
    /// unit³ (e.g. N/mm³ for the jaw scans in mm, giving forces in N). Force on B =
    /// stiffness × volume along the contact normal; the default 1 makes the force's magnitude
    /// equal to the penetration volume.
    #[arg(long, default_value_t = 1.0)]
    stiffness: f64,
    /// Penetration-within: node-pair tests the query may spend (about 75 ns each).
    #[arg(long, default_value_t = 8000)]
    budget: u64,
    /// Distance: report minus the deepest leaf overlap instead of 0 when overlapping.
    #[arg(long)]
    signed: bool,
    /// Distance: absolute error tolerance, in model units.
    #[arg(long, default_value_t = 0.0)]
    abs_tol: f64,
    /// Distance: relative error tolerance (a fraction of the distance).
    #[arg(long, default_value_t = 0.0)]
    rel_tol: f64,
    /// Refined distance: the meshes of A and B (default: a body's own mesh when given as
    /// one, else the mesh its tree was built from, where that file still holds it).
    #[arg(long, num_args = 2, value_names = ["MESH_A", "MESH_B"])]
    meshes: Option<Vec<PathBuf>>,
    /// Refined distance: radius of the balls searched around the closest points, as a
    /// multiple of the larger closest leaf's radius (plus --refine-margin).
    #[arg(long, default_value_t = innersphere::RefineOptions::default().radius_scale)]
    refine_radius_scale: f64,
    /// Refined distance: added to the balls' radius, in model units, ≥ 0 (default: the
    /// larger voxel size of the two trees).
    #[arg(long)]
    refine_margin: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Why the "separated by at least" of contact, multipoint and penetration is not the distance.
const SEPARATION_NOTE: &str = "(a proved lower bound, not the distance: these queries only look for overlap, so they stop descending wherever two node spheres are apart and report the smallest such gap between enclosing spheres; `--query distance` descends to the inner spheres and gives the exact distance of the sphere packings, which is at least this)";

fn v3(v: innersphere::glam::DVec3) -> [f64; 3] {
    v.to_array()
}

/// What `--json` prints: the answer's serde form (the library's, as every door prints it),
/// with the query's name, how long it took, whether its `distance` is only a proved lower
/// bound (`None`: it has none), and `more` (what the pair keeps beside the answer: contacts,
/// patches).
fn answer_json(
    query: &str,
    answer: &impl serde::Serialize,
    lower_bound: Option<bool>,
    seconds: f64,
    more: serde_json::Value,
) -> serde_json::Value {
    let mut v = serde_json::to_value(answer).expect("answers serialize");
    let o = v.as_object_mut().expect("an answer is a record");
    o.insert("query".into(), json!(query));
    if let Some(b) = lower_bound {
        o.insert("distance_is_lower_bound".into(), json!(b));
    }
    o.insert("seconds".into(), json!(seconds));
    if let serde_json::Value::Object(m) = more {
        o.extend(m);
    }
    v
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let pose_b: Pose = args
        .pose_b
        .parse()
        .with_context(|| format!("--pose-b \"{}\"", args.pose_b))?;
    innersphere::PenetrationOptions {
        stiffness: args.stiffness,
        ..Default::default()
    }
    .check()
    .context("--stiffness")?;
    if !(args.abs_tol >= 0.0 && args.rel_tol >= 0.0) {
        anyhow::bail!("--abs-tol and --rel-tol must be ≥ 0");
    }
    if args.k == 0 {
        anyhow::bail!("--k must be at least 1 (the most contacts multipoint reports)");
    }
    let refine = RefineOptions {
        radius_scale: args.refine_radius_scale,
        margin: args.refine_margin.unwrap_or(-1.0),
        ..Default::default()
    };
    refine.check().context("--refine-radius-scale")?;
    if let Some(m) = args.refine_margin {
        anyhow::ensure!(
            m >= 0.0 && m.is_finite(),
            "--refine-margin must be a finite length ≥ 0, got {m}"
        );
    }
    let (a, mesh_a) = crate::bodies::load_body(&args.a, &args.body)?;
    let (b, mesh_b) = crate::bodies::load_body(&args.b, &args.body)?;
    let (mut a, mut b) = (SharedTree::new(a), SharedTree::new(b));
    if matches!(args.query, Kind::RefinedDistance | Kind::MeshPenetration) {
        let given = args.meshes.as_deref().unwrap_or(&[]);
        a = crate::bodies::with_mesh(a, given.first(), mesh_a, "A", args.body.unit.unit)?;
        b = crate::bodies::with_mesh(b, given.get(1), mesh_b, "B", args.body.unit.unit)?;
    }
    let pose_a = Pose::IDENTITY;
    let mut pair = Pair::new(a, b);
    let (out, summary) = match args.query {
        Kind::Distance => distance(&mut pair, &pose_a, &pose_b, &args),
        Kind::RefinedDistance => refined_distance(&mut pair, &pose_a, &pose_b, &refine)?,
        Kind::MeshPenetration => mesh_penetration(&mut pair, &pose_a, &pose_b, &args)?,
        Kind::Contact | Kind::DistanceTraversal | Kind::Backtracking => {
            contact_kind(&mut pair, &pose_a, &pose_b, &args)
        }
        Kind::Multipoint => multipoint(&mut pair, &pose_a, &pose_b, &args),
        Kind::PenetrationWithin => penetration_within(&mut pair, &pose_a, &pose_b, &args),
        Kind::Penetration => penetration(&mut pair, &pose_a, &pose_b, &args),
    };
    if args.json {
        crate::print::print_json(&out)?;
    } else {
        println!("{summary}");
    }
    Ok(0)
}

/// The exact distance of the sphere packings.
fn distance(
    pair: &mut Pair,
    pose_a: &Pose,
    pose_b: &Pose,
    args: &Args,
) -> (serde_json::Value, String) {
    let t0 = std::time::Instant::now();
    let opts = DistanceOptions {
        abs_tolerance: args.abs_tol,
        rel_tolerance: args.rel_tol,
        signed: args.signed,
        coherence: false,
        best_first: false,
    };
    let p = pair.distance_with(pose_a, pose_b, &opts);
    let secs = t0.elapsed().as_secs_f64();
    (
        answer_json("distance", &p, Some(false), secs, json!({})),
        format!(
            "distance {:.6} units ({}), closest points A {:?} B {:?} (units), leaves {}/{}, {} node pairs, {:.1} µs",
            p.distance,
            if p.overlapping { "overlapping" } else { "separated" },
            v3(p.point_a),
            v3(p.point_b),
            p.leaf_a,
            p.leaf_b,
            p.visits,
            secs * 1e6
        ),
    )
}

/// The distance refined to the meshes.
fn refined_distance(
    pair: &mut Pair,
    pose_a: &Pose,
    pose_b: &Pose,
    refine: &RefineOptions,
) -> anyhow::Result<(serde_json::Value, String)> {
    let t0 = std::time::Instant::now();
    let r = pair.refined_distance_with(pose_a, pose_b, refine)?;
    let secs = t0.elapsed().as_secs_f64();
    Ok((
        answer_json("refined-distance", &r, Some(false), secs, json!({})),
        format!(
            "distance {:.6} units ({}), closest points A {:?} B {:?} (units){}; the sphere distance {:.6}, refined within {:.4} units of its closest points ({} triangle-node pairs, {} triangle pairs{}), {:.1} µs",
            r.distance,
            if r.intersecting { "touching" } else { "separated" },
            v3(r.point_a),
            v3(r.point_b),
            if r.refined {
                format!(", triangles {}/{}", r.tri_a, r.tri_b)
            } else {
                String::new()
            },
            r.spheres.distance,
            r.radius,
            r.node_pairs,
            r.triangle_pairs,
            if r.complete { "" } else { ", out of budget" },
            secs * 1e6
        ),
    ))
}

/// The meshes' own penetration: exact volume, force and torques.
fn mesh_penetration(
    pair: &mut Pair,
    pose_a: &Pose,
    pose_b: &Pose,
    args: &Args,
) -> anyhow::Result<(serde_json::Value, String)> {
    let t0 = std::time::Instant::now();
    let opts = PenetrationOptions {
        stiffness: args.stiffness,
        ..Default::default()
    };
    let m = pair.mesh_penetration_with(pose_a, pose_b, &opts)?;
    let secs = t0.elapsed().as_secs_f64();
    let patches = pair.patches();
    let mut summary = if m.contact {
        format!(
            "the meshes overlap by {:.6e} units³ ({} triangle pairs cross, largest mean depth of a patch {:.6} units), {:.1} µs\n\
             force on B {:?}, torque on B {:?}, torque on A {:?} (force = stiffness {} × volume along the direction that loses overlap fastest; torques about each body's centre of mass)",
            m.volume,
            m.crossing_pairs,
            m.max_depth,
            secs * 1e6,
            v3(m.force),
            v3(m.torque_b),
            v3(m.torque_a),
            args.stiffness
        )
    } else {
        format!("the meshes do not overlap, {:.1} µs", secs * 1e6)
    };
    for q in patches {
        summary += &format!(
            "\n  patch at {:?} units, normal {:?}, mean depth {:.6} units, volume {:.6e} units³, {} triangle pairs",
            v3(q.point),
            v3(q.normal),
            q.depth,
            q.volume,
            q.pairs
        );
    }
    Ok((
        answer_json(
            "mesh-penetration",
            &m,
            None,
            secs,
            json!({ "patches": patches }),
        ),
        summary,
    ))
}

/// First contact, or the paper's distance traversal or backtracking (`args.query`): a proved lower bound when apart.
fn contact_kind(
    pair: &mut Pair,
    pose_a: &Pose,
    pose_b: &Pose,
    args: &Args,
) -> (serde_json::Value, String) {
    let t0 = std::time::Instant::now();
    let traversal = TraversalOptions { safe_motion: false };
    let (q, name) = match args.query {
        Kind::DistanceTraversal => (
            pair.paper().distance_traversal(pose_a, pose_b, &traversal),
            "distance-traversal",
        ),
        Kind::Backtracking => (
            pair.paper().backtracking(pose_a, pose_b, &traversal),
            "backtracking",
        ),
        _ => (pair.contact(pose_a, pose_b), "contact"),
    };
    let secs = t0.elapsed().as_secs_f64();
    (
        // "distance" here is a proved lower bound, not the distance (see SEPARATION_NOTE);
        // said in the JSON too, for scripts.
        answer_json(name, &q, Some(true), secs, json!({})),
        match q.contact {
            Some(c) => format!(
                "contact at {:?} units (depth {:.6} units, leaves {}/{}), {} node pairs, {:.1} µs",
                v3(c.point),
                c.depth,
                c.leaf_a,
                c.leaf_b,
                q.visits,
                secs * 1e6
            ),
            None => format!(
                "no contact, separated by at least {:.6} units, {} node pairs, {:.1} µs\n{SEPARATION_NOTE}",
                q.distance,
                q.visits,
                secs * 1e6
            ),
        },
    )
}

/// Up to `--k` contacts.
fn multipoint(
    pair: &mut Pair,
    pose_a: &Pose,
    pose_b: &Pose,
    args: &Args,
) -> (serde_json::Value, String) {
    let t0 = std::time::Instant::now();
    let opts = MultipointOptions {
        k: args.k,
        split_depth: args.split_depth,
        reuse: false,
        safe_motion: false,
        tracking: false,
    };
    let m = pair.multipoint(pose_a, pose_b, &opts);
    let secs = t0.elapsed().as_secs_f64();
    let contacts = pair.contacts();
    let mut s = format!(
        "{} contacts (k = {}, split depth {}), {} node pairs, {:.1} µs",
        m.count,
        args.k,
        args.split_depth,
        m.visits,
        secs * 1e6
    );
    for c in contacts {
        s += &format!("\n  at {:?} units, depth {:.6} units", v3(c.point), c.depth);
    }
    if contacts.is_empty() {
        s += &format!(
            "; separated by at least {:.6} units\n{SEPARATION_NOTE}",
            m.distance
        );
    }
    (
        answer_json(
            "multipoint",
            &m,
            Some(true),
            secs,
            json!({ "contacts": contacts }),
        ),
        s,
    )
}

/// The penetration volume within a node-pair budget.
fn penetration_within(
    pair: &mut Pair,
    pose_a: &Pose,
    pose_b: &Pose,
    args: &Args,
) -> (serde_json::Value, String) {
    let t0 = std::time::Instant::now();
    let opts = PenetrationOptions {
        stiffness: args.stiffness,
        ..Default::default()
    };
    let w = pair.penetration_within_with(pose_a, pose_b, args.budget, &opts);
    let secs = t0.elapsed().as_secs_f64();
    (
        answer_json(
            "penetration-within",
            &w,
            None,
            secs,
            json!({ "budget": args.budget }),
        ),
        format!(
            "penetration volume found {:.6e} units³, at most {:.6e} units³ ({}), deepest {:.6} units, {} of {} node-pair tests, {:.1} µs\n\
             force on B {:?}, torque on B {:?} (the pairs found, and any left unrefined as their bounds)",
            w.volume,
            w.upper_bound,
            if w.complete { "complete: the exact volume" } else { "the budget ran out" },
            w.max_depth,
            w.visits,
            args.budget,
            secs * 1e6,
            v3(w.force),
            v3(w.torque_b)
        ),
    )
}

/// The penetration volume, force, torques and patches.
fn penetration(
    pair: &mut Pair,
    pose_a: &Pose,
    pose_b: &Pose,
    args: &Args,
) -> (serde_json::Value, String) {
    let t0 = std::time::Instant::now();
    let opts = PenetrationOptions {
        stiffness: args.stiffness,
        safe_motion: false,
        ..Default::default()
    };
    let p = pair.penetration_with(pose_a, pose_b, &opts);
    let patches = pair.patches();
    let secs = t0.elapsed().as_secs_f64();
    let mut s = format!(
        "penetration volume {:.6e} units³ over {} leaf pairs (deepest {:.6} units), {} node pairs, {:.1} µs\n\
         force on B {:?}, torque on B {:?}, torque on A {:?}\n\
         (force = stiffness {} × volume, in the force unit of --stiffness: N for N/mm³ on mm meshes; torques in that unit × units, each about its body's centre of mass)",
        p.volume,
        p.pairs,
        p.max_depth,
        p.visits,
        secs * 1e6,
        v3(p.force),
        v3(p.torque_b),
        v3(p.torque_a),
        args.stiffness
    );
    for q in patches {
        s += &format!(
            "\n  patch at {:?} units, normal {:?}, depth {:.6} units, volume {:.6e} units³",
            v3(q.point),
            v3(q.normal),
            q.depth,
            q.volume
        );
    }
    if p.pairs == 0 {
        s += &format!(
            "\nno contact, separated by at least {:.6} units\n{SEPARATION_NOTE}",
            p.distance
        );
    }
    (
        answer_json(
            "penetration",
            &p,
            Some(true),
            secs,
            json!({ "patches": patches }),
        ),
        s,
    )
}
