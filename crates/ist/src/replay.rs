//! `ist replay`: run a motion frame by frame through a pair's state, as a haptic loop would.

use anyhow::Context;
use innersphere::exact::ExactMesh;
use innersphere_eval::replay::{replay, QueryKind, ReplayOptions, ReplayReport};
use std::path::PathBuf;
use std::sync::Arc;

/// Arguments of `ist replay`.
#[derive(clap::Args)]
pub struct Args {
    /// Tree of body A (at the identity), or its mesh (built with --preset, cached).
    a: PathBuf,
    /// Tree or mesh of body B (moved by the motion).
    b: PathBuf,
    /// How a mesh given for A or B becomes its tree.
    #[command(flatten)]
    body: crate::bodies::BodyArgs,
    /// Motion CSV (`t,tx,ty,tz,qw,qx,qy,qz`: the pose of B in A's frame; t in seconds,
    /// translations in model units, mm for the jaw scans).
    #[arg(long)]
    motion: PathBuf,
    /// Query kind to time (`all`: every sphere kind, the refined distance too when --exact
    /// gives the meshes; the meshes' penetration only by name).
    #[arg(long, value_enum, default_value = "all")]
    query: Kind,
    /// Compare with the exact mesh distance of these meshes (A's, then B's); the refined
    /// distance searches their triangles.
    #[arg(long, num_args = 2, value_names = ["MESH_A", "MESH_B"])]
    exact: Option<Vec<PathBuf>>,
    /// Compare only every K-th frame with the exact reference (frames 0, K, 2K, ...); the
    /// exact method is timed on those frames, each warm-started from the previous compared
    /// frame (K frames back).
    #[arg(long, default_value_t = 1)]
    every: usize,
    /// Multipoint: most contacts per frame, at least 1 (the same default as `ist query
    /// --k`: the k = 16 of the benchmarks and of multipoint's speed bar, p99 ≤ 100 µs).
    #[arg(long, default_value_t = 16)]
    k: usize,
    /// Multipoint: at most one contact below each pair of nodes at this depth (the same
    /// default as `ist query --split-depth`).
    #[arg(long, default_value_t = 4)]
    split_depth: u32,
    /// Passes over the motion, each from a fresh state. The first pass gives the single-pass
    /// numbers (what a haptic loop sees); with more, each frame's fastest pass gives
    /// best-of-N numbers beside them (filters the stalls of a shared or virtual machine).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    passes: u32,
    /// Refined distance: radius of the balls searched around the closest points, as a
    /// multiple of the larger closest leaf's radius (plus --refine-margin).
    #[arg(long, default_value_t = innersphere::RefineOptions::default().radius_scale)]
    refine_radius_scale: f64,
    /// Refined distance: added to the balls' radius, in model units, ≥ 0 (default: the
    /// larger voxel size of the two trees).
    #[arg(long)]
    refine_margin: Option<f64>,
    /// With --query mesh-penetration: compare with this reference, a CSV of `frame,volume`
    /// and optionally `gx,gy,gz` from an independent mesh boolean
    /// (`tools/mesh-volume-check/check.py A B --motion MOTION --reference OUT.csv`).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Write one row per frame to this CSV file.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
enum Kind {
    Distance,
    Contact,
    Multipoint,
    Penetration,
    /// The sphere distance refined to the meshes' triangles (needs --exact).
    RefinedDistance,
    /// The meshes' own penetration: exact intersection volume and its gradient (needs
    /// --exact; --reference compares it).
    MeshPenetration,
    All,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    anyhow::ensure!(args.every >= 1, "--every must be at least 1");
    anyhow::ensure!(
        args.k >= 1,
        "--k must be at least 1 (the most contacts multipoint reports per frame)"
    );
    innersphere::RefineOptions {
        radius_scale: args.refine_radius_scale,
        margin: args.refine_margin.unwrap_or(-1.0),
        ..Default::default()
    }
    .check()
    .context("--refine-radius-scale")?;
    if let Some(m) = args.refine_margin {
        anyhow::ensure!(
            m >= 0.0 && m.is_finite(),
            "--refine-margin must be a finite length ≥ 0, got {m}"
        );
    }
    if let Some(csv) = &args.csv {
        let mut inputs = vec![args.a.as_path(), args.b.as_path(), args.motion.as_path()];
        inputs.extend(args.exact.iter().flatten().map(|p| p.as_path()));
        crate::files::check_outputs(&[(csv, crate::files::PLAIN_CSV)], &inputs)?;
    }
    let on_meshes = matches!(args.query, Kind::RefinedDistance | Kind::MeshPenetration);
    anyhow::ensure!(
        !on_meshes || args.exact.is_some(),
        "--query refined-distance and mesh-penetration need the meshes: --exact MESH_A MESH_B"
    );
    anyhow::ensure!(
        args.reference.is_none() || args.query == Kind::MeshPenetration,
        "--reference compares the meshes' penetration: --query mesh-penetration"
    );
    let mesh_reference = args
        .reference
        .as_deref()
        .map(innersphere_eval::mesh_reference::MeshReference::load)
        .transpose()?;
    let mut a = innersphere::SharedTree::new(crate::bodies::load(&args.a, &args.body)?);
    let mut b = innersphere::SharedTree::new(crate::bodies::load(&args.b, &args.body)?);
    let motion = innersphere_eval::motion::Motion::load(&args.motion)?;
    let exact = match &args.exact {
        Some(m) => {
            let (ma, mb) = (
                crate::files::load_mesh(&m[0], args.body.unit.unit)?,
                crate::files::load_mesh(&m[1], args.body.unit.unit)?,
            );
            // Meshes that are not the trees' own make the accuracy meaningless: say so.
            for (mesh, path, tree, tree_path) in
                [(&ma, &m[0], &a, &args.a), (&mb, &m[1], &b, &args.b)]
            {
                if let Some(why) = innersphere::tree::check::source_mismatch(tree, mesh) {
                    eprintln!(
                        "warning: --exact {} is not the mesh {} was built from ({why}): the accuracy figures compare unrelated shapes",
                        path.display(),
                        tree_path.display()
                    );
                }
            }
            let (ea, eb) = (
                Arc::new(ExactMesh::new(&ma)?),
                Arc::new(ExactMesh::new(&mb)?),
            );
            // The refined distance searches the same meshes (when they are the trees' own).
            let refine = [(&a, &ea), (&b, &eb)]
                .iter()
                .all(|(t, m)| innersphere::tree::check::source_mismatch(t, m.mesh()).is_none());
            if refine {
                a = a.with_exact_mesh(ea.clone())?;
                b = b.with_exact_mesh(eb.clone())?;
            } else {
                anyhow::ensure!(
                    !on_meshes,
                    "--query refined-distance and mesh-penetration need the meshes the trees were built from"
                );
            }
            Some((ea, eb, refine))
        }
        None => None,
    };
    let kinds = match args.query {
        Kind::Distance => vec![QueryKind::Distance],
        Kind::Contact => vec![QueryKind::Contact],
        Kind::Multipoint => vec![QueryKind::Multipoint],
        Kind::Penetration => vec![QueryKind::Penetration],
        Kind::RefinedDistance => vec![QueryKind::RefinedDistance],
        Kind::MeshPenetration => vec![QueryKind::MeshPenetration],
        Kind::All if matches!(exact, Some((_, _, true))) => QueryKind::WITH_REFINED.to_vec(),
        Kind::All => QueryKind::ALL.to_vec(),
    };
    let opts = ReplayOptions {
        kinds,
        k: args.k,
        split_depth: args.split_depth,
        every: args.every,
        passes: args.passes as usize,
        refine: innersphere::RefineOptions {
            radius_scale: args.refine_radius_scale,
            margin: args.refine_margin.unwrap_or(-1.0),
            ..Default::default()
        },
        mesh_reference,
        ..Default::default()
    };
    // The meshes' penetration has its own reference (--reference): the exact distance's
    // comparison, milliseconds a frame, is left out.
    let meshes = exact
        .as_ref()
        .filter(|_| args.query != Kind::MeshPenetration)
        .map(|(x, y, _)| (&**x, &**y));
    let report = replay(&a, &b, &motion, meshes, &opts);
    if let Some(path) = &args.csv {
        innersphere::output::write_atomic(path, |w| report.write_csv(w))?;
    }
    if args.json {
        crate::print::print_json(&report)?;
        return Ok(0);
    }
    print_text(&report, opts.deep);
    Ok(0)
}

/// The report as text: the timing table, disagreeing passes on stderr, and the accuracy
/// against the exact reference (`deep`: the depth a missed contact counts as deep from).
fn print_text(report: &ReplayReport, deep: f64) {
    let n = report.passes;
    println!(
        "{} frames, one thread; 1 pass = the first pass in motion order, state carried frame to frame (what a haptic loop sees){}",
        report.frames,
        if n > 1 {
            format!("; best-of-{n} = each frame's fastest of {n} passes, each from a fresh state")
        } else {
            String::new()
        }
    );
    if n > 1 {
        println!("| query | p50 µs (1 pass) | p99 µs (1 pass) | max µs (1 pass) [frame] | frames over 1 ms (1 pass) | p99 µs best-of-{n} | max µs best-of-{n} | frames over 1 ms best-of-{n} |");
        println!("|---|---|---|---|---|---|---|---|");
    } else {
        println!("| query | p50 µs (1 pass) | p99 µs (1 pass) | max µs (1 pass) [frame] | frames over 1 ms (1 pass) |");
        println!("|---|---|---|---|---|");
    }
    for k in &report.kinds {
        let best = if n > 1 {
            format!(
                " {:.1} | {:.1} | {} |",
                k.best_of_passes_p99_us, k.best_of_passes_max_us, k.best_of_passes_frames_over_1ms
            )
        } else {
            String::new()
        };
        println!(
            "| {:?} | {:.1} | {:.1} | {:.1} [{}] | {} |{best}",
            k.kind, k.p50_us, k.p99_us, k.max_us, k.max_frame, k.frames_over_1ms
        );
    }
    for k in report.kinds.iter().filter(|k| !k.passes_agree) {
        eprintln!(
            "warning: {:?}: the passes did not all give the same answers (best-of-{n} may compare unlike work)",
            k.kind
        );
    }
    if let Some(acc) = &report.accuracy {
        println!(
            "exact reference on {} frames ({} separated): abs error p50 {:.4} p95 {:.4} max {:.4} units (model units, mm for the jaw scans), relative p50 {:.4} p95 {:.4}; missed contacts {} ({} deeper than {} units, the deepest {:.4}), false contacts {}",
            acc.frames, acc.separated_frames, acc.errors.abs_err_p50, acc.errors.abs_err_p95, acc.errors.abs_err_max,
            acc.errors.rel_err_p50, acc.errors.rel_err_p95, acc.errors.missed_contacts, acc.errors.missed_contacts_deep,
            deep, acc.errors.missed_contacts_max_depth, acc.errors.false_contacts
        );
        let best = if n > 1 {
            format!(
                " (best-of-{n}: p99 {:.1} µs, max {:.1} µs)",
                acc.exact_best_of_passes_p99_us, acc.exact_best_of_passes_max_us
            )
        } else {
            String::new()
        };
        println!(
            "exact mesh distance, timed on each compared frame, warm-started from the previous compared frame ({} frames back; the first cold), 1 pass: p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs{best}; our distance p99 (1 pass) on the same frames {:.1} µs ({:.1}× faster)",
            acc.exact_warm_start_frames, acc.exact_p50_us, acc.exact_p99_us, acc.exact_max_us,
            acc.distance_p99_us, acc.speedup_p99
        );
        if let Some(r) = &acc.refined {
            println!(
                "refined distance against the exact reference: abs error p50 {:.5} p95 {:.5} max {:.5} units, relative p50 {:.5} p95 {:.5}; missed contacts {} ({} deeper than {} units, the deepest {:.4}), false contacts {}; {} frames out of budget; p99 (1 pass) on the compared frames {:.1} µs ({:.1}× faster than the exact mesh distance)",
                r.errors.abs_err_p50, r.errors.abs_err_p95, r.errors.abs_err_max, r.errors.rel_err_p50, r.errors.rel_err_p95,
                r.errors.missed_contacts, r.errors.missed_contacts_deep, deep, r.errors.missed_contacts_max_depth,
                r.errors.false_contacts, r.incomplete_frames, r.p99_us, r.speedup_p99
            );
        }
        if !acc.exact_passes_agree {
            eprintln!("warning: the exact method's passes did not all give the same answers");
        }
    }
    if let Some(m) = &report.mesh_accuracy {
        println!(
            "the meshes' penetration against the reference on {} frames ({} overlapping): volume within 2 % (or {} units³) on {} ({:.1} %), median ratio {:.5}; missed contacts {} (reference ≥ {} units³), invented {}; gradient direction on {} frames: p95 {:.3}°, max {:.3}°",
            m.frames, m.contact_frames, innersphere_eval::mesh_reference::TINY, m.within_bar,
            100.0 * m.within_bar_fraction, m.median_ratio, m.missed_contacts,
            innersphere_eval::mesh_reference::TINY, m.invented_contacts, m.direction_frames,
            m.direction_err_p95_deg, m.direction_err_max_deg
        );
    }
}
