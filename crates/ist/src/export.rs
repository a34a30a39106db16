//! `ist export`: the spheres of a tree as PLY or CSV.

use anyhow::Context;
use innersphere::tree::export::{self, Which};
use std::io::Write;
use std::path::PathBuf;

/// Arguments of `ist export`.
#[derive(clap::Args)]
pub struct Args {
    /// Tree file written by `ist build`.
    tree: PathBuf,
    /// Output format.
    #[arg(long, value_enum, default_value = "ply")]
    format: Format,
    /// Output file (default: standard output).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Write every node, not only the leaves (inner spheres).
    #[arg(long)]
    all_nodes: bool,
}

#[derive(Clone, Copy, clap::ValueEnum)]
enum Format {
    Ply,
    Csv,
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let tree = crate::load_tree(&args.tree)?;
    let which = if args.all_nodes {
        Which::All
    } else {
        Which::Leaves
    };
    let mut out: Box<dyn Write> = match &args.output {
        Some(p) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(p).with_context(|| format!("cannot create {}", p.display()))?,
        )),
        None => Box::new(std::io::BufWriter::new(std::io::stdout().lock())),
    };
    match args.format {
        Format::Ply => export::write_ply(&tree, which, &mut out)?,
        Format::Csv => export::write_csv(&tree, which, &mut out)?,
    }
    out.flush()?;
    Ok(0)
}
