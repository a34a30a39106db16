//! The contact query of one tick (or one collision-thread round), within a deadline: the
//! exact penetration query when its predicted time fits what is left, else the time-critical
//! one with a node-pair budget sized to the time left. A complete answer becomes a new
//! [`ContactModel`]; an unfinished time-critical one only bounds the force of the model in use
//! (its unrefined node pairs' bounds are far larger than the contact, and pushing with them
//! kicks the hand).

use crate::model::ContactModel;
use innersphere::pose::Pose;
use innersphere::query::{Pair, PenetrationOptions};
use std::time::{Duration, Instant};

/// A node-pair test of the time-critical query, assumed before any was measured (s): the
/// figure measured on the jaw trees (see [`Pair::penetration_within`]).
const FIRST_VISIT_COST: f64 = 75e-9;

/// Complete time-critical answers in a row before the exact query is tried again (the very
/// first one, before any exact query, counts at once).
const RETURN_AFTER: u32 = 50;

/// What a query round learnt.
#[derive(Debug, Clone, Copy)]
// Not boxed: a box would allocate once per query on the real-time path.
#[allow(clippy::large_enum_variant)]
pub(crate) enum Answer {
    /// A complete answer (exact, or a time-critical query that finished): the new model.
    Model(ContactModel),
    /// The time-critical query ran out of budget; the model in use stays.
    Bound {
        /// The contact's penalty force is at most this (N).
        cap: f64,
        /// Volume of the leaf pairs found (mm³).
        found: f64,
        /// Upper bound on the volume (mm³).
        bound: f64,
        /// Deepest leaf-pair overlap found (mm).
        depth: f64,
    },
}

/// Where the deadline logic reads the time: the wall clock in a loop; a scripted clock in
/// tests, which drive the choice of query tick by tick.
pub(crate) trait Clock {
    fn now(&mut self) -> Instant;
}

/// The wall clock ([`Instant::now`]).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct WallClock;

impl Clock for WallClock {
    fn now(&mut self) -> Instant {
        Instant::now()
    }
}

/// Chooses between the exact and the time-critical query from their measured costs.
#[derive(Debug, Clone)]
pub(crate) struct Deadline<C: Clock = WallClock> {
    /// Times of the last exact queries (s), a ring; infinite until a query showed the
    /// contact small. Their minimum predicts the next: a preempted query (a spike) does not
    /// send the loop to the time-critical path, a contact that grew does.
    exact: [f64; 4],
    /// Where the next exact time goes in the ring.
    next: usize,
    /// Measured seconds per node-pair test of the time-critical query.
    per_visit: f64,
    /// Time-critical answers in a row that found everything.
    complete_run: u32,
    clock: C,
}

impl Deadline {
    pub(crate) fn new() -> Deadline {
        Deadline::with_clock(WallClock)
    }
}

impl<C: Clock> Deadline<C> {
    /// A deadline that reads the time from `clock`.
    pub(crate) fn with_clock(clock: C) -> Deadline<C> {
        Deadline {
            exact: [f64::INFINITY; 4],
            next: 0,
            per_visit: FIRST_VISIT_COST,
            complete_run: 0,
            clock,
        }
    }

    /// The contact at the tool pose `pose_b` (taken at `sampled`), answering before
    /// `deadline` (what is left after `reserve` for the rest of the tick), or exactly
    /// whatever it costs when `force_exact` (the model in use is too old to stand in).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn query(
        &mut self,
        pair: &mut Pair,
        pose_a: &Pose,
        pose_b: &Pose,
        sampled: Instant,
        opts: &PenetrationOptions,
        deadline: Instant,
        reserve: Duration,
        force_exact: bool,
    ) -> Answer {
        let start = self.clock.now();
        let left = deadline
            .checked_duration_since(start)
            .unwrap_or_default()
            .saturating_sub(reserve)
            .as_secs_f64();
        // The exact query's time follows the motion smoothly from tick to tick: 1.5× the
        // recent ones, plus a little for the clock's and the scheduler's noise.
        let predicted = self.exact.iter().copied().fold(f64::INFINITY, f64::min);
        if force_exact || 1.5 * predicted + 5e-6 <= left {
            let p = pair.penetration_with(pose_a, pose_b, opts);
            let t = self
                .clock
                .now()
                .saturating_duration_since(start)
                .as_secs_f64();
            self.exact[self.next] = t;
            self.next = (self.next + 1) % self.exact.len();
            let mut m = ContactModel::from_penetration(*pose_b, &p, sampled);
            m.query_seconds = t;
            return Answer::Model(m);
        }
        let visits = ((0.7 * left / self.per_visit) as u64).max(1);
        let w = pair.penetration_within_with(pose_a, pose_b, visits, opts);
        let t = self
            .clock
            .now()
            .saturating_duration_since(start)
            .as_secs_f64();
        if w.visits > 16 {
            self.per_visit = 0.8 * self.per_visit + 0.2 * (t / w.visits as f64);
        }
        if !w.complete {
            self.complete_run = 0;
            // Decay, so that a contact that shrank is eventually tried exactly again.
            for e in &mut self.exact {
                *e *= 0.999;
            }
            return Answer::Bound {
                cap: opts.stiffness * w.upper_bound,
                found: w.volume,
                bound: w.upper_bound,
                depth: w.max_depth,
            };
        }
        // Everything was found in the budget: after enough such answers in a row the exact
        // query (cheaper per frame, on its front) is expected to fit. Not at once: flipping
        // between the two every few ticks would only cost time.
        self.complete_run += 1;
        if self.complete_run >= RETURN_AFTER || self.exact.iter().all(|e| e.is_infinite()) {
            self.exact = [predicted.min(t); 4];
            self.complete_run = 0;
        }
        Answer::Model(ContactModel {
            pose: *pose_b,
            force: w.force,
            torque: w.torque_b,
            stiffness: w.stiffness.to_matrix6(),
            volume: w.volume,
            max_depth: w.max_depth,
            normal: w.normal,
            patches: 0,
            force_cap: f64::INFINITY,
            sampled,
            query_seconds: t,
            seq: 0,
        })
    }
}

/// Whether a time-critical `answer` that ran out of budget must be replaced by the exact
/// one: it found a contact the model in use (`last`) knows nothing of, which a bound on the
/// old model's force cannot stand in for.
pub(crate) fn needs_exact(answer: &Answer, last: &ContactModel) -> bool {
    matches!(*answer, Answer::Bound { found, .. } if found > 0.0 && !last.touching())
}

#[cfg(test)]
mod tests {
    //! The choice between the exact and the time-critical query, driven tick by tick by a
    //! scripted clock: which path runs when, the decay of the predicted time, the return to
    //! the exact path.
    use super::*;
    use glam::DVec3;
    use innersphere::build::{BuildOptions, Resolution};
    use innersphere::shapes;
    use innersphere::tree::SphereTree;
    use std::sync::OnceLock;

    /// A clock whose query takes `query`: a query reads it twice (start, end); the end
    /// reading is `query` after the start.
    struct Script {
        base: Instant,
        at: Duration,
        query: Duration,
        reads: u32,
    }

    impl Clock for Script {
        fn now(&mut self) -> Instant {
            self.reads += 1;
            if self.reads.is_multiple_of(2) {
                self.at += self.query;
            }
            self.base + self.at
        }
    }

    fn deadline(query_us: u64) -> Deadline<Script> {
        Deadline::with_clock(Script {
            base: Instant::now(),
            at: Duration::ZERO,
            query: Duration::from_micros(query_us),
            reads: 0,
        })
    }

    /// A slab (A) and a block (B) resting 0.3 mm into it: a contact of a few hundred leaf
    /// pairs.
    fn pair() -> Pair {
        static T: OnceLock<(SphereTree, SphereTree)> = OnceLock::new();
        let (a, b) = T.get_or_init(|| {
            let build = |h: DVec3, cells| {
                let o = BuildOptions {
                    resolution: Resolution::Cells(cells),
                    ..Default::default()
                };
                SphereTree::build(&shapes::cuboid(h), &o).unwrap()
            };
            (
                build(DVec3::new(10.0, 10.0, 1.0), 64),
                build(DVec3::new(2.0, 2.0, 1.0), 24),
            )
        });
        Pair::new(a.clone(), b.clone())
    }

    const INTO: Pose = Pose {
        translation: DVec3::new(0.0, 0.0, 1.7),
        rotation: glam::DQuat::IDENTITY,
    };

    /// One query with `left` seconds before the deadline (no reserve).
    fn ask(d: &mut Deadline<Script>, pair: &mut Pair, left: f64, force: bool) -> Answer {
        let opts = PenetrationOptions::default();
        let start = d.clock.base + d.clock.at;
        let by = start + Duration::from_secs_f64(left);
        d.query(
            pair,
            &Pose::IDENTITY,
            &INTO,
            start,
            &opts,
            by,
            Duration::ZERO,
            force,
        )
    }

    /// Whether the answer came from the exact query (it groups patches; the time-critical
    /// one does not).
    fn exact(a: &Answer) -> bool {
        matches!(a, Answer::Model(m) if m.patches > 0)
    }

    #[test]
    fn the_first_answer_is_time_critical_and_its_time_predicts_the_exact_query() {
        let (mut d, mut p) = (deadline(20), pair());
        let a = ask(&mut d, &mut p, 1.0, false);
        assert!(matches!(a, Answer::Model(_)) && !exact(&a), "{a:?}");
        assert_eq!(d.exact, [20e-6; 4]);
        let a = ask(&mut d, &mut p, 1.0, false);
        assert!(exact(&a), "{a:?}");
        assert_eq!((d.exact[0], d.next), (20e-6, 1));
        if let Answer::Model(m) = a {
            assert_eq!(m.query_seconds, 20e-6);
            assert!(m.volume > 0.0);
        }
    }

    #[test]
    fn the_exact_query_runs_when_its_predicted_time_fits_what_is_left() {
        let (mut d, mut p) = (deadline(10), pair());
        d.exact = [10e-6, 40e-6, 30e-6, 50e-6];
        // Predicted: the fastest recent one, 10 µs; it must fit 1.5× + 5 µs = 20 µs.
        assert!(exact(&ask(&mut d, &mut p, 25e-6, false)));
        assert_eq!(d.next, 1);
        let a = ask(&mut d, &mut p, 19e-6, false);
        assert!(!exact(&a), "{a:?}");
        assert_eq!(d.next, 1, "the time-critical query does not enter the ring");
        // The model in use too old: exact whatever is left.
        assert!(exact(&ask(&mut d, &mut p, 0.0, true)));
        assert_eq!(d.next, 2);
    }

    #[test]
    fn an_unfinished_answer_decays_the_predicted_time() {
        let (mut d, mut p) = (deadline(1), pair());
        d.exact = [1e-3; 4];
        d.complete_run = 7;
        let a = ask(&mut d, &mut p, 1e-6, false);
        let Answer::Bound {
            cap,
            found,
            bound,
            depth,
        } = a
        else {
            panic!("a budget of a few node pairs finished: {a:?}");
        };
        assert!(found <= bound && cap == bound && depth >= 0.0, "{a:?}");
        assert_eq!(d.exact, [1e-3 * 0.999; 4]);
        assert_eq!(d.complete_run, 0);
        for _ in 0..9 {
            ask(&mut d, &mut p, 1e-6, false);
        }
        let mut want = 1e-3;
        for _ in 0..10 {
            want *= 0.999;
        }
        assert_eq!(d.exact, [want; 4]);
    }

    #[test]
    fn the_exact_query_returns_after_fifty_complete_answers_in_a_row() {
        let (mut d, mut p) = (deadline(30), pair());
        // The exact query last took 1 s: it cannot fit 10 ms.
        d.exact = [1.0; 4];
        for k in 1..RETURN_AFTER {
            let a = ask(&mut d, &mut p, 10e-3, false);
            assert!(matches!(a, Answer::Model(_)) && !exact(&a), "{k}: {a:?}");
            assert_eq!((d.exact, d.complete_run), ([1.0; 4], k));
        }
        ask(&mut d, &mut p, 10e-3, false);
        assert_eq!((d.exact, d.complete_run), ([30e-6; 4], 0));
        assert!(exact(&ask(&mut d, &mut p, 10e-3, false)));
    }

    #[test]
    fn the_cost_per_node_pair_follows_the_measured_one() {
        let (mut d, mut p) = (deadline(1000), pair());
        d.exact = [1.0; 4];
        ask(&mut d, &mut p, 10e-3, false);
        // 1 ms over more than 16 node pairs: between the prior and the prior's 0.8 plus a
        // fifth of 1 ms / 17.
        let (lo, hi) = (
            FIRST_VISIT_COST,
            0.8 * FIRST_VISIT_COST + 0.2 * (1e-3 / 17.0),
        );
        assert!(d.per_visit > lo && d.per_visit < hi, "{}", d.per_visit);
        // The budget is 70 % of what is left at the cost per node pair: 10 µs at 75 ns is 93
        // node pairs, which the contact outlasts; the measured cost per pair tells how many
        // ran.
        let (mut d, mut p) = (deadline(93), pair());
        d.exact = [1.0; 4];
        let a = ask(&mut d, &mut p, 10e-6, false);
        assert!(matches!(a, Answer::Bound { .. }), "{a:?}");
        let per_pair = (d.per_visit - 0.8 * FIRST_VISIT_COST) / 0.2;
        let ran = 93e-6 / per_pair;
        assert!(
            (90.0..=97.0).contains(&ran),
            "{ran} node pairs for a budget of 93"
        );
    }

    #[test]
    fn only_a_new_contact_found_out_of_budget_asks_for_the_exact_query() {
        let apart = ContactModel::none(Pose::IDENTITY);
        let touching = ContactModel {
            force: DVec3::new(0.0, 0.0, 2.0),
            volume: 0.1,
            ..apart
        };
        assert!(touching.touching() && !apart.touching());
        let bound = |found| Answer::Bound {
            cap: 1.0,
            found,
            bound: 1.0,
            depth: 0.1,
        };
        assert!(needs_exact(&bound(0.01), &apart));
        assert!(!needs_exact(&bound(0.0), &apart));
        assert!(!needs_exact(&bound(0.01), &touching));
        assert!(!needs_exact(&bound(0.0), &touching));
        assert!(!needs_exact(&Answer::Model(touching), &apart));
    }
}
