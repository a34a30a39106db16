//! `ist bench build`: the whole build on real meshes, stage by stage, for BENCHMARKS.md.

use innersphere::build::{build_tree, BuildOptions};
use innersphere::progress::Silent;
use innersphere::Result;
use std::path::Path;
use std::time::Instant;

/// One measured build.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BuildBenchRow {
    /// Mesh file name.
    pub mesh: String,
    /// Triangles of the mesh.
    pub triangles: usize,
    /// Voxel size used.
    pub voxel_size: f64,
    /// Inside voxels.
    pub voxels_inside: usize,
    /// Inner spheres.
    pub spheres: usize,
    /// Tree depth.
    pub depth: u16,
    /// Coverage (sphere volume / mesh volume).
    pub coverage: f64,
    /// Median over repeats of the load time (s).
    pub load_s: f64,
    /// Median of the distance-field time (s).
    pub distance_field_s: f64,
    /// Median of the packing time (s).
    pub packing_s: f64,
    /// Median of the hierarchy time (s).
    pub hierarchy_s: f64,
    /// Median of the total (load + build) time (s).
    pub total_s: f64,
    /// Fastest total (s).
    pub total_min_s: f64,
    /// Slowest total (s).
    pub total_max_s: f64,
    /// Peak resident memory of the process after this build (bytes; includes earlier ones).
    pub peak_memory_bytes: Option<u64>,
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Loads and builds `mesh_path` `repeats` times and reports medians per stage.
pub fn bench_build(mesh_path: &Path, opts: &BuildOptions, repeats: usize) -> Result<BuildBenchRow> {
    let repeats = repeats.max(1);
    let (mut load, mut field, mut pack, mut hier, mut total) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut last = None;
    for _ in 0..repeats {
        let t0 = Instant::now();
        let mesh = innersphere::mesh::io::load(mesh_path)?;
        let t_load = t0.elapsed().as_secs_f64();
        let (_tree, report) = build_tree(&mesh, opts, &Silent)?;
        total.push(t0.elapsed().as_secs_f64());
        load.push(t_load);
        field.push(report.stage_seconds.distance_field);
        pack.push(report.stage_seconds.packing);
        hier.push(report.stage_seconds.hierarchy);
        last = Some(report);
    }
    let r = last.expect("at least one repeat");
    let (tmin, tmax) = total
        .iter()
        .fold((f64::MAX, 0.0f64), |(a, b), &t| (a.min(t), b.max(t)));
    Ok(BuildBenchRow {
        mesh: mesh_path
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default(),
        triangles: r.mesh.triangles,
        voxel_size: r.voxel_size,
        voxels_inside: r.voxels_inside,
        spheres: r.spheres,
        depth: r.depth,
        coverage: r.coverage,
        load_s: median(&mut load),
        distance_field_s: median(&mut field),
        packing_s: median(&mut pack),
        hierarchy_s: median(&mut hier),
        total_s: median(&mut total),
        total_min_s: tmin,
        total_max_s: tmax,
        peak_memory_bytes: super::sysinfo::peak_memory_bytes(),
    })
}

/// One thread count of [`bench_batch`].
#[derive(Debug, Clone, serde::Serialize)]
pub struct BatchBenchRow {
    /// Worker threads.
    pub threads: usize,
    /// Best wall time of the repeats, s.
    pub seconds: f64,
    /// Poses per second at the best time.
    pub poses_per_second: f64,
    /// Speed over the first row's.
    pub speedup: f64,
    /// Whether the answers equal the first row's bit for bit.
    pub same_answers: bool,
}

/// `n` poses of B around the identity (where a scanned jaw pair bites): a rotation of up to
/// `deg` degrees about a random axis through `centre` and a shift of up to `mm` along each
/// axis, from `seed` (xorshift64*; the same seed gives the same poses).
pub fn perturbed_poses(
    n: usize,
    seed: u64,
    mm: f64,
    deg: f64,
    centre: innersphere::glam::DVec3,
) -> Vec<innersphere::Pose> {
    use innersphere::glam::{DQuat, DVec3};
    let mut s = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
    let mut u = move || {
        s ^= s >> 12;
        s ^= s << 25;
        s ^= s >> 27;
        (s.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    (0..n)
        .map(|_| {
            let axis = loop {
                let v = DVec3::new(u(), u(), u());
                if v.length_squared() > 1e-6 && v.length_squared() <= 1.0 {
                    break v.normalize();
                }
            };
            let q = DQuat::from_axis_angle(axis, u() * deg.to_radians());
            let t = centre - q * centre + DVec3::new(u(), u(), u()) * mm;
            innersphere::Pose::new(t, q).expect("finite")
        })
        .collect()
}

/// Times the batch of `query` ("distance", "refined-distance" or "mesh-penetration" (both
/// trees with their meshes), "contact" or "penetration") over `poses` on each thread count of `threads`, the
/// best of `repeats`, and checks that every count answers the first's bits.
pub fn bench_batch(
    a: &innersphere::SharedTree,
    b: &innersphere::SharedTree,
    poses: &[innersphere::Pose],
    query: &str,
    threads: &[usize],
    chunk: usize,
    repeats: usize,
) -> Result<Vec<BatchBenchRow>> {
    use innersphere::query::batch::{self, BatchOptions};
    let id = [innersphere::Pose::IDENTITY];
    let run = |t: usize| -> Result<Vec<u64>> {
        let o = BatchOptions { threads: t, chunk };
        Ok(match query {
            "distance" => batch::distance_many(a, b, &id, poses, &o)?
                .iter()
                .map(|d| d.distance.to_bits())
                .collect(),
            "refined-distance" => {
                batch::refined_distance_many(a, b, &id, poses, &Default::default(), &o)?
                    .iter()
                    .flat_map(|r| [r.distance.to_bits(), r.tri_a as u64, r.tri_b as u64])
                    .collect()
            }
            "contact" => batch::contact_many(a, b, &id, poses, &o)?
                .iter()
                .map(|c| c.in_contact() as u64)
                .collect(),
            "penetration" => batch::penetration_many(a, b, &id, poses, &Default::default(), &o)?
                .iter()
                .flat_map(|p| {
                    [
                        p.volume.to_bits(),
                        p.force.x.to_bits(),
                        p.torque_b.z.to_bits(),
                    ]
                })
                .collect(),
            "mesh-penetration" => {
                batch::mesh_penetration_many(a, b, &id, poses, &Default::default(), &o)?
                    .iter()
                    .flat_map(|m| {
                        [
                            m.volume.to_bits(),
                            m.force.x.to_bits(),
                            m.torque_b.z.to_bits(),
                        ]
                    })
                    .collect()
            }
            other => {
                return Err(innersphere::Error::InvalidOption(format!(
                    "query must be distance, refined-distance, contact, penetration or mesh-penetration, not {other}"
                )))
            }
        })
    };
    let mut rows: Vec<BatchBenchRow> = Vec::new();
    let mut first: Option<Vec<u64>> = None;
    for &t in threads {
        let mut best = f64::INFINITY;
        let mut answers = Vec::new();
        for _ in 0..repeats.max(1) {
            let t0 = Instant::now();
            answers = run(t)?;
            best = best.min(t0.elapsed().as_secs_f64());
        }
        let same = first.as_ref().is_none_or(|f| *f == answers);
        first.get_or_insert(answers);
        let base = rows.first().map_or(best, |r| r.seconds);
        rows.push(BatchBenchRow {
            threads: t,
            seconds: best,
            poses_per_second: poses.len() as f64 / best,
            speedup: base / best,
            same_answers: same,
        });
    }
    Ok(rows)
}
