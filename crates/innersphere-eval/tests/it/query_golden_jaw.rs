//! Every query answer on the jaw arches along the recorded chew, bit for bit: a digest of all
//! answer bits per query kind (and of the node-pair tests, the work done), compared with
//! recorded digests. A change to any answer, or to the work a query does, changes a digest;
//! a deliberate change of an answer must update the digest here and say why in its commit.

use innersphere_testkit::data as common;

use innersphere::build::{build_tree, BuildOptions, Resolution};
use innersphere::glam::DVec3;
use innersphere::query::TraversalOptions;
use innersphere::{
    ContactResult, DistanceOptions, MultipointOptions, Pair, PenetrationOptions, Pose, Tracking,
};
use innersphere_eval::motion::Motion;

/// FNV-1a over the bits of everything fed to it.
struct Digest(u64);

impl Digest {
    fn new() -> Digest {
        Digest(0xcbf2_9ce4_8422_2325)
    }
    fn u(&mut self, x: u64) {
        for b in x.to_le_bytes() {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0100_0000_01b3);
        }
    }
    fn f(&mut self, x: f64) {
        self.u(x.to_bits())
    }
    fn v(&mut self, x: DVec3) {
        self.f(x.x);
        self.f(x.y);
        self.f(x.z);
    }
}

/// The query kinds and options compared.
const KINDS: [&str; 14] = [
    "proximity",
    "proximity best first",
    "proximity signed",
    "distance traversal",
    "backtracking",
    "contact",
    "multipoint k=16",
    "multipoint k=16 tracking",
    "penetration",
    "penetration traversal",
    "penetration front",
    "penetration budget 8000",
    "refined distance",
    "all kinds on one state",
];

/// Runs query kind `kind` (an index into [`KINDS`]) with state `st` at `pose_b` and feeds its
/// answer to `ans` and its node-pair tests to `work`.
fn query(kind: usize, st: &mut Pair, pose_b: &Pose, ans: &mut Digest, work: &mut Digest) {
    let pa = Pose::IDENTITY;
    let prox = |o: DistanceOptions, st: &mut Pair, ans: &mut Digest, work: &mut Digest| {
        let p = st.distance_with(&pa, pose_b, &o);
        ans.f(p.distance);
        ans.f(p.pair_distance);
        ans.f(p.lower_bound);
        ans.u(p.overlapping as u64);
        ans.v(p.point_a);
        ans.v(p.point_b);
        ans.v(p.normal);
        ans.u(p.leaf_a as u64);
        ans.u(p.leaf_b as u64);
        work.u(p.visits);
    };
    let cq = |q: ContactResult, ans: &mut Digest, work: &mut Digest| {
        ans.f(q.distance);
        ans.u(q.skipped as u64);
        match q.contact {
            None => ans.u(u64::MAX),
            Some(c) => {
                ans.u(c.leaf_a as u64);
                ans.u(c.leaf_b as u64);
                ans.v(c.point);
                ans.v(c.normal);
                ans.f(c.depth);
            }
        }
        work.u(q.visits);
    };
    let mp = |tracking: bool, st: &mut Pair, ans: &mut Digest, work: &mut Digest| {
        let o = MultipointOptions {
            k: 16,
            tracking,
            ..Default::default()
        };
        let m = st.multipoint(&pa, pose_b, &o);
        ans.u(m.count as u64);
        for c in st.contacts() {
            ans.u(c.leaf_a as u64);
            ans.u(c.leaf_b as u64);
            ans.v(c.point);
            ans.v(c.normal);
            ans.f(c.depth);
        }
        ans.u(m.reused as u64);
        ans.f(m.distance);
        ans.u(m.skipped as u64);
        work.u(m.visits);
    };
    let pen = |tracking: Tracking, st: &mut Pair, ans: &mut Digest, work: &mut Digest| {
        let o = PenetrationOptions {
            tracking,
            ..Default::default()
        };
        let p = st.penetration_with(&pa, pose_b, &o);
        ans.f(p.volume);
        ans.u(p.pairs as u64);
        ans.f(p.max_depth);
        ans.v(p.normal);
        ans.v(p.force);
        ans.v(p.torque_a);
        ans.v(p.torque_b);
        ans.u(p.patch_count as u64);
        for q in st.patches() {
            ans.v(q.point);
            ans.v(q.normal);
            ans.f(q.depth);
            ans.f(q.volume);
            ans.u(q.pairs as u64);
        }
        ans.f(p.distance);
        ans.u(p.skipped as u64);
        work.u(p.visits);
    };
    let co = TraversalOptions::default();
    match kind {
        0 => prox(DistanceOptions::default(), st, ans, work),
        1 => prox(
            DistanceOptions {
                best_first: true,
                ..Default::default()
            },
            st,
            ans,
            work,
        ),
        2 => prox(
            DistanceOptions {
                signed: true,
                ..Default::default()
            },
            st,
            ans,
            work,
        ),
        3 => cq(st.paper().distance_traversal(&pa, pose_b, &co), ans, work),
        4 => cq(st.paper().backtracking(&pa, pose_b, &co), ans, work),
        5 => cq(st.contact(&pa, pose_b), ans, work),
        6 => mp(false, st, ans, work),
        7 => mp(true, st, ans, work),
        8 => pen(Tracking::Auto, st, ans, work),
        9 => pen(Tracking::Traversal, st, ans, work),
        10 => pen(Tracking::Front, st, ans, work),
        11 => {
            let v = st.penetration_within(&pa, pose_b, 8000);
            ans.f(v.volume);
            ans.f(v.upper_bound);
            ans.u(v.complete as u64);
            work.u(v.visits);
        }
        12 => {
            let r = st.refined_distance(&pa, pose_b).unwrap();
            ans.f(r.distance);
            ans.v(r.point_a);
            ans.v(r.point_b);
            ans.u(r.tri_a as u64);
            ans.u(r.tri_b as u64);
            ans.u(r.intersecting as u64 | (r.refined as u64) << 1 | (r.complete as u64) << 2);
            ans.f(r.spheres.distance);
            work.u(r.node_pairs);
            work.u(r.triangle_pairs);
            work.u(r.spheres.visits);
        }
        _ => {
            for k in [5, 0, 8, 7, 4, 11] {
                query(k, st, pose_b, ans, work);
            }
        }
    }
}

/// The recorded digests: (kind, answers, work).
const RECORDED: [(&str, u64, u64); 14] = [
    ("proximity", 0x218d2c1549ef2c16, 0xaab3f5e6db0046b8),
    (
        "proximity best first",
        0x0cc431e0920ee966,
        0x5fbe7204f5888f9f,
    ),
    ("proximity signed", 0x49df92914743576d, 0x1a2d116f5d6653c2),
    ("distance traversal", 0x5beadafda2c73849, 0xb2d2abf284f96ed3),
    ("backtracking", 0x1493f6808a4849b4, 0xe565753cb9a62d7c),
    ("contact", 0x27aaddf3ad8a3f7a, 0xeb5f51806f5d3346),
    ("multipoint k=16", 0xb9e6a76dd86e2070, 0x9dd33b2a6c7a0b5b),
    (
        "multipoint k=16 tracking",
        0x25f6128235b8d466,
        0xe62beffe337440ae,
    ),
    ("penetration", 0xd4cda6adfd86fb39, 0x9dda5c6f0461f55e),
    (
        "penetration traversal",
        0xa5958fe84bd47a91,
        0x6e876681571190c9,
    ),
    ("penetration front", 0xd4cda6adfd86fb39, 0x9dda5c6f0461f55e),
    (
        "penetration budget 8000",
        0x73b1a947b17b4025,
        0xad38fc786b36af4c,
    ),
    ("refined distance", 0xccde29152c7aeda5, 0x1e5131776fa13938),
    (
        "all kinds on one state",
        0xc9d236f469345681,
        0x3639c7e19970bc18,
    ),
];

#[test]
#[ignore = "real data: run with --ignored"]
fn jaw_chew_answers_are_bit_for_bit_the_recorded_ones() {
    let load = |rel: &str| innersphere::mesh::io::load(&common::data(rel)).unwrap();
    let opts = BuildOptions {
        resolution: Resolution::VoxelSize(0.3),
        ..Default::default()
    };
    // The trees carry their meshes (for the refined distance; no other kind reads them).
    let build = |rel: &str| {
        let mesh = load(rel);
        let tree = build_tree(&mesh, &opts, &innersphere::progress::Silent)
            .unwrap()
            .0;
        innersphere::SharedTree::new(tree).with_mesh(&mesh).unwrap()
    };
    let a = build("jaw/ofj_p26_maxilla_teeth.stl.gz");
    let b = build("jaw/ofj_p26_mandible_teeth.stl.gz");
    let motion = Motion::load(common::data("motion/jaw_chew_demo.csv")).unwrap();
    let mut got = Vec::new();
    for (kind, name) in KINDS.iter().enumerate() {
        let mut st = Pair::new(&a, &b);
        let (mut ans, mut work) = (Digest::new(), Digest::new());
        for f in &motion.frames {
            query(kind, &mut st, &f.pose, &mut ans, &mut work);
        }
        eprintln!("    (\"{name}\", {:#018x}, {:#018x}),", ans.0, work.0);
        got.push((*name, ans.0, work.0));
    }
    assert_eq!(got, RECORDED);
}
