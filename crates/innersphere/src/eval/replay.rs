//! Replay of a motion through a pair's state, frame by frame, exactly as a haptic loop would
//! run it: per query kind the time of every frame, and — against the exact mesh distance —
//! the distance error and the contact disagreement (what `ist replay` prints).

use crate::exact::{self, ExactMesh, ExactScratch};
use crate::motion::Motion;
use crate::query::{
    backtracking, multipoint, penetration, proximity, ContactOptions, MultipointOptions, PairState,
    PenetrationOptions, Pose, ProximityOptions,
};
use crate::SphereTree;
use std::time::Instant;

/// The query kinds a replay can run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum QueryKind {
    /// Exact proximity of the sphere sets ([`proximity`]).
    Distance,
    /// First contact with backtracking ([`backtracking`]).
    Contact,
    /// Up to `k` contacts ([`multipoint`]).
    Multipoint,
    /// Penetration volume, force and torque ([`penetration`]).
    Penetration,
}

impl QueryKind {
    /// Every kind, in report order.
    pub const ALL: [QueryKind; 4] = [
        QueryKind::Distance,
        QueryKind::Contact,
        QueryKind::Multipoint,
        QueryKind::Penetration,
    ];
}

/// Options of a replay.
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Query kinds to time.
    pub kinds: Vec<QueryKind>,
    /// Contacts for multipoint.
    pub k: usize,
    /// Split depth for multipoint.
    pub split_depth: u32,
    /// Compare with the exact mesh distance on every `every`-th frame.
    pub every: usize,
    /// Interpenetration depth (model units) beyond which a missed contact counts against the
    /// accuracy bar (`missed_contacts_deep`).
    pub deep: f64,
    /// Passes over the motion (at least 1). Each pass starts from a fresh pair state, so
    /// every pass does the same work on every frame, and a frame's time is its fastest pass:
    /// on a shared or virtual machine this filters out the stalls where the operating system
    /// or hypervisor took the CPU away (milliseconds at random frames), which a haptic loop
    /// on a dedicated core would not see. One pass reports every stall as query time.
    pub passes: usize,
}

impl Default for ReplayOptions {
    fn default() -> Self {
        ReplayOptions {
            kinds: QueryKind::ALL.to_vec(),
            k: 16,
            split_depth: 4,
            every: 1,
            deep: 0.1,
            passes: 1,
        }
    }
}

/// Timing statistics of one query kind over a motion.
#[derive(Debug, Clone, serde::Serialize)]
pub struct KindStats {
    /// The query kind.
    pub kind: QueryKind,
    /// Frames run.
    pub frames: usize,
    /// Median time per frame (µs).
    pub p50_us: f64,
    /// 99th percentile (µs).
    pub p99_us: f64,
    /// Slowest frame (µs).
    pub max_us: f64,
    /// Frames that took more than 1 ms (a haptic frame missed).
    pub frames_over_1ms: usize,
}

/// Accuracy against the exact mesh distance.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Accuracy {
    /// Frames compared with the exact reference.
    pub frames: usize,
    /// Of those, frames where the meshes are separated.
    pub separated_frames: usize,
    /// Absolute distance error on separated frames: median, 95th percentile, maximum.
    pub abs_err_p50: f64,
    /// See `abs_err_p50`.
    pub abs_err_p95: f64,
    /// See `abs_err_p50`.
    pub abs_err_max: f64,
    /// The paper's relative error (absolute error / exact distance): median, 95th percentile.
    pub rel_err_p50: f64,
    /// See `rel_err_p50`.
    pub rel_err_p95: f64,
    /// Frames where the meshes intersect but the trees say separated.
    pub missed_contacts: usize,
    /// Missed contacts where the meshes interpenetrate by more than `deep`.
    pub missed_contacts_deep: usize,
    /// Frames where the trees overlap but the meshes are separated.
    pub false_contacts: usize,
    /// The exact method's own time per frame: median, 99th percentile, max (µs).
    pub exact_p50_us: f64,
    /// See `exact_p50_us`.
    pub exact_p99_us: f64,
    /// See `exact_p50_us`.
    pub exact_max_us: f64,
    /// Our exact proximity's 99th-percentile time over the same compared frames (µs; NaN
    /// when the distance query was not timed), the like-for-like partner of `exact_p99_us`.
    pub distance_p99_us: f64,
    /// `exact_p99_us / distance_p99_us`: how many times faster our proximity is at p99 than
    /// the exact mesh distance on the same frames.
    pub speedup_p99: f64,
}

/// One frame's results (for `--csv`).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FrameRow {
    /// Frame index.
    pub frame: usize,
    /// Time stamp (s).
    pub t: f64,
    /// Sphere-set distance from [`proximity`] (0 when overlapping).
    pub distance: f64,
    /// Whether the sphere sets overlap.
    pub contact: bool,
    /// Time of each kind in this frame (µs), in [`ReplayOptions::kinds`] order; NaN if not run.
    pub us: [f64; 4],
    /// Exact mesh distance (NaN when not compared).
    pub exact_distance: f64,
    /// Whether the meshes intersect (false when not compared).
    pub exact_intersecting: bool,
}

/// The result of a replay.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ReplayReport {
    /// Frames in the motion.
    pub frames: usize,
    /// Passes timed ([`ReplayOptions::passes`]): each frame's time is its fastest pass.
    pub passes: usize,
    /// Timing per query kind.
    pub kinds: Vec<KindStats>,
    /// Accuracy against the exact reference, when meshes were given.
    pub accuracy: Option<Accuracy>,
    /// Per-frame rows.
    #[serde(skip)]
    pub rows: Vec<FrameRow>,
}

fn percentile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let i = ((sorted.len() - 1) as f64 * q).round() as usize;
    sorted[i.min(sorted.len() - 1)]
}

fn sorted(mut v: Vec<f64>) -> Vec<f64> {
    v.sort_by(f64::total_cmp);
    v
}

/// Replays `motion` (pose of B in A's frame; A at the identity) through one [`PairState`] per
/// query kind, and compares with the exact mesh distance when `exact` meshes are given.
pub fn replay(
    a: &SphereTree,
    b: &SphereTree,
    motion: &Motion,
    exact: Option<(&ExactMesh, &ExactMesh)>,
    opts: &ReplayOptions,
) -> ReplayReport {
    let n = motion.frames.len();
    let mut rows: Vec<FrameRow> = motion
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| FrameRow {
            frame: i,
            t: f.t,
            us: [f64::NAN; 4],
            exact_distance: f64::NAN,
            ..Default::default()
        })
        .collect();
    let id = Pose::IDENTITY;
    let mut kinds = Vec::new();
    for (slot, &kind) in opts.kinds.iter().enumerate().take(4) {
        let mut times = vec![f64::INFINITY; n];
        for _ in 0..opts.passes.max(1) {
            replay_pass(a, b, motion, kind, opts, &mut times, &mut rows);
        }
        for (row, &us) in rows.iter_mut().zip(&times) {
            row.us[slot] = us;
        }
        let over = times.iter().filter(|&&t| t > 1000.0).count();
        let s = sorted(times);
        kinds.push(KindStats {
            kind,
            frames: n,
            p50_us: percentile(&s, 0.5),
            p99_us: percentile(&s, 0.99),
            max_us: s.last().copied().unwrap_or(f64::NAN),
            frames_over_1ms: over,
        });
    }
    let accuracy = exact.map(|(ma, mb)| {
        // The tree distance is needed on compared frames even if Distance was not timed.
        if !opts.kinds.contains(&QueryKind::Distance) {
            let mut st = PairState::new(a, b);
            for (i, f) in motion.frames.iter().enumerate() {
                let p = proximity(a, &id, b, &f.pose, &mut st, &ProximityOptions::default());
                rows[i].distance = p.distance;
                rows[i].contact = p.overlapping;
            }
        }
        let mut scratch = ExactScratch::new();
        let mut acc = Accuracy::default();
        let (mut abs, mut rel) = (Vec::new(), Vec::new());
        for (i, f) in motion.frames.iter().enumerate().step_by(opts.every.max(1)) {
            let e = exact::distance(ma, &id, mb, &f.pose, &mut scratch);
            rows[i].exact_distance = e.distance;
            rows[i].exact_intersecting = e.intersecting;
            acc.frames += 1;
            let tree_contact = rows[i].contact;
            if e.intersecting {
                if !tree_contact {
                    acc.missed_contacts += 1;
                    let depth = exact::penetration_depth(ma, &id, mb, &f.pose, &mut scratch);
                    if depth > opts.deep {
                        acc.missed_contacts_deep += 1;
                    }
                }
            } else {
                acc.separated_frames += 1;
                if tree_contact {
                    acc.false_contacts += 1;
                }
                let err = (rows[i].distance - e.distance).abs();
                abs.push(err);
                if e.distance > 0.0 {
                    rel.push(err / e.distance);
                }
            }
        }
        let times = time_exact(ma, mb, motion, opts.every, opts.passes, &mut scratch);
        let (abs, rel, times) = (sorted(abs), sorted(rel), sorted(times));
        acc.abs_err_p50 = percentile(&abs, 0.5);
        acc.abs_err_p95 = percentile(&abs, 0.95);
        acc.abs_err_max = abs.last().copied().unwrap_or(f64::NAN);
        acc.rel_err_p50 = percentile(&rel, 0.5);
        acc.rel_err_p95 = percentile(&rel, 0.95);
        acc.exact_p50_us = percentile(&times, 0.5);
        acc.exact_p99_us = percentile(&times, 0.99);
        acc.exact_max_us = times.last().copied().unwrap_or(f64::NAN);
        acc.distance_p99_us = match opts
            .kinds
            .iter()
            .take(4)
            .position(|&k| k == QueryKind::Distance)
        {
            Some(slot) => {
                let ours = rows
                    .iter()
                    .step_by(opts.every.max(1))
                    .map(|r| r.us[slot])
                    .collect();
                percentile(&sorted(ours), 0.99)
            }
            None => f64::NAN,
        };
        acc.speedup_p99 = acc.exact_p99_us / acc.distance_p99_us;
        acc
    });
    ReplayReport {
        frames: n,
        passes: opts.passes.max(1),
        kinds,
        accuracy,
        rows,
    }
}

/// Times (µs) of the exact mesh distance (A at the identity) on every `every`-th frame of
/// `motion`, each frame's fastest of `passes` passes over the whole sequence: the same rule
/// as the trees' queries, so that the two are compared like for like.
pub(crate) fn time_exact(
    ma: &ExactMesh,
    mb: &ExactMesh,
    motion: &Motion,
    every: usize,
    passes: usize,
    scratch: &mut ExactScratch,
) -> Vec<f64> {
    let id = Pose::IDENTITY;
    let every = every.max(1);
    let mut times = vec![f64::INFINITY; motion.frames.len().div_ceil(every)];
    for _ in 0..passes.max(1) {
        for (t, f) in times.iter_mut().zip(motion.frames.iter().step_by(every)) {
            let t0 = Instant::now();
            std::hint::black_box(exact::distance(ma, &id, mb, &f.pose, scratch));
            *t = t.min(t0.elapsed().as_secs_f64() * 1e6);
        }
    }
    times
}

/// One pass of `kind` over the motion from a fresh pair state: each frame's time (µs) lowers
/// `times[i]` where it is faster; distances and contacts go to `rows`.
fn replay_pass(
    a: &SphereTree,
    b: &SphereTree,
    motion: &Motion,
    kind: QueryKind,
    opts: &ReplayOptions,
    times: &mut [f64],
    rows: &mut [FrameRow],
) {
    let id = Pose::IDENTITY;
    let mut st = PairState::new(a, b);
    for (i, f) in motion.frames.iter().enumerate() {
        let pb = f.pose;
        let t0 = Instant::now();
        match kind {
            QueryKind::Distance => {
                let p = proximity(a, &id, b, &pb, &mut st, &ProximityOptions::default());
                let us = t0.elapsed().as_secs_f64() * 1e6;
                rows[i].distance = p.distance;
                rows[i].contact = p.overlapping;
                times[i] = times[i].min(us);
                continue;
            }
            QueryKind::Contact => {
                std::hint::black_box(backtracking(
                    a,
                    &id,
                    b,
                    &pb,
                    &mut st,
                    &ContactOptions::default(),
                ));
            }
            QueryKind::Multipoint => {
                let o = MultipointOptions {
                    k: opts.k,
                    split_depth: opts.split_depth,
                    ..Default::default()
                };
                std::hint::black_box(multipoint(a, &id, b, &pb, &mut st, &o).contacts.len());
            }
            QueryKind::Penetration => {
                std::hint::black_box(
                    penetration(a, &id, b, &pb, &mut st, &PenetrationOptions::default()).volume,
                );
            }
        }
        times[i] = times[i].min(t0.elapsed().as_secs_f64() * 1e6);
    }
}
