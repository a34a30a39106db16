//! The Rust answers the C test (`tests/c/abi_test.c`) must reproduce bit for bit, printed in
//! the same format: `tests/c/run.sh` diffs the two.
//!
//! `reference make DIR`: writes generated trees (a tooth pair), the query poses and a device
//! trajectory into DIR. `reference answer DIR`: prints the answers of every query at every
//! pose and of the haptic loop along the trajectory, through the Rust API.

use innersphere::glam::{DQuat, DVec3};
use innersphere::query::TraversalOptions;
use innersphere::{shapes, BuildOptions, MultipointOptions, Pair, Pose, Resolution, SphereTree};
use innersphere::{PenetrationOptions, SharedTree};
use innersphere_haptic::{DeviceClass, HapticLoop, HapticOptions};
use std::fmt::Write as _;
use std::path::Path;

fn bits(x: f64) -> String {
    format!("{:016x}", x.to_bits())
}

fn v(x: DVec3) -> String {
    format!("{} {} {}", bits(x.x), bits(x.y), bits(x.z))
}

fn pose_line(p: &Pose) -> String {
    let a = p.to_array();
    a.map(|x| format!("{x:.17e}")).join(" ")
}

fn read_poses(path: &Path) -> Vec<Vec<f64>> {
    std::fs::read_to_string(path)
        .unwrap()
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
        .collect()
}

fn pose(x: &[f64]) -> Pose {
    Pose::from_array(x.try_into().unwrap()).unwrap()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let dir = Path::new(&args[2]);
    match args[1].as_str() {
        "make" => make(dir),
        "answer" => print!("{}", answer(dir)),
        other => panic!("unknown command {other}"),
    }
}

fn make(dir: &Path) {
    let (upper, lower) = shapes::tooth_pair(4);
    let opts = BuildOptions {
        resolution: Resolution::Cells(48),
        ..Default::default()
    };
    SphereTree::build(&upper, &opts)
        .unwrap()
        .save(dir.join("a.ist"))
        .unwrap();
    SphereTree::build(&lower, &opts)
        .unwrap()
        .save(dir.join("b.ist"))
        .unwrap();
    // The meshes, for the refined distance.
    innersphere::mesh::io::save_stl(&upper, &dir.join("a.stl")).unwrap();
    innersphere::mesh::io::save_stl(&lower, &dir.join("b.stl")).unwrap();
    // Poses of A and B: apart, near, touching, overlapping, turned.
    let mut s = String::new();
    let a0 = Pose::IDENTITY;
    let a1 = Pose::new(DVec3::new(0.5, -0.3, 0.2), DQuat::from_rotation_z(0.3)).unwrap();
    for (i, dz) in [-6.0, -1.0, -0.3, 0.0, 0.2, 0.6].iter().enumerate() {
        let b = Pose::new(
            DVec3::new(0.1 * i as f64, -0.05, *dz),
            DQuat::from_rotation_x(0.02 * i as f64),
        )
        .unwrap();
        for a in [a0, a1] {
            let _ = writeln!(s, "{} {}", pose_line(&a), pose_line(&a.then(&b)));
        }
    }
    std::fs::write(dir.join("poses.txt"), s).unwrap();
    // A device trajectory of B (A at the identity): closing in, pressing, sliding, leaving.
    let mut d = String::new();
    let mut csv = String::from("t,tx,ty,tz,qw,qx,qy,qz\n");
    for i in 0..600 {
        let t = i as f64 / 1000.0;
        let z = -2.0 + 2.3 * (t / 0.3).min(1.0) - 2.3 * ((t - 0.45) / 0.15).clamp(0.0, 1.0);
        let p = Pose::new(
            DVec3::new(0.3 * (t * 10.0).sin(), 0.0, z),
            DQuat::from_rotation_z(0.05 * t),
        )
        .unwrap();
        let _ = writeln!(d, "{}", pose_line(&p));
        let _ = writeln!(csv, "{t},{}", pose_line(&p).replace(' ', ","));
    }
    std::fs::write(dir.join("device.txt"), d).unwrap();
    std::fs::write(dir.join("device.csv"), csv).unwrap();
}

// Over 120 lines: the reference answers, one query after another as the C test asks them,
// kept in that order so that the two files read side by side.
fn answer(dir: &Path) -> String {
    let a = SharedTree::new(SphereTree::load(dir.join("a.ist")).unwrap());
    let b = SharedTree::new(SphereTree::load(dir.join("b.ist")).unwrap());
    let mesh = |f: &str| innersphere::Mesh::load(dir.join(f)).unwrap();
    let (ma, mb) = (
        a.clone().with_mesh(&mesh("a.stl")).unwrap(),
        b.clone().with_mesh(&mesh("b.stl")).unwrap(),
    );
    let mut refined = Pair::new(ma, mb);
    let mut out = String::new();
    let mut pair = Pair::new(a.clone(), b.clone());
    for (i, p) in read_poses(&dir.join("poses.txt")).iter().enumerate() {
        let (pa, pb) = (pose(&p[..7]), pose(&p[7..]));
        let d = pair.distance(&pa, &pb);
        let _ = writeln!(
            out,
            "{i} distance {} {} {} {}",
            bits(d.distance),
            d.overlapping as i32,
            v(d.point_a),
            v(d.point_b)
        );
        let r = refined.refined_distance(&pa, &pb).unwrap();
        let _ = writeln!(
            out,
            "{i} refined {} {} {} {} {} {} {} {} {}",
            bits(r.distance),
            r.intersecting as i32,
            r.refined as i32,
            r.complete as i32,
            v(r.point_a),
            v(r.point_b),
            r.tri_a,
            r.tri_b,
            bits(r.spheres.distance)
        );
        let c = pair.contact(&pa, &pb);
        let _ = writeln!(out, "{i} contact {}", c.contact.is_some() as i32);
        let t = TraversalOptions::default();
        let dt = pair.paper().distance_traversal(&pa, &pb, &t).in_contact();
        let bt = pair.paper().backtracking(&pa, &pb, &t).in_contact();
        let _ = writeln!(out, "{i} traversals {} {}", dt as i32, bt as i32);
        let w = pair.penetration_within_with(
            &pa,
            &pb,
            500,
            &PenetrationOptions {
                stiffness: 2.5,
                ..Default::default()
            },
        );
        let _ = writeln!(
            out,
            "{i} within {} {} {} {} {} {} {} {}",
            bits(w.volume),
            bits(w.upper_bound),
            w.complete as i32,
            bits(w.max_depth),
            v(w.normal),
            v(w.force),
            v(w.torque_b),
            w.visits
        );
        let opts = PenetrationOptions {
            stiffness: 2.5,
            ..Default::default()
        };
        let q = pair.penetration_with(&pa, &pb, &opts);
        let _ = writeln!(
            out,
            "{i} penetration {} {} {} {} {} {} {}",
            bits(q.volume),
            bits(q.max_depth),
            v(q.normal),
            v(q.force),
            v(q.torque_a),
            v(q.torque_b),
            q.patch_count
        );
        for (j, x) in pair.patches().iter().enumerate() {
            let _ = writeln!(
                out,
                "{i} patch {j} {} {} {} {} {}",
                v(x.point),
                v(x.normal),
                bits(x.depth),
                bits(x.volume),
                x.pairs
            );
        }
        let m = MultipointOptions {
            k: 8,
            ..Default::default()
        };
        pair.multipoint(&pa, &pb, &m);
        let cs = pair.contacts();
        let _ = writeln!(out, "{i} multipoint {}", cs.len().min(8));
        for (j, c) in cs.iter().take(8).enumerate() {
            let _ = writeln!(
                out,
                "{i} contact_point {j} {} {} {} {} {}",
                v(c.point),
                v(c.normal),
                bits(c.depth),
                c.leaf_a,
                c.leaf_b
            );
        }
    }
    // The haptic loop along the device trajectory (budget 1 s: the same path every run).
    let mut o = HapticOptions::for_device(DeviceClass::Omega);
    o.budget = 1.0;
    o.contact_stiffness = 2.0;
    let dev = read_poses(&dir.join("device.txt"));
    let mut hl = HapticLoop::new(Pair::new(a, b), Pose::IDENTITY, pose(&dev[0]), o).unwrap();
    for (i, p) in dev.iter().enumerate() {
        let t = hl.tick_step(&pose(p), 0.001);
        let tool = t.tool.to_array().map(bits).join(" ");
        let _ = writeln!(
            out,
            "{i} tick {} {} {} {} {}",
            v(t.force),
            v(t.torque),
            tool,
            bits(t.volume),
            bits(t.max_depth)
        );
    }
    let _ = writeln!(out, "energy {}", bits(hl.energy_to_user()));
    out
}
