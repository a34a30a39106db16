//! The contact query of one tick (or one collision-thread round), within a deadline: the
//! exact penetration query when its predicted time fits what is left, else the time-critical
//! one with a node-pair budget sized to the time left. A complete answer becomes a new
//! [`ContactModel`]; an unfinished time-critical one only bounds the force of the model in use
//! (its unrefined node pairs' bounds are far larger than the contact, and pushing with them
//! kicks the hand).

use super::model::ContactModel;
use crate::pose::Pose;
use crate::query::{Pair, PenetrationOptions};
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

/// Chooses between the exact and the time-critical query from their measured costs.
#[derive(Debug, Clone)]
pub(crate) struct Deadline {
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
}

impl Deadline {
    pub(crate) fn new() -> Deadline {
        Deadline {
            exact: [f64::INFINITY; 4],
            next: 0,
            per_visit: FIRST_VISIT_COST,
            complete_run: 0,
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
        let start = Instant::now();
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
            let t = start.elapsed().as_secs_f64();
            self.exact[self.next] = t;
            self.next = (self.next + 1) % self.exact.len();
            let mut m = ContactModel::from_penetration(*pose_b, &p, sampled);
            m.query_seconds = t;
            return Answer::Model(m);
        }
        let visits = ((0.7 * left / self.per_visit) as u64).max(1);
        let w = pair.penetration_within_with(pose_a, pose_b, visits, opts);
        let t = start.elapsed().as_secs_f64();
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
