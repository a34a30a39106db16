//! `ist bench paper`: the paper's evaluation (section IV) on a pair of meshes along a motion,
//! with our queries beside the paper's: speed against leaf count (Fig. 6), against fan-out and
//! depth at about 3k and 16k leaves (Figs. 7–8), distance error against leaf count (Fig. 9),
//! backtracking against the full traversal while in contact, multipoint against `k`, and our
//! exact proximity and penetration volume beside the paper's traversals and the exact mesh
//! distance. Writes one CSV per figure and a PNG chart of each.

use super::plot::{line_chart, Chart, Series};
use super::replay::{replay, time_exact, Accuracy, QueryKind, ReplayOptions};
use crate::motion::Motion;
use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::exact::ExactMesh;
use innersphere::mesh::Mesh;
use innersphere::progress::Silent;
use innersphere::query::TraversalOptions;
use innersphere::{Error, MultipointOptions, Pair, Pose, Result, SharedTree};
use std::fmt::Write as _;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

/// Every file [`run`] may write into its output folder (so that a caller can check before
/// the run that none of them is one of its inputs).
pub const FILES: [&str; 12] = [
    "fig6_speed_vs_leaves.csv",
    "fig6_speed_vs_leaves.png",
    "fig9_error_vs_leaves.csv",
    "fig9_error_vs_leaves.png",
    "fig7_8_fanout.csv",
    "fig7_8_fanout.png",
    "backtracking.csv",
    "backtracking.png",
    "multipoint_k.csv",
    "multipoint_k.png",
    "ours_vs_paper.csv",
    "ours_vs_paper.png",
];

/// What `ist bench paper` measures.
#[derive(Debug, Clone)]
pub struct PaperOptions {
    /// Voxel sizes (model units) of the trees of the leaf-count sweep (Figs. 6 and 9).
    pub voxel_sizes: Vec<f64>,
    /// Fan-outs of the depth sweep (Figs. 7–8).
    pub fanouts: Vec<u32>,
    /// Leaf counts (per body, about) at which the fan-out sweep runs; the sweep's voxel size
    /// with the nearest count is used.
    pub fanout_leaves: Vec<usize>,
    /// Contacts asked of multipoint.
    pub ks: Vec<usize>,
    /// Compare with the exact mesh distance on every `every`-th frame.
    pub every: usize,
    /// Build options of the main trees (backtracking, multipoint, ours vs paper).
    pub main: BuildOptions,
}

impl PaperOptions {
    /// Defaults for a pair whose larger bounding box has longest side `size`: voxel sizes
    /// from size/48 to size/384, fan-outs 2–16 at about 3k and 16k leaves, k = 1–32, the exact
    /// reference on every 10th frame, main trees at size/384.
    pub fn for_size(size: f64) -> PaperOptions {
        PaperOptions {
            voxel_sizes: [48.0, 64.0, 96.0, 128.0, 192.0, 256.0, 384.0]
                .iter()
                .map(|d| size / d)
                .collect(),
            fanouts: vec![2, 4, 8, 16],
            fanout_leaves: vec![3_000, 16_000],
            ks: vec![1, 2, 4, 8, 16, 32],
            every: 10,
            main: BuildOptions {
                resolution: Resolution::VoxelSize(size / 384.0),
                ..Default::default()
            },
        }
    }
}

/// Per-frame times (µs) of one query kind along the motion and whether it reported contact.
struct Timed {
    /// Each frame's faster of the two passes (the sweeps' curves).
    us: Vec<f64>,
    /// Each frame's time in the first pass: what a haptic loop sees.
    first: Vec<f64>,
    contact: Vec<bool>,
}

/// Runs `f` over every frame twice through one state, reset before each pass (so both passes
/// do the same work). The first pass, from a fresh state in motion order, is the single-pass
/// time a haptic loop sees; each frame's faster pass (the same rule as `ist replay --passes
/// 2` and the query benchmark's best-of-N) filters the stalls of a shared or virtual machine
/// and gives the sweeps' curves.
fn time_frames<F: FnMut(&Pose, &mut Pair) -> bool>(
    a: &SharedTree,
    b: &SharedTree,
    motion: &Motion,
    mut f: F,
) -> Timed {
    let mut st = Pair::new(a, b);
    let mut out = Timed {
        us: vec![f64::INFINITY; motion.frames.len()],
        first: vec![f64::NAN; motion.frames.len()],
        contact: vec![false; motion.frames.len()],
    };
    for pass in 0..2 {
        st.reset();
        for (i, fr) in motion.frames.iter().enumerate() {
            let t0 = Instant::now();
            let c = f(&fr.pose, &mut st);
            let us = t0.elapsed().as_secs_f64() * 1e6;
            if pass == 0 {
                out.first[i] = us;
            }
            out.us[i] = out.us[i].min(us);
            out.contact[i] = c;
        }
    }
    out
}

/// p50, p99, max, mean of `v` (µs).
fn stats(v: &[f64]) -> [f64; 4] {
    if v.is_empty() {
        return [f64::NAN; 4];
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let q = |p: f64| s[((s.len() - 1) as f64 * p).round() as usize];
    [
        q(0.5),
        q(0.99),
        s[s.len() - 1],
        s.iter().sum::<f64>() / s.len() as f64,
    ]
}

/// The query kinds of the sweeps: the paper's two traversals and ours.
const SWEEP_KINDS: [&str; 5] = [
    "paper distance traversal",
    "paper backtracking",
    "proximity (ours)",
    "contact kinetic front (ours)",
    "penetration (ours)",
];

fn time_kind(a: &SharedTree, b: &SharedTree, motion: &Motion, kind: &str) -> Timed {
    let id = Pose::IDENTITY;
    let off = TraversalOptions { safe_motion: false };
    match kind {
        "paper distance traversal" => time_frames(a, b, motion, |p, st| {
            st.paper().distance_traversal(&id, p, &off).in_contact()
        }),
        "paper backtracking" => time_frames(a, b, motion, |p, st| {
            st.paper().backtracking(&id, p, &off).in_contact()
        }),
        "proximity (ours)" => time_frames(a, b, motion, |p, st| st.distance(&id, p).overlapping),
        "contact kinetic front (ours)" => {
            time_frames(a, b, motion, |p, st| st.contact(&id, p).in_contact())
        }
        _ => time_frames(a, b, motion, |p, st| st.penetration(&id, p).pairs > 0),
    }
}

fn build(mesh: &Mesh, opts: &BuildOptions) -> Result<(SharedTree, f64)> {
    let t0 = Instant::now();
    let (t, _) = build_tree(mesh, opts, &Silent)?;
    Ok((SharedTree::new(t), t0.elapsed().as_secs_f64()))
}

/// The output folder and the files written into it so far.
struct Out<'a> {
    dir: &'a Path,
    files: Vec<String>,
}

impl Out<'_> {
    /// Writes `text` to `name` (one of [`FILES`]), through a temporary file renamed into
    /// place.
    fn csv(&mut self, name: &str, text: &str) -> Result<()> {
        debug_assert!(FILES.contains(&name), "{name} missing from FILES");
        innersphere::output::write_file(&self.dir.join(name), text.as_bytes())?;
        self.files.push(name.into());
        Ok(())
    }

    /// Draws `series` into the PNG file `name` (one of [`FILES`]), through a temporary file
    /// renamed into place.
    fn png(&mut self, name: &str, chart: &Chart, series: &[Series]) -> Result<()> {
        debug_assert!(FILES.contains(&name), "{name} missing from FILES");
        innersphere::output::render_atomic(&self.dir.join(name), |tmp| {
            line_chart(tmp, chart, series)
        })?;
        self.files.push(name.into());
        Ok(())
    }
}

/// The main trees' accuracy along the motion against the exact meshes, the refined
/// distance's too (`Accuracy::refined`; the trees carry the meshes).
fn accuracy_refined(
    ta: &SharedTree,
    tb: &SharedTree,
    motion: &Motion,
    exact: (&Arc<ExactMesh>, &Arc<ExactMesh>),
    every: usize,
) -> Result<Option<Accuracy>> {
    let ta = ta.clone().with_exact_mesh(exact.0.clone())?;
    let tb = tb.clone().with_exact_mesh(exact.1.clone())?;
    Ok(replay(
        &ta,
        &tb,
        motion,
        Some((exact.0, exact.1)),
        &ReplayOptions {
            kinds: vec![QueryKind::RefinedDistance],
            every,
            ..Default::default()
        },
    )
    .accuracy)
}

/// What [`run`] measured, in brief (the CSV files hold everything).
#[derive(Debug, Clone, serde::Serialize)]
pub struct PaperSummary {
    /// Files written into the output folder.
    pub files: Vec<String>,
    /// Leaves of A and B of the main trees.
    pub main_leaves: (usize, usize),
    /// Single-pass p99 (µs) of our exact proximity on the main trees, all frames.
    pub proximity_p99_us: f64,
    /// Single-pass p99 (µs) of the exact mesh distance on the compared frames (every
    /// `every`-th), each warm-started from the previous compared frame.
    pub exact_p99_us: f64,
    /// Backtracking against the full traversal on contact frames: (mean full / mean
    /// backtracking).
    pub backtracking_speedup_in_contact: f64,
    /// Distance error p95 of the main trees (model units).
    pub main_abs_err_p95: f64,
    /// The refined distance's error p95 on the main trees (model units).
    pub main_refined_abs_err_p95: f64,
}

/// Figs. 6 and 9: query time and distance error against the leaf count, one tree pair per
/// voxel size of `opts`; the voxel sizes and leaf counts built, for the fan-out figure.
// Over 120 lines: one loop over the voxel sizes whose build, timings and accuracy feed two
// figures (Figs. 6 and 9) row by row.
fn leaf_sweep(
    mesh_a: &Mesh,
    mesh_b: &Mesh,
    motion: &Motion,
    opts: &PaperOptions,
    (ea, eb): (&Arc<ExactMesh>, &Arc<ExactMesh>),
    out: &mut Out,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<(f64, usize)>> {
    // Figs. 6 and 9: speed and error against leaf count.
    let mut speed = String::from(
        "voxel,leaves_a,leaves_b,depth_a,depth_b,build_s,query,p50_us,p99_us,max_us,mean_us\n",
    );
    let mut error = String::from(
        "voxel,leaves_a,leaves_b,abs_err_p50,abs_err_p95,abs_err_max,rel_err_p50,rel_err_p95,missed_contacts,missed_contacts_deep,false_contacts,missed_contacts_max_depth,refined_abs_err_p50,refined_abs_err_p95,refined_abs_err_max,refined_missed_contacts,refined_missed_contacts_max_depth,refined_incomplete_frames,refined_p99_us\n",
    );
    let mut speed_series: Vec<Series> = SWEEP_KINDS
        .iter()
        .map(|k| Series {
            name: format!("{k}, mean"),
            points: vec![],
        })
        .collect();
    let mut err_series = vec![
        Series {
            name: "abs error p50".into(),
            points: vec![],
        },
        Series {
            name: "abs error p95".into(),
            points: vec![],
        },
        Series {
            name: "refined distance: abs error p95".into(),
            points: vec![],
        },
        Series {
            name: "refined distance: abs error max".into(),
            points: vec![],
        },
    ];
    let mut sweep_leaves: Vec<(f64, usize)> = Vec::new();
    for &h in &opts.voxel_sizes {
        let bo = BuildOptions {
            resolution: Resolution::VoxelSize(h),
            ..Default::default()
        };
        let (ta, sa) = build(mesh_a, &bo)?;
        let (tb, sb) = build(mesh_b, &bo)?;
        let leaves = (ta.leaf_count() + tb.leaf_count()) / 2;
        sweep_leaves.push((h, leaves));
        log(&format!(
            "voxel {h:.4}: {} + {} leaves, built in {:.1} s",
            ta.leaf_count(),
            tb.leaf_count(),
            sa + sb
        ));
        for (k, kind) in SWEEP_KINDS.iter().enumerate() {
            let t = time_kind(&ta, &tb, motion, kind);
            let [p50, p99, max, mean] = stats(&t.us);
            let _ = writeln!(
                speed,
                "{h},{},{},{},{},{:.3},{kind},{p50:.2},{p99:.2},{max:.2},{mean:.2}",
                ta.leaf_count(),
                tb.leaf_count(),
                ta.max_depth(),
                tb.max_depth(),
                sa + sb
            );
            speed_series[k].points.push((leaves as f64, mean));
        }
        if let Some(acc) = accuracy_refined(&ta, &tb, motion, (ea, eb), opts.every)? {
            let r = acc.refined.clone().unwrap_or_default();
            let _ = writeln!(
                error,
                "{h},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.1}",
                ta.leaf_count(),
                tb.leaf_count(),
                acc.errors.abs_err_p50,
                acc.errors.abs_err_p95,
                acc.errors.abs_err_max,
                acc.errors.rel_err_p50,
                acc.errors.rel_err_p95,
                acc.errors.missed_contacts,
                acc.errors.missed_contacts_deep,
                acc.errors.false_contacts,
                acc.errors.missed_contacts_max_depth,
                r.errors.abs_err_p50,
                r.errors.abs_err_p95,
                r.errors.abs_err_max,
                r.errors.missed_contacts,
                r.errors.missed_contacts_max_depth,
                r.incomplete_frames,
                r.p99_us
            );
            err_series[2]
                .points
                .push((leaves as f64, r.errors.abs_err_p95));
            err_series[3]
                .points
                .push((leaves as f64, r.errors.abs_err_max));
            err_series[0]
                .points
                .push((leaves as f64, acc.errors.abs_err_p50));
            err_series[1]
                .points
                .push((leaves as f64, acc.errors.abs_err_p95));
        }
    }
    out.csv("fig6_speed_vs_leaves.csv", &speed)?;
    out.png(
        "fig6_speed_vs_leaves.png",
        &Chart {
            title: "Fig. 6: query time against leaf spheres (mean per frame)",
            x_label: "leaf spheres per body",
            y_label: "time per frame (µs)",
            log_x: true,
            log_y: true,
        },
        &speed_series,
    )?;
    out.csv("fig9_error_vs_leaves.csv", &error)?;
    out.png(
        "fig9_error_vs_leaves.png",
        &Chart {
            title: "Fig. 9: distance error against the exact mesh distance",
            x_label: "leaf spheres per body",
            y_label: "absolute error (model units)",
            log_x: true,
            log_y: true,
        },
        &err_series,
    )?;
    Ok(sweep_leaves)
}

/// Figs. 7–8: query time against the fan-out at the voxel sizes of the sweep nearest each
/// target leaf count of `opts`.
fn fan_out_figure(
    mesh_a: &Mesh,
    mesh_b: &Mesh,
    motion: &Motion,
    opts: &PaperOptions,
    sweep_leaves: &[(f64, usize)],
    out: &mut Out,
    log: &mut dyn FnMut(&str),
) -> Result<()> {
    // Figs. 7–8: fan-out and depth at about 3k and 16k leaves.
    let mut fan = String::from(
        "target_leaves,voxel,fanout,leaves_a,leaves_b,depth_a,depth_b,query,p50_us,p99_us,mean_us\n",
    );
    let mut fan_series = Vec::new();
    for &target in &opts.fanout_leaves {
        let Some(&(h, _)) = sweep_leaves.iter().min_by(|x, y| {
            let dx = (x.1 as f64 / target as f64).ln().abs();
            let dy = (y.1 as f64 / target as f64).ln().abs();
            dx.total_cmp(&dy)
        }) else {
            continue;
        };
        let mut s_dist = Series {
            name: format!("~{}k leaves, paper distance traversal", target / 1000),
            points: vec![],
        };
        let mut s_prox = Series {
            name: format!("~{}k leaves, proximity (ours)", target / 1000),
            points: vec![],
        };
        for &fo in &opts.fanouts {
            let mut bo = BuildOptions {
                resolution: Resolution::VoxelSize(h),
                ..Default::default()
            };
            bo.hierarchy.fanout = fo;
            let (ta, _) = build(mesh_a, &bo)?;
            let (tb, _) = build(mesh_b, &bo)?;
            for kind in ["paper distance traversal", "proximity (ours)"] {
                let t = time_kind(&ta, &tb, motion, kind);
                let [p50, p99, _, mean] = stats(&t.us);
                let _ = writeln!(
                    fan,
                    "{target},{h},{fo},{},{},{},{},{kind},{p50:.2},{p99:.2},{mean:.2}",
                    ta.leaf_count(),
                    tb.leaf_count(),
                    ta.max_depth(),
                    tb.max_depth()
                );
                let s = if kind.starts_with("paper") {
                    &mut s_dist
                } else {
                    &mut s_prox
                };
                s.points.push((fo as f64, mean));
            }
            log(&format!(
                "fan-out {fo} at voxel {h:.4}: depth {} / {}",
                ta.max_depth(),
                tb.max_depth()
            ));
        }
        fan_series.push(s_dist);
        fan_series.push(s_prox);
    }
    out.csv("fig7_8_fanout.csv", &fan)?;
    out.png(
        "fig7_8_fanout.png",
        &Chart {
            title: "Figs. 7-8: query time against fan-out (depth falls as fan-out grows)",
            x_label: "fan-out (children per node)",
            y_label: "mean time per frame (µs)",
            log_x: true,
            log_y: true,
        },
        &fan_series,
    )?;
    Ok(())
}

/// The multipoint traversal's time against k (each of `ks`) on the main trees.
fn multipoint_figure(
    ta: &SharedTree,
    tb: &SharedTree,
    motion: &Motion,
    ks: &[usize],
    out: &mut Out,
) -> Result<()> {
    let id = Pose::IDENTITY;
    let mut mp = String::from("k,p50_us,p99_us,max_us,mean_us,mean_contacts\n");
    let mut mp_series = vec![
        Series {
            name: "p50".into(),
            points: vec![],
        },
        Series {
            name: "p99".into(),
            points: vec![],
        },
    ];
    for &k in ks {
        let o = MultipointOptions {
            k,
            ..Default::default()
        };
        let mut n_contacts = 0usize;
        let t = time_frames(ta, tb, motion, |p, st| {
            let r = st.multipoint(&id, p, &o);
            n_contacts += r.count;
            r.count > 0
        });
        let [p50, p99, max, mean] = stats(&t.us);
        let _ = writeln!(
            mp,
            "{k},{p50:.3},{p99:.3},{max:.3},{mean:.3},{:.2}",
            n_contacts as f64 / (2 * motion.frames.len()) as f64
        );
        mp_series[0].points.push((k as f64, p50));
        mp_series[1].points.push((k as f64, p99));
    }
    out.csv("multipoint_k.csv", &mp)?;
    out.png(
        "multipoint_k.png",
        &Chart {
            title: "Multipoint traversal against k",
            x_label: "k (contacts asked)",
            y_label: "time per frame (µs)",
            log_x: true,
            log_y: true,
        },
        &mp_series,
    )?;
    Ok(())
}

/// Runs the whole evaluation of the pair (`mesh_a` fixed, `mesh_b` moved by `motion`) and
/// The distribution of `v` as a series: (percentile, value), values floored at 0.01 for the
/// log axis.
fn cdf(name: &str, v: &[f64]) -> Series {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len().max(1) as f64;
    Series {
        name: name.to_string(),
        points: s
            .iter()
            .enumerate()
            .map(|(i, &t)| (100.0 * (i + 1) as f64 / n, t.max(0.01)))
            .collect(),
    }
}

/// The backtracking figure on the main trees: the paper's full distance traversal and its
/// backtracking timed along the motion, compared on the frames in contact
/// (`backtracking.csv`, `backtracking.png`). Returns both timings and their statistics on
/// those frames.
fn backtracking_figure(
    ta: &SharedTree,
    tb: &SharedTree,
    motion: &Motion,
    out: &mut Out,
    log: &mut dyn FnMut(&str),
) -> Result<(Timed, Timed, [f64; 4], [f64; 4])> {
    let full = time_kind(ta, tb, motion, "paper distance traversal");
    let back = time_kind(ta, tb, motion, "paper backtracking");
    let in_contact: Vec<usize> = (0..motion.frames.len())
        .filter(|&i| full.contact[i])
        .collect();
    let pick = |t: &Timed| -> Vec<f64> { in_contact.iter().map(|&i| t.us[i]).collect() };
    let (fc, bc) = (pick(&full), pick(&back));
    let (sf, sbk) = (stats(&fc), stats(&bc));
    let mut bt = String::from("query,contact_frames,p50_us,p99_us,max_us,mean_us\n");
    for (name, s) in [("full distance traversal", sf), ("backtracking", sbk)] {
        let _ = writeln!(
            bt,
            "{name},{},{:.3},{:.3},{:.3},{:.3}",
            in_contact.len(),
            s[0],
            s[1],
            s[2],
            s[3]
        );
    }
    out.csv("backtracking.csv", &bt)?;
    if !in_contact.is_empty() {
        out.png(
            "backtracking.png",
            &Chart {
                title: "Backtracking against the full traversal, frames in contact",
                x_label: "percentile of contact frames",
                y_label: "time per frame (µs)",
                log_x: false,
                log_y: true,
            },
            &[
                cdf("paper distance traversal (full)", &fc),
                cdf("paper backtracking", &bc),
            ],
        )?;
    } else {
        log("no frame in contact: no backtracking chart");
    }

    Ok((full, back, sf, sbk))
}

/// writes CSV files and PNG charts into `out`; `log` receives one line per step.
pub fn run(
    mesh_a: &Mesh,
    mesh_b: &Mesh,
    motion: &Motion,
    opts: &PaperOptions,
    out: &Path,
    log: &mut dyn FnMut(&str),
) -> Result<PaperSummary> {
    if motion.frames.is_empty() {
        return Err(Error::InvalidOption("the motion has no frames".into()));
    }
    if opts.voxel_sizes.is_empty() || opts.voxel_sizes.iter().any(|h| h.is_nan() || *h <= 0.0) {
        return Err(Error::InvalidOption(
            "voxel sizes must be positive numbers".into(),
        ));
    }
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let mut out = Out {
        dir: out,
        files: Vec::new(),
    };
    let ea = Arc::new(ExactMesh::new(mesh_a)?);
    let eb = Arc::new(ExactMesh::new(mesh_b)?);

    let sweep_leaves = leaf_sweep(mesh_a, mesh_b, motion, opts, (&ea, &eb), &mut out, log)?;
    fan_out_figure(mesh_a, mesh_b, motion, opts, &sweep_leaves, &mut out, log)?;

    // The main trees: backtracking, multipoint, ours against the paper and the exact mesh.
    let (ta, sa) = build(mesh_a, &opts.main)?;
    let (tb, sb) = build(mesh_b, &opts.main)?;
    log(&format!(
        "main trees: {} + {} leaves, built in {:.1} s",
        ta.leaf_count(),
        tb.leaf_count(),
        sa + sb
    ));
    let (full, back, sf, sbk) = backtracking_figure(&ta, &tb, motion, &mut out, log)?;
    multipoint_figure(&ta, &tb, motion, &opts.ks, &mut out)?;

    // Ours beside the paper's traversals and the exact mesh distance, per frame: single pass
    // (what a haptic loop sees) first, the best of two passes beside it.
    let mut kinds: Vec<(String, Timed)> = vec![
        ("paper distance traversal".into(), full),
        ("paper backtracking".into(), back),
    ];
    for kind in [
        "proximity (ours)",
        "contact kinetic front (ours)",
        "penetration (ours)",
    ] {
        kinds.push((kind.into(), time_kind(&ta, &tb, motion, kind)));
    }
    // Timed on every compared frame, each pass from a fresh scratch: every compared frame is
    // warm-started from the previous compared frame (`every` frames back).
    let origin = Instant::now();
    let ex = time_exact(&ea, &eb, motion, opts.every, 2, &mut || {
        origin.elapsed().as_secs_f64() * 1e6
    });
    kinds.push((
        format!(
            "exact mesh distance (every {} frames; each warm-started from the previous compared frame)",
            opts.every.max(1)
        ),
        Timed {
            us: ex.best,
            first: ex.first,
            contact: ex.answers.iter().map(|e| e.intersecting).collect(),
        },
    ));
    let mut ours = String::from(
        "query,frames,p50_us_1pass,p99_us_1pass,max_us_1pass,mean_us_1pass,frames_over_1ms_1pass,p99_us_best_of_2,max_us_best_of_2\n",
    );
    for (name, t) in &kinds {
        let s = stats(&t.first);
        let b = stats(&t.us);
        let _ = writeln!(
            ours,
            "{name},{},{:.3},{:.3},{:.3},{:.3},{},{:.3},{:.3}",
            t.first.len(),
            s[0],
            s[1],
            s[2],
            s[3],
            t.first.iter().filter(|&&t| t > 1000.0).count(),
            b[1],
            b[2]
        );
    }
    out.csv("ours_vs_paper.csv", &ours)?;
    let series: Vec<Series> = kinds.iter().map(|(n, t)| cdf(n, &t.first)).collect();
    out.png(
        "ours_vs_paper.png",
        &Chart {
            title: "Per-frame time along the motion, single pass (main trees)",
            x_label: "percentile of frames",
            y_label: "time per frame (µs)",
            log_x: false,
            log_y: true,
        },
        &series,
    )?;

    let acc = accuracy_refined(&ta, &tb, motion, (&ea, &eb), opts.every)?;
    let prox = &kinds[2].1.first;
    let exact_first = &kinds[kinds.len() - 1].1.first;
    Ok(PaperSummary {
        files: out.files,
        main_leaves: (ta.leaf_count(), tb.leaf_count()),
        proximity_p99_us: stats(prox)[1],
        exact_p99_us: stats(exact_first)[1],
        backtracking_speedup_in_contact: sf[3] / sbk[3],
        main_abs_err_p95: acc.as_ref().map_or(f64::NAN, |a| a.errors.abs_err_p95),
        main_refined_abs_err_p95: acc
            .and_then(|a| a.refined)
            .map_or(f64::NAN, |r| r.errors.abs_err_p95),
    })
}
