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
