//! `ist`: the command-line shell over the `innersphere` library. One file per subcommand,
//! `files` (loading trees and meshes, checking outputs) and `print` (JSON, numbers, errors)
//! for what they share; every piece of logic lives in the library. This file: the command
//! line and the dispatch.

mod bench;
mod bodies;
mod build;
mod check;
mod demo;
mod export;
mod files;
mod haptic;
mod inspect;
mod motion;
mod occlude;
mod occlusion_map;
mod plan;
mod print;
mod progress;
mod query;
mod replay;
mod splint;
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
    /// Both arches coloured by their exact signed gap to each other (PLY), with the contacts
    /// per tooth.
    OcclusionMap(occlusion_map::Args),
    /// Plan a case: one case file from the scans to the bite, the contact map, the wafers
    /// and a report (docs/PLAN.md).
    Plan(plan::Args),
    /// The occlusal splint (surgical wafer) between two arches at a planned pose, as a
    /// watertight binary STL.
    Splint(splint::Args),
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
        Command::OcclusionMap(a) => occlusion_map::run(a),
        Command::Plan(a) => plan::run(a),
        Command::Splint(a) => splint::run(a),
        Command::View(a) => view::run(a),
    };
    match result {
        Ok(code) => std::process::exit(code),
        Err(e) => {
            eprintln!("error: {}", print::error_text(&e));
            std::process::exit(2);
        }
    }
}
