//! `ist replay`: run a motion frame by frame through a pair's state, as a haptic loop would.

use anyhow::Context;
use innersphere::eval::replay::{replay, QueryKind, ReplayOptions};
use innersphere::exact::ExactMesh;
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `ist replay`.
#[derive(clap::Args)]
pub struct Args {
    /// Tree of body A (at the identity).
    a: PathBuf,
    /// Tree of body B (moved by the motion).
    b: PathBuf,
    /// Motion CSV (`t,tx,ty,tz,qw,qx,qy,qz`: the pose of B in A's frame).
    #[arg(long)]
    motion: PathBuf,
    /// Query kind to time.
    #[arg(long, value_enum, default_value = "all")]
    query: Kind,
    /// Compare with the exact mesh distance of these meshes (A's, then B's).
    #[arg(long, num_args = 2, value_names = ["MESH_A", "MESH_B"])]
    exact: Option<Vec<PathBuf>>,
    /// Compare only every K-th frame with the exact reference.
    #[arg(long, default_value_t = 1)]
    every: usize,
    /// Contacts for multipoint.
    #[arg(long, default_value_t = 16)]
    k: usize,
    /// Split depth for multipoint.
    #[arg(long, default_value_t = 4)]
    split_depth: u32,
    /// Passes over the motion, each from a fresh state; a frame's time is its fastest pass
    /// (filters out the stalls of a shared or virtual machine; 1 reports every stall).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    passes: u32,
    /// Write one row per frame to this CSV file.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Kind {
    Distance,
    Contact,
    Multipoint,
    Penetration,
    All,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    anyhow::ensure!(args.every >= 1, "--every must be at least 1");
    let a = innersphere::tree::file::load(&args.a)?;
    let b = innersphere::tree::file::load(&args.b)?;
    crate::warn_if_stale(&args.a, &a);
    crate::warn_if_stale(&args.b, &b);
    let motion = innersphere::motion::Motion::load(&args.motion)?;
    let exact = match &args.exact {
        Some(m) => Some((
            ExactMesh::new(&innersphere::mesh::io::load(&m[0])?)?,
            ExactMesh::new(&innersphere::mesh::io::load(&m[1])?)?,
        )),
        None => None,
    };
    let kinds = match args.query {
        Kind::Distance => vec![QueryKind::Distance],
        Kind::Contact => vec![QueryKind::Contact],
        Kind::Multipoint => vec![QueryKind::Multipoint],
        Kind::Penetration => vec![QueryKind::Penetration],
        Kind::All => QueryKind::ALL.to_vec(),
    };
    let opts = ReplayOptions {
        kinds,
        k: args.k,
        split_depth: args.split_depth,
        every: args.every,
        passes: args.passes as usize,
        ..Default::default()
    };
    let report = replay(&a, &b, &motion, exact.as_ref().map(|(x, y)| (x, y)), &opts);
    if let Some(path) = &args.csv {
        let mut out = std::io::BufWriter::new(
            std::fs::File::create(path)
                .with_context(|| format!("cannot create {}", path.display()))?,
        );
        let names: Vec<String> = opts
            .kinds
            .iter()
            .map(|k| format!("{k:?}_us").to_lowercase())
            .collect();
        writeln!(
            out,
            "frame,t,distance,contact,{},exact_distance,exact_intersecting",
            names.join(",")
        )?;
        for r in &report.rows {
            let us: Vec<String> = r.us[..opts.kinds.len()]
                .iter()
                .map(|u| format!("{u:.3}"))
                .collect();
            writeln!(
                out,
                "{},{},{},{},{},{},{}",
                r.frame,
                r.t,
                r.distance,
                r.contact,
                us.join(","),
                r.exact_distance,
                r.exact_intersecting
            )?;
        }
        out.flush()?;
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
        return Ok(0);
    }
    println!(
        "{} frames, each timed as its fastest of {} pass(es)",
        report.frames, report.passes
    );
    println!("| query | p50 µs | p99 µs | max µs | frames over 1 ms |");
    println!("|---|---|---|---|---|");
    for k in &report.kinds {
        println!(
            "| {:?} | {:.1} | {:.1} | {:.1} | {} |",
            k.kind, k.p50_us, k.p99_us, k.max_us, k.frames_over_1ms
        );
    }
    if let Some(acc) = &report.accuracy {
        println!(
            "exact reference on {} frames ({} separated): abs error p50 {:.4} p95 {:.4} max {:.4}, relative p50 {:.4} p95 {:.4}; missed contacts {} ({} deeper than 0.1), false contacts {}; exact method p50 {:.1} µs p99 {:.1} µs max {:.1} µs; our distance p99 on the same frames {:.1} µs ({:.1}× faster)",
            acc.frames, acc.separated_frames, acc.abs_err_p50, acc.abs_err_p95, acc.abs_err_max,
            acc.rel_err_p50, acc.rel_err_p95, acc.missed_contacts, acc.missed_contacts_deep,
            acc.false_contacts, acc.exact_p50_us, acc.exact_p99_us, acc.exact_max_us,
            acc.distance_p99_us, acc.speedup_p99
        );
    }
    Ok(0)
}
