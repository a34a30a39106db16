//! The contact wrench of one tick, within a deadline: the exact penetration query when its
//! predicted time fits what is left of the tick, else the time-critical one with a node-pair
//! budget sized to the time left.

use super::mat6::Mat6;
use super::step::Wrench;
use crate::{Pair, PenetrationOptions, Pose};
use std::time::{Duration, Instant};

/// A node-pair test of the time-critical query, assumed before any was measured (s): the
/// figure measured on the jaw trees (see [`Pair::penetration_within`]).
const FIRST_VISIT_COST: f64 = 75e-9;

/// Complete time-critical ticks in a row before the exact query is tried again (the very
/// first one, before any exact query, counts at once).
const RETURN_AFTER: u32 = 50;

/// The contact of one tick.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ContactSample {
    /// Penalty force and torque on the tool (world, about its centre of mass).
    pub wrench: Wrench,
    /// Their linearisation (`−∂w/∂x`, 6×6).
    pub stiffness: Mat6,
    /// Penetration volume (mm³): exact, or what the time-critical query found.
    pub volume: f64,
    /// Upper bound on the volume (= `volume` when exact).
    pub volume_bound: f64,
    /// Deepest leaf-pair overlap found (mm).
    pub max_depth: f64,
    /// Contact patches of the exact query (0 on the time-critical path).
    pub patches: usize,
    /// True when the time-critical query answered.
    pub budgeted: bool,
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
    /// Time-critical ticks in a row that found everything.
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

    /// The contact at the tool pose `pose_b`, answering before `deadline` (what is left of
    /// the tick after `reserve` for the rest of the tick).
    pub(crate) fn sample(
        &mut self,
        pair: &mut Pair,
        pose_a: &Pose,
        pose_b: &Pose,
        opts: &PenetrationOptions,
        deadline: Instant,
        reserve: Duration,
    ) -> ContactSample {
        let start = Instant::now();
        let left = deadline
            .checked_duration_since(start)
            .unwrap_or_default()
            .saturating_sub(reserve)
            .as_secs_f64();
        // The exact query's time follows the motion smoothly from tick to tick: 1.5× the
        // recent ones, plus a little for the clock's and the scheduler's noise.
        let predicted = self.exact.iter().copied().fold(f64::INFINITY, f64::min);
        if 1.5 * predicted + 5e-6 <= left {
            let p = pair.penetration_with(pose_a, pose_b, opts);
            self.exact[self.next] = start.elapsed().as_secs_f64();
            self.next = (self.next + 1) % self.exact.len();
            return ContactSample {
                wrench: Wrench {
                    force: p.force,
                    torque: p.torque_b,
                },
                stiffness: p.stiffness.to_matrix6(),
                volume: p.volume,
                volume_bound: p.volume,
                max_depth: p.max_depth,
                patches: p.patch_count,
                budgeted: false,
            };
        }
        let visits = ((0.7 * left / self.per_visit) as u64).max(1);
        let w = pair.penetration_within_with(pose_a, pose_b, visits, opts);
        let t = start.elapsed().as_secs_f64();
        if w.visits > 16 {
            self.per_visit = 0.8 * self.per_visit + 0.2 * (t / w.visits as f64);
        }
        if w.complete {
            // Everything was found in the budget: after enough such ticks in a row the exact
            // query (cheaper per frame, on its front) is expected to fit. Not at once: the
            // two paths feel the surface a little apart, and flipping between them every few
            // ticks would be felt as a buzz.
            self.complete_run += 1;
            if self.complete_run >= RETURN_AFTER || self.exact.iter().all(|e| e.is_infinite()) {
                self.exact = [predicted.min(t); 4];
                self.complete_run = 0;
            }
        } else {
            self.complete_run = 0;
            // Decay, so that a contact that shrank is eventually tried exactly again.
            for e in &mut self.exact {
                *e *= 0.999;
            }
        }
        ContactSample {
            wrench: Wrench {
                force: w.force,
                torque: w.torque_b,
            },
            stiffness: w.stiffness.to_matrix6(),
            volume: w.volume,
            volume_bound: w.upper_bound,
            max_depth: w.max_depth,
            patches: 0,
            budgeted: true,
        }
    }
}
