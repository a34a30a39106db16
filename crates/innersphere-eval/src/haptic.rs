//! A haptic session over a recorded device trajectory (`ist haptic`): the library's
//! [`HapticLoop`] at a given rate, each tick recorded, and the figures that say whether the
//! loop kept its deadline, stayed passive and rendered a smooth force.

use crate::histogram::Histogram;
use crate::motion::Motion;
use innersphere::error::num;
use innersphere::glam::DVec3;
use innersphere::{Error, Mesh, Pair, Pose, Result, SphereTree};
use innersphere_dental::contact_map::{ArchContext, Teeth};
use innersphere_haptic::{
    CollisionOptions, CollisionStats, ContactSource, HapticLoop, HapticOptions, MultirateLoop, Tick,
};
use std::fmt::Write as _;
use std::time::{Duration, Instant};

/// One recorded tick.
#[derive(Debug, Clone, Copy)]
pub struct TickRecord {
    /// Time (s).
    pub t: f64,
    /// The device's pose that tick.
    pub device: Pose,
    /// What the loop answered.
    pub tick: Tick,
}

/// The figures of a session (units in the names: µs, N, N·mm, mm, mm³, J).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HapticSummary {
    /// Ticks run.
    pub ticks: usize,
    /// Device ticks per second.
    pub rate_hz: f64,
    /// The tick budget (µs).
    pub budget_us: f64,
    /// Ticks that took longer than the budget.
    pub deadline_misses: usize,
    /// Median tick time (µs; from a histogram, within 0.25 %).
    pub compute_p50_us: f64,
    /// 99th percentile of the tick time (µs; within 0.25 %).
    pub compute_p99_us: f64,
    /// Slowest tick (µs).
    pub compute_max_us: f64,
    /// Ticks answered by the time-critical query.
    pub budgeted_ticks: usize,
    /// Largest force sent (N).
    pub max_force_n: f64,
    /// Largest torque sent (N·mm).
    pub max_torque_nmm: f64,
    /// Largest penetration depth of the tool (mm).
    pub max_depth_mm: f64,
    /// Largest penetration volume of the tool (mm³).
    pub max_volume_mm3: f64,
    /// Largest running total of the energy the device delivered to the hand (J); at most 0
    /// up to rounding for a passive loop.
    pub energy_to_user_max_j: f64,
    /// The same total at the end (J).
    pub energy_to_user_end_j: f64,
    /// Largest change of the force sent between two ticks (N).
    pub max_force_step_n: f64,
    /// Whether the ticks were paced at the device rate (else as fast as possible).
    pub realtime: bool,
    /// Whether the pacing thread got real-time (FIFO) scheduling.
    pub realtime_priority: bool,
    /// 99th percentile of the contact model's age at a tick (µs): since the tool pose its
    /// query answered for was taken (simulated time in one thread, real time with the
    /// collision thread).
    pub model_age_p99_us: f64,
    /// Oldest contact model a tick used (µs).
    pub model_age_max_us: f64,
    /// Whether the penetration query ran in a collision thread of its own.
    pub collision_thread: bool,
    /// The collision thread's stress delay before each query (µs).
    pub collision_delay_us: Option<f64>,
    /// Where the contact came from (`spheres` or `mesh`).
    pub contact: ContactSource,
    /// Contact models the collision thread published per second.
    pub collision_rate_hz: Option<f64>,
    /// The fewest models the collision thread published in any quarter second of the
    /// session, per second: the rate in the phase where the contact cost most.
    pub collision_rate_min_hz: Option<f64>,
    /// 99th percentile of the collision thread's query time (µs).
    pub collision_p99_us: Option<f64>,
    /// Collision queries answered by the time-critical query (the model kept, bounded).
    pub collision_budgeted: Option<u64>,
}

/// How a session runs its loop.
#[derive(Debug, Clone, Copy, Default)]
pub struct Session {
    /// Pace the ticks at the rate in real time (spinning), asking for real-time (FIFO)
    /// scheduling; else back to back.
    pub realtime: bool,
    /// Run the penetration query in a collision thread of its own ([`MultirateLoop`]);
    /// `None`: in the tick ([`HapticLoop`]).
    pub collision: Option<CollisionOptions>,
    /// Keep every tick in [`HapticRun::ticks`] (for a trace or a plot); else only the
    /// figures are gathered, in constant memory.
    pub keep_ticks: bool,
}

/// Either loop.
#[allow(clippy::large_enum_variant)] // one per session, on the stack
enum Looper {
    Single(HapticLoop),
    Servo(MultirateLoop),
}

impl Looper {
    fn tick(&mut self, pose: &Pose) -> Tick {
        match self {
            Looper::Single(h) => h.tick(pose),
            Looper::Servo(h) => h.tick(pose),
        }
    }
}

/// A session's ticks and figures.
#[derive(Debug, Clone)]
pub struct HapticRun {
    /// Every tick when the session kept them ([`Session::keep_ticks`]), else none.
    pub ticks: Vec<TickRecord>,
    /// The figures.
    pub summary: HapticSummary,
}

/// The most ticks a session runs (the trajectory's length times the rate).
pub const MAX_TICKS: usize = 50_000_000;

/// The most ticks a session keeps for its trace or plot (about 270 bytes each).
pub const MAX_KEPT_TICKS: usize = 2_000_000;

/// Runs the loop over `device` (B's device pose in A's frame, A at the identity) at
/// `opts.rate`, starting with the tool at the first device pose, as `session` says. The
/// figures are gathered as the ticks go (constant memory); the ticks themselves are kept
/// only with `session.keep_ticks`, at most [`MAX_KEPT_TICKS`] of them.
// Over 120 lines: the session's loop and what it gathers per tick share the clock, the
// collision thread and the running figures; the per-tick work itself is the library's.
pub fn run(
    pair: Pair,
    device: &Motion,
    opts: HapticOptions,
    session: &Session,
) -> Result<HapticRun> {
    if device.frames.is_empty() {
        return Err(Error::InvalidOption(
            "the device trajectory has no frames".into(),
        ));
    }
    if session.collision.is_some() && !session.realtime {
        return Err(Error::InvalidOption(
            "the collision thread runs in real time: pace the ticks in real time too (--realtime); \
             ticks run faster than real time would use ever older contact models"
                .into(),
        ));
    }
    let t0 = device.frames[0].t;
    let ticks_f = (device.duration() * opts.rate).floor() + 1.0;
    if ticks_f.is_nan() || ticks_f > MAX_TICKS as f64 {
        return Err(Error::InvalidOption(format!(
            "{} s of device trajectory at {} Hz is {} ticks, more than the {} a session runs",
            num(device.duration()),
            num(opts.rate),
            num(ticks_f),
            num(MAX_TICKS as f64)
        )));
    }
    let n = ticks_f as usize;
    if session.keep_ticks && n > MAX_KEPT_TICKS {
        return Err(Error::InvalidOption(format!(
            "a trace or a plot keeps every tick: at most {} ticks ({} s at {} Hz), not {n}; \
             shorten the trajectory or leave out --trace and --plot",
            num(MAX_KEPT_TICKS as f64),
            num(MAX_KEPT_TICKS as f64 / opts.rate),
            num(opts.rate)
        )));
    }
    let at = |i: usize| t0 + i as f64 / opts.rate;
    let first = device.pose_at(t0);
    // Real time: the collision thread is started at a real-time priority just below the
    // servo's (it inherits the policy), so that neither waits behind ordinary threads and
    // the collision thread never preempts the servo.
    use innersphere_haptic::realtime::{realtime_priority, SERVO_PRIORITY};
    let priority = session.realtime && realtime_priority(Some(SERVO_PRIORITY - 1));
    let made = match session.collision {
        None => HapticLoop::new(pair, Pose::IDENTITY, first, opts).map(Looper::Single),
        Some(c) => MultirateLoop::spawn(pair, Pose::IDENTITY, first, opts, c).map(Looper::Servo),
    };
    let mut hl = match made {
        Ok(h) => h,
        Err(e) => {
            if priority {
                realtime_priority(None);
            }
            return Err(e);
        }
    };
    let priority = priority && realtime_priority(Some(SERVO_PRIORITY));
    let mut ticks = Vec::with_capacity(if session.keep_ticks { n } else { 0 });
    let mut figures = Figures::default();
    if let Looper::Servo(s) = &hl {
        // The collision thread's first model, before the clock starts.
        let wait = Instant::now();
        while s.collision_queries() == 0 && wait.elapsed() < Duration::from_secs(5) {
            std::thread::yield_now();
        }
    }
    let start = Instant::now();
    for i in 0..n {
        // The device's pose: read from the trajectory at the tick's time, as a device driver
        // would be read (a binary search; nothing allocated).
        let pose = device.pose_at(at(i));
        if session.realtime {
            pace(start + Duration::from_secs_f64(i as f64 / opts.rate));
        }
        let tick = hl.tick(&pose);
        figures.add(&tick);
        if let Looper::Servo(s) = &hl {
            figures.models(i as f64 / opts.rate, s.collision_queries());
        }
        if session.keep_ticks {
            ticks.push(TickRecord {
                t: at(i),
                device: pose,
                tick,
            });
        }
    }
    if session.realtime {
        realtime_priority(None);
    }
    let (energy_max, energy_end) = match &hl {
        Looper::Single(h) => (h.energy_to_user_max(), h.energy_to_user()),
        Looper::Servo(h) => (h.energy_to_user_max(), h.energy_to_user()),
    };
    let stats: Option<CollisionStats> = match hl {
        Looper::Single(_) => None,
        Looper::Servo(h) => Some(h.finish()),
    };
    let f = &figures;
    let summary = HapticSummary {
        ticks: n,
        rate_hz: opts.rate,
        budget_us: opts.budget * 1e6,
        deadline_misses: f.late,
        compute_p50_us: f.compute_us.quantile(0.5),
        compute_p99_us: f.compute_us.quantile(0.99),
        compute_max_us: f.compute_us.max(),
        budgeted_ticks: f.budgeted,
        max_force_n: f.max_force,
        max_torque_nmm: f.max_torque,
        max_depth_mm: f.max_depth,
        max_volume_mm3: f.max_volume,
        energy_to_user_max_j: energy_max,
        energy_to_user_end_j: energy_end,
        max_force_step_n: f.max_step,
        realtime: session.realtime,
        realtime_priority: priority,
        model_age_p99_us: f.age_us.quantile(0.99),
        model_age_max_us: f.age_us.max(),
        collision_thread: stats.is_some(),
        collision_delay_us: session.collision.map(|c| c.delay * 1e6),
        contact: session
            .collision
            .map_or(ContactSource::Spheres, |c| c.contact),
        collision_rate_hz: stats.as_ref().map(|s| s.rate_hz()),
        collision_rate_min_hz: f.min_rate(),
        collision_p99_us: stats.as_ref().map(|s| s.quantile(0.99) * 1e6),
        collision_budgeted: stats.as_ref().map(|s| s.budgeted),
    };
    Ok(HapticRun { ticks, summary })
}

/// The session's figures, gathered tick by tick.
#[derive(Default)]
struct Figures {
    compute_us: Histogram,
    age_us: Histogram,
    late: usize,
    budgeted: usize,
    max_force: f64,
    max_torque: f64,
    max_depth: f64,
    max_volume: f64,
    max_step: f64,
    last_force: Option<DVec3>,
    /// Start (s) and models published then of the current quarter second, and the fewest
    /// models of a whole quarter second so far.
    window: Option<(f64, u64)>,
    fewest: Option<u64>,
}

/// The window of [`HapticSummary::collision_rate_min_hz`] (s).
const RATE_WINDOW: f64 = 0.25;

impl Figures {
    fn add(&mut self, t: &Tick) {
        self.compute_us.add(t.compute * 1e6);
        self.age_us.add(t.model_age * 1e6);
        self.late += t.late as usize;
        self.budgeted += t.budgeted as usize;
        self.max_force = self.max_force.max(t.force.length());
        self.max_torque = self.max_torque.max(t.torque.length());
        self.max_depth = self.max_depth.max(t.max_depth);
        self.max_volume = self.max_volume.max(t.volume);
        if let Some(f) = self.last_force {
            self.max_step = self.max_step.max((t.force - f).length());
        }
        self.last_force = Some(t.force);
    }

    /// Counts the collision thread's models: `published` so far at session time `t`.
    fn models(&mut self, t: f64, published: u64) {
        match self.window {
            None => self.window = Some((t, published)),
            Some((t0, n0)) if t - t0 >= RATE_WINDOW => {
                let n = published - n0;
                self.fewest = Some(self.fewest.map_or(n, |f| f.min(n)));
                self.window = Some((t, published));
            }
            Some(_) => {}
        }
    }

    /// The fewest models of a whole window, per second.
    fn min_rate(&self) -> Option<f64> {
        self.fewest.map(|n| n as f64 / RATE_WINDOW)
    }
}

/// Waits until `due`: sleeps until shortly before, then spins. A loop that only spins keeps
/// its core busy under real-time scheduling, and the kernel's real-time throttling then
/// stops it (and its collision thread) for 50 ms in every second.
fn pace(due: Instant) {
    const SPIN: Duration = Duration::from_micros(40);
    if let Some(left) = due.checked_duration_since(Instant::now()) {
        if left > SPIN {
            std::thread::sleep(left - SPIN);
        }
    }
    while Instant::now() < due {
        std::hint::spin_loop();
    }
}

/// The trace as CSV, one row per tick: `t`, the device pose (7), the tool pose (7), force
/// xyz (N), torque xyz (N·mm), volume (mm³), depth (mm), compute_us, budgeted (0/1),
/// model_age_us.
pub fn trace_csv(run: &HapticRun) -> String {
    let mut s = String::from(
        "t,dev_tx,dev_ty,dev_tz,dev_qw,dev_qx,dev_qy,dev_qz,tool_tx,tool_ty,tool_tz,tool_qw,tool_qx,tool_qy,tool_qz,fx,fy,fz,tx,ty,tz,volume,depth,compute_us,budgeted,model_age_us\n",
    );
    for r in &run.ticks {
        let d = r.device.to_array();
        let p = r.tick.tool.to_array();
        let (f, q) = (r.tick.force, r.tick.torque);
        let _ = write!(s, "{}", r.t);
        for x in d.iter().chain(&p) {
            let _ = write!(s, ",{x}");
        }
        let _ = writeln!(
            s,
            ",{},{},{},{},{},{},{},{},{:.2},{},{:.1}",
            f.x,
            f.y,
            f.z,
            q.x,
            q.y,
            q.z,
            r.tick.volume,
            r.tick.max_depth,
            r.tick.compute * 1e6,
            r.tick.budgeted as u8,
            r.tick.model_age * 1e6
        );
    }
    s
}

/// The landmarks of `ist occlude --landmarks`: the crown centres of a teeth-axes file (read
/// by the library's one reader, [`Teeth::load`]), named `tooth N`, in tooth order.
pub fn crown_centres(teeth: &Teeth) -> Vec<(String, DVec3)> {
    teeth
        .teeth
        .iter()
        .map(|t| (format!("tooth {}", t.number), t.centre))
        .collect()
}

/// Checks landmarks of body B against B as `ist occlusion-map` checks a teeth file
/// ([`Teeth::check_against`]), with A opposing where it is with B at `reference` (B's pose
/// in A's frame: the scanned bite). Each body is its mesh when given, else the mesh its tree
/// was built from while that file still holds it, else its tree's leaf centres (which get
/// the box and reach checks only). The warnings, or an error when the file does not fit B.
pub fn check_landmarks(
    teeth: &Teeth,
    b: (&SphereTree, Option<&Mesh>),
    a: (&SphereTree, Option<&Mesh>),
    reference: &Pose,
) -> Result<Vec<String>> {
    use std::borrow::Cow;
    fn body<'m>((tree, mesh): (&SphereTree, Option<&'m Mesh>)) -> Cow<'m, Mesh> {
        if let Some(m) = mesh {
            return Cow::Borrowed(m);
        }
        if let Some(m) = tree.meta.source.as_ref().and_then(|s| s.load().ok()) {
            return Cow::Owned(m);
        }
        Cow::Owned(Mesh {
            vertices: tree.leaves().map(|n| tree.sphere(n).0.as_dvec3()).collect(),
            triangles: Vec::new(),
        })
    }
    let (arch, opposing) = (body(b), body(a));
    let fit = teeth.check_against(&ArchContext {
        arch: &arch,
        opposing: Some((&opposing, reference.inverse())),
        jaw: None,
    })?;
    Ok(fit.warnings)
}
