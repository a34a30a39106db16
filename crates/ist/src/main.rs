//! `ist`: the command-line shell over the `innersphere` library. One file per subcommand;
//! every piece of logic lives in the library.

mod bench;
mod build;
mod check;
mod demo;
mod export;
mod haptic;
mod inspect;
mod motion;
mod occlude;
mod progress;
mod query;
mod replay;
mod view;

use clap::{Parser, Subcommand};

/// Inner Sphere Trees: build, inspect, check and query collision trees of complex 3D models.
#[derive(Parser)]
#[command(name = "ist", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// The main job on a built-in model: generate two tooth-like bodies and build their trees.
    Demo(demo::Args),
    /// Build the Inner Sphere Tree of a mesh and write it to a tree file.
    Build(build::Args),
    /// Print the defect report of a mesh.
    Inspect(inspect::Args),
    /// Verify a tree against its mesh (spheres inside, disjoint, parents enclosing children).
    Check(check::Args),
    /// Write the inner spheres of a tree as PLY or CSV for viewers.
    Export(export::Args),
    /// Run one query between two trees.
    Query(query::Args),
    /// Generate a hand-recorded-looking motion of body B against body A (a CSV at 1 kHz).
    Motion(motion::Args),
    /// Replay a motion frame by frame as a haptic loop would: timings, and accuracy against
    /// the exact mesh distance.
    Replay(replay::Args),
    /// Benchmarks (build).
    Bench(bench::Args),
    /// Run the 6-DOF haptic loop over a recorded device trajectory (mm, N, s): force to the
    /// device, tool pose, deadline, passivity.
    Haptic(haptic::Args),
    /// Close body B onto body A under a constant force until it rests: the bite.
    Occlude(occlude::Args),
    /// A live 3D view in the browser: move B, watch contacts, forces, the inner spheres.
    View(view::Args),
}

fn main() {
    // Die quietly like other Unix tools when the reader of our output goes away
    // (`ist export ... | head`), instead of panicking on a broken pipe.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of SIGPIPE before any thread starts.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Build(a) => build::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Check(a) => check::run(a),
        Command::Export(a) => export::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Motion(a) => motion::run(a),
        Command::Replay(a) => replay::run(a),
        Command::Query(a) => query::run(a),
        Command::Haptic(a) => haptic::run(a),
        Command::Occlude(a) => occlude::run(a),
        Command::View(a) => view::run(a),
    };
    match result {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {}", error_text(&e));
            std::process::exit(2);
        }
    }
}

/// The error and its causes on one line, each cause once: the library's I/O error already
/// shows its source ("a.ist: No such file or directory"), so a cause whose text the line
/// already holds is not repeated.
fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if text.contains(&c) {
            continue;
        }
        if !text.is_empty() {
            text += ": ";
        }
        text += &c;
    }
    text
}

/// What "units" means in the human-readable output: the library never converts lengths.
pub const UNITS: &str =
    "lengths in model units (the mesh file's own unit: mm for the jaw scans), volumes in units³";

/// `x` with at most 6 significant digits and no trailing zeros (0.1, 0.005208, 1.5e-7).
fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return x.to_string();
    }
    let magnitude = x.abs().log10().floor();
    if !(-4.0..=9.0).contains(&magnitude) {
        return format!("{x:.5e}");
    }
    let decimals = (5.0 - magnitude).max(0.0) as usize;
    let text = format!("{x:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// Prints `value` as pretty JSON on stdout, always ending with a newline (so that
/// `ist ... --json > f.json` gives a complete text file and shells print the prompt on a
/// new line).
fn print_json(value: &impl serde::Serialize) -> anyhow::Result<()> {
    use std::io::Write;
    let mut text = serde_json::to_string_pretty(value)?;
    text.push('\n');
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())?;
    out.flush()?;
    Ok(())
}

/// Refuses, before any work, outputs that are one of the inputs or the same file twice: the
/// library's [`innersphere::output`] checks (canonical paths, and device and inode on Unix, so
/// links are caught). Every output is then written through
/// [`innersphere::output::write_atomic`].
fn check_outputs(outputs: &[&std::path::Path], inputs: &[&std::path::Path]) -> anyhow::Result<()> {
    innersphere::output::ensure_distinct_outputs(outputs)?;
    for o in outputs {
        innersphere::output::ensure_not_input(o, inputs)?;
    }
    Ok(())
}

/// Loads a tree file; a mesh given instead (by its extension) is named as such, with the fix.
/// Every error names the file once (the library's errors already carry the path).
fn load_tree(path: &std::path::Path) -> anyhow::Result<innersphere::SphereTree> {
    match innersphere::SphereTree::load(path) {
        Ok(tree) => Ok(tree),
        Err(innersphere::Error::CorruptTree(_))
            if innersphere::mesh::Format::from_path(path).is_ok() =>
        {
            anyhow::bail!(
                "{} is a mesh, not a tree file: run `ist build` on it first (`ist build MESH -o TREE.ist`) and give the tree",
                path.display()
            )
        }
        Err(e) => Err(e.into()),
    }
}

/// Loads a mesh file; a tree file given instead (by its magic number) is named as such, with
/// the fix. Every error names the file once.
fn load_mesh(path: &std::path::Path) -> anyhow::Result<innersphere::Mesh> {
    match innersphere::Mesh::load(path) {
        Ok(mesh) => Ok(mesh),
        Err(e @ (innersphere::Error::UnsupportedFormat(_) | innersphere::Error::Parse { .. })) => {
            if is_tree_file(path) {
                anyhow::bail!(
                    "{} is an Inner Sphere Tree file, not a mesh: give a mesh file here (.stl, .obj, .ply or .off, optionally .gz; for `ist check --mesh`, the mesh the tree was built from)",
                    path.display()
                )
            }
            Err(e.into())
        }
        Err(e) => Err(e.into()),
    }
}

/// True when the file starts with the tree file's magic number.
fn is_tree_file(path: &std::path::Path) -> bool {
    use std::io::Read;
    let mut magic = [0u8; 8];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut magic))
        .is_ok()
        && magic == innersphere::tree::file::MAGIC
}

/// Prints the library's warning about a tree not built by the current builder
/// ([`innersphere::SphereTree::staleness`]) to stderr; the command goes on.
fn warn_if_stale(path: &std::path::Path, tree: &innersphere::SphereTree) {
    if let Some(w) = tree.staleness() {
        eprintln!("warning: {}: {w}", path.display());
    }
}
