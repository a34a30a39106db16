//! Runs a [`Case`]: the arches read in their unit, their trees built (through the build
//! cache when one is given), the bite found, the contact map at the bite, each wafer made at
//! its opening. [`Plan`] is the answer every door prints; [`Planned`] carries the meshes
//! and maps beside it for [`write`](super::write).

use super::schema::{BiteMethod, Case, DEFAULT_START_OPENING};
use crate::anatomy::AnatomicalFrame;
use crate::contact_map::{
    arch_regions, check_pair, summarise, ArchRegion, Balance, ContactMap, RegionSummary, Teeth,
};
use crate::occlusion_status::OcclusionStatus;
use crate::splint::{self, Splint, SplintReport};
use innersphere::build::{BuildCache, BuildOptions};
use innersphere::error::{Error, Result};
use innersphere::exact::ExactMesh;
use innersphere::mesh::{Mesh, Unit};
use innersphere::pose::Pose;
use innersphere::progress::Progress;
use innersphere::query::SharedTree;
use innersphere::tree::SphereTree;
use innersphere_haptic::ContactSource;
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

/// An input file as the plan read it: its role, its name (without the folder: a report
/// moved to another machine says the same) and the BLAKE3 hash of its bytes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct InputFile {
    /// `upper`, `lower`, `teeth_upper` or `teeth_lower`.
    pub role: &'static str,
    /// The file's name.
    pub file: String,
    /// Its size in bytes.
    pub bytes: u64,
    /// BLAKE3 of its bytes, hex.
    pub blake3: String,
}

/// The bite the plan rests on.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanBite {
    /// How it was found.
    pub method: BiteMethod,
    /// B (the lower arch) in A's frame, `[tx, ty, tz, qw, qx, qy, qz]` (mm).
    pub pose: [f64; 7],
    /// How the closing ended (`converged` for a given pose).
    pub status: OcclusionStatus,
    /// Where B started, same form (`null` for a given pose).
    pub from: Option<[f64; 7]>,
    /// The contact the closing used.
    pub contact: &'static str,
    /// The overlap of the arches' packings at the rest (mm³; 0 for a given pose).
    pub volume: f64,
    /// Free: the distinct rest poses found (0 otherwise).
    pub candidates: usize,
}

/// One arch's side of the contact map.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ArchMap {
    /// The PLY written (`upper_map.ply`, `lower_map.ply`).
    pub file: &'static str,
    /// Its vertices.
    pub vertices: usize,
    /// The smallest signed gap (mm; negative inside the other arch).
    pub min_gap: f64,
    /// Vertices inside the other arch.
    pub vertices_inside: usize,
    /// Per tooth, when a teeth file was given.
    pub teeth: Option<Vec<RegionSummary>>,
    /// Per region of the arch ([`ARCH_REGIONS`](crate::contact_map::ARCH_REGIONS)).
    pub regions: Vec<ArchRegion>,
    /// Left against right.
    pub balance: Balance,
}

/// The contact map at the bite.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanMap {
    /// The upper arch (A): its gaps to the lower.
    pub upper: ArchMap,
    /// The lower arch (B) at the bite: its gaps to the upper.
    pub lower: ArchMap,
}

/// One wafer.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PlanSplint {
    /// Its name.
    pub name: String,
    /// The STL written (`NAME.stl`), `null` when it is not fit to print (it is not written).
    pub file: Option<String>,
    /// Its measurements and guarantees ([`SplintReport`]; its times are in [`Plan::seconds`]
    /// and zero here, so that the plan is the same, run after run); `null` when it could not
    /// be made.
    pub report: Option<SplintReport>,
    /// Why it could not be made (the arches leave no room for it, ...); `null` when made.
    pub error: Option<String>,
}

impl PlanSplint {
    /// Made, and every guarantee kept.
    pub fn fit(&self) -> bool {
        self.report.as_ref().is_some_and(|r| r.fit)
    }
}

/// Wall-clock seconds of each step (the one part of a plan that differs between runs).
#[derive(Debug, Clone, PartialEq, Serialize, Default)]
pub struct PlanSeconds {
    /// Reading the meshes and building (or reading) the trees.
    pub prepare: f64,
    /// The bite.
    pub bite: f64,
    /// The contact map.
    pub map: f64,
    /// Each wafer, in order.
    pub splints: Vec<f64>,
    /// All of it.
    pub total: f64,
}

/// What a case gave: the answer of `ist plan --json`, of Python's `plan` and of the page.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Plan {
    /// The case file version it read.
    pub case_version: u32,
    /// The library's version.
    pub library: &'static str,
    /// The unit the scans were read in (everything here is in mm).
    pub unit: Unit,
    /// The build preset of the trees.
    pub preset: &'static str,
    /// The inputs, hashed.
    pub inputs: Vec<InputFile>,
    /// The bite.
    pub bite: PlanBite,
    /// The contact map (`null` when the case turns it off).
    pub map: Option<PlanMap>,
    /// The wafers, in the case's order.
    pub splints: Vec<PlanSplint>,
    /// Every wafer is fit to print.
    pub fit: bool,
    /// Timings.
    pub seconds: PlanSeconds,
}

/// A [`Plan`] and what [`write`](super::write) needs to write its files.
#[derive(Debug, Clone)]
pub struct Planned {
    /// The answer.
    pub plan: Plan,
    /// The case as run (paths as given to [`run`]).
    pub case: Case,
    /// The upper arch, mm.
    pub upper: Mesh,
    /// The lower arch, mm, in its own frame (the bite pose places it).
    pub lower: Mesh,
    /// The pair's anatomical frame at the bite.
    pub frame: AnatomicalFrame,
    /// The contact map's gaps, when made.
    pub map: Option<ContactMap>,
    /// The wafers, in the case's order (`None` where one could not be made).
    pub splints: Vec<Option<Splint>>,
}

/// Where the trees come from: the build cache (a folder), or built afresh.
#[derive(Debug, Clone, Default)]
pub struct PlanEnv {
    /// The build cache; `None` builds without one.
    pub cache: Option<BuildCache>,
}

/// The hash of a file's bytes, streamed.
fn hash_file(role: &'static str, path: &Path) -> Result<InputFile> {
    let mut h = blake3::Hasher::new();
    let file = std::fs::File::open(path)
        .map_err(|e| Error::InvalidOption(format!("{}: {e}", path.display())))?;
    h.update_reader(file)
        .map_err(|e| Error::InvalidOption(format!("{}: {e}", path.display())))?;
    let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
    Ok(InputFile {
        role,
        file: path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        bytes,
        blake3: h.finalize().to_hex().to_string(),
    })
}

/// Runs `case` (its paths resolved, [`Case::load`]): see the module docs. Stages are
/// reported to `progress` (`build upper`, `build lower`, `bite`, `contact map`, `wafer
/// NAME`). Fails with the step named: an input that cannot be read or does not fit (a
/// teeth file of the other arch), a bite that does not converge (no wafer is made on a
/// bite that is not one). A wafer the arches cannot make is in the plan with its `error`;
/// one made that fails a guarantee with its report's `fit` false; neither has a file.
pub fn run(case: &Case, env: &PlanEnv, progress: &dyn Progress) -> Result<Planned> {
    case.check()?;
    let t0 = Instant::now();
    let mut seconds = PlanSeconds::default();
    let named = |what: &str, e: Error| Error::InvalidOption(format!("{what}: {e}"));
    let mut inputs = vec![
        hash_file("upper", &case.upper)?,
        hash_file("lower", &case.lower)?,
    ];
    let load_teeth = |role: &'static str, p: &Option<std::path::PathBuf>| -> Result<_> {
        p.as_deref()
            .map(|p| {
                Ok::<_, Error>((
                    hash_file(role, p)?,
                    Teeth::load_in(p, case.unit).map_err(|e| named(role, e))?,
                ))
            })
            .transpose()
    };
    let teeth_upper = load_teeth("teeth_upper", &case.teeth_upper)?;
    let teeth_lower = load_teeth("teeth_lower", &case.teeth_lower)?;
    inputs.extend(teeth_upper.iter().chain(&teeth_lower).map(|t| t.0.clone()));
    let upper = Mesh::load_in(&case.upper, case.unit).map_err(|e| named("upper", e))?;
    let lower = Mesh::load_in(&case.lower, case.unit).map_err(|e| named("lower", e))?;
    let build = |mesh: &Mesh, role: &str| -> Result<SphereTree> {
        let opts = BuildOptions::preset(case.preset, mesh).map_err(|e| named(role, e))?;
        let built = match &env.cache {
            Some(cache) => cache.get_or_build(mesh, &opts, progress).map(|r| r.0),
            None => SphereTree::build_with_progress(mesh, &opts, progress).map(|r| r.0),
        };
        built.map_err(|e| named(role, e))
    };
    let (mut a, mut b) = (
        SharedTree::new(build(&upper, "upper")?),
        SharedTree::new(build(&lower, "lower")?),
    );
    if case.bite.contact == ContactSource::Mesh {
        a = a.with_mesh(&upper)?;
        b = b.with_mesh(&lower)?;
    }
    seconds.prepare = t0.elapsed().as_secs_f64();

    let t1 = Instant::now();
    progress.start("bite", 1);
    let bite = find_bite(case, &a, &b)?;
    progress.finish();
    seconds.bite = t1.elapsed().as_secs_f64();
    let pose = Pose::from_array(bite.pose)
        .map_err(|e| Error::InvalidOption(format!("the bite pose: {e}")))?;
    let lower_at: Vec<_> = lower
        .vertices
        .iter()
        .map(|v| pose.transform_point(*v))
        .collect();
    let frame = AnatomicalFrame::from_points(&upper.vertices, &lower_at)?;

    let t2 = Instant::now();
    let (map, map_answer) = if case.contact_map {
        progress.start("contact map", 1);
        let (fit_a, fit_b) = check_pair(
            &upper,
            teeth_upper.as_ref().map(|t| &t.1),
            &lower,
            teeth_lower.as_ref().map(|t| &t.1),
            &pose,
        )?;
        let (ea, eb) = (ExactMesh::new(&upper)?, ExactMesh::new(&lower)?);
        let map = ContactMap::new(&ea, &Pose::IDENTITY, &eb, &pose, f64::INFINITY)?;
        let lower_placed = Mesh {
            vertices: lower_at.clone(),
            triangles: lower.triangles.clone(),
        };
        let side = |file, mesh: &Mesh, gaps: &[f64], teeth: Option<(&Teeth, &[u32])>| ArchMap {
            file,
            vertices: gaps.len(),
            min_gap: gaps.iter().copied().fold(f64::INFINITY, f64::min),
            vertices_inside: gaps.iter().filter(|&&g| g < 0.0).count(),
            teeth: teeth.map(|(t, r)| summarise(mesh, gaps, t, r)),
            regions: arch_regions(&frame, mesh, gaps),
            balance: Balance::of(&frame, mesh, gaps),
        };
        let answer = PlanMap {
            upper: side(
                UPPER_MAP,
                &upper,
                &map.gaps_a,
                teeth_upper
                    .as_ref()
                    .zip(fit_a.as_ref())
                    .map(|(t, f)| (&t.1, f.regions.as_slice())),
            ),
            // The lower arch's regions are read at the bite (its teeth file is in its own
            // frame: its regions were found there).
            lower: side(
                LOWER_MAP,
                &lower_placed,
                &map.gaps_b,
                teeth_lower
                    .as_ref()
                    .zip(fit_b.as_ref())
                    .map(|(t, f)| (&t.1, f.regions.as_slice())),
            ),
        };
        progress.finish();
        (Some(map), Some(answer))
    } else {
        (None, None)
    };
    seconds.map = t2.elapsed().as_secs_f64();

    let mut splints = vec![];
    let mut answers = vec![];
    for spec in &case.splints {
        let name = spec.name.as_str();
        let t = Instant::now();
        progress.start(&format!("wafer {name}"), 1);
        // A wafer the arches cannot make is one failed wafer of the plan, not a failed plan:
        // the map and the other wafers are still made, and the report says why.
        let made = splint::make_opened(&upper, &lower, &pose, spec.open.opening(), &spec.options());
        progress.finish();
        seconds.splints.push(t.elapsed().as_secs_f64());
        match made {
            Ok(mut s) => {
                s.report.seconds = 0.0;
                s.report.stage_seconds = [0.0; 5];
                answers.push(PlanSplint {
                    name: name.to_string(),
                    file: s.report.fit.then(|| format!("{name}.stl")),
                    report: Some(s.report.clone()),
                    error: None,
                });
                splints.push(Some(s));
            }
            Err(e) => {
                answers.push(PlanSplint {
                    name: name.to_string(),
                    file: None,
                    report: None,
                    error: Some(e.to_string()),
                });
                splints.push(None);
            }
        }
    }
    seconds.total = t0.elapsed().as_secs_f64();
    let plan = Plan {
        case_version: case.version,
        library: env!("CARGO_PKG_VERSION"),
        unit: case.unit,
        preset: case.preset.name(),
        inputs,
        bite,
        map: map_answer,
        fit: answers.iter().all(PlanSplint::fit),
        splints: answers,
        seconds,
    };
    Ok(Planned {
        plan,
        case: case.clone(),
        upper,
        lower,
        frame,
        map,
        splints,
    })
}

/// The contact map's file of the upper arch.
pub const UPPER_MAP: &str = "upper_map.ply";
/// The contact map's file of the lower arch (at the bite, in the upper's frame).
pub const LOWER_MAP: &str = "lower_map.ply";

/// The bite of `case` on trees `a`, `b`: given, or closed ([`bite`](crate::bite::bite)) from the
/// case's start or the scanned pose opened [`DEFAULT_START_OPENING`] along the pair's up.
/// A closing that does not converge is an error naming how it ended.
fn find_bite(case: &Case, a: &SharedTree, b: &SharedTree) -> Result<PlanBite> {
    let (from, given) = case.poses()?;
    let contact = match case.bite.contact {
        ContactSource::Spheres => "spheres",
        ContactSource::Mesh => "mesh",
    };
    if let Some(pose) = given {
        return Ok(PlanBite {
            method: BiteMethod::Pose,
            pose: pose.to_array(),
            status: OcclusionStatus::Converged,
            from: None,
            contact,
            volume: 0.0,
            candidates: 0,
        });
    }
    let from = match from {
        Some(p) => p,
        None => {
            let frame = crate::bite::frame_of(a.tree(), b.tree())?;
            Pose::from_translation(-frame.up * (DEFAULT_START_OPENING * frame.scale))
        }
    };
    let opts = crate::bite::BiteOptions {
        free: case.bite.method == BiteMethod::Free,
        starts: case.bite.starts,
        seed: case.bite.seed,
        contact: case.bite.contact,
        ..crate::bite::BiteOptions::default()
    };
    let found = crate::bite::bite(a, b, &from, &opts)?;
    let o = &found.occlusion;
    if !o.converged() {
        return Err(Error::InvalidOption(format!(
            "the bite did not converge (status {:?}): no wafer is made on a pose that is not a bite; give the bite's start (\"from\") or its pose",
            o.status
        )));
    }
    Ok(PlanBite {
        method: case.bite.method,
        pose: o.pose.to_array(),
        status: o.status,
        from: Some(from.to_array()),
        contact,
        volume: o.volume,
        candidates: found.candidates.len(),
    })
}
