use innersphere::query::*;
use std::time::Instant;
#[test]
#[ignore]
fn pen_stats() {
    let a = innersphere::tree::file::load(std::path::Path::new("/work/main/target/bench-trees/maxilla_0.15.ist")).unwrap();
    let b = innersphere::tree::file::load(std::path::Path::new("/work/main/target/bench-trees/mandible_0.15.ist")).unwrap();
    let text = std::fs::read_to_string("/work/shared/data/motion/jaw_chew_demo.csv").unwrap();
    let poses: Vec<Pose> = text.lines().skip(1).map(|l| { let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect(); Pose::from_array([v[1],v[2],v[3],v[4],v[5],v[6],v[7]]).unwrap() }).collect();
    let mut st = PairState::new(&a, &b);
    let id = Pose::IDENTITY;
    let opts = PenetrationOptions { tracking: false, safe_motion: false, ..Default::default() };
    let mode = std::env::var("MODE").unwrap_or_default();
    for f in [400usize, 600, 700, 800, 900, 1500] {
        let p = &poses[f];
        let mut best = f64::MAX; let mut vis = 0;
        for _ in 0..7 {
            let t0 = Instant::now();
            vis = match mode.as_str() {
                "prox" => proximity(&a, &id, &b, p, &mut st, &ProximityOptions { coherence: false, ..Default::default() }).visits,
                "full" => distance_traversal(&a, &id, &b, p, &mut st, &ContactOptions { safe_motion: false }).visits,
                _ => penetration(&a, &id, &b, p, &mut st, &opts).visits,
            };
            best = best.min(t0.elapsed().as_secs_f64() * 1e6);
        }
        println!("{f:5} {best:9.1}us visits {vis:7} ns/visit {:.1}", best * 1e3 / vis as f64);
    }
}
