//! The two-thread (multi-rate) haptic loop: the penetration query runs in a collision thread
//! of its own, as fast as it can, and publishes a [`ContactModel`] (the wrench and its
//! linearisation at the tool pose it answered for); the servo tick, at the device's rate,
//! evaluates the newest model at the tool's current pose, blends a new model in without a
//! force step, and moves the tool. Both directions go through lock-free triple buffers: the
//! servo tick never waits for the collision thread, takes no lock and allocates nothing, so
//! its time does not depend on the contact (Mark et al. 1996; Otaduy & Lin 2006).

use crate::body::{BodyState, RigidBody};
use crate::deadline::{needs_exact, Answer, Deadline};
use crate::model::{ContactModel, ContactSource};
use crate::render::{HapticOptions, Tick};
use crate::servo::Servo;
use innersphere::error::num;
use innersphere::error::{Error, Result};
use innersphere::pose::Pose;
use innersphere::query::{Pair, PenetrationOptions};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::thread::JoinHandle;
use std::time::{Duration, Instant};
use triple_buffer::{triple_buffer, Input, Output};

/// Settings of the collision thread of a [`MultirateLoop`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CollisionOptions {
    /// Seconds to sleep before each collision query (0: none). A stress knob that stands
    /// for a slow machine: the models arrive that much later and older.
    pub delay: f64,
    /// Most time one collision query may take (s): beyond it the time-critical query
    /// answers instead, bounding the model in use rather than replacing it (a last resort,
    /// for contacts whose exact query takes milliseconds). Default 5 ms.
    pub budget: f64,
    /// Collision query times kept for [`CollisionStats`] (a ring allocated when the thread
    /// starts, 4 bytes each). Default 2²⁰.
    pub history: usize,
    /// Where the contact comes from. Default the spheres (see docs/HAPTICS.md for why). With
    /// [`ContactSource::Mesh`] every query is the meshes' exact one, whatever it costs:
    /// `budget` does not apply, the servo renders the newest model meanwhile.
    pub contact: ContactSource,
}

impl Default for CollisionOptions {
    fn default() -> Self {
        CollisionOptions {
            delay: 0.0,
            budget: 5e-3,
            history: 1 << 20,
            contact: ContactSource::Spheres,
        }
    }
}

impl CollisionOptions {
    /// Refuses a delay that is negative, not finite or over a second, a budget that is not
    /// positive and finite, or a history that is empty or over 2²⁶ entries.
    pub fn check(&self) -> Result<()> {
        if !(self.delay.is_finite() && (0.0..=1.0).contains(&self.delay)) {
            return Err(Error::InvalidOption(format!(
                "the collision delay must be between 0 and 1 s, not {} s",
                num(self.delay)
            )));
        }
        if !(self.budget.is_finite() && self.budget > 0.0 && self.budget <= 1.0) {
            return Err(Error::InvalidOption(format!(
                "the collision budget must be above 0 and at most 1 s, not {} s",
                num(self.budget)
            )));
        }
        if !(1..=1 << 26).contains(&self.history) {
            return Err(Error::InvalidOption(format!(
                "the collision history must hold 1 to 67108864 times, not {}",
                self.history
            )));
        }
        Ok(())
    }
}

/// What the collision thread did, returned by [`MultirateLoop::finish`].
#[derive(Debug, Clone, PartialEq)]
pub struct CollisionStats {
    /// Queries run (models published).
    pub queries: u64,
    /// Queries answered by the time-critical query (the model in use kept, bounded).
    pub budgeted: u64,
    /// Seconds from the thread's start to its end.
    pub elapsed: f64,
    /// Seconds of the last `history` queries, oldest first (the stress delay excluded).
    pub times: Vec<f32>,
}

impl CollisionStats {
    /// Models published per second.
    pub fn rate_hz(&self) -> f64 {
        if self.elapsed > 0.0 {
            self.queries as f64 / self.elapsed
        } else {
            0.0
        }
    }

    /// The `q` quantile (0..=1) of the query times kept (s); 0 without any.
    pub fn quantile(&self, q: f64) -> f64 {
        if self.times.is_empty() {
            return 0.0;
        }
        let mut t = self.times.clone();
        t.sort_by(f32::total_cmp);
        t[((t.len() - 1) as f64 * q.clamp(0.0, 1.0)).round() as usize] as f64
    }
}

/// The tool pose the servo asks the collision thread about.
#[derive(Debug, Clone, Copy)]
struct PoseSample {
    pose: Pose,
    at: Instant,
    seq: u64,
}

/// The haptic loop of [`HapticLoop`](crate::HapticLoop) with its penetration query in a
/// collision thread of its own. Make it with [`spawn`](Self::spawn) from the servo thread's
/// side, call [`tick`](Self::tick) once per device tick from one thread (the device's servo
/// callback): it reads the newest contact model, never waits, takes no lock and allocates
/// nothing. Dropping it (or [`finish`](Self::finish)) stops and joins the collision thread.
#[derive(Debug)]
pub struct MultirateLoop {
    tool: Servo,
    poses: Input<PoseSample>,
    models: Output<ContactModel>,
    seq: u64,
    model_seq: u64,
    stop: Arc<AtomicBool>,
    published: Arc<AtomicU64>,
    thread: Option<JoinHandle<CollisionStats>>,
}

impl MultirateLoop {
    /// Starts the collision thread on `pair` (A fixed at `pose_a`, the tool B at rest at
    /// `start`) and returns the servo side. Fails on bad options, a tree of B without mass
    /// properties, mesh contact without both trees' meshes, or a thread the system would not
    /// start.
    pub fn spawn(
        pair: Pair,
        pose_a: Pose,
        start: Pose,
        opts: HapticOptions,
        collision: CollisionOptions,
    ) -> Result<MultirateLoop> {
        opts.check()?;
        collision.check()?;
        if collision.contact == ContactSource::Mesh
            && (pair.tree_a().mesh().is_none() || pair.tree_b().mesh().is_none())
        {
            return Err(Error::InvalidOption(
                "mesh contact needs both trees' meshes (SharedTree::with_mesh)".into(),
            ));
        }
        let body = RigidBody::from_tree(pair.tree_b(), opts.density)?;
        let now = Instant::now();
        let (poses_in, poses_out) = triple_buffer(&PoseSample {
            pose: start,
            at: now,
            seq: 1,
        });
        let (models_in, models_out) = triple_buffer(&ContactModel::none(start));
        let stop = Arc::new(AtomicBool::new(false));
        let published = Arc::new(AtomicU64::new(0));
        let worker = Collision {
            pair,
            pose_a,
            penetration: opts.penetration(),
            options: collision,
            poses: poses_out,
            models: models_in,
            stop: stop.clone(),
            published: published.clone(),
        };
        let thread = std::thread::Builder::new()
            .name("innersphere-collision".into())
            .spawn(move || worker.run())
            .map_err(|e| {
                Error::InvalidOption(format!("the collision thread did not start: {e}"))
            })?;
        Ok(MultirateLoop {
            tool: Servo::start(body, start, opts),
            poses: poses_in,
            models: models_out,
            seq: 1,
            model_seq: 0,
            stop,
            published,
            thread: Some(thread),
        })
    }

    /// One device tick at the period of the options' rate (see
    /// [`HapticLoop::tick`](crate::HapticLoop::tick)).
    pub fn tick(&mut self, device: &Pose) -> Tick {
        // A step of 0 stands for one period.
        self.tick_step(device, 0.0)
    }

    /// One device tick with the caller's measured `dt` (see
    /// [`HapticLoop::tick_step`](crate::HapticLoop::tick_step)).
    pub fn tick_step(&mut self, device: &Pose, dt: f64) -> Tick {
        let start = Instant::now();
        let sensed = self.tool.sense(device, dt);
        if self.models.update() {
            let m = *self.models.output_buffer();
            if m.seq != self.model_seq {
                self.model_seq = m.seq;
                self.tool.new_model(m);
            }
        }
        let sent = self.tool.step(&sensed);
        // The pose the collision thread answers for next: where the tool is now.
        self.seq += 1;
        self.poses.write(PoseSample {
            pose: self.tool.state.pose,
            at: Instant::now(),
            seq: self.seq,
        });
        let compute = start.elapsed().as_secs_f64();
        self.tool.tick_of(&sent, compute, start)
    }

    /// Models the collision thread has published so far (read without waiting).
    pub fn collision_queries(&self) -> u64 {
        self.published.load(Ordering::Relaxed)
    }

    /// Stops and joins the collision thread; what it did.
    pub fn finish(mut self) -> CollisionStats {
        self.stop_thread().unwrap_or(CollisionStats {
            queries: 0,
            budgeted: 0,
            elapsed: 0.0,
            times: vec![],
        })
    }

    fn stop_thread(&mut self) -> Option<CollisionStats> {
        self.stop.store(true, Ordering::Release);
        self.thread.take().and_then(|t| t.join().ok())
    }

    /// Energy the device has delivered to the hand so far (J; see
    /// [`HapticLoop::energy_to_user`](crate::HapticLoop::energy_to_user)).
    pub fn energy_to_user(&self) -> f64 {
        self.tool.energy_to_user()
    }

    /// The largest value [`energy_to_user`](Self::energy_to_user) has had.
    pub fn energy_to_user_max(&self) -> f64 {
        self.tool.energy_to_user_max()
    }

    /// The tool's state.
    pub fn state(&self) -> &BodyState {
        &self.tool.state
    }

    /// The tool's mass properties.
    pub fn body(&self) -> &RigidBody {
        &self.tool.body
    }

    /// The options.
    pub fn options(&self) -> &HapticOptions {
        &self.tool.opts
    }

    /// The newest contact model the servo has taken.
    pub fn model(&self) -> &ContactModel {
        self.tool.blend.target()
    }
}

impl Drop for MultirateLoop {
    fn drop(&mut self) {
        self.stop_thread();
    }
}

/// The collision thread's side.
struct Collision {
    pair: Pair,
    pose_a: Pose,
    penetration: PenetrationOptions,
    options: CollisionOptions,
    poses: Output<PoseSample>,
    models: Input<ContactModel>,
    stop: Arc<AtomicBool>,
    published: Arc<AtomicU64>,
}

impl Collision {
    /// Answers the newest tool pose, publishes, and again, until stopped.
    fn run(mut self) -> CollisionStats {
        let began = Instant::now();
        let mut times = vec![0f32; self.options.history];
        let (mut queries, mut budgeted) = (0u64, 0u64);
        let mut deadline = Deadline::new();
        let mut answered = 0u64;
        let mut last = ContactModel::none(self.poses.output_buffer().pose);
        let budget = Duration::from_secs_f64(self.options.budget);
        let delay = Duration::from_secs_f64(self.options.delay);
        let mut idle = 0u32;
        while !self.stop.load(Ordering::Acquire) {
            self.poses.update();
            let p = *self.poses.output_buffer();
            if p.seq == answered {
                // Nothing new: spin a little, then nap. Not yield in a loop: under real-time
                // scheduling that keeps the core busy, and the kernel's real-time throttling
                // then stops the thread for 50 ms in every second (measured).
                idle = idle.saturating_add(1);
                match idle_wait(idle) {
                    None => std::hint::spin_loop(),
                    Some(nap) => std::thread::sleep(nap),
                }
                continue;
            }
            idle = 0;
            answered = p.seq;
            if !delay.is_zero() {
                std::thread::sleep(delay);
            }
            let t0 = Instant::now();
            let answer = match self.options.contact {
                ContactSource::Spheres => self.spheres(&mut deadline, &p, t0 + budget, &last),
                ContactSource::Mesh => Answer::Model(self.mesh(&p)),
            };
            let t = t0.elapsed().as_secs_f64();
            budgeted += matches!(answer, Answer::Bound { .. }) as u64;
            let mut model = model_of(answer, &last);
            queries += 1;
            model.seq = queries;
            model.query_seconds = t;
            last = model;
            self.models.write(model);
            self.published.store(queries, Ordering::Relaxed);
            let slot = ring_slot(queries, times.len());
            times[slot] = t as f32;
            if let Some(rest) = rest_after(t) {
                std::thread::sleep(rest);
            }
        }
        CollisionStats {
            queries,
            budgeted,
            elapsed: began.elapsed().as_secs_f64(),
            times: oldest_first(&times, queries),
        }
    }
}

impl Collision {
    /// The spheres' answer at the sampled pose `p`: exact when it fits before `due`, else the
    /// time-critical one, unless that found a contact the model in use (`last`) does not know.
    fn spheres(
        &mut self,
        deadline: &mut Deadline,
        p: &PoseSample,
        due: Instant,
        last: &ContactModel,
    ) -> Answer {
        let answer = deadline.query(
            &mut self.pair,
            &self.pose_a,
            &p.pose,
            p.at,
            &self.penetration,
            due,
            Duration::ZERO,
            false,
        );
        if !needs_exact(&answer, last) {
            return answer;
        }
        deadline.query(
            &mut self.pair,
            &self.pose_a,
            &p.pose,
            p.at,
            &self.penetration,
            due,
            Duration::ZERO,
            true,
        )
    }

    /// The meshes' model at the sampled pose `p` (both meshes are there: checked at spawn).
    fn mesh(&mut self, p: &PoseSample) -> ContactModel {
        match self
            .pair
            .mesh_penetration_with(&self.pose_a, &p.pose, &self.penetration)
        {
            Ok(m) => ContactModel::from_mesh_penetration(p.pose, &m, p.at),
            Err(_) => ContactModel::none(p.pose),
        }
    }
}

/// The model an `answer` makes: a complete answer's own; for one that ran out of budget, the
/// model in use (`last`) with the bound's force cap.
fn model_of(answer: Answer, last: &ContactModel) -> ContactModel {
    match answer {
        Answer::Model(m) => m,
        Answer::Bound { cap, .. } => ContactModel {
            force_cap: cap,
            ..*last
        },
    }
}

/// Queries longer than this are followed by a rest ([`rest_after`]).
const REST_AFTER: f64 = 200e-6;

/// The rest after a query of `t` seconds: an eighth of it when it is long. A collision thread
/// that never idles (queries of milliseconds, a new pose every tick: the meshes' contact)
/// runs more than 95 % of every second, and under real-time scheduling the kernel's
/// throttling then stops it for the rest of that second, 50 ms of ever older models
/// (measured on the jaw press at 10 kHz: models 52 ms old once a second). Resting an eighth
/// keeps it busy at most 89 % of the time, models a tenth older.
fn rest_after(t: f64) -> Option<Duration> {
    (t > REST_AFTER).then(|| Duration::from_secs_f64(t / 8.0))
}

/// Where query `k` (1, 2, …) keeps its time in a ring of `len`.
fn ring_slot(k: u64, len: usize) -> usize {
    ((k - 1) % len as u64) as usize
}

/// The times of `queries` queries kept in the ring `times`, oldest first.
fn oldest_first(times: &[f32], queries: u64) -> Vec<f32> {
    let n = times.len() as u64;
    let mut ordered = times[..queries.min(n) as usize].to_vec();
    // Once the ring is full the oldest is in the slot written next; before, in slot 0.
    ordered.rotate_left((queries.max(n) % n) as usize);
    ordered
}

/// How the collision thread waits after `idle` rounds in a row found no new pose: `None`, a
/// spin, for the first 63; then naps of 20 µs. Not a yield in a loop: under real-time
/// scheduling that keeps the core busy, and the kernel's real-time throttling then stops the
/// thread for 50 ms in every second (measured).
fn idle_wait(idle: u32) -> Option<Duration> {
    (idle >= 64).then_some(Duration::from_micros(20))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn only_a_long_query_is_followed_by_a_rest_of_an_eighth() {
        assert_eq!(rest_after(150e-6), None);
        assert_eq!(rest_after(REST_AFTER), None);
        assert_eq!(rest_after(4e-3), Some(Duration::from_micros(500)));
    }

    #[test]
    fn bad_collision_options_are_refused_and_the_edges_taken() {
        let ok = CollisionOptions::default();
        assert!(ok.check().is_ok());
        let with = |delay, budget, history| CollisionOptions {
            delay,
            budget,
            history,
            contact: ContactSource::Mesh,
        };
        for good in [with(0.0, 1.0, 1), with(1.0, 1e-9, 1 << 26)] {
            assert!(good.check().is_ok(), "{good:?}");
        }
        for bad in [
            with(-1e-3, 5e-3, 8),
            with(2.0, 5e-3, 8),
            with(f64::NAN, 5e-3, 8),
            with(f64::INFINITY, 5e-3, 8),
            with(0.0, 0.0, 8),
            with(0.0, -1.0, 8),
            with(0.0, 2.0, 8),
            with(0.0, f64::NAN, 8),
            with(0.0, f64::INFINITY, 8),
            with(0.0, 5e-3, 0),
            with(0.0, 5e-3, (1 << 26) + 1),
        ] {
            assert!(
                matches!(bad.check(), Err(Error::InvalidOption(_))),
                "{bad:?}"
            );
        }
    }

    fn stats(queries: u64, elapsed: f64, times: &[f32]) -> CollisionStats {
        CollisionStats {
            queries,
            budgeted: 0,
            elapsed,
            times: times.to_vec(),
        }
    }

    #[test]
    fn the_collision_rate_and_the_time_quantiles() {
        assert_eq!(stats(300, 1.5, &[]).rate_hz(), 200.0);
        assert_eq!(stats(300, 0.0, &[]).rate_hz(), 0.0);
        assert_eq!(stats(0, 0.0, &[]).quantile(0.5), 0.0);
        // 11 times in a scrambled order: the quantiles are the sorted ones at q · 10.
        let t: Vec<f32> = (0..11).map(|k| ((k * 7) % 11) as f32 + 1.0).collect();
        let s = stats(11, 1.0, &t);
        assert_eq!(s.quantile(0.0), 1.0);
        assert_eq!(s.quantile(0.5), 6.0);
        assert_eq!(s.quantile(0.94), 10.0);
        assert_eq!(s.quantile(1.0), 11.0);
        assert_eq!(s.quantile(7.0), 11.0);
        assert_eq!(s.quantile(-1.0), 1.0);
    }

    #[test]
    fn the_query_times_ring_keeps_the_last_ones_oldest_first() {
        // Queries 1..=k into a ring of 4, each time its number.
        let ring = |k: u64| {
            let mut times = [0f32; 4];
            for q in 1..=k {
                times[ring_slot(q, 4)] = q as f32;
            }
            oldest_first(&times, k)
        };
        assert_eq!(ring(0), Vec::<f32>::new());
        assert_eq!(ring(3), [1.0, 2.0, 3.0]);
        assert_eq!(ring(4), [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(ring(6), [3.0, 4.0, 5.0, 6.0]);
        assert_eq!(ring(9), [6.0, 7.0, 8.0, 9.0]);
        assert_eq!(ring_slot(1, 1), 0);
        assert_eq!(ring_slot(7, 1), 0);
    }

    #[test]
    fn an_answer_out_of_budget_keeps_the_model_in_use_under_its_cap() {
        let last = ContactModel {
            force: DVec3::new(0.0, 0.0, 2.0),
            volume: 0.1,
            seq: 7,
            ..ContactModel::none(Pose::IDENTITY)
        };
        let bound = Answer::Bound {
            cap: 1.5,
            found: 0.05,
            bound: 0.03,
            depth: 0.1,
        };
        let kept = model_of(bound, &last);
        assert_eq!(kept.force_cap, 1.5);
        assert_eq!(
            ContactModel {
                force_cap: last.force_cap,
                ..kept
            },
            last
        );
        let new = ContactModel {
            force: DVec3::X,
            ..last
        };
        assert_eq!(model_of(Answer::Model(new), &last), new);
    }

    #[test]
    fn the_thread_spins_first_then_naps() {
        assert_eq!(idle_wait(1), None);
        assert_eq!(idle_wait(63), None);
        assert_eq!(idle_wait(64), Some(Duration::from_micros(20)));
        assert_eq!(idle_wait(u32::MAX), Some(Duration::from_micros(20)));
    }
}
