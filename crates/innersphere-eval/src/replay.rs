//! Replay of a motion through a pair's state, frame by frame, exactly as a haptic loop would
//! run it: per query kind the time of every frame, and — against the exact mesh distance —
//! the distance error and the contact disagreement (what `ist replay` prints).
//!
//! Timing rule. A haptic loop runs each query once per frame, in motion order, with the
//! pair's state carried from frame to frame. The first pass over the motion (from a fresh
//! [`Pair`]) is exactly that, and the headline statistics ([`KindStats::p99_us`],
//! [`KindStats::max_us`], [`KindStats::frames_over_1ms`]) come from it alone: they are
//! *single-pass* numbers. With [`ReplayOptions::passes`] `N > 1` the motion is run `N − 1`
//! more times, each from a fresh state, and each frame's fastest of the `N` passes gives the
//! *best-of-N* statistics beside them (`best_of_passes_*`): on a shared or virtual machine
//! that filters out the stalls where the operating system or hypervisor took the CPU away,
//! but a haptic loop never gets a second try, so best-of-N is a lower bound on what it sees.
//!
//! The exact reference ([`innersphere::exact::distance`]) is timed the same way on every frame it
//! is compared on: the timed call is the one whose answer the accuracy uses. Its scratch
//! keeps its warm start (the last answer's triangle pair) from the previous *compared* frame,
//! i.e. [`ReplayOptions::every`] frames back (the first compared frame starts cold), while
//! our queries are warm-started from the previous frame.

use crate::motion::Motion;
use innersphere::exact::{self, ExactDistance, ExactMesh, ExactScratch};
use innersphere::{MultipointOptions, Pair, PenetrationOptions, Pose, RefineOptions, SharedTree};

pub use crate::mesh_reference::{MeshAccuracy, MeshReference};
use std::time::Instant;

/// The query kinds a replay can run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum QueryKind {
    /// Exact distance of the sphere sets ([`Pair::distance`]).
    Distance,
    /// First contact ([`Pair::contact`]).
    Contact,
    /// Up to `k` contacts ([`Pair::multipoint`]).
    Multipoint,
    /// Penetration volume, force and torque ([`Pair::penetration`]).
    Penetration,
    /// The sphere distance refined to the meshes ([`Pair::refined_distance`]; the trees
    /// need their meshes, [`SharedTree::with_mesh`]).
    RefinedDistance,
    /// The meshes' own penetration ([`Pair::mesh_penetration_with`]; the trees need their
    /// meshes).
    MeshPenetration,
}

impl QueryKind {
    /// Every kind, in report order.
    pub const ALL: [QueryKind; 4] = [
        QueryKind::Distance,
        QueryKind::Contact,
        QueryKind::Multipoint,
        QueryKind::Penetration,
    ];

    /// The sphere kinds and the refined distance (what `ist replay --query all` times when
    /// the trees carry their meshes; the meshes' penetration, milliseconds a frame in deep
    /// contact, only when asked for).
    pub const WITH_REFINED: [QueryKind; 5] = [
        QueryKind::Distance,
        QueryKind::Contact,
        QueryKind::Multipoint,
        QueryKind::Penetration,
        QueryKind::RefinedDistance,
    ];
}

/// How many query kinds a replay can time (the length of the per-frame arrays).
pub const KINDS: usize = 6;

/// Options of a replay.
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    /// Query kinds to time.
    pub kinds: Vec<QueryKind>,
    /// Contacts for multipoint.
    pub k: usize,
    /// Split depth for multipoint.
    pub split_depth: u32,
    /// Compare with the exact mesh distance on every `every`-th frame (frames 0, `every`,
    /// `2·every`, ...); the exact method's warm start then comes from `every` frames back.
    pub every: usize,
    /// Interpenetration depth (model units) beyond which a missed contact counts against the
    /// accuracy bar (`missed_contacts_deep`).
    pub deep: f64,
    /// Passes over the motion (at least 1), each from a fresh pair state. The first pass
    /// gives the single-pass statistics (what a haptic loop sees); every pass, the first
    /// included, feeds the best-of-N statistics (each frame's fastest pass). See the
    /// [module docs](self).
    pub passes: usize,
    /// Options of the refined distance.
    pub refine: RefineOptions,
    /// A reference for the meshes' penetration (an independent mesh boolean's volumes and
    /// gradients: `tools/mesh-volume-check`), compared frame by frame when that kind runs.
    pub mesh_reference: Option<MeshReference>,
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
            refine: RefineOptions::default(),
            mesh_reference: None,
        }
    }
}

/// Timing statistics of one query kind over a motion. The unqualified fields are single-pass
/// (the first pass, what a haptic loop sees); `best_of_passes_*` take each frame's fastest of
/// [`ReplayReport::passes`] passes (equal to the single-pass ones with one pass).
#[derive(Debug, Clone, serde::Serialize)]
pub struct KindStats {
    /// The query kind.
    pub kind: QueryKind,
    /// Frames run (per pass).
    pub frames: usize,
    /// Median time per frame, single pass (µs).
    pub p50_us: f64,
    /// 99th percentile, single pass (µs).
    pub p99_us: f64,
    /// Slowest frame, single pass (µs).
    pub max_us: f64,
    /// Index of the slowest frame of the single pass.
    pub max_frame: usize,
    /// Frames of the single pass that took more than 1 ms (haptic frames missed).
    pub frames_over_1ms: usize,
    /// Median of each frame's fastest pass (µs).
    pub best_of_passes_p50_us: f64,
    /// 99th percentile of each frame's fastest pass (µs).
    pub best_of_passes_p99_us: f64,
    /// Slowest frame of each frame's fastest pass (µs).
    pub best_of_passes_max_us: f64,
    /// Frames whose fastest pass took more than 1 ms.
    pub best_of_passes_frames_over_1ms: usize,
    /// Whether every later pass gave, on every frame, the same answer and the same number of
    /// node-pair tests as the first (the passes did the same work).
    pub passes_agree: bool,
}

/// Accuracy against the exact mesh distance, and the exact method's time.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Accuracy {
    /// Frames compared with the exact reference.
    pub frames: usize,
    /// Of those, frames where the meshes are separated.
    pub separated_frames: usize,
    /// The sphere distance's errors ([`Pair::distance`]; flattened into the JSON).
    #[serde(flatten)]
    pub errors: Errors,
    /// Frames between a compared frame and the one the exact method's warm start comes from
    /// (the previous compared frame: [`ReplayOptions::every`]; the first starts cold).
    pub exact_warm_start_frames: usize,
    /// The exact method's own time per compared frame, single pass (the call whose answer is
    /// compared, warm-started from the previous compared frame): median, 99th percentile,
    /// max (µs).
    pub exact_p50_us: f64,
    /// See `exact_p50_us`.
    pub exact_p99_us: f64,
    /// See `exact_p50_us`.
    pub exact_max_us: f64,
    /// The exact method's 99th percentile of each compared frame's fastest pass (µs; each
    /// pass from a fresh scratch, warm-started the same way).
    pub exact_best_of_passes_p99_us: f64,
    /// The exact method's slowest compared frame, best of the passes (µs).
    pub exact_best_of_passes_max_us: f64,
    /// Whether every pass of the exact method gave the first pass's answers.
    pub exact_passes_agree: bool,
    /// The refined distance's accuracy ([`Pair::refined_distance`]), when it was timed.
    pub refined: Option<RefinedAccuracy>,
    /// Our exact proximity's single-pass 99th-percentile time over the same compared frames
    /// (µs; NaN when the distance query was not timed), the like-for-like partner of
    /// `exact_p99_us`.
    pub distance_p99_us: f64,
    /// `exact_p99_us / distance_p99_us`: how many times faster our proximity is at p99 than
    /// the exact mesh distance on the same frames, both single pass.
    pub speedup_p99: f64,
}

/// A distance's errors against the exact mesh distance on the compared frames.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Errors {
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
    /// Frames where the meshes intersect but the distance says separated.
    pub missed_contacts: usize,
    /// Missed contacts where the meshes interpenetrate by more than `deep`.
    pub missed_contacts_deep: usize,
    /// The deepest interpenetration among the missed contacts (model units, mm for the jaw
    /// scans; 0 when none): how deep a contact it can miss.
    #[serde(rename = "missed_contacts_max_depth_mm")]
    pub missed_contacts_max_depth: f64,
    /// Frames where it says touching but the meshes are separated.
    pub false_contacts: usize,
}

/// [`Errors`] gathered frame by frame.
#[derive(Default)]
struct Tally {
    abs: Vec<f64>,
    rel: Vec<f64>,
    e: Errors,
}

impl Tally {
    /// One compared frame: the exact answer `e`, ours (`distance`, `contact`), the meshes'
    /// interpenetration depth when asked for (a missed contact), `deep` the bar.
    fn frame(
        &mut self,
        e: &ExactDistance,
        distance: f64,
        contact: bool,
        depth: impl FnOnce() -> f64,
        deep: f64,
    ) {
        if e.intersecting {
            if !contact {
                let d = depth();
                self.e.missed_contacts += 1;
                self.e.missed_contacts_max_depth = self.e.missed_contacts_max_depth.max(d);
                self.e.missed_contacts_deep += usize::from(d > deep);
            }
        } else {
            self.e.false_contacts += usize::from(contact);
            let err = (distance - e.distance).abs();
            self.abs.push(err);
            if e.distance > 0.0 {
                self.rel.push(err / e.distance);
            }
        }
    }

    fn finish(self) -> Errors {
        let (abs, rel) = (sorted(self.abs), sorted(self.rel));
        Errors {
            abs_err_p50: percentile(&abs, 0.5),
            abs_err_p95: percentile(&abs, 0.95),
            abs_err_max: abs.last().copied().unwrap_or(f64::NAN),
            rel_err_p50: percentile(&rel, 0.5),
            rel_err_p95: percentile(&rel, 0.95),
            ..self.e
        }
    }
}

/// The refined distance against the exact mesh distance, on the same compared frames as
/// [`Accuracy`] (whose top-level figures are the sphere distance's).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct RefinedAccuracy {
    /// Its errors (flattened into the JSON).
    #[serde(flatten)]
    pub errors: Errors,
    /// Compared frames whose local search ran out of its budget.
    pub incomplete_frames: usize,
    /// Its single-pass 99th-percentile time over the compared frames (µs).
    pub p99_us: f64,
    /// `exact_p99_us / p99_us`, both single pass on the same frames.
    pub speedup_p99: f64,
}

/// One frame's results (for `--csv`: [`ReplayReport::write_csv`]).
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct FrameRow {
    /// Frame index.
    pub frame: usize,
    /// Time stamp (s).
    pub t: f64,
    /// Sphere-set distance from [`Pair::distance`] (0 when overlapping); NaN when it was not
    /// computed (the distance query not timed and no exact comparison).
    pub distance: f64,
    /// Whether the sphere sets overlap ([`Pair::distance`]); `None` when not computed.
    pub contact: Option<bool>,
    /// Each timed kind's own answer on this frame in the first pass, in
    /// [`ReplayOptions::kinds`] order; `None` if not run.
    pub answers: [Option<KindAnswer>; KINDS],
    /// Time of each kind in this frame in the first pass (µs), in [`ReplayOptions::kinds`]
    /// order; NaN if not run.
    pub us: [f64; KINDS],
    /// Time of each kind in this frame, fastest of the passes (µs); NaN if not run.
    pub best_of_passes_us: [f64; KINDS],
    /// Exact mesh distance (NaN when not compared).
    pub exact_distance: f64,
    /// Whether the meshes intersect (`None` when not compared).
    pub exact_intersecting: Option<bool>,
    /// Time of the exact mesh distance in the first pass (µs; NaN when not compared).
    pub exact_us: f64,
    /// Whether the refined distance's local search ran out of its budget (first pass).
    pub refine_incomplete: bool,
    /// The meshes' penetration's volume gradient (first pass; zero when not run).
    pub mesh_gradient: [f64; 3],
}

/// What one query kind answered on one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct KindAnswer {
    /// Whether this kind found the bodies in contact (distance: the sphere sets overlap;
    /// contact: a contact found; multipoint: at least one contact; penetration: at least one
    /// overlapping leaf pair; refined distance: the meshes touch).
    pub in_contact: bool,
    /// Distance: the sphere-set distance (0 when overlapping). Contact and multipoint: 0 in
    /// contact, else their proved lower bound on the separation. Penetration: the penetration
    /// volume (model units³). Refined distance: the refined distance (0 in contact). Mesh
    /// penetration: the meshes' intersection volume.
    pub value: f64,
    /// Multipoint: contacts found. Penetration: overlapping leaf pairs. Distance and contact:
    /// 1 in contact, else 0. Refined distance: triangle pairs measured. Mesh penetration:
    /// triangle pairs that cross.
    pub count: usize,
}

impl KindAnswer {
    /// The CSV columns of `kind`'s answer ([`ReplayReport::write_csv`]).
    fn columns(kind: QueryKind) -> &'static [&'static str] {
        match kind {
            QueryKind::Distance => &["distance_in_contact", "distance"],
            QueryKind::Contact => &["contact_in_contact", "contact_separation_bound"],
            QueryKind::Multipoint => &[
                "multipoint_in_contact",
                "multipoint_contacts",
                "multipoint_separation_bound",
            ],
            QueryKind::Penetration => &[
                "penetration_in_contact",
                "penetration_volume",
                "penetration_pairs",
            ],
            QueryKind::RefinedDistance => &[
                "refined_distance_in_contact",
                "refined_distance",
                "refined_distance_triangle_pairs",
            ],
            QueryKind::MeshPenetration => &[
                "mesh_penetration_in_contact",
                "mesh_penetration_volume",
                "mesh_penetration_crossing_pairs",
            ],
        }
    }

    /// The cells of [`columns`](Self::columns).
    fn cells(&self, kind: QueryKind) -> Vec<String> {
        let c = self.in_contact.to_string();
        match kind {
            QueryKind::Distance | QueryKind::Contact => vec![c, self.value.to_string()],
            QueryKind::Multipoint => vec![c, self.count.to_string(), self.value.to_string()],
            QueryKind::Penetration | QueryKind::RefinedDistance | QueryKind::MeshPenetration => {
                vec![c, self.value.to_string(), self.count.to_string()]
            }
        }
    }
}

/// The result of a replay.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ReplayReport {
    /// Frames in the motion.
    pub frames: usize,
    /// Passes run ([`ReplayOptions::passes`]): the first gives the single-pass statistics,
    /// all of them the best-of-passes ones.
    pub passes: usize,
    /// Timing per query kind.
    pub kinds: Vec<KindStats>,
    /// Accuracy against the exact reference, when meshes were given.
    pub accuracy: Option<Accuracy>,
    /// The meshes' penetration against its reference, when both ran.
    pub mesh_accuracy: Option<MeshAccuracy>,
    /// Per-frame rows.
    #[serde(skip)]
    pub rows: Vec<FrameRow>,
}

impl ReplayReport {
    /// Writes one CSV row per frame: `frame,t`, then each timed kind's own answer (the
    /// columns of [`KindAnswer`], prefixed by the kind), then each kind's first-pass time
    /// (`{kind}_us_1pass`, and `{kind}_us_best_of_{N}` with N > 1 passes), then, with an exact
    /// comparison, the tree distance it used (`distance_in_contact,distance`, unless the
    /// distance kind was timed) and `exact_distance,exact_intersecting,exact_us_1pass`, empty
    /// on the frames not compared. A cell is empty where nothing was computed; no answer is
    /// ever filled in for a kind that did not run.
    pub fn write_csv(&self, w: &mut dyn std::io::Write) -> std::io::Result<()> {
        let kinds: Vec<QueryKind> = self.kinds.iter().map(|k| k.kind).collect();
        let best = self.passes > 1;
        let tree_distance = self.accuracy.is_some() && !kinds.contains(&QueryKind::Distance);
        let mut head = vec!["frame".to_string(), "t".to_string()];
        for &k in &kinds {
            head.extend(KindAnswer::columns(k).iter().map(|c| c.to_string()));
        }
        for &k in &kinds {
            let k = match k {
                QueryKind::RefinedDistance => "refined_distance".to_string(),
                QueryKind::MeshPenetration => "mesh_penetration".to_string(),
                k => format!("{k:?}").to_lowercase(),
            };
            head.push(format!("{k}_us_1pass"));
            if best {
                head.push(format!("{k}_us_best_of_{}", self.passes));
            }
        }
        if tree_distance {
            head.extend(["distance_in_contact".into(), "distance".into()]);
        }
        if self.accuracy.is_some() {
            head.extend([
                "exact_distance".into(),
                "exact_intersecting".into(),
                "exact_us_1pass".into(),
            ]);
        }
        writeln!(w, "{}", head.join(","))?;
        let num = |x: f64| {
            if x.is_nan() {
                String::new()
            } else {
                x.to_string()
            }
        };
        let us = |x: f64| {
            if x.is_nan() {
                String::new()
            } else {
                format!("{x:.3}")
            }
        };
        for r in &self.rows {
            let mut cells = vec![r.frame.to_string(), r.t.to_string()];
            for (slot, &k) in kinds.iter().enumerate() {
                match &r.answers[slot] {
                    Some(a) => cells.extend(a.cells(k)),
                    None => cells.extend(KindAnswer::columns(k).iter().map(|_| String::new())),
                }
            }
            for slot in 0..kinds.len() {
                cells.push(us(r.us[slot]));
                if best {
                    cells.push(us(r.best_of_passes_us[slot]));
                }
            }
            if tree_distance {
                cells.push(r.contact.map(|c| c.to_string()).unwrap_or_default());
                cells.push(num(r.distance));
            }
            if self.accuracy.is_some() {
                cells.push(num(r.exact_distance));
                cells.push(
                    r.exact_intersecting
                        .map(|c| c.to_string())
                        .unwrap_or_default(),
                );
                cells.push(us(r.exact_us));
            }
            writeln!(w, "{}", cells.join(","))?;
        }
        Ok(())
    }
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

fn over_1ms(v: &[f64]) -> usize {
    v.iter().filter(|&&t| t > 1000.0).count()
}

/// A monotonic clock in µs from its creation.
fn instant_clock() -> impl FnMut() -> f64 {
    let origin = Instant::now();
    move || origin.elapsed().as_secs_f64() * 1e6
}

/// Replays `motion` (pose of B in A's frame; A at the identity) through one [`Pair`] per
/// query kind and pass, and compares with the exact mesh distance when `exact` meshes are
/// given (see the [module docs](self) for what is timed).
pub fn replay(
    a: &SharedTree,
    b: &SharedTree,
    motion: &Motion,
    exact: Option<(&ExactMesh, &ExactMesh)>,
    opts: &ReplayOptions,
) -> ReplayReport {
    replay_with_clock(a, b, motion, exact, opts, &mut instant_clock())
}

/// [`replay`] with a given clock (the current time in µs, read just before and just after
/// each timed query). The timed queries run in this order: per kind in
/// [`ReplayOptions::kinds`] order, pass after pass, frame after frame; then the exact method,
/// pass after pass, compared frame after compared frame.
pub fn replay_with_clock<C: FnMut() -> f64>(
    a: &SharedTree,
    b: &SharedTree,
    motion: &Motion,
    exact: Option<(&ExactMesh, &ExactMesh)>,
    opts: &ReplayOptions,
    clock: &mut C,
) -> ReplayReport {
    let n = motion.frames.len();
    let passes = opts.passes.max(1);
    let mut rows: Vec<FrameRow> = motion
        .frames
        .iter()
        .enumerate()
        .map(|(i, f)| FrameRow {
            frame: i,
            t: f.t,
            distance: f64::NAN,
            us: [f64::NAN; KINDS],
            best_of_passes_us: [f64::NAN; KINDS],
            exact_distance: f64::NAN,
            exact_us: f64::NAN,
            ..Default::default()
        })
        .collect();
    let mut kinds = Vec::new();
    let mut times = vec![0.0; n];
    let mut answers = vec![Answer::default(); n];
    for (slot, &kind) in opts.kinds.iter().enumerate().take(KINDS) {
        let mut first = vec![0.0; n];
        let mut first_answers = vec![Answer::default(); n];
        let mut best = vec![f64::INFINITY; n];
        let mut agree = true;
        for pass in 0..passes {
            replay_pass(a, b, motion, kind, opts, clock, &mut times, &mut answers);
            if pass == 0 {
                first.copy_from_slice(&times);
                first_answers.copy_from_slice(&answers);
            } else {
                agree &= answers == first_answers;
            }
            for (b, &t) in best.iter_mut().zip(&times) {
                *b = b.min(t);
            }
        }
        for (i, row) in rows.iter_mut().enumerate() {
            row.us[slot] = first[i];
            row.best_of_passes_us[slot] = best[i];
            row.answers[slot] = Some(first_answers[i].answer);
            if kind == QueryKind::RefinedDistance {
                row.refine_incomplete = first_answers[i].incomplete;
            }
            if kind == QueryKind::MeshPenetration {
                row.mesh_gradient = first_answers[i].gradient;
            }
            if kind == QueryKind::Distance {
                row.distance = first_answers[i].answer.value;
                row.contact = Some(first_answers[i].answer.in_contact);
            }
        }
        let (max_frame, max_us) =
            first
                .iter()
                .copied()
                .enumerate()
                .fold((0, f64::NAN), |(j, m), (i, t)| {
                    if m.is_nan() || t > m {
                        (i, t)
                    } else {
                        (j, m)
                    }
                });
        let (over, best_over) = (over_1ms(&first), over_1ms(&best));
        let (s, sb) = (sorted(first), sorted(best));
        kinds.push(KindStats {
            kind,
            frames: n,
            p50_us: percentile(&s, 0.5),
            p99_us: percentile(&s, 0.99),
            max_us,
            max_frame,
            frames_over_1ms: over,
            best_of_passes_p50_us: percentile(&sb, 0.5),
            best_of_passes_p99_us: percentile(&sb, 0.99),
            best_of_passes_max_us: sb.last().copied().unwrap_or(f64::NAN),
            best_of_passes_frames_over_1ms: best_over,
            passes_agree: agree,
        });
    }
    let accuracy = exact.map(|meshes| accuracy(a, b, meshes, motion, opts, &mut rows, clock));
    let mesh_slot = opts
        .kinds
        .iter()
        .take(KINDS)
        .position(|&k| k == QueryKind::MeshPenetration);
    let mesh_accuracy = match (&opts.mesh_reference, mesh_slot) {
        (Some(r), Some(slot)) => Some(r.compare(&rows, slot)),
        _ => None,
    };
    ReplayReport {
        frames: n,
        passes,
        kinds,
        accuracy,
        mesh_accuracy,
        rows,
    }
}

/// The exact reference on every `every`-th frame ([`ReplayOptions::every`]): the exact
/// method timed (after the trees' queries, with the same clock), each row's exact answers
/// filled in, and the sphere and refined distances' errors against them.
fn accuracy<C: FnMut() -> f64>(
    a: &SharedTree,
    b: &SharedTree,
    (ma, mb): (&ExactMesh, &ExactMesh),
    motion: &Motion,
    opts: &ReplayOptions,
    rows: &mut [FrameRow],
    clock: &mut C,
) -> Accuracy {
    let id = Pose::IDENTITY;
    let (passes, every) = (opts.passes.max(1), opts.every.max(1));
    // The tree distance is needed on compared frames even if Distance was not timed.
    if !opts.kinds.contains(&QueryKind::Distance) {
        let mut pair = Pair::new(a, b);
        for (i, f) in motion.frames.iter().enumerate() {
            let p = pair.distance(&id, &f.pose);
            rows[i].distance = p.distance;
            rows[i].contact = Some(p.overlapping);
        }
    }
    let timed = time_exact(ma, mb, motion, every, passes, clock);
    let mut scratch = ExactScratch::new();
    let mut acc = Accuracy {
        exact_warm_start_frames: every,
        exact_passes_agree: timed.passes_agree,
        ..Default::default()
    };
    let mut spheres = Tally::default();
    let refined_slot = opts
        .kinds
        .iter()
        .take(KINDS)
        .position(|&k| k == QueryKind::RefinedDistance);
    let mut refined = refined_slot.map(|_| (Tally::default(), RefinedAccuracy::default()));
    let mut rus = Vec::new();
    let mut depth_of =
        |f: &crate::motion::Frame| exact::penetration_depth(ma, &id, mb, &f.pose, &mut scratch);
    for (j, (i, f)) in motion.frames.iter().enumerate().step_by(every).enumerate() {
        let e = timed.answers[j];
        rows[i].exact_distance = e.distance;
        rows[i].exact_intersecting = Some(e.intersecting);
        rows[i].exact_us = timed.first[j];
        acc.frames += 1;
        acc.separated_frames += usize::from(!e.intersecting);
        // The meshes' interpenetration depth, measured once per frame at most.
        let mut depth = None;
        if let (Some((tally, r)), Some(slot)) = (refined.as_mut(), refined_slot) {
            rus.push(rows[i].us[slot]);
            if let Some(ans) = rows[i].answers[slot] {
                let d = || *depth.get_or_insert_with(|| depth_of(f));
                tally.frame(&e, ans.value, ans.in_contact, d, opts.deep);
            }
            r.incomplete_frames += usize::from(rows[i].refine_incomplete);
        }
        let tree_contact = rows[i].contact == Some(true);
        let d = || *depth.get_or_insert_with(|| depth_of(f));
        spheres.frame(&e, rows[i].distance, tree_contact, d, opts.deep);
    }
    acc.errors = spheres.finish();
    let (first, best) = (sorted(timed.first), sorted(timed.best));
    acc.exact_p50_us = percentile(&first, 0.5);
    acc.exact_p99_us = percentile(&first, 0.99);
    acc.exact_max_us = first.last().copied().unwrap_or(f64::NAN);
    acc.exact_best_of_passes_p99_us = percentile(&best, 0.99);
    acc.exact_best_of_passes_max_us = best.last().copied().unwrap_or(f64::NAN);
    acc.distance_p99_us = match opts
        .kinds
        .iter()
        .take(KINDS)
        .position(|&k| k == QueryKind::Distance)
    {
        Some(slot) => {
            let ours = rows.iter().step_by(every).map(|r| r.us[slot]).collect();
            percentile(&sorted(ours), 0.99)
        }
        None => f64::NAN,
    };
    acc.speedup_p99 = acc.exact_p99_us / acc.distance_p99_us;
    if let Some((tally, mut r)) = refined {
        r.errors = tally.finish();
        r.p99_us = percentile(&sorted(rus), 0.99);
        r.speedup_p99 = acc.exact_p99_us / r.p99_us;
        acc.refined = Some(r);
    }
    acc
}

/// The exact mesh distance timed on the compared frames ([`time_exact`]).
#[derive(Debug, Clone)]
pub(crate) struct ExactTimes {
    /// Time of each compared frame in the first pass (µs).
    pub first: Vec<f64>,
    /// Each compared frame's fastest pass (µs).
    pub best: Vec<f64>,
    /// The first pass's answers.
    pub answers: Vec<ExactDistance>,
    /// Whether every pass gave the first pass's answers.
    pub passes_agree: bool,
}

/// Times (µs) of the exact mesh distance (A at the identity) on every `every`-th frame of
/// `motion` (frames 0, `every`, ...), in `passes` passes over those frames. Each pass starts
/// from a fresh [`ExactScratch`] with warm start on, so every compared frame is warm-started
/// from the previous compared frame (`every` frames back) and the first starts cold. The
/// first pass is the single-pass timing; each frame's fastest pass the best-of-N one.
pub(crate) fn time_exact<C: FnMut() -> f64>(
    ma: &ExactMesh,
    mb: &ExactMesh,
    motion: &Motion,
    every: usize,
    passes: usize,
    clock: &mut C,
) -> ExactTimes {
    let id = Pose::IDENTITY;
    let every = every.max(1);
    let m = motion.frames.len().div_ceil(every);
    let mut out = ExactTimes {
        first: Vec::with_capacity(m),
        best: Vec::with_capacity(m),
        answers: Vec::with_capacity(m),
        passes_agree: true,
    };
    for pass in 0..passes.max(1) {
        let mut scratch = ExactScratch::new();
        for (j, f) in motion.frames.iter().step_by(every).enumerate() {
            let t0 = clock();
            let e = std::hint::black_box(exact::distance(ma, &id, mb, &f.pose, &mut scratch));
            let us = clock() - t0;
            if pass == 0 {
                out.first.push(us);
                out.best.push(us);
                out.answers.push(e);
            } else {
                out.best[j] = out.best[j].min(us);
                let a = &out.answers[j];
                out.passes_agree &= a.distance.to_bits() == e.distance.to_bits()
                    && a.intersecting == e.intersecting;
            }
        }
    }
    out
}

/// What one query answered on one frame, and the node pairs it tested: passes that agree
/// on both did the same work.
#[derive(Debug, Clone, Copy, Default)]
struct Answer {
    answer: KindAnswer,
    visits: u64,
    /// The refined distance's search ran out of budget.
    incomplete: bool,
    /// The meshes' penetration's volume gradient.
    gradient: [f64; 3],
}

impl PartialEq for Answer {
    fn eq(&self, o: &Answer) -> bool {
        let (a, b) = (&self.answer, &o.answer);
        a.value.to_bits() == b.value.to_bits()
            && a.in_contact == b.in_contact
            && a.count == b.count
            && self.visits == o.visits
    }
}

/// One pass of `kind` over the motion from a fresh pair state: each frame's time (µs) into
/// `times` and its answer into `answers`.
#[allow(clippy::too_many_arguments)]
fn replay_pass<C: FnMut() -> f64>(
    a: &SharedTree,
    b: &SharedTree,
    motion: &Motion,
    kind: QueryKind,
    opts: &ReplayOptions,
    clock: &mut C,
    times: &mut [f64],
    answers: &mut [Answer],
) {
    let id = Pose::IDENTITY;
    let mut pair = Pair::new(a, b);
    let mo = MultipointOptions {
        k: opts.k,
        split_depth: opts.split_depth,
        ..Default::default()
    };
    for (i, f) in motion.frames.iter().enumerate() {
        let pb = f.pose;
        let t0 = clock();
        let (ans, t1) = match kind {
            QueryKind::Distance => {
                let r = std::hint::black_box(pair.distance(&id, &pb));
                let t1 = clock();
                (
                    Answer {
                        answer: KindAnswer {
                            in_contact: r.overlapping,
                            value: r.distance,
                            count: usize::from(r.overlapping),
                        },
                        visits: r.visits,
                        incomplete: false,
                        gradient: [0.0; 3],
                    },
                    t1,
                )
            }
            QueryKind::Contact => {
                let r = std::hint::black_box(pair.contact(&id, &pb));
                let t1 = clock();
                (
                    Answer {
                        answer: KindAnswer {
                            in_contact: r.in_contact(),
                            value: r.distance,
                            count: usize::from(r.in_contact()),
                        },
                        visits: r.visits,
                        incomplete: false,
                        gradient: [0.0; 3],
                    },
                    t1,
                )
            }
            QueryKind::Multipoint => {
                let r = std::hint::black_box(pair.multipoint(&id, &pb, &mo));
                let t1 = clock();
                (
                    Answer {
                        answer: KindAnswer {
                            in_contact: r.count > 0,
                            value: r.distance,
                            count: r.count,
                        },
                        visits: r.visits,
                        incomplete: false,
                        gradient: [0.0; 3],
                    },
                    t1,
                )
            }
            QueryKind::Penetration => {
                let r = std::hint::black_box(pair.penetration(&id, &pb));
                let t1 = clock();
                (
                    Answer {
                        answer: KindAnswer {
                            in_contact: r.pairs > 0,
                            value: r.volume,
                            count: r.pairs,
                        },
                        visits: r.visits,
                        incomplete: false,
                        gradient: [0.0; 3],
                    },
                    t1,
                )
            }
            QueryKind::RefinedDistance => {
                let r = std::hint::black_box(pair.refined_distance_with(&id, &pb, &opts.refine));
                let t1 = clock();
                let answer = match r {
                    Ok(r) => Answer {
                        answer: KindAnswer {
                            in_contact: r.intersecting,
                            value: r.distance,
                            count: r.triangle_pairs as usize,
                        },
                        visits: r.spheres.visits + r.node_pairs,
                        incomplete: !r.complete,
                        gradient: [0.0; 3],
                    },
                    // Trees without meshes: no answer (`ist replay` refuses this first).
                    Err(_) => Answer {
                        answer: KindAnswer {
                            in_contact: false,
                            value: f64::NAN,
                            count: 0,
                        },
                        visits: 0,
                        incomplete: true,
                        gradient: [0.0; 3],
                    },
                };
                (answer, t1)
            }
            QueryKind::MeshPenetration => {
                let r = std::hint::black_box(pair.mesh_penetration_with(
                    &id,
                    &pb,
                    &PenetrationOptions::default(),
                ));
                let t1 = clock();
                let answer = match r {
                    Ok(m) => Answer {
                        answer: KindAnswer {
                            in_contact: m.contact,
                            value: m.volume,
                            count: m.crossing_pairs,
                        },
                        visits: m.crossing_pairs as u64,
                        incomplete: false,
                        gradient: m.gradient.to_array(),
                    },
                    // Trees without meshes: no answer (`ist replay` refuses this first).
                    Err(_) => Answer {
                        answer: KindAnswer {
                            in_contact: false,
                            value: f64::NAN,
                            count: 0,
                        },
                        visits: 0,
                        incomplete: true,
                        gradient: [0.0; 3],
                    },
                };
                (answer, t1)
            }
        };
        times[i] = t1 - t0;
        answers[i] = ans;
    }
}
