//! `ist plan`: one patient's case file run from the scans to the wafers and a report
//! (`innersphere_dental::case`).

use crate::progress::Bars;
use innersphere_dental::case::{self, Case, PlanEnv};
use std::path::PathBuf;

/// Arguments of `ist plan`.
#[derive(clap::Args)]
#[command(
    after_help = "The case file (JSON, docs/PLAN.md): {\"version\": 1, \"upper\": \"maxilla.stl\", \"lower\": \"mandible.stl\", \"unit\": \"mm\", \"bite\": {\"method\": \"free\"}, \"splints\": [{\"name\": \"final\", \"open\": \"auto\"}, {\"name\": \"intermediate\", \"open\": 3}]}; paths relative to the case file.\nOutputs in OUTDIR: upper_map.ply and lower_map.ply (the contact map), NAME.stl and NAME.3mf per wafer fit to print, report.html (self-contained), case.json (the case as run) and plan-files.txt (what the plan wrote). OUTDIR must be new, empty or a previous plan's; nothing else in it is touched. Run twice, the files are the same bytes but for the report's \"Made\" line.\nExit codes: 0 every wafer fit to print; 3 a wafer failed a guarantee or could not be made (not written; the report and the JSON's `error` say why; the rest is written); 2 a case that cannot be planned (with the reason).\nJSON: case_version, library, unit, preset, inputs (role, file, bytes, blake3), bite (method, pose: B in A's frame, status, from, contact, volume, candidates), map (upper, lower: file, vertices, min_gap, vertices_inside, teeth, regions, balance), splints (name, file, report: as `ist splint --json`, or null with error: why it could not be made), fit, seconds."
)]
pub struct Args {
    /// The case file.
    case: PathBuf,
    /// The output folder.
    #[arg(short, long)]
    out: PathBuf,
    /// Folder of the build cache (as the other commands take it; default: $IST_CACHE, else
    /// the platform's cache folder).
    #[arg(long, env = "IST_CACHE")]
    cache: Option<PathBuf>,
    /// Build the trees without reading or writing the cache.
    #[arg(long)]
    no_cache: bool,
    /// Print the plan as JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let case = Case::load(&args.case)?;
    // Before the work: a folder the plan may not write into is refused at once.
    case::check_folder(&args.out)?;
    let cache = crate::bodies::build_cache(args.cache.as_ref(), args.no_cache);
    let bars = Bars::new(false);
    let planned = case::run(&case, &PlanEnv { cache }, &bars)?;
    case::write(&planned, &args.out, &case::utc_stamp())?;
    let plan = &planned.plan;
    if args.json {
        crate::print::print_json(plan)?;
    } else {
        let b = &plan.bite;
        println!(
            "bite ({:?}): {:?}, B at {}",
            b.method,
            b.status,
            b.pose.map(|x| format!("{x:.4}")).join(" ")
        );
        if let Some(m) = &plan.map {
            for (name, a) in [("upper", &m.upper), ("lower", &m.lower)] {
                println!(
                    "{name}: least gap {:.3} mm, {} vertices inside the other arch, contact {:.1} mm² left / {:.1} mm² right",
                    a.min_gap, a.vertices_inside, a.balance.left, a.balance.right
                );
            }
        }
        for s in &plan.splints {
            let Some(r) = &s.report else {
                println!(
                    "wafer {}: NOT made: {}",
                    s.name,
                    s.error.as_deref().unwrap_or("")
                );
                continue;
            };
            println!(
                "wafer {}: {} ({} triangles, opened {:.2} mm, coverage {:.1} % / {:.1} %)",
                s.name,
                s.file
                    .as_deref()
                    .map_or("NOT fit to print, not written".to_string(), |f| f
                        .to_string()),
                r.triangles,
                r.opened,
                100.0 * r.coverage_a,
                100.0 * r.coverage_b
            );
        }
        println!(
            "report: {} ({:.1} s)",
            args.out.join(case::REPORT).display(),
            plan.seconds.total
        );
    }
    Ok(if plan.fit { 0 } else { 3 })
}
