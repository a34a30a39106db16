//! The penetration query alone along a motion, per frame the fastest of N passes: the replay
//! behind BENCHMARKS.md's linearised A/B (build the same file against an older checkout of
//! the library to compare).
//!
//! `cargo run --release -p innersphere-eval --example penetration_replay -- A.ist B.ist
//! MOTION.csv` with `PASSES` (default 3), `LINEARIZE=1` (the area and the 6×6 stiffness, as
//! the haptic contact model asks), `TOP=N` (the N slowest frames, with their node-pair
//! tests), `PATCHES=N` (`max_patches`, default 8; 0 shows what the patches cost).

use innersphere::{Pair, PenetrationOptions, Pose, SharedTree, SphereTree};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b, motion] = args.as_slice() else {
        return Err("usage: penetration_replay A.ist B.ist MOTION.csv".into());
    };
    let a = SharedTree::new(SphereTree::load(a)?);
    let b = SharedTree::new(SphereTree::load(b)?);
    let m = innersphere_motion::Motion::load(motion)?;
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<usize>().ok());
    let passes = env("PASSES").unwrap_or(3).max(1);
    let opts = PenetrationOptions {
        linearize: env("LINEARIZE").unwrap_or(0) != 0,
        max_patches: env("PATCHES").unwrap_or(8),
        ..Default::default()
    };
    let n = m.frames.len();
    if n == 0 {
        return Err("the motion has no frames".into());
    }
    let mut best = vec![f64::INFINITY; n];
    let mut pairs = vec![0usize; n];
    let mut visits = vec![0u64; n];
    let mut pair = Pair::new(a, b);
    for _ in 0..passes {
        pair.reset();
        for (i, f) in m.frames.iter().enumerate() {
            let t = Instant::now();
            let p = pair.penetration_with(&Pose::IDENTITY, &f.pose, &opts);
            best[i] = best[i].min(t.elapsed().as_secs_f64() * 1e6);
            visits[i] = p.visits;
            pairs[i] = std::hint::black_box(p).pairs;
        }
    }
    let mut sorted = best.clone();
    sorted.sort_by(f64::total_cmp);
    let q = |x: f64| sorted[((n - 1) as f64 * x).round() as usize];
    let worst = (0..n)
        .max_by(|&i, &j| best[i].total_cmp(&best[j]))
        .unwrap_or(0);
    println!(
        "{n} frames, best of {passes}: p50 {:.1} µs, p99 {:.1} µs, max {:.1} µs (frame {worst}, {} leaf pairs); most leaf pairs {}",
        q(0.5),
        q(0.99),
        best[worst],
        pairs[worst],
        pairs.iter().max().unwrap_or(&0)
    );
    let mut tests = visits.clone();
    tests.sort_unstable();
    println!(
        "node-pair tests: {} in all, p99 {}, max {}",
        visits.iter().sum::<u64>(),
        tests[((n - 1) as f64 * 0.99).round() as usize],
        tests[n - 1]
    );
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&i, &j| best[j].total_cmp(&best[i]));
    for &i in order.iter().take(env("TOP").unwrap_or(0)) {
        println!(
            "frame {i}: {:.1} µs, {} leaf pairs, {} tests",
            best[i], pairs[i], visits[i]
        );
    }
    Ok(())
}
