//! Exact mesh–mesh distance on the real jaw pair along the chewing motion.
//!
//! `cargo bench -p innersphere --bench exact` (optional: `EXACT_STRIDE=n` uses every n-th
//! frame, default 10; `INNERSPHERE_DATA` points at the data folder). Prints median, p99 and
//! max per query for the cold distance (no warm start, comparable to FCL), the warm-started
//! distance, the intersection test and the penetration depth. Skips with a message when the
//! data files are missing.

use innersphere::exact::{distance, intersects, penetration_depth, ExactMesh, ExactScratch};
use innersphere::query::Pose;
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
        let v: Vec<f64> = line.split(',').filter_map(|x| x.trim().parse().ok()).collect();
        if v.len() == 8 {
            poses.push(Pose::from_array([v[1], v[2], v[3], v[4], v[5], v[6], v[7]])?);
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
        println!("exact bench skipped: jaw data not found under {}", dir.display());
        return;
    }
    let stride = std::env::var("EXACT_STRIDE")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(10usize)
        .max(1);
    let t = Instant::now();
    let (ma, mb) = match (innersphere::mesh::io::load(&fa), innersphere::mesh::io::load(&fb)) {
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
    println!("{} poses (every {stride}th frame of the chew motion)", poses.len());
    let id = Pose::IDENTITY;

    // Cold distance: every query from scratch (what FCL does).
    let mut s = ExactScratch::cold();
    let mut times = Vec::with_capacity(poses.len());
    let mut hits = 0;
    let mut dsum = 0.0;
    for p in &poses {
        let t = Instant::now();
        let r = distance(&a, &id, &b, p, &mut s);
        times.push(t.elapsed());
        hits += r.intersecting as usize;
        dsum += r.distance;
    }
    println!("  {hits} intersecting, mean distance {:.4} mm", dsum / poses.len() as f64);
    stats("distance (cold)", times);

    let mut s = ExactScratch::new();
    let mut times = Vec::with_capacity(poses.len());
    for p in &poses {
        let t = Instant::now();
        let _ = distance(&a, &id, &b, p, &mut s);
        times.push(t.elapsed());
    }
    stats("distance (warm start)", times);

    let mut s = ExactScratch::cold();
    let mut times = Vec::with_capacity(poses.len());
    for p in &poses {
        let t = Instant::now();
        let _ = intersects(&a, &id, &b, p, &mut s);
        times.push(t.elapsed());
    }
    stats("intersects (cold)", times);

    let mut s = ExactScratch::new();
    let mut times = Vec::with_capacity(poses.len());
    let mut deep = 0.0f64;
    for p in &poses {
        let t = Instant::now();
        deep = deep.max(penetration_depth(&a, &id, &b, p, &mut s));
        times.push(t.elapsed());
    }
    stats("penetration_depth", times);
    println!("  deepest penetration along the motion {deep:.3} mm");
}
