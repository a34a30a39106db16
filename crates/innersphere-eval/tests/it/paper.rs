//! `eval::paper` on the generated tooth pair: every figure's CSV and chart is written, the
//! sweep's leaf counts grow as the voxels shrink and its error is finite and non-negative.

use innersphere::build::{BuildOptions, Resolution};
use innersphere_eval::motion::{generate, Scenario};
use innersphere_eval::paper::{run, PaperOptions, FILES};

#[test]
fn paper_figures_on_the_tooth_pair() {
    let (ma, mb) = innersphere::shapes::tooth_pair(3);
    let motion = generate(Scenario::Chew, 2.5, 7, &ma, &mb).unwrap();
    let (lo, hi) = ma.bbox();
    let size = (hi - lo).max_element();
    let mut o = PaperOptions::for_size(size);
    o.voxel_sizes = vec![size / 16.0, size / 32.0];
    o.fanouts = vec![2, 8];
    o.fanout_leaves = vec![200];
    o.ks = vec![1, 4];
    o.every = 5;
    o.main = BuildOptions {
        resolution: Resolution::VoxelSize(size / 32.0),
        ..Default::default()
    };
    let dir = std::env::temp_dir().join(format!("innersphere-paper-{}", std::process::id()));
    let mut lines = 0;
    let s = run(&ma, &mb, &motion, &o, &dir, &mut |_| lines += 1).unwrap();
    assert!(lines >= 4);
    // The backtracking chart needs frames in contact, which coarse trees may not reach.
    assert!(s.files.len() >= 11, "{:?}", s.files);
    // Every file written is listed in FILES (what the CLI checks against its inputs), and no
    // temporary file is left behind.
    for entry in std::fs::read_dir(&dir).unwrap() {
        let name = entry.unwrap().file_name().to_string_lossy().into_owned();
        assert!(FILES.contains(&name.as_str()), "{name} is not in FILES");
    }
    for f in &s.files {
        let p = dir.join(f);
        let len = std::fs::metadata(&p).unwrap().len();
        assert!(len > 100, "{f} is nearly empty");
    }
    // Fig. 9: one row per voxel size, more leaves for smaller voxels, sane errors.
    let err = std::fs::read_to_string(dir.join("fig9_error_vs_leaves.csv")).unwrap();
    let rows: Vec<Vec<f64>> = err
        .lines()
        .skip(1)
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(rows.len(), 2);
    assert!(rows[1][1] > rows[0][1], "leaves must grow as voxels shrink");
    for r in &rows {
        assert!(r[3].is_finite() && r[3] >= 0.0, "abs error p50 {}", r[3]);
    }
    // Fig. 6: five query kinds per voxel size.
    let speed = std::fs::read_to_string(dir.join("fig6_speed_vs_leaves.csv")).unwrap();
    assert_eq!(speed.lines().count(), 1 + 2 * 5);
    // Multipoint: one row per k.
    let mp = std::fs::read_to_string(dir.join("multipoint_k.csv")).unwrap();
    assert_eq!(mp.lines().count(), 3);
    std::fs::remove_dir_all(&dir).ok();
}
