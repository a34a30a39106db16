//! `ist build`: mesh → Inner Sphere Tree file.

use crate::progress::Bars;
use anyhow::Context;
use innersphere::build::Preset;
use innersphere::{BuildOptions, Resolution, SphereTree};
use serde_json::json;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `ist build`.
#[derive(clap::Args)]
pub struct Args {
    /// Mesh file: .stl, .obj, .ply or .off, optionally .gz.
    mesh: PathBuf,
    #[command(flatten)]
    unit: crate::files::UnitArg,
    /// Output tree file.
    #[arg(short, long)]
    output: PathBuf,
    /// Named settings, computed from the mesh; any build flag given beside it overrides
    /// that one field (e.g. `--preset jaw --refine-steps 16`).
    #[arg(long, value_enum)]
    preset: Option<PresetArg>,
    #[command(flatten)]
    opts: BuildArgs,
    /// Print the build report as JSON on stdout (stage progress still goes to stderr
    /// unless --quiet).
    #[arg(long)]
    json: bool,
    /// No progress on stderr (neither bars on a terminal nor stage lines otherwise);
    /// warnings are still printed.
    #[arg(short, long)]
    quiet: bool,
}

/// `--preset`: the library's [`Preset`]s (see their documentation for the measured costs).
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PresetArg {
    /// Quick look: 64 cells along the longest side, plain greedy packing.
    Fast,
    /// The defaults: 128 cells along the longest side, plain greedy packing (the paper's).
    Default,
    /// Calibrated packing scaled to the mesh: voxel = longest side / 384, minimum radius
    /// half a voxel, 8 refinement steps (the library's recommendation for unknown units).
    Fine,
    /// Jaw scans in mm, accuracy-calibrated: 0.1 mm voxels, 0.05 mm minimum radius, 8
    /// refinement steps (p95 error 0.028 mm on the arches along a chew, ≤ 0.0008 mm refined to
    /// the meshes by `ist query --query refined-distance`; ~2.3–2.6 s and ~0.38 GB per arch on
    /// 2 cores, ~1 s on 16).
    Jaw,
    /// Jaw scans in mm, the query benchmark's trees: 0.15 mm voxels, 0.05 mm minimum radius,
    /// 8 refinement steps (~1.6 s and 0.18 GB per arch on 2 cores, 1.8× faster than jaw; p95
    /// error 0.046 mm on the molars).
    JawFast,
}

impl From<PresetArg> for Preset {
    fn from(p: PresetArg) -> Preset {
        match p {
            PresetArg::Fast => Preset::Fast,
            PresetArg::Default => Preset::Default,
            PresetArg::Fine => Preset::Fine,
            PresetArg::Jaw => Preset::Jaw,
            PresetArg::JawFast => Preset::JawFast,
        }
    }
}

/// Build options shared by every subcommand that builds trees. Each is optional so that an
/// explicit flag can override a preset's field; the defaults are [`BuildOptions::default`]'s.
#[derive(clap::Args, Clone)]
pub struct BuildArgs {
    /// Voxel edge length, in model units (the mesh file's own unit: mm for the jaw scans).
    #[arg(long, conflicts_with = "resolution")]
    pub voxel_size: Option<f64>,
    /// Cells along the longest side of the bounding box [default: 128].
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Smallest inner-sphere radius to place, in model units (mm for the jaw scans)
    /// [default: 0 = down to 1e-4 voxel].
    #[arg(long)]
    pub min_radius: Option<f64>,
    /// Stop after this many inner spheres [default: no limit].
    #[arg(long)]
    pub max_spheres: Option<usize>,
    /// Off-grid refinement steps per sphere [default: 0 = centres on voxel centres, as in
    /// the paper].
    #[arg(long)]
    pub refine_steps: Option<u32>,
    /// Children per inner node [default: 4].
    #[arg(long)]
    pub fanout: Option<u32>,
}

impl BuildArgs {
    /// The library's options from the command line, on top of the defaults.
    pub fn options(&self) -> BuildOptions {
        self.apply(BuildOptions::default())
    }

    /// `base` with every field given on the command line replaced.
    pub fn apply(&self, base: BuildOptions) -> BuildOptions {
        let mut o = base;
        if let Some(h) = self.voxel_size {
            o.resolution = Resolution::VoxelSize(h);
        } else if let Some(n) = self.resolution {
            o.resolution = Resolution::Cells(n);
        }
        if let Some(r) = self.min_radius {
            o.packing.min_radius = r;
        }
        if let Some(n) = self.max_spheres {
            o.packing.max_spheres = n;
        }
        if let Some(n) = self.refine_steps {
            o.packing.refine_steps = n;
        }
        if let Some(f) = self.fanout {
            o.hierarchy.fanout = f;
        }
        o
    }
}

/// Runs the subcommand; returns the process exit code.
pub fn run(args: Args) -> anyhow::Result<i32> {
    let t0 = Instant::now();
    // Bad flags and an output that would overwrite the mesh fail before a large mesh is
    // loaded.
    innersphere::build::validate_options(&args.opts.options())?;
    crate::files::check_outputs(&[(&args.output, crate::files::TREE_FILE)], &[&args.mesh])?;
    let bars = Bars::new(args.quiet);
    let mesh = crate::files::load_mesh(&args.mesh, args.unit.unit)?;
    if args.preset.is_some_and(|p| Preset::from(p).is_dental()) {
        crate::files::warn_unit(&args.mesh, &mesh, args.unit.unit);
    }
    let t_load = t0.elapsed().as_secs_f64();
    let opts = match args.preset {
        Some(p) => args.opts.apply(
            BuildOptions::preset(p.into(), &mesh)
                .with_context(|| format!("{}", args.mesh.display()))?,
        ),
        None => args.opts.options(),
    };
    innersphere::build::validate_options(&opts)?;
    let (mut tree, report) = SphereTree::build_with_progress(&mesh, &opts, &bars)
        .with_context(|| format!("building the tree of {}", args.mesh.display()))?;
    tree.meta.source = Some(innersphere::tree::MeshSource::of_unit(
        &args.mesh,
        &mesh,
        args.unit.unit,
    ));
    let t1 = Instant::now();
    // Through a temporary file renamed into place: a failed write leaves no partial tree.
    let bytes = innersphere::tree::file::to_bytes(&tree);
    innersphere::output::write_atomic(&args.output, |w| w.write_all(&bytes))
        .context("writing the tree")?;
    let t_write = t1.elapsed().as_secs_f64();
    let total = t0.elapsed().as_secs_f64();
    let preset = args.preset.map(|p| Preset::from(p).name());
    let voxel_option = match opts.resolution {
        Resolution::VoxelSize(h) => json!({ "voxel_size": h }),
        Resolution::Cells(n) => json!({ "resolution": n }),
    };
    if args.json {
        let mut v = serde_json::to_value(&report)?;
        v["seconds"] = total.into();
        v["build_seconds"] = report.seconds.into();
        v["stage_seconds"]["load"] = t_load.into();
        v["stage_seconds"]["write"] = t_write.into();
        v["output"] = args.output.display().to_string().into();
        let mut o = json!({
            "preset": preset,
            "min_radius": opts.packing.min_radius,
            "refine_steps": opts.packing.refine_steps,
            "max_spheres": (opts.packing.max_spheres != usize::MAX).then_some(opts.packing.max_spheres),
            "fanout": opts.hierarchy.fanout,
        });
        for (k, val) in voxel_option.as_object().into_iter().flatten() {
            o[k] = val.clone();
        }
        v["options"] = o;
        crate::print::print_json(&v)?;
    } else {
        for w in &report.warnings {
            eprintln!("warning: {w}");
        }
        let s = &report.stage_seconds;
        println!("{} -> {}", args.mesh.display(), args.output.display());
        println!("  units       {}", crate::print::UNITS);
        println!(
            "  options     {}{}, min radius {} units, {} refinement steps, fan-out {}{}",
            preset.map(|p| format!("preset {p}: ")).unwrap_or_default(),
            match opts.resolution {
                Resolution::VoxelSize(h) => format!("voxel size {} units", crate::print::short(h)),
                Resolution::Cells(n) => format!("{n} cells along the longest side"),
            },
            crate::print::short(opts.packing.min_radius),
            opts.packing.refine_steps,
            opts.hierarchy.fanout,
            if opts.packing.max_spheres == usize::MAX {
                String::new()
            } else {
                format!(", at most {} spheres", opts.packing.max_spheres)
            }
        );
        println!(
            "  mesh        {} vertices, {} triangles, volume {:.6} units³",
            report.mesh.vertices, report.mesh.triangles, report.mesh_volume
        );
        println!(
            "  grid        {} x {} x {} cells of {:.6} units, {} inside",
            report.grid_dims[0],
            report.grid_dims[1],
            report.grid_dims[2],
            report.voxel_size,
            report.voxels_inside
        );
        println!(
            "  spheres     {} (radius {:.6} .. {:.6} units), coverage {:.3} of the {}",
            report.spheres,
            report.min_sphere_radius,
            report.max_sphere_radius,
            report.coverage,
            if report.coverage_basis == "mesh_volume" {
                "mesh volume"
            } else {
                "inside-voxel volume (open mesh)"
            }
        );
        println!(
            "  tree        {} nodes, depth {}, fan-out {}, enclosing ratio {:.4}",
            report.nodes, report.depth, report.fanout, report.enclosing_ratio_mean
        );
        println!(
            "  seconds     {total:.2} total: load {t_load:.2}, prepare {:.2}, distance field {:.2}, packing {:.2}, hierarchy {:.2}, tree {:.2}, write {t_write:.2}",
            s.prepare, s.distance_field, s.packing, s.hierarchy, s.tree
        );
    }
    Ok(0)
}
