//! The 1 kHz loop thread: reads the control (B's target pose, the mode, the motion's play
//! state) from the HTTP side, runs the library's queries (and its haptic loop in haptic
//! mode) and publishes its state. Both directions go through triple buffers: the loop never
//! waits for the HTTP side, and no tick allocates.

use innersphere::glam::DVec3;
use innersphere::{DistanceOptions, Pair, Patch, PenetrationOptions, Pose, SharedTree};
use innersphere_haptic::{
    CollisionOptions, ContactModel, ContactSource, DeviceClass, HapticOptions, MultirateLoop,
};
use innersphere_motion::Motion;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Patches kept in the state.
pub const PATCHES: usize = 8;
/// Tick times kept for the page's chart.
pub const HISTORY: usize = 240;
/// Ticks the p99 is taken over.
const WINDOW: usize = 1000;

/// What drives body B.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// B is where the page puts it.
    Free,
    /// The page's pose is a haptic device's; B is the coupled tool that stops at A.
    Haptic,
    /// B follows the motion (play, pause, scrub).
    Motion,
}

impl Mode {
    /// `free`, `haptic` or `motion`.
    pub fn name(self) -> &'static str {
        match self {
            Mode::Free => "free",
            Mode::Haptic => "haptic",
            Mode::Motion => "motion",
        }
    }
}

/// What the HTTP side asks of the loop.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Control {
    pub target: Pose,
    pub mode: Mode,
    pub playing: bool,
    /// A scrub: the motion time to jump to, applied when `seek_id` changes.
    pub seek: f64,
    pub seek_id: u64,
}

/// The loop's latest state (plain values: copied through the triple buffer).
#[derive(Debug, Clone, Copy)]
pub struct LoopState {
    /// Seconds since the loop started.
    pub t: f64,
    /// The mode of this tick.
    pub mode: Mode,
    /// Where to draw B (the tool in haptic mode).
    pub pose_b: Pose,
    /// B's target: the page's or the motion's pose (the device's in haptic mode).
    pub target_b: Pose,
    /// Distance apart (0 in contact): between the meshes when the trees carry them
    /// (`distance_refined`), else between the sphere packings.
    pub distance: f64,
    /// True when `distance` and the closest points are the refined distance's.
    pub distance_refined: bool,
    /// True when they overlap.
    pub contact: bool,
    /// Closest point on A.
    pub point_a: DVec3,
    /// Closest point on B.
    pub point_b: DVec3,
    /// Penetration volume.
    pub volume: f64,
    /// Deepest leaf overlap.
    pub max_depth: f64,
    /// Penalty force on B.
    pub force: DVec3,
    /// Torque on B.
    pub torque: DVec3,
    /// Contact patches (the first `patch_count`).
    pub patches: [Patch; PATCHES],
    /// How many of `patches` are set.
    pub patch_count: usize,
    /// Haptic mode: the force the device would render.
    pub device_force: DVec3,
    /// Ticks run.
    pub ticks: u64,
    /// Ticks whose work took over 1 ms.
    pub over_1ms: u64,
    /// Measured tick rate (Hz).
    pub rate_hz: f64,
    /// This tick's work (µs).
    pub tick_us: f64,
    /// 99th percentile of the last 1000 ticks' work (µs).
    pub tick_us_p99: f64,
    /// Slowest tick's work so far (µs).
    pub tick_us_max: f64,
    /// Recent tick times (µs), a ring: `history_us[history_next..]` then `[..history_next]`.
    pub history_us: [f32; HISTORY],
    /// Where the next tick time goes in the ring.
    pub history_next: usize,
    /// Motion time (s).
    pub motion_t: f64,
    /// Whether the motion plays.
    pub playing: bool,
    /// Whether the loop thread got real-time scheduling (SCHED_FIFO), as haptic loops ask
    /// for: without it other threads (the HTTP side, the browser) can preempt a tick.
    pub realtime: bool,
    /// Haptic mode: contact models the collision thread publishes per second.
    pub collision_rate_hz: f64,
    /// Haptic mode: age of the contact model this tick used (µs).
    pub model_age_us: f64,
    /// Where the volume, depth, force and patches come from.
    pub contact_source: ContactSource,
}

const NO_PATCH: Patch = Patch {
    point: DVec3::ZERO,
    normal: DVec3::ZERO,
    depth: 0.0,
    volume: 0.0,
    pairs: 0,
};

impl LoopState {
    pub(crate) fn initial(pose: Pose) -> LoopState {
        LoopState {
            t: 0.0,
            mode: Mode::Free,
            pose_b: pose,
            target_b: pose,
            distance: 0.0,
            distance_refined: false,
            contact: false,
            point_a: DVec3::ZERO,
            point_b: DVec3::ZERO,
            volume: 0.0,
            max_depth: 0.0,
            force: DVec3::ZERO,
            torque: DVec3::ZERO,
            patches: [NO_PATCH; PATCHES],
            patch_count: 0,
            device_force: DVec3::ZERO,
            ticks: 0,
            over_1ms: 0,
            rate_hz: 0.0,
            tick_us: 0.0,
            tick_us_p99: 0.0,
            tick_us_max: 0.0,
            history_us: [0.0; HISTORY],
            history_next: 0,
            motion_t: 0.0,
            playing: false,
            realtime: false,
            collision_rate_hz: 0.0,
            model_age_us: 0.0,
            contact_source: ContactSource::Spheres,
        }
    }
}

/// The loop's inputs and outputs.
pub(crate) struct LoopIo {
    pub control: triple_buffer::Output<Control>,
    pub state: triple_buffer::Input<LoopState>,
    pub stop: Arc<AtomicBool>,
}

/// Runs the loop at `rate` Hz until `io.stop` is set.
pub(crate) fn run(
    a: SharedTree,
    b: SharedTree,
    motion: Option<Motion>,
    stiffness: f64,
    rate: f64,
    contact: ContactSource,
    mut io: LoopIo,
) {
    let mut pair = Pair::new(a.clone(), b.clone());
    let haptic_opts = HapticOptions::for_device(DeviceClass::Omega);
    let mut haptic: Option<MultirateLoop> = None;
    let dist = DistanceOptions::default();
    let pen = penetration_options(stiffness);
    let period = Duration::from_secs_f64(1.0 / rate);
    let mut clock = WallClock;
    let start = clock.now();
    let mut deadline = start;
    let mut state = LoopState::initial(io.control.read().target);
    state.contact_source = contact;
    let mut stats = TickStats::new();
    let mut last_mode = Mode::Free;
    let mut seek_id = 0u64;
    let mut rate_from = (start, 0u64, 0u64);
    state.realtime = innersphere_haptic::realtime::realtime_priority(Some(
        innersphere_haptic::realtime::SERVO_PRIORITY,
    ));
    while !io.stop.load(Ordering::Relaxed) {
        deadline += period;
        let t0 = clock.now();
        let c = *io.control.read();
        if let Some(m) = &motion {
            motion_clock(&mut state.motion_t, &mut seek_id, &c, m.duration(), rate);
            state.playing = c.playing;
        }
        let target = target_of(motion.as_ref(), &c, state.motion_t);
        // Entering haptic mode puts the tool at rest at the device's pose, its penetration
        // query in a collision thread of its own (a thread and an allocation when the mode
        // changes, never per tick); leaving it stops that thread.
        switch_haptic(&mut haptic, last_mode, c.mode, || {
            MultirateLoop::spawn(
                Pair::new(a.clone(), b.clone()),
                Pose::IDENTITY,
                target,
                haptic_opts,
                CollisionOptions {
                    contact,
                    ..Default::default()
                },
            )
            .ok()
        });
        last_mode = c.mode;
        let (pose_b, device_force) = match (c.mode, haptic.as_mut()) {
            (Mode::Haptic, Some(h)) => {
                let t = h.tick(&target);
                state.model_age_us = micros(t.model_age);
                (t.tool, t.force)
            }
            _ => {
                state.model_age_us = 0.0;
                (target, DVec3::ZERO)
            }
        };
        match contact {
            ContactSource::Spheres => observe(&mut pair, &pose_b, &pen, &dist, &mut state),
            ContactSource::Mesh => {
                let model = match (c.mode, haptic.as_ref()) {
                    (Mode::Haptic, Some(h)) => Some(*h.model()),
                    _ => None,
                };
                observe_meshes(&mut pair, &pose_b, &pen, model.as_ref(), &mut state);
            }
        }
        state.mode = c.mode;
        state.pose_b = pose_b;
        state.target_b = target;
        state.device_force = device_force;
        // Timing.
        stats.record(micros(t0.elapsed().as_secs_f64()), &mut state);
        let models = haptic.as_ref().map_or(0, |h| h.collision_queries());
        rates(&mut rate_from, t0, models, &mut state);
        state.t = t0.duration_since(start).as_secs_f64();
        io.state.write(state);
        pace(&mut deadline, &mut clock);
    }
}

/// The haptic loop across a mode change from `last` to `mode`: entering haptic mode starts
/// one (`start`), leaving it drops it (which stops its collision thread), else it stays.
fn switch_haptic<H>(
    haptic: &mut Option<H>,
    last: Mode,
    mode: Mode,
    start: impl FnOnce() -> Option<H>,
) {
    if mode == Mode::Haptic && last != Mode::Haptic {
        *haptic = start();
    } else if mode != Mode::Haptic {
        *haptic = None;
    }
}

/// The penetration options of the loop's query: the scene's `stiffness`, and the patches
/// the state keeps.
fn penetration_options(stiffness: f64) -> PenetrationOptions {
    PenetrationOptions {
        stiffness,
        max_patches: PATCHES,
        ..Default::default()
    }
}

/// B's target this tick: in motion mode the motion's pose `motion_t` after its first frame,
/// else the page's.
fn target_of(motion: Option<&Motion>, c: &Control, motion_t: f64) -> Pose {
    match (motion, c.mode) {
        (Some(m), Mode::Motion) => m.pose_at(m.frames[0].t + motion_t),
        _ => c.target,
    }
}

/// One tick's queries with B at `pose_b`, into `state`: penetration first, the distance only
/// while apart (in contact it is 0, and the patches say where), so that one query runs per
/// tick where the work is largest. The distance is refined to the meshes when the trees
/// carry them.
fn observe(
    pair: &mut Pair,
    pose_b: &Pose,
    pen: &PenetrationOptions,
    dist: &DistanceOptions,
    state: &mut LoopState,
) {
    let p = pair.penetration_with(&Pose::IDENTITY, pose_b, pen);
    if p.pairs > 0 {
        state.distance = 0.0;
        state.contact = true;
        let c = pair.patches().first().map_or(DVec3::ZERO, |q| q.point);
        state.point_a = c;
        state.point_b = c;
    } else if let Some(r) = refined(pair, pose_b) {
        state.distance = r.distance;
        state.contact = r.intersecting;
        state.point_a = r.point_a;
        state.point_b = r.point_b;
        state.distance_refined = true;
    } else {
        let d = pair.distance_with(&Pose::IDENTITY, pose_b, dist);
        state.distance = d.distance;
        state.contact = d.overlapping;
        state.point_a = d.point_a;
        state.point_b = d.point_b;
        state.distance_refined = false;
    }
    state.volume = p.volume;
    state.max_depth = p.max_depth;
    state.force = p.force;
    state.torque = p.torque_b;
    state.patch_count = pair.patches().len().min(PATCHES);
    for (s, q) in state.patches.iter_mut().zip(pair.patches()) {
        *s = *q;
    }
}

/// [`observe`] on the meshes' own contact: their penetration at `pose_b` (the loop runs
/// slower than its rate where that takes longer than a tick), or in haptic mode the model the
/// collision thread published (`model`: the query is its, not the loop's); the refined
/// distance while apart.
fn observe_meshes(
    pair: &mut Pair,
    pose_b: &Pose,
    pen: &PenetrationOptions,
    model: Option<&ContactModel>,
    state: &mut LoopState,
) {
    let (contact, volume, max_depth, force, torque) = match model {
        Some(m) => (m.volume > 0.0, m.volume, m.max_depth, m.force, m.torque),
        None => match pair.mesh_penetration_with(&Pose::IDENTITY, pose_b, pen) {
            Ok(m) => (m.contact, m.volume, m.max_depth, m.force, m.torque_b),
            Err(_) => Default::default(),
        },
    };
    state.contact = contact;
    state.volume = volume;
    state.max_depth = max_depth;
    state.force = force;
    state.torque = torque;
    // The patches are the loop's own query's (none when the collision thread answered).
    state.patch_count = if model.is_none() && contact {
        pair.patches().len().min(PATCHES)
    } else {
        0
    };
    for (s, q) in state.patches.iter_mut().zip(pair.patches()) {
        *s = *q;
    }
    if contact {
        state.distance = 0.0;
        let c = state.patches[..state.patch_count]
            .first()
            .map_or(DVec3::ZERO, |q| q.point);
        state.point_a = c;
        state.point_b = c;
    } else if let Some(r) = refined(pair, pose_b) {
        state.distance = r.distance;
        state.contact = r.intersecting;
        state.point_a = r.point_a;
        state.point_b = r.point_b;
        state.distance_refined = true;
    }
}

/// The refined distance at `pose_b` when both trees carry their meshes.
pub(crate) fn refined(pair: &mut Pair, pose_b: &Pose) -> Option<innersphere::RefinedDistance> {
    let meshes = pair.tree_a().mesh().is_some() && pair.tree_b().mesh().is_some();
    if !meshes {
        return None;
    }
    pair.refined_distance(&Pose::IDENTITY, pose_b).ok()
}

/// Seconds in microseconds, the unit of the state's times.
fn micros(seconds: f64) -> f64 {
    seconds * 1e6
}

/// How long before a tick's deadline the loop stops sleeping and spins: a plain sleep wakes
/// up late.
const SPIN: Duration = Duration::from_micros(200);

/// The loop's time: a trait so that the pacing can be tested on a clock the test drives.
trait Clock {
    fn now(&mut self) -> Instant;
    fn sleep(&mut self, d: Duration);
}

/// The machine's clock.
struct WallClock;

impl Clock for WallClock {
    fn now(&mut self) -> Instant {
        Instant::now()
    }
    fn sleep(&mut self, d: Duration) {
        std::thread::sleep(d);
    }
}

/// Waits for `deadline`: sleeps until [`SPIN`] before it, then spins. Behind it already
/// (the tick took longer than its period), it moves the deadline to now rather than run the
/// next ticks back to back to catch up.
fn pace(deadline: &mut Instant, clock: &mut impl Clock) {
    if let Some(d) = deadline.checked_duration_since(clock.now()) {
        if d > SPIN {
            clock.sleep(d - SPIN);
        }
        while clock.now() < *deadline {
            std::hint::spin_loop();
        }
    } else {
        *deadline = clock.now();
    }
}

/// Advances the motion's clock `t` (s) by one tick at `rate` Hz: a new scrub (`c.seek_id`
/// not `seek_id`) jumps to `c.seek` within the motion's `len`; else, while playing in motion
/// mode, it runs on and starts over past the end.
fn motion_clock(t: &mut f64, seek_id: &mut u64, c: &Control, len: f64, rate: f64) {
    let len = len.max(1e-9);
    if c.seek_id != *seek_id {
        *seek_id = c.seek_id;
        *t = c.seek.clamp(0.0, len);
    } else if c.playing && c.mode == Mode::Motion {
        *t += 1.0 / rate;
        if *t > len {
            *t = 0.0;
        }
    }
}

/// The ticks' work times: the last [`WINDOW`] for the p99 (taken every 100 ticks), with
/// room to select in place, so that recording allocates nothing.
struct TickStats {
    window: [f32; WINDOW],
    scratch: [f32; WINDOW],
}

impl TickStats {
    fn new() -> TickStats {
        TickStats {
            window: [0.0; WINDOW],
            scratch: [0.0; WINDOW],
        }
    }

    /// Records a tick of `work` µs in `state`: the count, the count over 1 ms, the last and
    /// largest, the history ring, and every 100 ticks the p99 over the window.
    fn record(&mut self, work: f64, state: &mut LoopState) {
        let n = state.ticks as usize;
        self.window[n % WINDOW] = work as f32;
        state.ticks += 1;
        state.over_1ms += (work > 1000.0) as u64;
        state.tick_us = work;
        state.tick_us_max = state.tick_us_max.max(work);
        state.history_us[state.history_next] = work as f32;
        state.history_next = (state.history_next + 1) % HISTORY;
        if state.ticks % 100 == 0 {
            let k = (state.ticks as usize).min(WINDOW);
            self.scratch[..k].copy_from_slice(&self.window[..k]);
            let i = ((k - 1) as f64 * 0.99).round() as usize;
            let (_, v, _) = self.scratch[..k].select_nth_unstable_by(i, f32::total_cmp);
            state.tick_us_p99 = *v as f64;
        }
    }
}

/// The tick and collision-model rates over the last half second or more: `from` holds when
/// the span began, the ticks then and the collision queries then (`models` now).
fn rates(from: &mut (Instant, u64, u64), now: Instant, models: u64, state: &mut LoopState) {
    let since = now.duration_since(from.0).as_secs_f64();
    if since >= 0.5 {
        state.rate_hz = (state.ticks - from.1) as f64 / since;
        state.collision_rate_hz = models.saturating_sub(from.2) as f64 / since;
        *from = (now, state.ticks, models);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn control(mode: Mode, playing: bool, seek: f64, seek_id: u64) -> Control {
        Control {
            target: Pose::IDENTITY,
            mode,
            playing,
            seek,
            seek_id,
        }
    }

    #[test]
    fn the_motion_clock_plays_wraps_holds_and_jumps() {
        // A 1 s motion at 1 kHz.
        let (mut t, mut id) = (0.0, 0u64);
        let mut tick = |mode, playing, seek, seek_id| {
            motion_clock(
                &mut t,
                &mut id,
                &control(mode, playing, seek, seek_id),
                1.0,
                1000.0,
            );
            (t, id)
        };
        for _ in 0..249 {
            tick(Mode::Motion, true, 0.0, 0);
        }
        assert!((tick(Mode::Motion, true, 0.0, 0).0 - 0.25).abs() < 1e-9);
        // Paused, or playing in another mode: held.
        tick(Mode::Motion, false, 0.0, 0);
        let (held, _) = tick(Mode::Free, true, 0.0, 0);
        assert!((held - 0.25).abs() < 1e-9, "{held}");
        // A scrub jumps (within the motion) and does not also advance; once.
        assert_eq!(tick(Mode::Motion, true, 0.9995, 1), (0.9995, 1));
        // Past the end: back to the start.
        assert_eq!(tick(Mode::Motion, true, 0.9995, 1).0, 0.0);
        assert_eq!(tick(Mode::Motion, false, 7.0, 2).0, 1.0);
        assert_eq!(tick(Mode::Motion, false, -3.0, 3).0, 0.0);
        // At 4 Hz the clock lands on the end exactly: the last frame shows, then the first.
        let (mut t, mut id) = (0.0, 0u64);
        let c = control(Mode::Motion, true, 0.0, 0);
        let ts: Vec<f64> = (0..6)
            .map(|_| {
                motion_clock(&mut t, &mut id, &c, 1.0, 4.0);
                t
            })
            .collect();
        assert_eq!(ts, [0.25, 0.5, 0.75, 1.0, 0.0, 0.25]);
    }

    #[test]
    fn the_tick_statistics_count_ring_and_take_the_p99() {
        let mut stats = TickStats::new();
        let mut state = LoopState::initial(Pose::IDENTITY);
        // Ticks of 1..=1000 µs in a scrambled order, then 1500 µs twice.
        for k in 0..WINDOW {
            stats.record(((k * 389) % WINDOW + 1) as f64, &mut state);
            if k == 99 {
                // The first p99, over the first 100 ticks.
                let mut first: Vec<usize> = (0..100).map(|k| (k * 389) % WINDOW + 1).collect();
                first.sort();
                assert_eq!(state.tick_us_p99, first[98] as f64);
            }
        }
        assert_eq!(state.ticks, WINDOW as u64);
        assert_eq!(state.tick_us_p99, 990.0);
        assert_eq!((state.over_1ms, state.tick_us_max), (0, 1000.0));
        stats.record(1500.0, &mut state);
        stats.record(1500.0, &mut state);
        assert_eq!(
            (state.over_1ms, state.tick_us, state.tick_us_max),
            (2, 1500.0, 1500.0)
        );
        // Not a hundredth tick: the p99 stays as it was.
        assert_eq!(state.tick_us_p99, 990.0);
        // The ring: the newest entry just before `history_next`.
        let next = (WINDOW + 2) % HISTORY;
        assert_eq!(state.history_next, next);
        assert_eq!(state.history_us[(next + HISTORY - 1) % HISTORY], 1500.0);
        assert_eq!(
            state.history_us[(next + HISTORY - 3) % HISTORY],
            (((WINDOW - 1) * 389) % WINDOW + 1) as f32
        );
    }

    #[test]
    fn the_rates_are_taken_over_half_a_second_or_more() {
        let mut state = LoopState::initial(Pose::IDENTITY);
        let t0 = Instant::now();
        let mut from = (t0, 100u64, 10u64);
        state.ticks = 300;
        rates(&mut from, t0 + Duration::from_millis(400), 50, &mut state);
        assert_eq!((state.rate_hz, from.1), (0.0, 100));
        state.ticks = 700;
        rates(&mut from, t0 + Duration::from_millis(600), 70, &mut state);
        assert!((state.rate_hz - 1000.0).abs() < 1e-9, "{}", state.rate_hz);
        assert!((state.collision_rate_hz - 100.0).abs() < 1e-9);
        assert_eq!(from, (t0 + Duration::from_millis(600), 700, 70));
    }

    /// A clock the test drives: each reading returns the time, then moves it on by 1 µs (a
    /// spin's step); a sleep moves it on by exactly what was asked.
    struct FakeClock {
        t: Instant,
        sleeps: Vec<Duration>,
    }

    impl Clock for FakeClock {
        fn now(&mut self) -> Instant {
            let t = self.t;
            self.t += Duration::from_micros(1);
            t
        }
        fn sleep(&mut self, d: Duration) {
            self.sleeps.push(d);
            self.t += d;
        }
    }

    fn us(n: u64) -> Duration {
        Duration::from_micros(n)
    }

    #[test]
    fn the_pacing_sleeps_to_just_before_the_deadline_then_spins_onto_it() {
        let t0 = Instant::now();
        // A millisecond ahead: sleeps 800 µs, then spins until the first reading at the
        // deadline, and the deadline stays.
        let mut clock = FakeClock {
            t: t0,
            sleeps: Vec::new(),
        };
        let mut deadline = t0 + us(1000);
        pace(&mut deadline, &mut clock);
        assert_eq!(clock.sleeps, [us(800)]);
        assert_eq!(clock.t, t0 + us(1001), "the last reading is the deadline's");
        assert_eq!(deadline, t0 + us(1000));
        // Within the spin's span: no sleep at all.
        let mut clock = FakeClock {
            t: t0,
            sleeps: Vec::new(),
        };
        let mut deadline = t0 + SPIN;
        pace(&mut deadline, &mut clock);
        assert!(clock.sleeps.is_empty(), "{:?}", clock.sleeps);
        assert_eq!(clock.t, t0 + SPIN + us(1));
        // Behind: no wait, and the deadline moves to now instead of catching up.
        let mut clock = FakeClock {
            t: t0 + us(50),
            sleeps: Vec::new(),
        };
        let mut deadline = t0;
        pace(&mut deadline, &mut clock);
        assert!(clock.sleeps.is_empty());
        assert_eq!(deadline, t0 + us(51));
    }

    #[test]
    fn the_haptic_loop_starts_on_entering_haptic_mode_and_stops_on_leaving_it() {
        use Mode::*;
        let mut started = 0;
        let mut haptic: Option<u32> = None;
        let mut step = |last, mode| {
            switch_haptic(&mut haptic, last, mode, || {
                started += 1;
                Some(started)
            });
            haptic
        };
        assert_eq!(step(Free, Free), None);
        assert_eq!(step(Motion, Free), None);
        assert_eq!(step(Free, Haptic), Some(1));
        assert_eq!(step(Haptic, Haptic), Some(1));
        assert_eq!(step(Haptic, Motion), None);
        assert_eq!(step(Motion, Haptic), Some(2));
        assert_eq!(step(Haptic, Free), None);
        assert_eq!(step(Free, Motion), None);
        assert_eq!(started, 2);
    }

    #[test]
    fn times_are_reported_in_microseconds() {
        assert_eq!(micros(0.0015), 1500.0);
        assert_eq!(micros(0.0), 0.0);
    }

    #[test]
    fn the_query_keeps_the_scenes_stiffness_and_the_states_patches() {
        let o = penetration_options(2.5e4);
        assert_eq!((o.stiffness, o.max_patches), (2.5e4, PATCHES));
        let rest = PenetrationOptions {
            stiffness: 2.5e4,
            max_patches: PATCHES,
            ..Default::default()
        };
        assert_eq!(o, rest);
    }

    #[test]
    fn the_target_is_the_motions_pose_in_motion_mode_else_the_pages() {
        let scene = crate::Scene::demo().unwrap();
        let mut m = scene.motion.unwrap();
        // A motion that does not start at 0 s.
        for f in &mut m.frames {
            f.t += 5.0;
        }
        let page = Pose::from_translation(DVec3::new(1.0, 2.0, 3.0));
        let c = |mode| Control {
            target: page,
            ..control(mode, true, 0.0, 0)
        };
        let at = target_of(Some(&m), &c(Mode::Motion), 0.3);
        assert_eq!(at, m.pose_at(5.3));
        assert_ne!(at, m.pose_at(0.3));
        assert_ne!(at, m.pose_at(5.0));
        assert_eq!(target_of(Some(&m), &c(Mode::Free), 0.3), page);
        assert_eq!(target_of(Some(&m), &c(Mode::Haptic), 0.3), page);
        assert_eq!(target_of(None, &c(Mode::Motion), 0.3), page);
    }

    #[test]
    fn a_tick_reports_the_penetration_in_contact_and_the_distance_apart() {
        let scene = crate::Scene::demo().unwrap();
        let motion = scene.motion.unwrap();
        let pen = penetration_options(1e4);
        let dist = DistanceOptions::default();
        let mut pair = Pair::new(scene.a.clone(), scene.b.clone());
        let mut reference = Pair::new(scene.a, scene.b);
        let (mut touched, mut apart, mut refined) = (0, 0, 0);
        for pose in motion.poses().step_by(10) {
            let mut state = LoopState::initial(Pose::IDENTITY);
            observe(&mut pair, &pose, &pen, &dist, &mut state);
            let p = reference.penetration_with(&Pose::IDENTITY, &pose, &pen);
            assert_eq!(
                (state.volume, state.max_depth, state.force, state.torque),
                (p.volume, p.max_depth, p.force, p.torque_b)
            );
            let patches = reference.patches();
            assert_eq!(state.patch_count, patches.len().min(PATCHES));
            assert_eq!(
                &state.patches[..state.patch_count],
                &patches[..state.patch_count]
            );
            if p.pairs > 0 {
                touched += 1;
                assert!(state.contact);
                assert_eq!(state.distance, 0.0);
                assert_eq!(
                    (state.point_a, state.point_b),
                    (patches[0].point, patches[0].point)
                );
                assert_ne!(state.point_a, DVec3::ZERO);
            } else {
                apart += 1;
                // The demo's trees carry their meshes: the distance is the refined one.
                let d = reference.refined_distance(&Pose::IDENTITY, &pose).unwrap();
                assert!(state.distance_refined);
                assert_eq!(
                    (state.distance, state.contact, state.point_a, state.point_b),
                    (d.distance, d.intersecting, d.point_a, d.point_b)
                );
                // Meshes that touch where the spheres do not: distance 0, in contact.
                assert!(state.distance <= d.spheres.distance);
                assert_eq!(state.distance == 0.0, state.contact);
                refined += usize::from(d.refined && !d.intersecting);
            }
        }
        assert!(
            touched > 5 && apart > 5 && refined > 5,
            "{touched} in contact, {apart} apart, {refined} refined"
        );
    }
}
