//! `ist haptic`: the library's 6-DOF haptic loop over a recorded device trajectory.

use anyhow::Context;
use innersphere::{Pair, SharedTree};
use innersphere_eval::haptic::{run as run_session, trace_csv, Session};
use innersphere_eval::motion::Motion;
use innersphere_haptic::{CollisionOptions, ContactSource, DeviceClass, HapticOptions};
use std::path::PathBuf;

/// Arguments of `ist haptic`. Units: millimetres, newtons, seconds (torques in N·mm).
#[derive(clap::Args)]
pub struct Args {
    /// Tree file of body A (fixed, at the identity pose), or its mesh (built with --preset,
    /// cached).
    a: PathBuf,
    /// Tree file of body B, the tool the device moves (its tree must hold mass properties:
    /// built by this version of `ist build`).
    b: PathBuf,
    /// How a mesh given for A or B becomes its tree.
    #[command(flatten)]
    body: crate::bodies::BodyArgs,
    /// The device trajectory: a motion CSV (`t,tx,ty,tz,qw,qx,qy,qz`, the device's pose of B
    /// in A's frame; mm and s), e.g. from `ist motion --scenario press`.
    #[arg(long)]
    device: PathBuf,
    /// Device class, for the force and torque limits and the default coupling: touch
    /// (3.3 N) or omega (12 N).
    #[arg(long, default_value = "omega", value_parser = parse_class)]
    device_class: DeviceClass,
    /// Coupling stiffness (N/mm; default 60 % of the device's, less below 1 kHz where the
    /// device's damping limit caps it; rotations get × 20² mm²).
    #[arg(long)]
    stiffness: Option<f64>,
    /// Coupling damping (N·s/mm; default 4 × k·T/2 at the rate or 1 kHz, whichever is
    /// slower; at least k·T/2; rotations get × 20² mm²).
    #[arg(long)]
    damping: Option<f64>,
    /// Contact stiffness: penalty force per penetration volume (N/mm³).
    #[arg(long)]
    contact_stiffness: Option<f64>,
    /// Device ticks per second (Hz).
    #[arg(long, default_value_t = 1000.0)]
    rate: f64,
    /// Tick budget (µs; default one tick period): the exact query gives way to the
    /// time-critical one when it would not fit.
    #[arg(long)]
    budget_us: Option<f64>,
    /// Pace the ticks at the rate in real time, asking for real-time (FIFO) scheduling
    /// (default: as fast as possible).
    #[arg(long)]
    realtime: bool,
    /// Run the penetration query in a collision thread of its own, the servo tick on the
    /// contact model it publishes (the multi-rate loop; see docs/HAPTICS.md).
    #[arg(long)]
    collision_thread: bool,
    /// With --collision-thread: sleep this long (µs) before each collision query, standing
    /// for a slow machine.
    #[arg(long)]
    collision_delay_us: Option<f64>,
    /// Where the contact comes from: `spheres` (the packings' penetration volume, tens of
    /// µs a query) or `mesh` (the meshes' own exact intersection volume, milliseconds in
    /// deep contact; runs in the collision thread, which it implies, and needs the meshes
    /// as `ist query --query mesh-penetration` does). docs/HAPTICS.md says why spheres is the
    /// default.
    #[arg(long, default_value = "spheres", value_parser = parse_contact)]
    contact: ContactSource,
    /// The meshes of A and B for --contact mesh (default: the bodies' own when given as
    /// meshes, else the meshes their tree files name as their source).
    #[arg(long, num_args = 2, value_names = ["MESH_A", "MESH_B"])]
    meshes: Option<Vec<PathBuf>>,
    /// Write one row per tick: t, device pose, tool pose, force xyz (N), torque xyz (N·mm),
    /// volume (mm³), depth (mm), compute_us, budgeted.
    #[arg(long)]
    trace: Option<PathBuf>,
    /// Draw force, depth and compute time against time into this PNG.
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
}

fn parse_contact(s: &str) -> Result<ContactSource, String> {
    s.parse().map_err(|e: innersphere::Error| e.to_string())
}

fn parse_class(s: &str) -> Result<DeviceClass, String> {
    s.parse().map_err(|e: innersphere::Error| e.to_string())
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let mut outputs = vec![];
    outputs.extend(args.trace.as_deref().map(|p| (p, crate::files::CSV_FILE)));
    outputs.extend(args.plot.as_deref().map(|p| (p, crate::files::PNG_FILE)));
    crate::files::check_outputs(&outputs, &[&args.a, &args.b, &args.device])?;
    let mut opts = HapticOptions::for_device_at(args.device_class, args.rate);
    opts.budget = args.budget_us.map_or(1.0 / args.rate, |us| us * 1e-6);
    if let Some(k) = args.stiffness {
        opts.coupling.stiffness = k;
        opts.coupling.angular_stiffness = k * innersphere_haptic::device::LEVER.powi(2);
    }
    if let Some(b) = args.damping {
        opts.coupling.damping = b;
        opts.coupling.angular_damping = b * innersphere_haptic::device::LEVER.powi(2);
    }
    if let Some(k) = args.contact_stiffness {
        opts.contact_stiffness = k;
    }
    opts.check()?;
    let mesh = args.contact == ContactSource::Mesh;
    anyhow::ensure!(
        args.collision_thread || mesh || args.collision_delay_us.is_none(),
        "--collision-delay-us needs the collision thread (--collision-thread or --contact mesh)"
    );
    anyhow::ensure!(
        mesh || args.meshes.is_none(),
        "--meshes gives the meshes of --contact mesh"
    );
    let collision = if args.collision_thread || mesh {
        let c = CollisionOptions {
            delay: args.collision_delay_us.unwrap_or(0.0) * 1e-6,
            contact: args.contact,
            ..Default::default()
        };
        c.check()?;
        Some(c)
    } else {
        None
    };
    let (a, mesh_a) = crate::bodies::load_body(&args.a, &args.body)?;
    let (b, mesh_b) = crate::bodies::load_body(&args.b, &args.body)?;
    let (mut a, mut b) = (SharedTree::new(a), SharedTree::new(b));
    if mesh {
        let given = args.meshes.as_deref().unwrap_or(&[]);
        a = crate::bodies::with_mesh(a, given.first(), mesh_a, "A", args.body.unit.unit)?;
        b = crate::bodies::with_mesh(b, given.get(1), mesh_b, "B", args.body.unit.unit)?;
    }
    let device = Motion::load(&args.device)?;
    let session = Session {
        realtime: args.realtime,
        collision,
        keep_ticks: args.trace.is_some() || args.plot.is_some(),
    };
    let r = run_session(Pair::new(a, b), &device, opts, &session)?;
    if let Some(path) = &args.trace {
        innersphere::output::write_file(path, trace_csv(&r).as_bytes())
            .context("writing the trace")?;
    }
    if let Some(path) = &args.plot {
        innersphere_eval::plot::haptic_chart(path, &r).context("drawing the plot")?;
    }
    let s = &r.summary;
    if args.json {
        println!("{}", serde_json::to_string_pretty(s)?);
    } else {
        println!(
            "{} ticks at {} Hz ({}): compute p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs; {} over the {:.0} µs budget, {} budgeted\n\
             force max {:.3} N (largest step {:.4} N), torque max {:.1} N·mm; depth max {:.3} mm, volume max {:.3} mm³\n\
             energy to the hand: max {:.3e} J, end {:.3e} J (≤ 0: passive)\n\
             contact model age p99 {:.1} µs, max {:.1} µs{}",
            s.ticks,
            s.rate_hz,
            if s.realtime { "real time" } else { "as fast as possible" },
            s.compute_p50_us,
            s.compute_p99_us,
            s.compute_max_us,
            s.deadline_misses,
            s.budget_us,
            s.budgeted_ticks,
            s.max_force_n,
            s.max_force_step_n,
            s.max_torque_nmm,
            s.max_depth_mm,
            s.max_volume_mm3,
            s.energy_to_user_max_j,
            s.energy_to_user_end_j,
            s.model_age_p99_us,
            s.model_age_max_us,
            match (s.collision_rate_hz, s.collision_p99_us) {
                (Some(r), Some(p)) => format!(
                    "; collision thread ({} contact) {r:.0} models/s (fewest in a quarter second: {:.0}/s), query p99 {p:.1} µs",
                    match s.contact {
                        ContactSource::Spheres => "sphere",
                        ContactSource::Mesh => "mesh",
                    },
                    s.collision_rate_min_hz.unwrap_or(0.0)
                ),
                _ => String::new(),
            }
        );
    }
    Ok(0)
}
