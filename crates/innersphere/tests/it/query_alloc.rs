//! Queries allocate nothing and take no lock: a counting global allocator (this test binary
//! only, `alloc_util`) counts the allocations of every query kind and option of the public
//! API, from the first frame of a fresh [`Pair`] on (no warm-up) and on a second,
//! different motion after the first, on small generated trees. The same on the jaw arches
//! along a generated grind is `innersphere-eval`'s `tests/query_alloc_jaw.rs`.
//!
//! `INNERSPHERE_ALLOC_TRACE=1` prints a backtrace of every counted allocation.

use innersphere_testkit::alloc as alloc_util;

use crate::query_util;

use alloc_util::*;
use glam::DVec3;
use innersphere::{
    DistanceOptions, MultipointOptions, Pair, Pose, SharedTree, SphereTree, Tracking,
};
use query_util::*;

/// A motion of B against A in contact: `n` frames along which B, turning about `axis` by
/// `spin` radians per frame and sliding along `side`, is held along `dir` between `depth`
/// apart from first contact and `depth` pressed in beyond it (found per frame by bisection
/// on the signed distance); A moves rigidly too.
#[allow(clippy::too_many_arguments)]
fn pressing(
    a: &SphereTree,
    b: &SphereTree,
    dir: DVec3,
    side: DVec3,
    axis: DVec3,
    spin: f64,
    depth: f64,
    n: usize,
) -> Vec<(Pose, Pose)> {
    let mut pair = pair(a, b);
    let signed = DistanceOptions {
        signed: true,
        ..Default::default()
    };
    let reach = (a.r[0] + b.r[0]) as f64 * 1.1;
    let dir = dir.normalize();
    let side = (side - dir * side.dot(dir)).normalize_or_zero();
    let axis = axis.normalize();
    (0..n)
        .map(|i| {
            let s = i as f64 / n as f64 * std::f64::consts::TAU;
            let rot_b = glam::DQuat::from_axis_angle(axis, spin * i as f64);
            let pose_a = Pose::new(
                DVec3::new(0.1 * s.sin(), -0.2, 0.05 * i as f64 / n as f64),
                glam::DQuat::from_rotation_z(0.3 * s.sin()),
            )
            .unwrap();
            let lateral = side * 0.25 * reach * s.sin();
            let at = |t: f64| pair_poses(a, b, pose_a, rot_b, dir * t + lateral);
            let mut dist = |t: f64| {
                let (pa, pb) = at(t);
                pair.distance_with(&pa, &pb, &signed).distance
            };
            let (mut hi, mut lo) = (reach, reach);
            while dist(lo) > 0.0 && lo > -reach {
                hi = lo;
                lo -= reach / 32.0;
            }
            for _ in 0..40 {
                let m = 0.5 * (lo + hi);
                if dist(m) > 0.0 {
                    hi = m;
                } else {
                    lo = m;
                }
            }
            at(hi - depth * (3.0 * s).sin())
        })
        .collect()
}

/// The small trees' pairs: fan-outs 4/8 (pair-by-pair front), 2/3 and 4/2 (blocks), 8/8.
const PAIRS: [(usize, usize); 4] = [(0, 2), (1, 3), (0, 1), (2, 2)];

/// Two different motions in contact (up to 5 % of the smaller root radius pressed in).
fn contact_motions(a: &SphereTree, b: &SphereTree) -> [Vec<(Pose, Pose)>; 2] {
    let depth = 0.05 * a.r[0].min(b.r[0]) as f64;
    [
        pressing(
            a,
            b,
            DVec3::new(1.0, 0.3, 0.2),
            DVec3::Y,
            DVec3::new(0.2, 1.0, 0.1),
            0.01,
            depth,
            300,
        ),
        pressing(
            a,
            b,
            DVec3::new(-0.3, 1.0, 0.6),
            DVec3::Z,
            DVec3::new(1.0, -0.4, 0.3),
            0.003,
            depth,
            400,
        ),
    ]
}

#[test]
fn queries_allocate_nothing_from_the_first_frame() {
    let t = trees();
    for (ia, ib) in PAIRS {
        let (a, b) = (&t[ia], &t[ib]);
        let [m1, m2] = contact_motions(a, b);
        let (sa, sb) = (SharedTree::new(a.clone()), SharedTree::new(b.clone()));
        assert_allocation_free(&format!("trees {ia}, {ib}"), &sa, &sb, &m1, &m2);
    }
}

/// The demo's tooth pair at 24 cells, each tree with its mesh.
fn tooth_pair_with_meshes() -> (SharedTree, SharedTree) {
    let (upper, lower) = innersphere::shapes::tooth_pair(3);
    let opts = innersphere::BuildOptions {
        resolution: innersphere::Resolution::Cells(24),
        ..Default::default()
    };
    let tree = |m: &innersphere::Mesh| {
        SharedTree::new(SphereTree::build(m, &opts).unwrap())
            .with_mesh(m)
            .unwrap()
    };
    (tree(&upper), tree(&lower))
}

/// The refined distance (the trees with their meshes: the demo's tooth pair) allocates
/// nothing from the first frame, pressed in and pulled apart, with every option of the
/// matrix; the other kinds on the same trees too.
#[test]
fn the_refined_distance_allocates_nothing_from_the_first_frame() {
    let (a, b) = tooth_pair_with_meshes();
    let [m1, m2] = contact_motions(a.tree(), b.tree());
    // Apart as well: the local search runs only while the spheres are.
    let apart: Vec<(Pose, Pose)> = (0..200)
        .map(|i| {
            let s = i as f64 / 200.0 * std::f64::consts::TAU;
            let t = DVec3::new(0.8 * s.cos(), 0.5 * s.sin(), -0.2 - 0.6 * (1.0 + s.sin()));
            (Pose::IDENTITY, Pose::from_translation(t))
        })
        .collect();
    let m1: Vec<(Pose, Pose)> = m1.into_iter().chain(apart.iter().copied()).collect();
    let m2: Vec<(Pose, Pose)> = apart.into_iter().chain(m2).collect();
    assert_allocation_free("tooth pair with meshes", &a, &b, &m1, &m2);
}

/// The meshes' penetration allocates nothing once its scratch has grown: a warm-up pass
/// along both motions (pressed in and pulled apart), then the same poses again and a second
/// pass in reverse order, counted.
#[test]
fn the_meshes_penetration_allocates_nothing_after_a_warm_up() {
    let (a, b) = tooth_pair_with_meshes();
    let [m1, m2] = contact_motions(a.tree(), b.tree());
    let poses: Vec<(Pose, Pose)> = m1.into_iter().chain(m2).collect();
    let mut pair = Pair::new(a, b);
    let p = innersphere::PenetrationOptions::default();
    let mut touching = 0;
    for (pa, pb) in &poses {
        touching += pair.mesh_penetration_with(pa, pb, &p).unwrap().contact as usize;
    }
    assert!(
        touching > poses.len() / 4,
        "{touching} of {} frames touch",
        poses.len()
    );
    let (n, bytes, _) = counted(|| {
        for (pa, pb) in poses.iter().chain(poses.iter().rev()) {
            std::hint::black_box(pair.mesh_penetration_with(pa, pb, &p).unwrap());
        }
    });
    assert_eq!((n, bytes), (0, 0), "allocations after the warm-up");
}

/// Whether `kind` keeps something whose size a deep overlap, not the trees, decides: the
/// fronts, the best-first queue and the budgeted queue beyond its reservation.
fn grows_in_deep_overlap(kind: &Kind) -> bool {
    match kind {
        Kind::Contact => true,
        Kind::Multipoint(o) => o.tracking,
        Kind::Penetration(o) => o.tracking != Tracking::Traversal,
        Kind::Distance(o) => o.best_first,
        Kind::Budgeted(budget) => *budget >= 4096,
        Kind::Refined(_) => false,
        Kind::DistanceTraversal(_) | Kind::Backtracking(_) => false,
    }
}

/// Every kind whose scratch the trees bound, and one of each way of keeping a front (all
/// the tracked kinds share the one front; running each would only take time).
fn deep_sample(kind: &Kind) -> bool {
    match kind {
        Kind::Contact => true,
        Kind::Multipoint(o) if o.tracking => o.k == 256 && o.split_depth == 9,
        Kind::Penetration(o) if o.tracking != Tracking::Traversal => {
            o.max_patches == 64 && o.safe_motion == (o.tracking == Tracking::Auto)
        }
        _ => true,
    }
}

/// B swinging right through A (far deeper than any contact): what the trees bound allocates
/// nothing from the first frame; the fronts and queues grow a few times, once: the same
/// motions again allocate nothing.
#[test]
fn deep_overlap_grows_only_the_fronts_and_once() {
    let t = trees();
    for (ia, ib) in PAIRS {
        let (a, b) = (&t[ia], &t[ib]);
        let m1 = motion(
            a,
            b,
            DVec3::new(1.0, 0.3, 0.2),
            DVec3::Y,
            DVec3::new(0.2, 1.0, 0.1),
            0.01,
            200,
        );
        let m2 = motion(
            a,
            b,
            DVec3::new(-0.3, 1.0, 0.6),
            DVec3::Z,
            DVec3::new(1.0, -0.4, 0.3),
            0.03,
            240,
        );
        let (sa, sb) = (SharedTree::new(a.clone()), SharedTree::new(b.clone()));
        for kind in kinds().into_iter().filter(deep_sample) {
            let mut pair = Pair::new(&sa, &sb);
            let mut pass = || {
                counted(|| {
                    m1.iter()
                        .chain(&m2)
                        .map(|(pa, pb)| run(&kind, &mut pair, pa, pb))
                        .sum::<f64>()
                })
            };
            let (first, _, x) = pass();
            let (again, _, y) = pass();
            assert!(!(x + y).is_nan());
            let label = format!("trees {ia}, {ib}, {kind:?}");
            if grows_in_deep_overlap(&kind) {
                assert!(first <= 64, "{label}: {first} allocations");
            } else {
                assert_eq!(first, 0, "{label}");
            }
            assert_eq!(again, 0, "{label}: allocations after the same motions");
        }
    }
}

/// The counting allocator does count (the tests above are not vacuous): an allocation, a
/// growth and an allocation inside a pair's construction.
#[test]
fn the_counter_counts() {
    let (n, bytes, v) = counted(|| std::hint::black_box(vec![1u8; 10]));
    assert!(n == 1 && bytes == 10 && v.len() == 10);
    let mut w = Vec::<u64>::with_capacity(1);
    let (n, _, ()) = counted(|| {
        for i in 0..100 {
            std::hint::black_box(&mut w).push(i);
        }
    });
    assert!(n >= 1 && w.len() == 100);
    let t = trees();
    let (sa, sb) = (SharedTree::new(t[0].clone()), SharedTree::new(t[1].clone()));
    let (n, bytes, pair) = counted(|| Pair::new(&sa, &sb));
    assert!(n > 0 && bytes > 0 && pair.tree_a().info().nodes == t[0].len());
}

/// Identifiers in Rust source outside comments.
fn identifiers(src: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let mut block = 0usize;
    for line in src.lines() {
        let mut code = line;
        let mut kept = Vec::new();
        loop {
            if block > 0 {
                match (code.find("/*"), code.find("*/")) {
                    (Some(o), Some(c)) if o < c => {
                        block += 1;
                        code = &code[o + 2..];
                    }
                    (_, Some(c)) => {
                        block -= 1;
                        code = &code[c + 2..];
                    }
                    _ => break,
                }
            } else {
                let line_comment = code.find("//");
                match code.find("/*") {
                    Some(o) if line_comment.is_none_or(|l| o < l) => {
                        kept.push(&code[..o]);
                        block += 1;
                        code = &code[o + 2..];
                    }
                    _ => {
                        kept.push(&code[..line_comment.unwrap_or(code.len())]);
                        break;
                    }
                }
            }
        }
        for part in kept {
            out.extend(
                part.split(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
                    .filter(|w| !w.is_empty()),
            );
        }
    }
    out
}

/// Names of locks, lazy and one-time initialisation (each may block or take a lock).
const LOCKING: [&str; 20] = [
    "Mutex",
    "MutexGuard",
    "RwLock",
    "Condvar",
    "Barrier",
    "Once",
    "OnceLock",
    "OnceCell",
    "OnceState",
    "LazyLock",
    "LazyCell",
    "Lazy",
    "lazy_static",
    "once_cell",
    "parking_lot",
    "call_once",
    "get_or_init",
    "lock",
    "try_lock",
    "park",
];

/// The locking names used in `src` (outside comments).
fn locking_names(src: &str) -> Vec<&str> {
    identifiers(src)
        .into_iter()
        .filter(|w| LOCKING.contains(w))
        .collect()
}

/// No lock anywhere on the query path: the query sources (`src/query` and its
/// subdirectories) name no lock, lazy or one-time initialisation.
#[test]
fn no_locks_in_the_query_sources() {
    let mut dirs = vec![std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("src/query")];
    let mut checked = 0;
    while let Some(dir) = dirs.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                dirs.push(p);
            } else if p.extension().is_some_and(|x| x == "rs") {
                let s = std::fs::read_to_string(&p).unwrap();
                let found = locking_names(&s);
                assert!(found.is_empty(), "{} uses {found:?}", p.display());
                checked += 1;
            }
        }
    }
    assert!(checked >= 10);
}

/// The lock search finds every kind of lock in code and ignores comments.
#[test]
fn the_lock_search_finds_locks() {
    let cases = [
        "static S: std::sync::LazyLock<u32> = LazyLock::new(|| 1);",
        "static S: OnceLock<u32> = OnceLock::new();",
        "let c = std::cell::OnceCell::new();",
        "static O: std::sync::Once = std::sync::Once::new();",
        "let m = Mutex::new(0);",
        "let r: RwLock<u8> = Default::default();",
        "let (m, c) = (x, Condvar::new());",
        "let g = state.lock().unwrap();",
        "INIT.call_once(|| ());",
        "let v = CELL.get_or_init(f);",
        "let x = /* c */ Mutex::new(0);",
    ];
    for c in cases {
        assert!(!locking_names(c).is_empty(), "missed: {c}");
    }
    let clean =
        "// a Mutex in a comment\n/* Once\n LazyLock */ let blocked = 1; /// Once the front\n";
    assert!(locking_names(clean).is_empty());
}

/// Trees and pairs can be shared and sent across threads.
#[test]
fn trees_and_pairs_are_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<innersphere::SphereTree>();
    check::<Pair>();
    check::<innersphere::query::TreeInfo>();
}

/// Many pairs queried from many threads at once (shared immutable trees, one [`Pair`] per
/// pair of trees and thread) give the same answers as one thread.
#[test]
fn many_pairs_from_many_threads() {
    let t = trees();
    let pairs: Vec<(usize, usize)> = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).collect();
    let run = |ia: usize, ib: usize| -> Vec<(u64, u64, usize)> {
        let (a, b) = (&t[ia], &t[ib]);
        let frames = motion(
            a,
            b,
            DVec3::new(0.3, 1.0, 0.2),
            DVec3::Z,
            DVec3::X,
            0.02,
            80,
        );
        let mut pair = pair(a, b);
        frames
            .iter()
            .map(|(pa, pb)| {
                let d = pair.distance(pa, pb).distance;
                let v = pair.penetration(pa, pb).volume;
                pair.multipoint(pa, pb, &MultipointOptions::default());
                let c = pair.contacts().len();
                (d.to_bits(), v.to_bits(), c)
            })
            .collect()
    };
    let serial: Vec<_> = pairs.iter().map(|&(i, j)| run(i, j)).collect();
    let parallel: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = pairs
            .iter()
            .map(|&(i, j)| s.spawn(move || run(i, j)))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(serial, parallel);
}
