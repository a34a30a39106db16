//! An accuracy experiment (docs/RESULTS.md, "Error against sphere count"): the inner-sphere
//! distance refined by the exact distance between the triangles near its closest leaves.
//!
//! `cargo run --release -p innersphere-eval --example local_refine -- A.ist B.ist MESH_A
//! MESH_B MOTION.csv [EVERY] [SCALE]`: on every EVERY-th separated frame (default 5), the
//! triangles of each mesh within `SCALE · max(ra, rb) + 0.05` (default SCALE 2) of the closest
//! leaf pair's points, all their pairs' exact distances, the smallest of them and the sphere
//! distance; printed: the error of both against the exact mesh distance and the triangle
//! pairs per frame and the time to measure all of them (no pruning). The refined distance lies between the exact one and the sphere
//! distance (a subset's minimum). The triangles are found by a scan of the whole mesh: this
//! measures accuracy, not time.

use innersphere::exact::{self, ExactMesh};
use innersphere::glam::DVec3;
use innersphere::{Mesh, Pair, Pose, SharedTree, SphereTree};

fn near(mesh: &Mesh, p: DVec3, rho: f64) -> Vec<[DVec3; 3]> {
    mesh.triangles
        .iter()
        .map(|t| t.map(|i| mesh.vertices[i as usize]))
        .filter(|t| {
            let c = (t[0] + t[1] + t[2]) / 3.0;
            let reach = t.iter().map(|v| (*v - c).length()).fold(0.0, f64::max);
            (c - p).length() <= rho + reach
        })
        .collect()
}

fn q(v: &mut [f64], x: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * x).round() as usize]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let every: usize = args.get(5).and_then(|s| s.parse().ok()).unwrap_or(5);
    let scale: f64 = args.get(6).and_then(|s| s.parse().ok()).unwrap_or(2.0);
    let ta = SharedTree::new(SphereTree::load(&args[0])?);
    let tb = SharedTree::new(SphereTree::load(&args[1])?);
    let ma = Mesh::load(&args[2])?;
    let mb = Mesh::load(&args[3])?;
    let (ea, eb) = (ExactMesh::new(&ma)?, ExactMesh::new(&mb)?);
    let m = innersphere_motion::Motion::load(&args[4])?;
    let mut pair = Pair::new(ta.clone(), tb.clone());
    let mut scratch = exact::ExactScratch::new();
    let (mut raw, mut refined, mut counts) = (Vec::new(), Vec::new(), Vec::new());
    let mut micros = Vec::new();
    for (i, f) in m.frames.iter().enumerate() {
        if i % every != 0 {
            continue;
        }
        let d = pair.distance(&Pose::IDENTITY, &f.pose);
        let x = exact::distance(&ea, &Pose::IDENTITY, &eb, &f.pose, &mut scratch);
        if d.overlapping || x.intersecting || x.distance <= 0.0 {
            continue;
        }
        let ra = ta.sphere(d.leaf_a as usize).1 as f64;
        let rb = tb.sphere(d.leaf_b as usize).1 as f64;
        let rho = scale * ra.max(rb) + 0.05;
        let na = near(&ma, d.point_a, rho);
        let inv = f.pose.inverse();
        let nb: Vec<[DVec3; 3]> = near(&mb, inv.transform_point(d.point_b), rho)
            .into_iter()
            .map(|t| t.map(|v| f.pose.transform_point(v)))
            .collect();
        let t = std::time::Instant::now();
        let mut best = d.distance;
        for a in &na {
            for b in &nb {
                best = best.min(exact::tri_tri::triangle_distance(a, b).dist_sq.sqrt());
            }
        }
        micros.push(t.elapsed().as_secs_f64() * 1e6);
        raw.push(d.distance - x.distance);
        refined.push(best - x.distance);
        counts.push((na.len() * nb.len()) as f64);
    }
    println!(
        "{} separated frames, radius {scale}·max r + 0.05: spheres p50 {:.4} p95 {:.4} max {:.4}; refined p50 {:.5} p95 {:.5} max {:.5}; triangle pairs p50 {} p95 {}, all of them in p50 {:.1} p95 {:.1} µs",
        raw.len(),
        q(&mut raw, 0.5),
        q(&mut raw, 0.95),
        q(&mut raw, 1.0),
        q(&mut refined, 0.5),
        q(&mut refined, 0.95),
        q(&mut refined, 1.0),
        q(&mut counts, 0.5),
        q(&mut counts, 0.95),
        q(&mut micros, 0.5),
        q(&mut micros, 0.95)
    );
    Ok(())
}
