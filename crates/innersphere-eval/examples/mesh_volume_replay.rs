//! The meshes' exact intersection volume along a motion (`exact::intersection_volume`), per
//! frame the fastest of N passes, and a CSV of every frame's answer for an independent
//! check (`tools/mesh-volume-check/check.py` recomputes the volumes with manifold3d).
//!
//! `cargo run --release -p innersphere-eval --example mesh_volume_replay -- A.stl B.stl
//! MOTION.csv OUT.csv` with `PASSES` (default 3) and `EVERY` (every Nth frame, default 1);
//! `TREES=A.ist,B.ist` adds the sphere packings' penetration volume and normal per frame
//! (`Pair::penetration` on those trees, a fresh pair per frame) beside it, for the side by
//! side of docs/RESULTS.md.

use innersphere::exact::{intersection_volume, ExactMesh, ExactScratch};
use innersphere::glam::DVec3;
use innersphere::{Mesh, Pair, Pose, SharedTree, SphereTree};
use std::fmt::Write as _;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b, motion, out] = args.as_slice() else {
        return Err("usage: mesh_volume_replay A.stl B.stl MOTION.csv OUT.csv".into());
    };
    let env = |k: &str| std::env::var(k).ok().and_then(|s| s.parse::<usize>().ok());
    let passes = env("PASSES").unwrap_or(3).max(1);
    let every = env("EVERY").unwrap_or(1).max(1);
    let t0 = Instant::now();
    let (ma, mb) = (Mesh::load(a)?, Mesh::load(b)?);
    let (ea, eb) = (ExactMesh::new(&ma)?, ExactMesh::new(&mb)?);
    eprintln!(
        "prepared both meshes in {:.2} s",
        t0.elapsed().as_secs_f64()
    );
    let com_b = mb
        .mass_properties()
        .map_or(DVec3::ZERO, |m| m.center_of_mass);
    let m = innersphere_motion::Motion::load(motion)?;
    let frames: Vec<usize> = (0..m.frames.len()).step_by(every).collect();
    let mut best = vec![f64::INFINITY; frames.len()];
    let mut answers = vec![Default::default(); frames.len()];
    let mut scratch = ExactScratch::new();
    for _ in 0..passes {
        for (k, &i) in frames.iter().enumerate() {
            let pose = m.frames[i].pose;
            let t = Instant::now();
            let v = intersection_volume(&ea, &Pose::IDENTITY, &eb, &pose, com_b, &mut scratch);
            best[k] = best[k].min(t.elapsed().as_secs_f64() * 1e6);
            answers[k] = std::hint::black_box(v);
        }
    }
    // The spheres' answers on the same frames, where trees are given.
    let spheres: Option<Vec<innersphere::Penetration>> = match std::env::var("TREES") {
        Ok(t) => {
            let (ta, tb) = t.split_once(',').ok_or("TREES=A.ist,B.ist")?;
            let (ta, tb) = (
                SharedTree::new(SphereTree::load(ta)?),
                SharedTree::new(SphereTree::load(tb)?),
            );
            Some(
                frames
                    .iter()
                    .map(|&i| {
                        let mut pair = Pair::new(ta.clone(), tb.clone());
                        pair.penetration(&Pose::IDENTITY, &m.frames[i].pose)
                    })
                    .collect(),
            )
        }
        Err(_) => None,
    };
    let mut csv = String::from(
        "frame,tx,ty,tz,qw,qx,qy,qz,volume,gx,gy,gz,rx,ry,rz,crossing_pairs,us,sphere_volume,snx,sny,snz\n",
    );
    for (k, &i) in frames.iter().enumerate() {
        let p = m.frames[i].pose.to_array();
        let v: &innersphere::exact::MeshOverlap = &answers[k];
        let _ = writeln!(
            csv,
            "{i},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.1},{}",
            p[0],
            p[1],
            p[2],
            p[3],
            p[4],
            p[5],
            p[6],
            v.volume,
            v.gradient.x,
            v.gradient.y,
            v.gradient.z,
            v.rotation_gradient.x,
            v.rotation_gradient.y,
            v.rotation_gradient.z,
            v.crossing_pairs,
            best[k],
            spheres.as_ref().map_or(",,,".to_string(), |s| {
                let p = &s[k];
                format!("{},{},{},{}", p.volume, p.normal.x, p.normal.y, p.normal.z)
            })
        );
    }
    std::fs::write(out, csv)?;
    let mut touching: Vec<f64> = (0..frames.len())
        .filter(|&k| answers[k].volume > 0.0)
        .map(|k| best[k])
        .collect();
    touching.sort_by(f64::total_cmp);
    let q = |s: &[f64], x: f64| {
        s.get(((s.len().max(1) - 1) as f64 * x).round() as usize)
            .copied()
    };
    println!(
        "{} frames ({} overlapping), best of {passes}: overlapping p50 {:?} µs, p99 {:?} µs, max {:?} µs",
        frames.len(),
        touching.len(),
        q(&touching, 0.5),
        q(&touching, 0.99),
        touching.last()
    );
    Ok(())
}
