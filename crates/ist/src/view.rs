//! `ist view`: the live 3D view in the browser (the innersphere-view crate's server).

use anyhow::Context;
use innersphere::SharedTree;
use innersphere_dental::contact_map::Teeth;
use innersphere_eval::motion::Motion;
use innersphere_haptic::ContactSource;
use innersphere_view::{serve, Scene, ServeOptions};
use std::path::PathBuf;

/// Arguments of `ist view`.
#[derive(clap::Args)]
pub struct Args {
    /// Tree file of body A (fixed, at the identity pose), or its mesh (built with --preset,
    /// cached, and drawn); with B, or --demo.
    a: Option<PathBuf>,
    /// Tree file or mesh of body B (moved).
    b: Option<PathBuf>,
    /// How a mesh given for A or B becomes its tree.
    #[command(flatten)]
    body: crate::bodies::BodyArgs,
    /// Body A's mesh, to draw its surface (without meshes the inner spheres are the picture).
    #[arg(long)]
    mesh_a: Option<PathBuf>,
    /// Body B's mesh.
    #[arg(long)]
    mesh_b: Option<PathBuf>,
    /// A motion of B in A's frame to play (CSV t,tx,ty,tz,qw,qx,qy,qz).
    #[arg(long)]
    motion: Option<PathBuf>,
    /// Port on 127.0.0.1 (0: any free one).
    #[arg(long, default_value_t = 8000)]
    port: u16,
    /// Start the system's browser on the page.
    #[arg(long)]
    open: bool,
    /// Penetration force per unit volume (force unit per model unit³; 1 = ist query's).
    #[arg(long, default_value_t = 1.0)]
    stiffness: f64,
    /// Where the readout's volume, depth, force and patches and the haptic mode's contact
    /// come from: `spheres` (the packings') or `mesh` (the meshes' own exact intersection,
    /// milliseconds a query in deep contact: the loop slows there; needs --mesh-a and
    /// --mesh-b, the trees' own meshes).
    #[arg(long, default_value = "spheres", value_parser = parse_contact)]
    contact: ContactSource,
    /// The built-in scene instead of files: the generated tooth pair with a chewing motion.
    #[arg(long)]
    demo: bool,
    /// Start in contact-map mode: both meshes coloured by their gap to each other (needs
    /// both meshes; the page's "contact map" checkbox turns it on and off).
    #[arg(long)]
    contact_map: bool,
    /// Teeth of A for the contact map's per-tooth list: a teeth-axes JSON (`{"3": {"c":
    /// [x, y, z], ...}, ...}`, A's mesh frame); each vertex belongs to the nearest crown
    /// centre within 10 mm.
    #[arg(long)]
    teeth_a: Option<PathBuf>,
    /// Teeth of B (B's mesh frame).
    #[arg(long)]
    teeth_b: Option<PathBuf>,
    /// A splint to draw between the arches (an STL from `ist splint`, in A's frame); start
    /// B at the splint's pose (`--pose-b`, the `pose` of its JSON) to see it seated.
    #[arg(long)]
    splint: Option<PathBuf>,
    /// Where B starts, "tx ty tz qw qx qy qz" in A's frame (default: where the motion
    /// starts, else beside A).
    #[arg(long, allow_hyphen_values = true)]
    pose_b: Option<String>,
}

fn parse_contact(s: &str) -> Result<ContactSource, String> {
    s.parse().map_err(|e: innersphere::Error| e.to_string())
}

/// Runs the subcommand; returns the process exit code (it serves until interrupted).
pub fn run(args: Args) -> anyhow::Result<i32> {
    let teeth = |p: &Option<PathBuf>, flag: &str| -> anyhow::Result<Option<Teeth>> {
        p.as_deref()
            .map(|p| {
                Teeth::load_in(p, args.body.unit.unit).with_context(|| format!("loading {flag}"))
            })
            .transpose()
    };
    let (teeth_a, teeth_b) = (
        teeth(&args.teeth_a, "--teeth-a")?,
        teeth(&args.teeth_b, "--teeth-b")?,
    );
    let scene = if args.demo {
        if args.a.is_some() || args.b.is_some() {
            anyhow::bail!("--demo takes no tree files");
        }
        Scene::demo()?
    } else {
        scene_from_files(&args)?
    };
    let meshes = scene.mesh_a.is_some() && scene.mesh_b.is_some();
    // The distance shown: between the meshes where they are the trees' own.
    let (mut scene, why) = if args.demo {
        (scene, None)
    } else {
        scene.refining_with_meshes()
    };
    match why {
        None => eprintln!("distance: between the meshes (refined from the spheres)"),
        Some(why) => eprintln!("warning: {why}"),
    }
    if !meshes && (args.contact_map || teeth_a.is_some() || teeth_b.is_some()) {
        anyhow::bail!(
            "--contact-map, --teeth-a and --teeth-b need both meshes (--mesh-a and --mesh-b)"
        );
    }
    scene.teeth_a = teeth_a;
    scene.teeth_b = teeth_b;
    scene.splint = args
        .splint
        .as_ref()
        .map(|p| crate::files::load_mesh(p, args.body.unit.unit).context("loading --splint"))
        .transpose()?;
    scene.start = args
        .pose_b
        .as_ref()
        .map(|t| {
            t.parse::<innersphere::Pose>()
                .with_context(|| format!("--pose-b \"{t}\""))
        })
        .transpose()?;
    for w in scene.check_teeth()? {
        eprintln!("warning: {w}");
    }
    let opts = ServeOptions {
        port: args.port,
        stiffness: args.stiffness,
        contact_map: args.contact_map,
        contact: args.contact,
        ..ServeOptions::default()
    };
    let open = args.open;
    serve(scene, opts, move |addr| {
        let url = format!("http://{addr}/");
        println!("ist view: serving on {url} (127.0.0.1 only; Ctrl-C to stop)");
        use std::io::Write as _;
        let _ = std::io::stdout().flush();
        if open {
            let opener = if cfg!(target_os = "macos") {
                "open"
            } else {
                "xdg-open"
            };
            if let Err(e) = std::process::Command::new(opener).arg(&url).spawn() {
                eprintln!(
                    "warning: could not start a browser ({opener}: {e}); open {url} yourself"
                );
            }
        }
    })
    .map_err(|e| anyhow::anyhow!(e))?;
    Ok(0)
}

/// The scene of two bodies given as files: their trees (built from meshes through the cache
/// where a body is a mesh), the surfaces to draw (`--mesh-a/-b`, the body's own mesh, or
/// the mesh its tree was built from while it still holds it) and the motion.
fn scene_from_files(args: &Args) -> anyhow::Result<Scene> {
    let (Some(a), Some(b)) = (&args.a, &args.b) else {
        anyhow::bail!("give two tree files (A.ist B.ist), or --demo for the built-in scene");
    };
    let mesh = |p: &Option<PathBuf>, which: &str| -> anyhow::Result<_> {
        p.as_ref()
            .map(|p| {
                crate::files::load_mesh(p, args.body.unit.unit)
                    .with_context(|| format!("loading {which}"))
            })
            .transpose()
    };
    // A body given as a mesh is also its drawn surface (unless --mesh-a/-b say otherwise).
    // A tree built from a file draws that file's mesh while it still holds it.
    let (tree_a, body_a) = crate::bodies::load_body(a, &args.body)?;
    let (tree_b, body_b) = crate::bodies::load_body(b, &args.body)?;
    let remembered = |tree: &innersphere::SphereTree, which: &str, flag: &str| {
        let source = tree.meta.source.as_ref()?;
        match source.load() {
            Ok(m) => {
                eprintln!(
                    "{which}: drawing {} (the mesh its tree was built from)",
                    source.path
                );
                Some(m)
            }
            Err(e) => {
                eprintln!("{which}: not drawing its surface ({e}); give {flag}");
                None
            }
        }
    };
    let mesh_a = match (mesh(&args.mesh_a, "--mesh-a")?, body_a) {
        (Some(m), _) | (None, Some(m)) => Some(m),
        (None, None) => remembered(&tree_a, "A", "--mesh-a"),
    };
    let mesh_b = match (mesh(&args.mesh_b, "--mesh-b")?, body_b) {
        (Some(m), _) | (None, Some(m)) => Some(m),
        (None, None) => remembered(&tree_b, "B", "--mesh-b"),
    };
    Ok(Scene {
        a: SharedTree::new(tree_a),
        b: SharedTree::new(tree_b),
        mesh_a,
        mesh_b,
        motion: args
            .motion
            .as_ref()
            .map(|p| Motion::load(p).context("loading --motion"))
            .transpose()?,
        teeth_a: None,
        teeth_b: None,
        splint: None,
        start: None,
    })
}
