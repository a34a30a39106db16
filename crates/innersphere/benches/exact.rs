//! Exact mesh–mesh distance on the real jaw pair along the chewing motion.
//!
//! `cargo bench -p innersphere --bench exact` (optional: `EXACT_STRIDE=n` uses every n-th
//! frame, default 10; `INNERSPHERE_DATA` points at the data folder). Prints median, p99 and
//! max per query for the cold distance (no warm start, comparable to FCL), the warm-started
//! distance, the intersection test and the penetration depth. Skips with a message when the
//! data files are missing.

use innersphere::exact::{distance, intersects, penetration_depth, ExactMesh, ExactScratch};
use innersphere::Pose;
use std::path::PathBuf;
use std::time::{Duration, Instant};

fn data_dir() -> PathBuf {
    std::env::var_os("INNERSPHERE_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"))
}

/// Poses of `t,tx,ty,tz,qw,qx,qy,qz` rows, every `stride`-th.
fn read_motion(path: &PathBuf, stride: usize) -> Option<Vec<Pose>> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut poses = Vec::new();
    for (i, line) in text.lines().skip(1).enumerate() {
        if i % stride != 0 {
            continue;
        }
        let v: Vec<f64> = line
            .split(',')
            .filter_map(|x| x.trim().parse().ok())
            .collect();
        if v.len() == 8 {
            poses.push(Pose::from_array([v[1], v[2], v[3], v[4], v[5], v[6], v[7]]).ok()?);
        }
    }
    Some(poses)
}

fn stats(name: &str, mut t: Vec<Duration>) {
    t.sort();
    let q = |p: f64| t[((t.len() - 1) as f64 * p).round() as usize];
    let mean = t.iter().sum::<Duration>() / t.len() as u32;
    println!(
        "{name:<28} n={:<5} median {:>9.1?}  p99 {:>9.1?}  max {:>9.1?}  mean {:>9.1?}",
        t.len(),
        q(0.5),
        q(0.99),
        t[t.len() - 1],
        mean
    );
}

fn main() {
    let dir = data_dir();
    let fa = dir.join("jaw/ofj_p26_maxilla_teeth.stl.gz");
    let fb = dir.join("jaw/ofj_p26_mandible_teeth.stl.gz");
    let fm = dir.join("motion/jaw_chew_demo.csv");
    if !(fa.is_file() && fb.is_file() && fm.is_file()) {
        println!(
            "exact bench skipped: jaw data not found under {}",
            dir.display()
        );
        return;
    }
    let stride = std::env::var("EXACT_STRIDE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10usize)
        .max(1);
    let t = Instant::now();
    let (ma, mb) = match (
        innersphere::mesh::io::load(&fa),
        innersphere::mesh::io::load(&fb),
    ) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            println!("exact bench skipped: {e}");
            return;
        }
    };
    let load = t.elapsed();
    let t = Instant::now();
    let (a, b) = match (ExactMesh::new(&ma), ExactMesh::new(&mb)) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            println!("exact bench skipped: {e}");
            return;
        }
    };
    println!(
        "jaw pair: {} + {} triangles; load {load:.2?}, prepare {:.2?}",
        ma.triangles.len(),
        mb.triangles.len(),
        t.elapsed()
    );
    let Some(poses) = read_motion(&fm, stride) else {
        println!("exact bench skipped: cannot read {}", fm.display());
        return;
    };
    println!(
        "{} poses (every {stride}th frame of the chew motion)",
        poses.len()
    );
    let id = Pose::IDENTITY;
    let verbose = std::env::var_os("EXACT_VERBOSE").is_some();
    // EXACT_ONLY=distance,warm,intersects,penetration picks sections (default: all).
    let only = std::env::var("EXACT_ONLY").unwrap_or_default();
    let run = |name: &str| only.is_empty() || only.split(',').any(|x| x == name);
    // EXACT_REPEAT=k times every query k times (from the same scratch state) and keeps the
    // fastest, which filters out interference from other processes on a shared machine.
    let repeat: usize = std::env::var("EXACT_REPEAT")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1usize)
        .max(1);
    if repeat > 1 {
        println!("each query timed {repeat} times, fastest kept");
    }
    let timed = |s: &mut ExactScratch, f: &mut dyn FnMut(&mut ExactScratch)| -> Duration {
        let mut best = Duration::MAX;
        let start = s.clone();
        for k in 0..repeat {
            if k + 1 < repeat {
                let mut tmp = start.clone();
                let t = Instant::now();
                f(&mut tmp);
                best = best.min(t.elapsed());
            } else {
                // The last run advances the real scratch (warm start state).
                let t = Instant::now();
                f(s);
                best = best.min(t.elapsed());
            }
        }
        best
    };

    // Cold distance: every query from scratch (what FCL does).
    if run("distance") {
        let mut s = ExactScratch::cold();
        let mut times = Vec::with_capacity(poses.len());
        let (mut apart, mut touching) = (Vec::new(), Vec::new());
        let mut dsum = 0.0;
        for p in &poses {
            let mut r = None;
            let e = timed(&mut s, &mut |s| r = Some(distance(&a, &id, &b, p, s)));
            let Some(r) = r else { continue };
            times.push(e);
            if verbose {
                println!(
                    "    d {:9.4} {:9.1}us {:?}",
                    r.distance,
                    e.as_secs_f64() * 1e6,
                    s.stats()
                );
            }
            if r.intersecting {
                touching.push(e);
            } else {
                apart.push(e);
            }
            dsum += r.distance;
        }
        println!(
            "  {} intersecting, {} separated, mean distance {:.4} mm",
            touching.len(),
            apart.len(),
            dsum / poses.len() as f64
        );
        stats("distance (cold)", times);
        if !apart.is_empty() {
            stats("  of which separated", apart);
        }
        if !touching.is_empty() {
            stats("  of which intersecting", touching);
        }
    }

    if run("warm") {
        let mut s = ExactScratch::new();
        let times = poses
            .iter()
            .map(|p| {
                timed(&mut s, &mut |s| {
                    let _ = distance(&a, &id, &b, p, s);
                })
            })
            .collect();
        stats("distance (warm start)", times);
    }

    if run("intersects") {
        let mut s = ExactScratch::cold();
        let times = poses
            .iter()
            .map(|p| {
                timed(&mut s, &mut |s| {
                    let _ = intersects(&a, &id, &b, p, s);
                })
            })
            .collect();
        stats("intersects (cold)", times);
    }

    if run("penetration") {
        let mut s = ExactScratch::new();
        let mut deep = 0.0f64;
        let times = poses
            .iter()
            .map(|p| {
                timed(&mut s, &mut |s| {
                    deep = deep.max(penetration_depth(&a, &id, &b, p, s));
                })
            })
            .collect();
        stats("penetration_depth", times);
        println!("  deepest penetration along the motion {deep:.3} mm");
    }
}
