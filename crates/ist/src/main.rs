//! `ist`: the command-line shell over the `innersphere` library. One file per subcommand;
//! every piece of logic lives in the library.

// Enabled once the mesh loaders and field land:
// mod build;
// mod check;
mod export;
// mod inspect;
// mod progress;
mod query;

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
    /// Write the inner spheres of a tree as PLY or CSV for viewers.
    Export(export::Args),
    /// Run one query between two trees.
    Query(query::Args),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Export(a) => export::run(a),
        Command::Query(a) => query::run(a),
    };
    match result {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {e:#}");
            std::process::exit(2);
        }
    }
}
