//! `ist motion`: generate a hand-recorded-looking motion of body B against body A.

use anyhow::Context;
use innersphere_eval::motion::{
    generate_with, press, AnatomicalFrame, ClearanceOptions, GenerateOptions, PressOptions,
    Scenario,
};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `ist motion`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    unit: crate::files::UnitArg,
    /// What the motion does: chew, open-close, grind or contact (random contact); or press, a smooth 6 s haptic device
    /// trajectory (3 mm open → 1 mm past the bite, hold, ±0.8 mm sideways while pressing,
    /// release; --seconds, --seed and the labels do not apply).
    #[arg(long, default_value = "chew", value_parser = parse_scenario)]
    scenario: Kind,
    /// Length of the motion in seconds.
    #[arg(long, default_value_t = 5.0)]
    seconds: f64,
    /// Seed of the random choices (the same seed gives the same file).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Mesh of body A, the fixed upper body (.stl, .obj, .ply or .off, optionally .gz).
    #[arg(long)]
    a: PathBuf,
    /// Mesh of body B, the moving lower body, in A's frame at the identity pose.
    #[arg(long)]
    b: PathBuf,
    /// Output motion file (CSV `t,tx,ty,tz,qw,qx,qy,qz`; gzip when it ends in .gz).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the per-frame labels (`frame,t,clearance,phase`) to this CSV.
    #[arg(long)]
    labels: Option<PathBuf>,
    /// Frames per second.
    #[arg(long, default_value_t = 1000.0)]
    rate: f64,
    /// Touch threshold of the phase labels in model units (default 0.1 × the pair's scale,
    /// i.e. 0.1 mm for a human jaw in mm).
    #[arg(long)]
    touch: Option<f64>,
    /// About how many vertices of each body the clearance estimate samples (plus as many
    /// again where the bodies meet).
    #[arg(long, default_value_t = 4096)]
    samples: usize,
}

/// A generated hand motion, or the haptic press trajectory.
#[derive(Clone, Copy)]
enum Kind {
    Hand(Scenario),
    Press,
}

fn parse_scenario(s: &str) -> Result<Kind, String> {
    if s.trim().eq_ignore_ascii_case("press") {
        return Ok(Kind::Press);
    }
    s.parse()
        .map(Kind::Hand)
        .map_err(|e: innersphere::Error| format!("{e} or press"))
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let start = Instant::now();
    let mut outputs = vec![(args.output.as_path(), crate::files::CSV_FILE)];
    outputs.extend(args.labels.as_deref().map(|p| (p, crate::files::CSV_FILE)));
    crate::files::check_outputs(&outputs, &[&args.a, &args.b])?;
    // The library's errors name the file; the context says which body it was.
    let a = crate::files::load_mesh(&args.a, args.unit.unit).context("loading body A (--a)")?;
    let b = crate::files::load_mesh(&args.b, args.unit.unit).context("loading body B (--b)")?;
    let scenario = match args.scenario {
        Kind::Hand(s) => s,
        Kind::Press => {
            if args.labels.is_some() {
                anyhow::bail!("--labels does not apply to the press trajectory");
            }
            let frame = AnatomicalFrame::from_meshes(&a, &b)?;
            let opts = PressOptions {
                rate: args.rate,
                ..PressOptions::default()
            };
            let m = press(&frame, &opts)?;
            m.save(&args.output).context("writing the motion")?;
            println!(
                "{}: {} frames at {} Hz (press: {} open → {} past the bite along up {:.3?}, \
                 ±{} along left {:.3?}; model units)",
                args.output.display(),
                m.len(),
                args.rate,
                opts.open,
                opts.past,
                frame.up.to_array(),
                opts.slide,
                frame.left.to_array()
            );
            return Ok(0);
        }
    };
    let opts = GenerateOptions {
        rate: args.rate,
        touch: args.touch,
        clearance: ClearanceOptions {
            samples: args.samples,
            ..ClearanceOptions::default()
        },
        ..GenerateOptions::default()
    };
    let g = generate_with(scenario, args.seconds, args.seed, &a, &b, &opts)?;
    g.motion.save(&args.output).context("writing the motion")?;
    if let Some(path) = &args.labels {
        innersphere::output::write_file(path, g.labels_csv().as_bytes())
            .context("writing the labels")?;
    }
    let c = g.counts();
    println!(
        "{}: {} frames at {} Hz ({} s, {}, seed {}): {} separated, {} touching, {} interpenetrating \
         (clearance estimate from {} samples, touch threshold {:.3} units; bite clearance {:.3} units; {:.1} s; model units, mm for the jaw scans)",
        args.output.display(),
        g.motion.len(),
        args.rate,
        args.seconds,
        scenario,
        args.seed,
        c.separated,
        c.touching,
        c.overlap,
        g.samples,
        g.touch,
        g.bite_clearance,
        start.elapsed().as_secs_f64()
    );
    if !c.all_present() {
        eprintln!("warning: the motion does not pass through all three phases");
    }
    Ok(0)
}
