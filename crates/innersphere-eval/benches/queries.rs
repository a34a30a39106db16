//! Queries between the real jaw trees along several motions, per query kind and phase.
//!
//! `cargo bench -p innersphere-eval --bench queries`
//!
//! Builds (once, cached under `target/bench-trees/`) the trees of the maxilla (A) and the
//! mandible (B) at `Resolution::VoxelSize(0.15)`, and replays, pose of B in A's frame with A at
//! the identity, the shared `motion/jaw_chew_demo.csv` and three generated motions of the
//! pair (`chew`, `grind`, `open-close`: `innersphere_eval::motion::generate`, the same as `ist
//! motion --scenario S --seed 1 --seconds 3`; saved beside the cached trees for `ist replay`).
//! Every frame of every query kind is timed with `Instant` (criterion's per-iteration model
//! does not fit a stateful motion), single thread.
//!
//! Timing rule: each query runs `QUERY_BENCH_PASSES` (N, default 2) passes over a motion, the
//! first from a fresh `Pair`, the others after `Pair::reset`. The first pass is what
//! a haptic loop sees — every frame once, in motion order, the state carried frame to frame,
//! no warm-up — and gives the headline columns "(1 pass)": median, p99, max, frames over 1 ms.
//! Each frame's fastest of the N passes ("best-of-N": filters the stalls of a shared or
//! virtual machine, which a haptic loop would still suffer) is printed beside them only. Rows
//! per phase (labels of the motion: `jaw_chew_demo.phases.csv` labels every 5th frame and the
//! frames in between take the label of the frame before; generated motions label every
//! frame), and at the end one markdown table of every query on every motion; with the
//! default penetration query, a table of its output-sensitive floor (per frame in contact,
//! the overlapping leaf pairs summed alone with `Pair::penetration_of_leaves`, the same N
//! passes; query / floor is the search's overhead).
//!
//! Environment: `QUERY_BENCH_TREES` (cache folder), `QUERY_BENCH_VOXEL` (voxel size, default
//! 0.15), `QUERY_BENCH_MIN_RADIUS` and `QUERY_BENCH_REFINE` (packing options, default 0),
//! `QUERY_BENCH_REBUILD=1` (rebuild cached trees), `QUERY_BENCH_MOTIONS` (comma-separated
//! subset of `demo,chew,grind,open-close,far`, default the first four; `far`: B from 100 to
//! 10³⁰⁰ units away, see `far_motion`), `QUERY_BENCH_SECONDS` and
//! `QUERY_BENCH_SEED` (length and seed of the generated motions, default 3 s and 1),
//! `QUERY_BENCH_MAX_FRAMES` (only the first N frames of each motion), `QUERY_BENCH_MOTION` /
//! `QUERY_BENCH_PHASES` (one motion file and its labels instead, e.g. from `ist motion
//! --labels`; the labels default to the motion's name with `.phases.csv` for `.csv`),
//! `QUERY_BENCH_PASSES` (N), `QUERY_BENCH_ONLY` (comma-separated substrings of query names to
//! run; `headline`: the four of the quick mode), `QUERY_BENCH_AGG=max` (beside the single
//! pass, per frame the worst instead of the best of the N passes), `QUERY_BENCH_FRAMES=FILE`
//! (also write every frame's times, visits and contact as CSV), `INNERSPHERE_DATA` (data
//! folder).
//! `QUERY_BENCH_QUICK=1` is a check mode that finishes in a few minutes: unless set
//! otherwise, voxel 0.5, 1 s generated motions, the first 1000 frames of the demo motion, and
//! only the four headline queries (exact proximity, kinetic-front contact, multipoint k = 16,
//! penetration). Skips with a message when the data is missing.

use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::query::TraversalOptions;
use innersphere::tree::file;
use innersphere::SphereTree;
use innersphere::{
    DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose, SharedTree, Tracking,
};
use innersphere_eval::motion::{generate_with, GenerateOptions, Motion, Scenario};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn data_dir() -> PathBuf {
    std::env::var_os("INNERSPHERE_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

fn cache_dir() -> PathBuf {
    std::env::var_os("QUERY_BENCH_TREES")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../target/bench-trees")
        })
}

/// Build options of the benchmark trees: voxel size `h`, and the minimum radius and
/// off-grid refinement steps from `QUERY_BENCH_MIN_RADIUS` / `QUERY_BENCH_REFINE`.
fn options(h: f64) -> (BuildOptions, String) {
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<f64>().ok());
    let mr = env("QUERY_BENCH_MIN_RADIUS").unwrap_or(0.0);
    let rs = env("QUERY_BENCH_REFINE").unwrap_or(0.0) as u32;
    let mut o = BuildOptions {
        resolution: Resolution::VoxelSize(h),
        ..Default::default()
    };
    o.packing.min_radius = mr;
    o.packing.refine_steps = rs;
    let tag = if mr > 0.0 || rs > 0 {
        format!("{h}_m{mr}_r{rs}")
    } else {
        format!("{h}")
    };
    (o, tag)
}

/// The tree of `mesh` at voxel size `h`, from the cache or built and cached.
fn tree(mesh: &Path, name: &str, h: f64) -> SphereTree {
    let dir = cache_dir();
    std::fs::create_dir_all(&dir).unwrap();
    let (opts, tag) = options(h);
    let path = dir.join(format!("{name}_{tag}.ist"));
    if path.is_file() && std::env::var_os("QUERY_BENCH_REBUILD").is_none() {
        if let Ok(t) = file::load(&path) {
            return t;
        }
    }
    eprintln!(
        "building the tree of {} at voxel size {h} ...",
        mesh.display()
    );
    let t0 = Instant::now();
    let m = innersphere::mesh::io::load(mesh).unwrap();
    let (t, _) = build_tree(&m, &opts, &innersphere::progress::Silent).unwrap();
    file::save(&t, &path).unwrap();
    eprintln!(
        "  built in {:.1?}, cached at {}",
        t0.elapsed(),
        path.display()
    );
    t
}

/// Phase label of every frame from a labels CSV (`frame,t,clearance,phase,...`).
fn read_phases(path: &Path, frames: usize) -> Vec<String> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let mut marks: Vec<(usize, String)> = text
        .lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            Some((f.first()?.parse().ok()?, f.get(3)?.to_string()))
        })
        .collect();
    marks.sort();
    let mut out = Vec::with_capacity(frames);
    let mut m = 0;
    for i in 0..frames {
        while m + 1 < marks.len() && marks[m + 1].0 <= i {
            m += 1;
        }
        out.push(marks.get(m).map_or("all".to_string(), |x| x.1.clone()));
    }
    out
}

/// A motion to replay: its name, poses and the phase of every frame.
struct BenchMotion {
    name: String,
    poses: Vec<Pose>,
    phases: Vec<String>,
}

fn env_f64(k: &str) -> Option<f64> {
    std::env::var(k).ok().and_then(|s| s.trim().parse().ok())
}

/// The motions of the run (see the module docs).
fn motions(dir: &Path, fa: &Path, fb: &Path, quick: bool) -> Vec<BenchMotion> {
    let max_frames = env_f64("QUERY_BENCH_MAX_FRAMES")
        .map(|x| x as usize)
        .or(quick.then_some(1000))
        .unwrap_or(usize::MAX);
    let from_file = |name: String, motion: &Path, phases: &Path| {
        let m = Motion::load(motion).unwrap_or_else(|e| panic!("{}: {e}", motion.display()));
        let mut poses: Vec<Pose> = m.poses().collect();
        poses.truncate(max_frames);
        let phases = read_phases(phases, poses.len());
        BenchMotion {
            name,
            poses,
            phases,
        }
    };
    if let Some(m) = std::env::var_os("QUERY_BENCH_MOTION").map(PathBuf::from) {
        let ph = std::env::var_os("QUERY_BENCH_PHASES").map_or_else(
            || {
                let s = m.to_string_lossy();
                PathBuf::from(format!(
                    "{}.phases.csv",
                    s.strip_suffix(".csv").unwrap_or(&s)
                ))
            },
            PathBuf::from,
        );
        let name = m
            .file_stem()
            .map_or("motion".into(), |s| s.to_string_lossy().into_owned());
        return vec![from_file(name, &m, &ph)];
    }
    let names: Vec<String> = std::env::var("QUERY_BENCH_MOTIONS")
        .map(|s| s.split(',').map(|x| x.trim().to_string()).collect())
        .unwrap_or_else(|_| {
            ["demo", "chew", "grind", "open-close"]
                .map(String::from)
                .to_vec()
        });
    let seconds = env_f64("QUERY_BENCH_SECONDS").unwrap_or(if quick { 1.0 } else { 3.0 });
    let seed = env_f64("QUERY_BENCH_SEED").unwrap_or(1.0) as u64;
    let mut meshes = None;
    let mut out = Vec::new();
    for name in names {
        if name == "far" {
            out.push(far_motion(seed, max_frames.min(3000)));
            continue;
        }
        if name == "demo" {
            out.push(from_file(
                "demo".into(),
                &dir.join("motion/jaw_chew_demo.csv"),
                &dir.join("motion/jaw_chew_demo.phases.csv"),
            ));
            continue;
        }
        let scenario: Scenario = name
            .parse()
            .unwrap_or_else(|e| panic!("QUERY_BENCH_MOTIONS: {e} (or demo)"));
        let (ma, mb) = meshes.get_or_insert_with(|| {
            (
                innersphere::mesh::io::load(fa).unwrap(),
                innersphere::mesh::io::load(fb).unwrap(),
            )
        });
        let t0 = Instant::now();
        let g = generate_with(scenario, seconds, seed, ma, mb, &GenerateOptions::default())
            .unwrap_or_else(|e| panic!("generating {scenario}: {e}"));
        let cache = cache_dir();
        let file = cache.join(format!("motion_{scenario}_seed{seed}_{seconds}s.csv"));
        let labels = cache.join(format!(
            "motion_{scenario}_seed{seed}_{seconds}s.phases.csv"
        ));
        if let Err(e) = std::fs::create_dir_all(&cache)
            .map_err(|e| innersphere::Error::io(&cache, e))
            .and_then(|()| g.motion.save(&file))
            .and_then(|()| {
                std::fs::write(&labels, g.labels_csv())
                    .map_err(|e| innersphere::Error::io(&labels, e))
            })
        {
            eprintln!("could not save {}: {e}", file.display());
        }
        let c = g.counts();
        eprintln!(
            "generated {scenario} ({seconds} s, seed {seed}) in {:.1?}: {} separated, {} touching, {} overlapping frames; saved as {}",
            t0.elapsed(),
            c.separated,
            c.touching,
            c.overlap,
            file.display()
        );
        let mut poses: Vec<Pose> = g.motion.poses().collect();
        poses.truncate(max_frames);
        let phases = g
            .phases
            .iter()
            .take(poses.len())
            .map(|p| p.name().to_string())
            .collect();
        out.push(BenchMotion {
            name: scenario.name().into(),
            poses,
            phases,
        });
    }
    out
}

/// Far and huge poses: frame `i` of `n` moves B to `10^(2 + 298·i/n)` (model units) along a
/// pseudo-random direction with a pseudo-random rotation (from `seed`): from just clear of
/// the jaw (100 mm, beyond the arches' bounding spheres) out to 10³⁰⁰; phases by band.
fn far_motion(seed: u64, n: usize) -> BenchMotion {
    let mut x = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        (x >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let mut poses = Vec::with_capacity(n);
    let mut phases = Vec::with_capacity(n);
    for i in 0..n {
        let e = 2.0 + 298.0 * i as f64 / n as f64;
        let dir = innersphere::glam::DVec3::new(next(), next(), next())
            .normalize_or(innersphere::glam::DVec3::X);
        let q =
            innersphere::glam::DQuat::from_xyzw(next(), next(), next(), next() + 2.0).normalize();
        poses.push(Pose::new(dir * 10f64.powf(e), q).expect("finite pose"));
        phases.push(
            match e {
                e if e < 3.0 => "1e2-1e3",
                e if e < 10.0 => "1e3-1e10",
                e if e < 20.0 => "1e10-1e20",
                _ => "1e20-1e300",
            }
            .to_string(),
        );
    }
    BenchMotion {
        name: "far".into(),
        poses,
        phases,
    }
}

/// Per-frame nanoseconds → (median, p99, max, mean) in microseconds.
fn summary(t: &mut [u64]) -> (f64, f64, f64, f64) {
    t.sort_unstable();
    let q = |p: f64| t[((t.len() - 1) as f64 * p).round() as usize] as f64 / 1e3;
    let mean = t.iter().sum::<u64>() as f64 / t.len() as f64 / 1e3;
    (q(0.5), q(0.99), t[t.len() - 1] as f64 / 1e3, mean)
}

type Query<'a> = Box<dyn FnMut(&Pose, &mut Pair) -> (bool, u64) + 'a>;

/// The queries of the quick mode and of the final table's default selection.
const HEADLINE: [&str; 4] = [
    "proximity (exact, ours)",
    "contact (kinetic front, ours)",
    "multipoint k=16",
    PENETRATION,
];

/// The default penetration query, whose floor is reported.
const PENETRATION: &str = "penetration (default: auto)";

/// One line of the final table.
struct Line {
    query: &'static str,
    motion: String,
    frames: usize,
    p50: f64,
    p99: f64,
    max: f64,
    max_frame: usize,
    over: usize,
    agg_p99: f64,
    agg_max: f64,
    agg_over: usize,
}

/// The penetration floor on one motion (see [`floor`]).
struct Floor {
    motion: String,
    frames: usize,
    pairs_p50: usize,
    pairs_max: usize,
    query_p99: f64,
    floor_p99: f64,
    query_max: f64,
    floor_max: f64,
    ratio_p50: f64,
    ratio_p99: f64,
}

/// The output-sensitive floor of the penetration query along `m`: per frame in contact, the
/// overlapping leaf pairs (found once, untimed) summed alone, `passes` times (the best or
/// the worst per frame, like `query`, the query's per-frame times).
fn floor(
    a: &SharedTree,
    b: &SharedTree,
    m: &BenchMotion,
    query: &[u64],
    passes: usize,
    best: bool,
) -> Floor {
    let id = Pose::IDENTITY;
    let mut st = Pair::new(a, b);
    let opts = PenetrationOptions::default();
    let leaves: Vec<Vec<[u32; 2]>> = m
        .poses
        .iter()
        .map(|p| {
            let mut l = Vec::new();
            st.overlapping_leaves(&id, p, &mut l);
            l
        })
        .collect();
    let contact: Vec<usize> = (0..leaves.len())
        .filter(|&f| !leaves[f].is_empty())
        .collect();
    let mut t = vec![0u64; contact.len()];
    for pass in 0..passes {
        for (k, &f) in contact.iter().enumerate() {
            let t0 = Instant::now();
            let r = st.penetration_of_leaves(&id, &m.poses[f], &leaves[f], &opts);
            let ns = t0.elapsed().as_nanos() as u64;
            std::hint::black_box(r.expect("leaves of the trees"));
            if pass == 0 || (ns < t[k]) == best {
                t[k] = ns;
            }
        }
    }
    let mut ratio: Vec<f64> = contact
        .iter()
        .zip(&t)
        .map(|(&f, &ns)| query[f] as f64 / ns.max(1) as f64)
        .collect();
    ratio.sort_unstable_by(f64::total_cmp);
    let mut pairs: Vec<usize> = contact.iter().map(|&f| leaves[f].len()).collect();
    pairs.sort_unstable();
    let mut q: Vec<u64> = contact.iter().map(|&f| query[f]).collect();
    let q_at = |q: &mut Vec<u64>| {
        if q.is_empty() {
            (0.0, 0.0)
        } else {
            let (_, p99, max, _) = summary(q);
            (p99, max)
        }
    };
    let (query_p99, query_max) = q_at(&mut q);
    let (floor_p99, floor_max) = q_at(&mut t);
    let at = |v: &[f64], p: f64| {
        v.get(((v.len().max(1) - 1) as f64 * p).round() as usize)
            .copied()
            .unwrap_or(0.0)
    };
    Floor {
        motion: m.name.clone(),
        frames: contact.len(),
        pairs_p50: pairs.get(pairs.len() / 2).copied().unwrap_or(0),
        pairs_max: pairs.last().copied().unwrap_or(0),
        query_p99,
        floor_p99,
        query_max,
        floor_max,
        ratio_p50: at(&ratio, 0.5),
        ratio_p99: at(&ratio, 0.99),
    }
}

fn main() {
    let dir = data_dir();
    let fa = dir.join("jaw/ofj_p26_maxilla_teeth.stl.gz");
    let fb = dir.join("jaw/ofj_p26_mandible_teeth.stl.gz");
    if !(fa.is_file() && fb.is_file() && dir.join("motion/jaw_chew_demo.csv").is_file()) {
        println!(
            "queries bench skipped: jaw data not found under {}",
            dir.display()
        );
        return;
    }
    let quick = std::env::var("QUERY_BENCH_QUICK").is_ok_and(|s| !s.is_empty() && s != "0");
    let h: f64 = env_f64("QUERY_BENCH_VOXEL").unwrap_or(if quick { 0.5 } else { 0.15 });
    let passes: usize = env_f64("QUERY_BENCH_PASSES")
        .map_or(2, |x| x as usize)
        .max(1);
    let only: Vec<String> = std::env::var("QUERY_BENCH_ONLY")
        .map(|s| s.split(',').map(str::to_string).collect())
        .unwrap_or_default();
    // Beside the single pass, per frame the best (default; filters out interference from
    // other processes) or the worst of the passes.
    let best = std::env::var("QUERY_BENCH_AGG").map_or(true, |s| s != "max");
    let agg = format!("{}-of-{passes}", if best { "best" } else { "worst" });
    let a = tree(&fa, "maxilla", h);
    let b = tree(&fb, "mandible", h);
    let motions = motions(&dir, &fa, &fb, quick);
    println!(
        "trees: A maxilla {} leaves / {} nodes / depth {}, B mandible {} leaves / {} nodes / depth {} (voxel {h}); motions {}; single thread; 1 pass = the first pass in motion order, state carried frame to frame; {agg} beside it",
        a.leaf_count(),
        a.len(),
        a.max_depth(),
        b.leaf_count(),
        b.len(),
        b.max_depth(),
        motions
            .iter()
            .map(|m| format!("{} ({} frames)", m.name, m.poses.len()))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let id = Pose::IDENTITY;
    let (a, b) = (&SharedTree::new(a), &SharedTree::new(b));
    let off = TraversalOptions { safe_motion: false };
    let on = TraversalOptions { safe_motion: true };
    let mp = |k: usize| MultipointOptions {
        k,
        split_depth: 4,
        reuse: true,
        safe_motion: true,
        tracking: false,
    };
    let mpt = |k: usize| MultipointOptions {
        tracking: true,
        ..mp(k)
    };
    let mut queries: Vec<(&'static str, Query)> = vec![
        (
            "proximity (exact, ours)",
            Box::new(|p, st| {
                let r = st.distance(&id, p);
                (r.overlapping, r.visits)
            }),
        ),
        (
            "proximity best-first",
            Box::new(|p, st| {
                let o = DistanceOptions {
                    best_first: true,
                    ..Default::default()
                };
                let r = st.distance_with(&id, p, &o);
                (r.overlapping, r.visits)
            }),
        ),
        (
            "proximity rel_tol 1%",
            Box::new(|p, st| {
                let o = DistanceOptions {
                    rel_tolerance: 0.01,
                    ..Default::default()
                };
                let r = st.distance_with(&id, p, &o);
                (r.overlapping, r.visits)
            }),
        ),
        (
            "paper distance traversal",
            Box::new(|p, st| {
                let r = st.paper().distance_traversal(&id, p, &off);
                (r.in_contact(), r.visits)
            }),
        ),
        (
            "paper distance + safe motion",
            Box::new(|p, st| {
                let r = st.paper().distance_traversal(&id, p, &on);
                (r.in_contact(), r.visits)
            }),
        ),
        (
            "backtracking",
            Box::new(|p, st| {
                let r = st.paper().backtracking(&id, p, &off);
                (r.in_contact(), r.visits)
            }),
        ),
        (
            "backtracking + safe motion",
            Box::new(|p, st| {
                let r = st.paper().backtracking(&id, p, &on);
                (r.in_contact(), r.visits)
            }),
        ),
        (
            "contact (kinetic front, ours)",
            Box::new(|p, st| {
                let r = st.contact(&id, p);
                (r.in_contact(), r.visits)
            }),
        ),
        (
            "multipoint k=1",
            Box::new(move |p, st| {
                let r = st.multipoint(&id, p, &mp(1));
                (r.count > 0, r.visits)
            }),
        ),
        (
            "multipoint k=4",
            Box::new(move |p, st| {
                let r = st.multipoint(&id, p, &mp(4));
                (r.count > 0, r.visits)
            }),
        ),
        (
            "multipoint k=16",
            Box::new(move |p, st| {
                let r = st.multipoint(&id, p, &mp(16));
                (r.count > 0, r.visits)
            }),
        ),
        (
            "multipoint k=16 front",
            Box::new(move |p, st| {
                let r = st.multipoint(&id, p, &mpt(16));
                (r.count > 0, r.visits)
            }),
        ),
        (
            "penetration traversal",
            Box::new(|p, st| {
                let o = PenetrationOptions {
                    tracking: Tracking::Traversal,
                    ..Default::default()
                };
                let r = st.penetration_with(&id, p, &o);
                (r.pairs > 0, r.visits)
            }),
        ),
        (
            PENETRATION,
            Box::new(|p, st| {
                let r = st.penetration(&id, p);
                (r.pairs > 0, r.visits)
            }),
        ),
        (
            "penetration budget 8k",
            Box::new(|p, st| {
                let r = st.penetration_within(&id, p, 8_000);
                (r.volume > 0.0, r.visits)
            }),
        ),
    ];
    queries.retain(|(name, _)| {
        if only.is_empty() {
            !quick || HEADLINE.contains(name)
        } else {
            only.iter()
                .any(|o| (o == "headline" && HEADLINE.contains(name)) || name.contains(o.as_str()))
        }
    });
    let mut dump = std::env::var_os("QUERY_BENCH_FRAMES").map(|p| {
        let mut w = std::io::BufWriter::new(std::fs::File::create(p).expect("QUERY_BENCH_FRAMES"));
        writeln!(
            w,
            "motion,query,frame,phase,ns_1pass,ns_{},visits,contact",
            agg.replace('-', "_")
        )
        .expect("write");
        w
    });
    let mut table: Vec<Line> = Vec::new();
    let mut floors: Vec<Floor> = Vec::new();
    for m in &motions {
        let n = m.poses.len();
        if n == 0 {
            continue;
        }
        let mut phase_names: Vec<String> = Vec::new();
        for p in &m.phases {
            if !phase_names.contains(p) {
                phase_names.push(p.clone());
            }
        }
        println!();
        println!("motion {} ({n} frames)", m.name);
        println!(
            "{:<30} {:<10} {:>6} {:>9} {:>9} {:>9} {:>6} {:>9} {:>9} {:>9} {:>9} {:>9} {:>7}",
            "query",
            "phase",
            "frames",
            "median",
            "p99",
            "max",
            ">1ms",
            "mean",
            "p99",
            "max",
            "visits",
            "p99 vis",
            "contact"
        );
        println!(
            "{:<30} {:<10} {:>6} {:>9} {:>9} {:>9} {:>6} {:>9} {:>9} {:>9}",
            "",
            "",
            "",
            "µs 1pass",
            "µs 1pass",
            "µs 1pass",
            "1pass",
            "µs 1pass",
            format!("µs {}", if best { "best" } else { "worst" }),
            format!("µs {}", if best { "best" } else { "worst" }),
        );
        // The default penetration query's per-frame times, for its floor.
        let mut pen_times: Option<Vec<u64>> = None;
        for (name, q) in queries.iter_mut() {
            let name: &'static str = name;
            let mut first = vec![0u64; n];
            let mut aggt = vec![0u64; n];
            let mut visits = vec![0u64; n];
            let mut contact = vec![false; n];
            let mut agree = true;
            // A fresh state, as a haptic loop starts with; reset between passes so that
            // every pass does the same work.
            let mut st = Pair::new(a, b);
            for pass in 0..passes {
                if pass > 0 {
                    st.reset();
                }
                for (f, p) in m.poses.iter().enumerate() {
                    let t0 = Instant::now();
                    let (c, v) = q(p, &mut st);
                    let ns = t0.elapsed().as_nanos() as u64;
                    if pass == 0 {
                        first[f] = ns;
                        aggt[f] = ns;
                        visits[f] = v;
                        contact[f] = c;
                    } else {
                        if (ns < aggt[f]) == best {
                            aggt[f] = ns;
                        }
                        agree &= visits[f] == v && contact[f] == c;
                    }
                }
            }
            if !agree {
                eprintln!(
                    "warning: {name} on {}: the passes did not all do the same work",
                    m.name
                );
            }
            if name == PENETRATION {
                pen_times = Some(aggt.clone());
            }
            if let Some(w) = dump.as_mut() {
                for f in 0..n {
                    writeln!(
                        w,
                        "{},\"{name}\",{f},{},{},{},{},{}",
                        m.name, m.phases[f], first[f], aggt[f], visits[f], contact[f]
                    )
                    .expect("write");
                }
            }
            let mut rows: Vec<(String, Vec<usize>)> = phase_names
                .iter()
                .map(|ph| (ph.clone(), (0..n).filter(|&f| &m.phases[f] == ph).collect()))
                .collect();
            rows.push(("all".into(), (0..n).collect()));
            for (ph, frames) in rows {
                if frames.is_empty() {
                    continue;
                }
                let mut t: Vec<u64> = frames.iter().map(|&f| first[f]).collect();
                let over = t.iter().filter(|&&x| x > 1_000_000).count();
                let (med, p99, max, mean) = summary(&mut t);
                let mut ta: Vec<u64> = frames.iter().map(|&f| aggt[f]).collect();
                let agg_over = ta.iter().filter(|&&x| x > 1_000_000).count();
                let (_, ap99, amax, _) = summary(&mut ta);
                let mut v: Vec<u64> = frames.iter().map(|&f| visits[f]).collect();
                v.sort_unstable();
                let nc = frames.iter().filter(|&&f| contact[f]).count();
                println!(
                    "{name:<30} {ph:<10} {:>6} {med:>9.1} {p99:>9.1} {max:>9.1} {over:>6} {mean:>9.1} {ap99:>9.1} {amax:>9.1} {:>9} {:>9} {nc:>7}",
                    frames.len(),
                    v[v.len() / 2],
                    v[((v.len() - 1) as f64 * 0.99).round() as usize],
                );
                if ph == "all" {
                    let max_frame = (0..n).max_by_key(|&f| first[f]).unwrap_or(0);
                    table.push(Line {
                        query: name,
                        motion: m.name.clone(),
                        frames: n,
                        p50: med,
                        p99,
                        max,
                        max_frame,
                        over,
                        agg_p99: ap99,
                        agg_max: amax,
                        agg_over,
                    });
                }
            }
        }
        if let Some(query) = pen_times {
            floors.push(floor(a, b, m, &query, passes, best));
        }
    }
    if let Some(mut w) = dump {
        w.flush().expect("write");
    }
    if !floors.is_empty() {
        println!();
        println!(
            "Penetration floor ({agg}): per frame in contact, the overlapping leaf pairs and the time to only sum them (`Pair::penetration_of_leaves`); query / floor is the search's overhead."
        );
        println!();
        println!("| motion | frames in contact | pairs p50 | pairs max | query p99 µs | floor p99 µs | query max µs | floor max µs | query/floor p50 | query/floor p99 |");
        println!("|---|---|---|---|---|---|---|---|---|---|");
        for f in &floors {
            println!(
                "| {} | {} | {} | {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} |",
                f.motion,
                f.frames,
                f.pairs_p50,
                f.pairs_max,
                f.query_p99,
                f.floor_p99,
                f.query_max,
                f.floor_max,
                f.ratio_p50,
                f.ratio_p99
            );
        }
    }
    println!();
    println!(
        "All frames, µs. 1 pass: the first pass over the motion, what a haptic loop sees; {agg}: per frame the {} of {passes} passes (beside it only).",
        if best { "fastest" } else { "slowest" }
    );
    println!();
    println!("| query | motion | frames | p50 (1 pass) | p99 (1 pass) | max (1 pass) [frame] | frames > 1 ms (1 pass) | p99 {agg} | max {agg} | frames > 1 ms {agg} |");
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for l in &table {
        println!(
            "| {} | {} | {} | {:.1} | {:.1} | {:.1} [{}] | {} | {:.1} | {:.1} | {} |",
            l.query,
            l.motion,
            l.frames,
            l.p50,
            l.p99,
            l.max,
            l.max_frame,
            l.over,
            l.agg_p99,
            l.agg_max,
            l.agg_over
        );
    }
}
