//! `ist export`: the spheres of a tree as PLY or CSV.

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
    if let Some(p) = &args.output {
        let kind = match args.format {
            Format::Ply => crate::files::SPHERES_PLY,
            Format::Csv => crate::files::PLAIN_CSV,
        };
        crate::files::check_outputs(&[(p, kind)], &[&args.tree])?;
    }
    let tree = crate::files::load_tree(&args.tree)?;
    let which = if args.all_nodes {
        Which::All
    } else {
        Which::Leaves
    };
    let write = |out: &mut dyn Write| -> std::io::Result<()> {
        match args.format {
            Format::Ply => export::write_ply(&tree, which, out),
            Format::Csv => export::write_csv(&tree, which, out),
        }
    };
    match &args.output {
        Some(p) => innersphere::output::write_atomic(p, write)?,
        None => {
            let mut out = std::io::BufWriter::new(std::io::stdout().lock());
            write(&mut out)?;
            out.flush()?;
        }
    }
    Ok(0)
}
