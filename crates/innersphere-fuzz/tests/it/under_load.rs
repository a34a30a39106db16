//! Under load, on generated models and motions:
//!
//! - many [`Pair`]s sharing two [`SharedTree`]s, queried from rayon threads (and moved
//!   between threads from one frame to the next), answer bit for bit what one thread does;
//! - a soak of 10^6 frames along generated motions on one pair allocates nothing after
//!   warm-up, and the answer at sampled frames equals a fresh pair's at the same pose;
//! - builds are deterministic: the same mesh gives the same tree bytes with rayon pools of
//!   1, 2 and 4 threads.
//!
//! The figures are in `docs/RELIABILITY.md`, "Under load".

use innersphere_testkit::alloc as alloc_util;

use std::hash::{Hash, Hasher};
use std::sync::OnceLock;
use std::time::Instant;

use innersphere::tree::file;
use innersphere::{
    shapes, BuildOptions, MultipointOptions, Pair, Pose, Resolution, SharedTree, SphereTree,
};
use innersphere_motion::{generate, Scenario};
use rayon::prelude::*;

/// The generated tooth pair, both trees (with their meshes) and three generated motions (B in
/// A's frame).
struct Fixture {
    a: SharedTree,
    b: SharedTree,
    motions: Vec<Vec<Pose>>,
}

/// Seconds of each generated motion (1 kHz).
const MOTION_SECONDS: f64 = 2.0;

fn fixture() -> &'static Fixture {
    static F: OnceLock<Fixture> = OnceLock::new();
    F.get_or_init(|| {
        let (ma, mb) = shapes::tooth_pair(3);
        let opts = BuildOptions {
            resolution: Resolution::Cells(64),
            ..BuildOptions::default()
        };
        // With their meshes, for the refined distance.
        let tree = |m| {
            SharedTree::new(SphereTree::build(m, &opts).expect("builds"))
                .with_mesh(m)
                .expect("its own mesh")
        };
        let (a, b) = (tree(&ma), tree(&mb));
        let motions = Scenario::ALL
            .iter()
            .enumerate()
            .map(|(i, &s)| {
                generate(s, MOTION_SECONDS, 11 + i as u64, &ma, &mb)
                    .expect("generates")
                    .poses()
                    .collect()
            })
            .collect();
        Fixture { a, b, motions }
    })
}

/// The query kinds of the public API, one per frame in turn in the soak.
#[derive(Debug, Clone, Copy)]
enum Kind {
    Distance,
    Contact,
    Multipoint,
    Penetration,
    Budgeted,
}

const KINDS: [Kind; 5] = [
    Kind::Distance,
    Kind::Contact,
    Kind::Multipoint,
    Kind::Penetration,
    Kind::Budgeted,
];

/// Node pairs the time-critical volume may test per frame.
const BUDGET: u64 = 500;

/// Every answer of every query kind at one frame, with the contacts and patches, as the
/// `Debug` text (which writes each f64 in the shortest form that reads back to the same
/// bits, so equal text is equal bits), hashed.
fn all_answers(pair: &mut Pair, pa: &Pose, pb: &Pose) -> u64 {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    format!("{:?}", pair.distance(pa, pb)).hash(&mut h);
    format!("{:?}", pair.contact(pa, pb)).hash(&mut h);
    let m = pair.multipoint(pa, pb, &MultipointOptions::default());
    format!("{m:?}{:?}", pair.contacts()).hash(&mut h);
    let p = pair.penetration(pa, pb);
    format!("{p:?}{:?}", pair.patches()).hash(&mut h);
    format!("{:?}", pair.penetration_within(pa, pb, BUDGET)).hash(&mut h);
    format!(
        "{:?}",
        pair.refined_distance(pa, pb)
            .expect("the trees carry their meshes")
    )
    .hash(&mut h);
    h.finish()
}

/// Pairs of the concurrency test.
const PAIRS: usize = 64;
/// Frames each pair is asked.
const FRAMES: usize = 240;
/// Frames a pair is asked on one thread before the pairs are dealt out again.
const ROUND: usize = 8;

/// Pair `i` of the concurrency test: even pairs are (A, B) with B moving, odd ones (B, A)
/// with A moving by the inverse pose (the same relative motion seen from the other body);
/// each follows one motion from its own start frame.
struct Job {
    pair: Pair,
    swapped: bool,
    motion: usize,
    start: usize,
}

fn jobs(f: &Fixture) -> Vec<Job> {
    (0..PAIRS)
        .map(|i| {
            let swapped = i % 2 == 1;
            let pair = if swapped {
                Pair::new(&f.b, &f.a)
            } else {
                Pair::new(&f.a, &f.b)
            };
            Job {
                pair,
                swapped,
                motion: i % f.motions.len(),
                start: (i * 97) % f.motions[0].len(),
            }
        })
        .collect()
}

impl Job {
    fn frame(&mut self, f: &Fixture, j: usize) -> u64 {
        let m = &f.motions[self.motion];
        let pose = m[(self.start + j) % m.len()];
        if self.swapped {
            all_answers(&mut self.pair, &pose.inverse(), &Pose::IDENTITY)
        } else {
            all_answers(&mut self.pair, &Pose::IDENTITY, &pose)
        }
    }
}

#[test]
fn pairs_sharing_trees_on_many_threads_answer_as_one_thread() {
    let f = fixture();
    let t0 = Instant::now();
    let single: Vec<Vec<u64>> = jobs(f)
        .iter_mut()
        .map(|job| (0..FRAMES).map(|j| job.frame(f, j)).collect())
        .collect();
    let t_single = t0.elapsed();

    for threads in [2, 8, 64] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a thread pool");
        // One task per pair, all frames: pairs run concurrently on shared trees.
        let t0 = Instant::now();
        let per_pair: Vec<Vec<u64>> = pool.install(|| {
            jobs(f)
                .par_iter_mut()
                .map(|job| (0..FRAMES).map(|j| job.frame(f, j)).collect())
                .collect()
        });
        let t_per_pair = t0.elapsed();
        // Rounds of ROUND frames: every pair moves between threads as it goes.
        let mut js = jobs(f);
        let mut rounds: Vec<Vec<u64>> = (0..PAIRS).map(|_| Vec::with_capacity(FRAMES)).collect();
        let t0 = Instant::now();
        pool.install(|| {
            for r in (0..FRAMES).step_by(ROUND) {
                js.par_iter_mut()
                    .zip(rounds.par_iter_mut())
                    .for_each(|(job, out)| {
                        out.extend((r..(r + ROUND).min(FRAMES)).map(|j| job.frame(f, j)));
                    });
            }
        });
        let t_rounds = t0.elapsed();
        for (name, got) in [("one task per pair", &per_pair), ("rounds", &rounds)] {
            for (i, (want, got)) in single.iter().zip(got).enumerate() {
                if let Some(j) = (0..FRAMES).find(|&j| want[j] != got[j]) {
                    panic!(
                        "{threads} threads, {name}: pair {i} differs from one thread at frame {j}"
                    );
                }
            }
        }
        eprintln!(
            "{PAIRS} pairs x {FRAMES} frames x 5 query kinds: one thread {:.2} s; {threads} threads: \
             one task per pair {:.2} s, rounds of {ROUND} frames {:.2} s; all equal bit for bit",
            t_single.as_secs_f64(),
            t_per_pair.as_secs_f64(),
            t_rounds.as_secs_f64()
        );
    }
}

/// The answer of one query kind at one frame.
#[derive(Debug, Clone, Copy, Default)]
struct Answer {
    /// Fields compared bit for bit.
    exact: [u64; 16],
    /// Sums over the overlapping leaf pairs (penetration: volume, normal, force, torques;
    /// the time-critical volume: volume and bound). Their terms are added in the order the
    /// traversal meets the pairs, which depends on the front the pair remembers, so a warm
    /// and a fresh pair may differ in the last bits: compared to [`SUM_TOLERANCE`] relative.
    sums: [f64; 14],
    /// The proved lower bound on the separation that contact, multipoint and penetration
    /// report when the bodies are apart: a bound, not an answer (it depends on where the
    /// remembered descent stopped), so it is checked against the exact distance instead.
    bound: Option<f64>,
}

/// Relative tolerance of the sums (see [`Answer::sums`]).
const SUM_TOLERANCE: f64 = 1e-12;

/// The answer of one query kind. Not compared: the work counters (`visits`, `skipped`,
/// `reused`), and which overlapping leaf pairs distance, contact and multipoint report when
/// the packings overlap (any overlapping pair is a right answer; which is found first
/// depends on the remembered front).
fn answer(kind: Kind, pair: &mut Pair, pb: &Pose) -> Answer {
    let pa = Pose::IDENTITY;
    let mut a = Answer::default();
    let flag = |b: bool| u64::from(b);
    match kind {
        Kind::Distance => {
            let d = pair.distance(&pa, pb);
            a.exact[..3].copy_from_slice(&[
                d.distance.to_bits(),
                d.lower_bound.to_bits(),
                flag(d.overlapping),
            ]);
            if d.overlapping {
                // Distance 0 and some overlapping leaf pair: any is right.
                assert!(d.pair_distance < 0.0, "the reported leaf pair overlaps");
            } else {
                // The closest leaf pair.
                let [p, q, n] = [d.point_a, d.point_b, d.normal].map(|v| v.to_array());
                for (slot, x) in a.exact[3..]
                    .iter_mut()
                    .zip([d.pair_distance].iter().chain(&p).chain(&q).chain(&n))
                {
                    *slot = x.to_bits();
                }
                a.exact[13..15].copy_from_slice(&[u64::from(d.leaf_a), u64::from(d.leaf_b)]);
            }
        }
        Kind::Contact => {
            let c = pair.contact(&pa, pb);
            a.exact[0] = flag(c.in_contact());
            a.bound = (!c.in_contact()).then_some(c.distance);
        }
        Kind::Multipoint => {
            let m = pair.multipoint(&pa, pb, &MultipointOptions::default());
            a.exact[0] = flag(m.count > 0);
            assert!(pair.contacts().iter().all(|c| c.depth > 0.0));
            a.bound = (m.count == 0).then_some(m.distance);
        }
        Kind::Penetration => {
            let p = pair.penetration(&pa, pb);
            // Not the patch count: a patch is seeded by the first pair met far from the
            // others, so the grouping depends on the order, as the sums' last bits do.
            a.exact[..2].copy_from_slice(&[p.pairs as u64, p.max_depth.to_bits()]);
            a.sums[0] = p.volume;
            for (k, v) in [p.normal, p.force, p.torque_a, p.torque_b]
                .iter()
                .enumerate()
            {
                a.sums[1 + 3 * k..4 + 3 * k].copy_from_slice(&v.to_array());
            }
            a.bound = (p.pairs == 0).then_some(p.distance);
        }
        Kind::Budgeted => {
            let w = pair.penetration_within(&pa, pb, u64::MAX);
            a.exact[0] = flag(w.complete);
            a.sums[..2].copy_from_slice(&[w.volume, w.upper_bound]);
        }
    }
    a
}

/// Largest relative difference of two answers' sums, each group (a scalar or a vector)
/// relative to its magnitude.
fn sums_difference(a: &Answer, b: &Answer) -> f64 {
    let groups: [std::ops::Range<usize>; 6] = [0..1, 1..4, 4..7, 7..10, 10..13, 13..14];
    groups
        .iter()
        .map(|g| {
            let norm = |s: &[f64]| s.iter().map(|x| x * x).sum::<f64>().sqrt();
            let diff: Vec<f64> = g.clone().map(|i| a.sums[i] - b.sums[i]).collect();
            let scale = norm(&a.sums[g.clone()]).max(norm(&b.sums[g.clone()]));
            if scale == 0.0 {
                0.0
            } else {
                norm(&diff) / scale
            }
        })
        .fold(0.0, f64::max)
}

/// Frames of the soak.
const SOAK_FRAMES: usize = 1_000_000;
/// Every this many frames the answer is kept and compared with a fresh pair's.
const SAMPLE_EVERY: usize = 997;

#[test]
#[ignore = "heavy: a million frames (about 20 s on 2 cores); CI runs it with --ignored"]
fn a_soak_of_a_million_frames_allocates_nothing_and_does_not_drift() {
    let f = fixture();
    let cycle: Vec<Pose> = f.motions.iter().flatten().copied().collect();
    let pose = |k: usize| cycle[k % cycle.len()];
    let kind = |k: usize| KINDS[k % KINDS.len()];
    let mut pair = Pair::new(&f.a, &f.b);
    // Warm-up: one pass over every motion with every kind at every frame, then one period
    // of the soak's own sequence.
    let t0 = Instant::now();
    for p in &cycle {
        for kd in KINDS {
            answer(kd, &mut pair, p);
        }
    }
    for k in 0..cycle.len() * KINDS.len() {
        answer(kind(k), &mut pair, &pose(k));
    }
    let warm_up = t0.elapsed();

    let mut samples: Vec<(usize, Answer)> = Vec::with_capacity(SOAK_FRAMES / SAMPLE_EVERY + 1);
    let t0 = Instant::now();
    let (allocs, bytes, ()) = alloc_util::counted(|| {
        for k in 0..SOAK_FRAMES {
            let a = answer(kind(k), &mut pair, &pose(k));
            if k % SAMPLE_EVERY == 0 {
                samples.push((k, a));
            }
        }
    });
    let soak = t0.elapsed();
    assert_eq!(
        (allocs, bytes),
        (0, 0),
        "the soak allocated after warm-up (allocations, bytes)"
    );
    let mut drift = Vec::new();
    let (mut bounds, mut worst_sum) = (0, 0.0f64);
    for &(k, got) in &samples {
        let mut fresh = Pair::new(&f.a, &f.b);
        let want = answer(kind(k), &mut fresh, &pose(k));
        let sums = sums_difference(&got, &want);
        worst_sum = worst_sum.max(sums);
        // NaN sums fail too.
        let sums_ok = sums <= SUM_TOLERANCE;
        if want.exact != got.exact || !sums_ok {
            drift.push(format!(
                "frame {k} ({:?}): {got:?}\n  vs fresh {want:?}",
                kind(k)
            ));
        }
        if let Some(bound) = got.bound {
            bounds += 1;
            let exact = fresh.distance(&Pose::IDENTITY, &pose(k)).distance;
            let below = bound <= exact;
            if !below {
                drift.push(format!(
                    "frame {k} ({:?}): separation bound {bound} above the distance {exact}",
                    kind(k)
                ));
            }
        }
    }
    assert!(
        drift.is_empty(),
        "{} of {} sampled frames differ from a fresh pair:\n{}",
        drift.len(),
        samples.len(),
        drift.join("\n")
    );
    eprintln!(
        "soak: {SOAK_FRAMES} frames ({} motions of {} frames cycled, the 5 kinds in turn) in {:.1} s \
         ({:.2} us/frame) after a warm-up of {:.1} s; 0 allocations; {} sampled frames equal a fresh pair's \
         (sums within {worst_sum:.1e} relative; {bounds} separated, their bounds at most the distance)",
        f.motions.len(),
        f.motions[0].len(),
        soak.as_secs_f64(),
        soak.as_secs_f64() * 1e6 / SOAK_FRAMES as f64,
        warm_up.as_secs_f64(),
        samples.len()
    );
}

/// Tree bytes of `mesh` built in a rayon pool of `threads` threads.
fn build_in_pool(mesh: &innersphere::Mesh, opts: &BuildOptions, threads: usize) -> Vec<u8> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a thread pool");
    let tree = pool
        .install(|| SphereTree::build(mesh, opts))
        .expect("builds");
    file::to_bytes(&tree)
}

#[test]
fn builds_are_deterministic_at_any_thread_count() {
    let (upper, _) = shapes::tooth_pair(3);
    let torus = shapes::torus(2.0, 0.6, 48, 24);
    let plain = BuildOptions::default();
    let mut calibrated = BuildOptions::preset(innersphere::build::Preset::Fine, &torus)
        .expect("a preset for the torus");
    calibrated.resolution = Resolution::Cells(96);
    for (name, mesh, opts) in [
        ("molar, default options", &upper, plain),
        (
            "torus, calibrated packing (min radius, refinement)",
            &torus,
            calibrated,
        ),
    ] {
        let t0 = Instant::now();
        let one = build_in_pool(mesh, &opts, 1);
        for threads in [2, 4, 1] {
            let other = build_in_pool(mesh, &opts, threads);
            assert!(
                other == one,
                "{name}: the tree built with {threads} threads differs from the one built with 1"
            );
        }
        eprintln!(
            "{name}: {} bytes, identical with 1, 2, 4 and again 1 threads ({:.1} s for the four builds)",
            one.len(),
            t0.elapsed().as_secs_f64()
        );
    }
}
