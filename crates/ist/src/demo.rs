//! `ist demo`: the main job on a built-in model — no files needed.

use crate::build::{BuildArgs, PresetArg};
use crate::progress::Bars;
use anyhow::Context;
use innersphere::build::{BuildOptions, Preset};

/// Arguments of `ist demo`.
#[derive(clap::Args)]
pub struct Args {
    /// Build preset [default: jaw for the generated teeth (in mm: the accuracy-calibrated
    /// preset of the jaw figures), the library's recommendation (fine) for --a/--b]; any build
    /// flag given beside it overrides that one field.
    #[arg(long, value_enum)]
    preset: Option<PresetArg>,
    #[command(flatten)]
    opts: BuildArgs,
    #[command(flatten)]
    unit: crate::files::UnitArg,
    /// No progress on stderr (neither bars on a terminal nor stage lines otherwise).
    #[arg(short, long)]
    quiet: bool,
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Body A's mesh instead of the generated upper tooth (needs --b too).
    #[arg(long, requires = "b")]
    a: Option<std::path::PathBuf>,
    /// Body B's mesh instead of the generated lower tooth (needs --a too).
    #[arg(long, requires = "a")]
    b: Option<std::path::PathBuf>,
    /// Seconds of generated chewing motion to replay (0 = build only).
    #[arg(long, default_value_t = 2.0)]
    seconds: f64,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let bars = Bars::new(args.quiet);
    anyhow::ensure!(
        args.seconds.is_finite() && (0.0..=600.0).contains(&args.seconds),
        "--seconds must be between 0 and 600"
    );
    let (ma, mb) = match (&args.a, &args.b) {
        (Some(a), Some(b)) => (
            crate::files::load_mesh(a, args.unit.unit)?,
            crate::files::load_mesh(b, args.unit.unit)?,
        ),
        _ => innersphere::shapes::tooth_pair(innersphere_eval::demo::TOOTH_SUBDIVISIONS),
    };
    let generated = args.a.is_none();
    let preset = match args.preset {
        Some(p) => Preset::from(p),
        None if generated => Preset::Jaw,
        None => Preset::Fine,
    };
    // The preset for the larger body (its scale decides a relative preset's voxel).
    let larger = if ma.triangles.len() >= mb.triangles.len() {
        &ma
    } else {
        &mb
    };
    let opts = args
        .opts
        .apply(BuildOptions::preset(preset, larger).context("the build preset")?);
    // The motion first: it needs only the meshes, so a pair that admits none (the same mesh
    // twice, bodies that never meet) fails before the seconds of building.
    let motion = if args.seconds > 0.0 {
        Some(
            innersphere_eval::demo::motion_for(&ma, &mb, args.seconds).with_context(|| {
                match (&args.a, &args.b) {
                    (Some(a), Some(b)) => format!("--a {} and --b {}", a.display(), b.display()),
                    _ => "the generated tooth pair".into(),
                }
            })?,
        )
    } else {
        None
    };
    let pair = innersphere_eval::demo::build_pair_from(ma, mb, &opts, &bars)?;
    let replay = match &motion {
        Some(m) => Some(innersphere_eval::demo::replay_motion(&pair, m)?),
        None => None,
    };
    if args.json {
        crate::print::print_json(
            &serde_json::json!({ "a": pair.a.2, "b": pair.b.2, "replay": replay }),
        )?;
        return Ok(0);
    }
    let unit = match (&args.a, &args.b) {
        (Some(a), Some(b)) => {
            println!(
                "innersphere demo: {} (A) and {} (B); {}",
                a.display(),
                b.display(),
                crate::print::UNITS
            );
            "units"
        }
        _ => {
            println!("innersphere demo: two generated interlocking tooth-like bodies, in mm");
            "mm"
        }
    };
    println!(
        "trees: preset {preset}{}",
        if preset == Preset::Jaw {
            " (0.1 mm voxels, refined packing: the accuracy-calibrated preset of the jaw figures; \
             p95 distance error 0.0185 mm on the real scans, docs/RESULTS.md)"
        } else {
            ""
        }
    );
    println!("| body | triangles | inside voxels | spheres | nodes | depth | coverage | build s |");
    println!("|---|---|---|---|---|---|---|---|");
    for (name, (_, _, r)) in [("A (upper)", &pair.a), ("B (lower)", &pair.b)] {
        println!(
            "| {name} | {} | {} | {} | {} | {} | {:.3} | {:.2} |",
            r.mesh.triangles, r.voxels_inside, r.spheres, r.nodes, r.depth, r.coverage, r.seconds
        );
    }
    if let Some(rep) = replay {
        print_replay(&rep, args.seconds, unit);
    }
    Ok(0)
}

/// The replay's table and its accuracy against the exact mesh distance, in `unit`.
fn print_replay(rep: &innersphere_eval::replay::ReplayReport, seconds: f64, unit: &str) {
    println!();
    println!(
        "replay of a generated {:.1} s chewing motion ({} frames at 1 kHz), one thread:",
        seconds, rep.frames
    );
    println!(
        "| query | sustained rate (1/p99) | p50 µs | p99 µs | worst frame µs | frames over 1 ms |"
    );
    println!("|---|---|---|---|---|---|");
    for k in &rep.kinds {
        println!(
            "| {:?} | {:.0} Hz | {:.1} | {:.1} | {:.1} | {} |",
            k.kind,
            1e6 / k.p99_us.max(1e-3),
            k.p50_us,
            k.p99_us,
            k.max_us,
            k.frames_over_1ms
        );
    }
    if let Some(acc) = &rep.accuracy {
        println!(
            "distance error against the exact mesh distance ({} separated frames): p50 {:.4}, p95 {:.4}, max {:.4} {unit}; missed contacts {} ({} deeper than 0.1 {unit}), false contacts {}",
            acc.separated_frames, acc.errors.abs_err_p50, acc.errors.abs_err_p95, acc.errors.abs_err_max,
            acc.errors.missed_contacts, acc.errors.missed_contacts_deep, acc.errors.false_contacts
        );
        if let Some(r) = &acc.refined {
            println!(
                "the distance refined to the meshes (RefinedDistance): p50 {:.5}, p95 {:.5}, max {:.5} {unit}; missed contacts {} (the deepest {:.4} {unit}), false contacts {}",
                r.errors.abs_err_p50, r.errors.abs_err_p95, r.errors.abs_err_max,
                r.errors.missed_contacts, r.errors.missed_contacts_max_depth, r.errors.false_contacts
            );
        }
    }
}
