use innersphere::*;
fn main() {
    let dir = std::path::Path::new("target/bench-trees");
    let a = SharedTree::new(SphereTree::load(dir.join("maxilla_0.1_m0.05_r8.ist")).unwrap());
    let b = SharedTree::new(SphereTree::load(dir.join("mandible_0.1_m0.05_r8.ist")).unwrap());
    let m = innersphere_motion::Motion::load(
        std::env::args()
            .nth(1)
            .unwrap_or("target/bench-trees/motion_chew_seed1_3s.csv".into()),
    )
    .unwrap();
    let passes: usize = std::env::var("PASSES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let lin = std::env::var_os("LIN").is_some();
    let mut opts = PenetrationOptions {
        linearize: lin,
        ..Default::default()
    };
    if let Some(p) = std::env::var("MAXP").ok().and_then(|s| s.parse().ok()) {
        opts.max_patches = p;
    }
    let mut times = vec![0f64; m.frames.len()];
    let mut pairs = vec![0usize; m.frames.len()];
    let mut visits = vec![0u64; m.frames.len()];
    let mut answers = std::env::var_os("ANSWERS")
        .map(|p| std::io::BufWriter::new(std::fs::File::create(p).unwrap()));
    let mut maxfront = 0usize;
    for _ in 0..passes {
        let mut pair = Pair::new(a.clone(), b.clone());
        let lo: usize = std::env::var("START")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(0);
        let hi: usize = std::env::var("END")
            .ok()
            .and_then(|s| s.parse().ok())
            .unwrap_or(m.frames.len());
        for (i, f) in m.frames.iter().enumerate().take(hi).skip(lo) {
            let t = std::time::Instant::now();
            let p = pair.penetration_with(&Pose::IDENTITY, &f.pose, &opts);
            let dt = t.elapsed().as_secs_f64() * 1e6;
            if times[i] == 0.0 || dt < times[i] {
                times[i] = dt;
            }
            pairs[i] = p.pairs;
            if let Some(w) = answers.as_mut() {
                use std::io::Write;
                let pt: Vec<String> = pair
                    .patches()
                    .iter()
                    .map(|q| {
                        format!(
                            "{:e} {:e} {:e} {:e}",
                            q.volume, q.point.x, q.point.y, q.point.z
                        )
                    })
                    .collect();
                writeln!(
                    w,
                    "{i} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {:e} {} | {}",
                    p.volume,
                    p.force.x,
                    p.force.y,
                    p.force.z,
                    p.torque_b.x,
                    p.torque_b.y,
                    p.torque_b.z,
                    p.max_depth,
                    p.pairs,
                    pt.join(" ")
                )
                .unwrap();
            }
            visits[i] = p.visits;
            let fs = pair.front_size();
            maxfront = maxfront.max(fs.0 + fs.1);
            std::hint::black_box(p);
        }
    }
    let mut s = times.clone();
    s.sort_by(f64::total_cmp);
    let q = |x: f64| s[((s.len() - 1) as f64 * x).round() as usize];
    let mx = times
        .iter()
        .cloned()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .unwrap();
    println!(
        "p50 {:.1} p99 {:.1} max {:.1} [frame {} pairs {} visits {}] maxpairs {}",
        q(0.5),
        q(0.99),
        mx.1,
        mx.0,
        pairs[mx.0],
        visits[mx.0],
        pairs.iter().max().unwrap()
    );
    println!("max front {maxfront}");
    if std::env::var_os("TOP").is_some() {
        let mut idx: Vec<usize> = (0..times.len()).collect();
        idx.sort_by(|&x, &y| times[y].total_cmp(&times[x]));
        for &i in idx.iter().take(15) {
            println!(
                "frame {} {:.1} us pairs {} visits {}",
                i, times[i], pairs[i], visits[i]
            );
        }
    }
}
