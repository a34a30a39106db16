//! `ist check`: verify a tree against its mesh; exit code 1 when an invariant fails.

use anyhow::Context;
use std::path::PathBuf;

/// Arguments of `ist check`.
#[derive(clap::Args)]
pub struct Args {
    /// Tree file written by `ist build`.
    tree: PathBuf,
    /// The mesh the tree was built from.
    #[arg(long)]
    mesh: PathBuf,
    /// The unit of the mesh file (mm, cm, m, in; default: the unit the tree recorded for its
    /// source, else mm).
    #[arg(long, value_parser = crate::files::parse_unit)]
    unit: Option<innersphere::mesh::Unit>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

/// Runs the subcommand; returns the process exit code (1 when not ok).
pub fn run(args: Args) -> anyhow::Result<i32> {
    let tree = crate::files::load_tree(&args.tree)?;
    let unit = args
        .unit
        .or(tree.meta.source.as_ref().map(|s| s.unit))
        .unwrap_or_default();
    let mesh = crate::files::load_mesh(&args.mesh, unit)?;
    // A mesh other than the tree's own (by the facts the tree keeps) is an error, not "ok".
    let report = innersphere::tree::check::check_built_from(&tree, &mesh).with_context(|| {
        format!(
            "checking {} against {}",
            args.tree.display(),
            args.mesh.display()
        )
    })?;
    if args.json {
        crate::print::print_json(&report)?;
    } else {
        println!(
            "{}: {} spheres, {} nodes, max protrusion {:.3e} units, max overlap {:.3e} units, {} enclosure violations, {} centres outside (tolerance {:.1e} units; model units, mm for the jaw scans)",
            if report.ok { "ok" } else { "FAILED" },
            report.spheres,
            report.nodes,
            report.max_protrusion,
            report.max_overlap,
            report.enclosure_violations,
            report.centers_outside,
            report.tolerance
        );
    }
    Ok(if report.ok { 0 } else { 1 })
}
