//! The haptic loop: one call per device tick turns the device's pose into the force to
//! send, moving a virtual tool that the contact stops at the other body's surface.

use crate::body::{BodyState, RigidBody, TOOTH_DENSITY};
use crate::deadline::{needs_exact, Answer, Deadline};
use crate::device::{Coupling, DeviceClass, DeviceLimits};
use crate::model::ContactModel;
use crate::servo::Servo;
use glam::DVec3;
use innersphere::error::num;
use innersphere::error::{Error, Result};
use innersphere::pose::Pose;
use innersphere::query::{Pair, PenetrationOptions};
use std::time::{Duration, Instant};

/// The slowest loop rate accepted (Hz).
pub const MIN_RATE: f64 = 100.0;

/// Settings of a [`HapticLoop`]. Units: mm, N, s, kg.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct HapticOptions {
    /// Device ticks per second (Hz); the integration step is its inverse.
    pub rate: f64,
    /// Most time one tick may take (s), the query included; default one tick period.
    pub budget: f64,
    /// What the device can render; the force and torque sent are clamped to it.
    pub device: DeviceLimits,
    /// The virtual coupling between device and tool.
    pub coupling: Coupling,
    /// Penalty force per unit of penetration volume (N/mm³).
    pub contact_stiffness: f64,
    /// Contact damping (s): a damping matrix `contact_damping × K`, proportional to the
    /// linearised contact stiffness `K`, so that small and large contacts are damped alike.
    pub contact_damping: f64,
    /// Density of the tool (kg per model unit³) for its mass and inertia.
    pub density: f64,
    /// Contact patches kept per exact query.
    pub max_patches: usize,
    /// How fast a new contact model may take over from the one in use (N/s: force plus
    /// torque / 20 mm): the bound on the force step a model update causes (see
    /// `docs/HAPTICS.md`). Default 50 × the device's maximum force per second.
    pub model_slew: f64,
    /// Oldest a contact model may get (s) before the single-thread loop runs the exact query
    /// whatever it costs (a late tick) rather than go on extrapolating it; default 5 ms.
    pub max_model_age: f64,
    /// Fastest the loop lets the device move (mm/s; rotations at this speed at the
    /// coupling's 20 mm lever): a pose read further from the last than this and
    /// [`max_device_acceleration`](Self::max_device_acceleration) allow is approached as
    /// fast as they allow, so that a glitch, a jump or a far pose cannot fling the tool or
    /// kick the hand through the sampled coupling. Default 500 mm/s.
    pub max_device_speed: f64,
    /// Largest acceleration the loop lets the device have (mm/s²; rotations alike at the
    /// lever). Default 20,000 mm/s² (2 g).
    pub max_device_acceleration: f64,
}

impl HapticOptions {
    /// The defaults for a device class at 1 kHz: its limits and coupling
    /// ([`DeviceClass::coupling`]), a contact of 10 N/mm³ with 1 ms of damping, tooth
    /// density.
    pub fn for_device(class: DeviceClass) -> HapticOptions {
        HapticOptions {
            rate: 1000.0,
            budget: 1e-3,
            device: class.limits(),
            coupling: class.coupling(),
            contact_stiffness: 10.0,
            contact_damping: 1e-3,
            density: TOOTH_DENSITY,
            max_patches: 8,
            model_slew: 50.0 * class.limits().max_force,
            max_model_age: 5e-3,
            max_device_speed: 500.0,
            max_device_acceleration: 20_000.0,
        }
    }

    /// The penetration query's options for the contact model: this stiffness and patch
    /// count, with the linearised wrench.
    pub(crate) fn penetration(&self) -> PenetrationOptions {
        PenetrationOptions {
            stiffness: self.contact_stiffness,
            max_patches: self.max_patches,
            linearize: true,
            ..Default::default()
        }
    }

    /// The defaults of a device class for a loop at `rate` Hz (budget one period): as
    /// [`for_device`](Self::for_device), with the coupling of
    /// [`DeviceClass::coupling_at`] (passive at that rate).
    pub fn for_device_at(class: DeviceClass, rate: f64) -> HapticOptions {
        HapticOptions {
            rate,
            budget: 1.0 / rate,
            coupling: class.coupling_at(rate),
            ..HapticOptions::for_device(class)
        }
    }

    /// Refuses settings no loop can run with: a rate or budget that is not positive and
    /// finite, negative or non-finite stiffness, damping or limits, a coupling stiffer
    /// than the device renders.
    pub fn check(&self) -> Result<()> {
        let bad = |what: &str, x: f64| {
            Err(Error::InvalidOption(format!(
                "{what} must be positive and finite, not {}",
                num(x)
            )))
        };
        if !(self.rate.is_finite() && (MIN_RATE..=1e6).contains(&self.rate)) {
            return Err(Error::InvalidOption(format!(
                "the rate must be from {MIN_RATE} Hz to 1e6 Hz, not {} Hz: a device updated less \
                 often than every 10 ms renders no contact a hand feels as one (for the bite at \
                 rest, use the occlusion)",
                num(self.rate)
            )));
        }
        if !(self.budget.is_finite() && self.budget > 0.0) {
            return bad("the tick budget", self.budget);
        }
        let nonneg = [
            ("the coupling stiffness", self.coupling.stiffness),
            ("the coupling damping", self.coupling.damping),
            (
                "the angular coupling stiffness",
                self.coupling.angular_stiffness,
            ),
            (
                "the angular coupling damping",
                self.coupling.angular_damping,
            ),
            ("the contact stiffness", self.contact_stiffness),
            ("the contact damping", self.contact_damping),
            ("the device's maximum force", self.device.max_force),
            ("the device's maximum torque", self.device.max_torque),
        ];
        let positive = [
            ("the model slew rate", self.model_slew),
            ("the largest model age", self.max_model_age),
            ("the largest device speed", self.max_device_speed),
            (
                "the largest device acceleration",
                self.max_device_acceleration,
            ),
        ];
        for (what, x) in positive {
            if !(x.is_finite() && x > 0.0) {
                return bad(what, x);
            }
        }
        for (what, x) in nonneg {
            if !(x.is_finite() && x >= 0.0) {
                return Err(Error::InvalidOption(format!(
                    "{what} must be finite and not negative, not {}",
                    num(x)
                )));
            }
        }
        if !(self.coupling.stiffness > 0.0 && self.coupling.angular_stiffness > 0.0) {
            return bad("the coupling stiffness", self.coupling.stiffness);
        }
        if self.coupling.stiffness > self.device.max_stiffness * (1.0 + 1e-12) {
            return Err(Error::InvalidOption(format!(
                "a coupling of {} N/mm is stiffer than the device renders ({} N/mm)",
                num(self.coupling.stiffness),
                num(self.device.max_stiffness)
            )));
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad("the density", self.density);
        }
        // A sampled spring gives energy back unless its damping is at least k·T/2.
        let c = &self.coupling;
        for (what, k, b, unit) in [
            ("", c.stiffness, c.damping, "N·s/mm"),
            (
                "angular ",
                c.angular_stiffness,
                c.angular_damping,
                "N·mm·s/rad",
            ),
        ] {
            let least = k / (2.0 * self.rate);
            if b < least * (1.0 - 1e-12) {
                return Err(Error::InvalidOption(format!(
                    "the {what}coupling damping {} {unit} is below k·T/2 = {} {unit} at {} Hz: \
                     the sampled spring would give the hand energy; raise the damping or lower \
                     the stiffness (HapticOptions::for_device_at picks both for a rate)",
                    num(b),
                    num(least),
                    num(self.rate)
                )));
            }
        }
        Ok(())
    }
}

/// Refuses a caller's tick step `dt` (s) that is negative, NaN or infinite; 0 stands for one
/// period. What the bindings check before [`HapticLoop::tick_step`], which itself replaces
/// such a `dt` by one period (it never fails).
pub fn check_step(dt: f64) -> Result<()> {
    if dt.is_finite() && dt >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidOption(format!(
            "dt must be 0 (one period) or the positive seconds since the last tick, not {}",
            num(dt)
        )))
    }
}

/// What one tick did. Its serde form (the tool's pose as 7 numbers) is what Python's
/// `Tick.to_dict` gives.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Tick {
    /// Force to send to the device (N, world frame): the coupling's pull on the hand,
    /// clamped to the device's maximum.
    pub force: DVec3,
    /// Torque to send to the device (N·mm, world frame), clamped likewise.
    pub torque: DVec3,
    /// The tool's pose after the tick: what to draw.
    pub tool: Pose,
    /// Penalty force applied to the tool (N): the contact model in use, at the tool's pose.
    pub contact_force: DVec3,
    /// Penetration volume (mm³): of the model in use, or what the time-critical query found
    /// when it answered this tick.
    pub volume: f64,
    /// Upper bound on the penetration volume (mm³); equals `volume` unless budgeted.
    pub volume_bound: f64,
    /// Deepest leaf-pair overlap (mm) of the same.
    pub max_depth: f64,
    /// Contact patches of the model in use (exact queries only).
    pub patches: usize,
    /// True when the time-critical query answered because the exact one would not fit.
    pub budgeted: bool,
    /// Time the tick took (s).
    pub compute: f64,
    /// True when the tick took longer than its budget.
    pub late: bool,
    /// Age of the contact model in use (s): from when the tool pose it answered for was
    /// taken to this tick (in simulated time for [`HapticLoop`], in real time for
    /// [`MultirateLoop`](crate::MultirateLoop)).
    pub model_age: f64,
}

/// The 6-DOF haptic loop in one thread: a virtual tool (body B of the pair) coupled to the
/// device's pose by a spring-damper and pushed out of body A (fixed at its pose) by the
/// penalty wrench of the penetration query, run within each tick. Call
/// [`tick`](Self::tick) once per device tick, from one thread; it allocates nothing and takes
/// no lock. When the exact query does not fit the tick's budget, the tick uses the last
/// complete answer's linearised contact model (see [`ContactModel`]), bounded by the
/// time-critical query; for contacts whose exact query exceeds the tick period, use
/// [`MultirateLoop`](crate::MultirateLoop), which runs the query in a thread of its own.
#[derive(Debug)]
pub struct HapticLoop {
    pair: Pair,
    pose_a: Pose,
    tool: Servo,
    penetration: PenetrationOptions,
    deadline: Deadline,
    queries: u64,
    /// Simulated time (s): the sum of the steps so far.
    time: f64,
    /// Simulated time when the model in use was made.
    model_time: f64,
}

impl HapticLoop {
    /// A loop on `pair` with A fixed at `pose_a` and the tool (B) at rest at `start`.
    /// Fails on bad options or a tree of B without mass properties.
    pub fn new(pair: Pair, pose_a: Pose, start: Pose, opts: HapticOptions) -> Result<HapticLoop> {
        opts.check()?;
        let body = RigidBody::from_tree(pair.tree_b(), opts.density)?;
        Ok(HapticLoop {
            pair,
            pose_a,
            tool: Servo::start(body, start, opts),
            penetration: opts.penetration(),
            deadline: Deadline::new(),
            queries: 0,
            time: 0.0,
            model_time: 0.0,
        })
    }

    /// One device tick: the device's pose in (B's pose in the world, as read from the device
    /// this tick), the force and torque to send out, with the tool's new pose.
    pub fn tick(&mut self, device: &Pose) -> Tick {
        // A step of 0 stands for one period.
        self.tick_step(device, 0.0)
    }

    /// [`tick`](Self::tick) with the time since the last tick measured by the caller
    /// (`dt` seconds, e.g. from the device's clock when its servo loop jitters): the step
    /// and the device's velocity use it. A `dt` that is not positive and finite, or more
    /// than ten periods, is replaced by one period.
    pub fn tick_step(&mut self, device: &Pose, dt: f64) -> Tick {
        let start = Instant::now();
        let sensed = self.tool.sense(device, dt);
        let opts = self.tool.opts;
        let budget = Duration::from_secs_f64(opts.budget);
        let pose = self.tool.state.pose;
        // Ages in simulated time: a loop run faster than real time ages its model alike.
        self.time += sensed.h;
        let stale = self.time - self.model_time > opts.max_model_age;
        let mut answer = self.deadline.query(
            &mut self.pair,
            &self.pose_a,
            &pose,
            start,
            &self.penetration,
            start + budget,
            Duration::from_micros(3),
            stale,
        );
        // Leaf pairs found where the model in use has no contact: the model cannot stand in.
        if needs_exact(&answer, self.tool.blend.target()) {
            answer = self.deadline.query(
                &mut self.pair,
                &self.pose_a,
                &pose,
                start,
                &self.penetration,
                start,
                Duration::ZERO,
                true,
            );
        }
        let (volume, volume_bound, max_depth, budgeted) = match answer {
            Answer::Model(mut m) => {
                self.queries += 1;
                m.seq = self.queries;
                self.model_time = self.time;
                self.tool.new_model(m);
                (m.volume, m.volume, m.max_depth, false)
            }
            Answer::Bound {
                cap,
                found,
                bound,
                depth,
            } => {
                self.tool.blend.set_cap(cap);
                (found, bound, depth, true)
            }
        };
        let sent = self.tool.step(&sensed);
        let compute = start.elapsed().as_secs_f64();
        let model = self.tool.blend.target();
        Tick {
            force: sent.force,
            torque: sent.torque,
            tool: self.tool.state.pose,
            contact_force: sent.contact.force,
            volume,
            volume_bound,
            max_depth,
            patches: model.patches,
            budgeted,
            compute,
            late: compute > opts.budget,
            model_age: self.time - self.model_time,
        }
    }

    /// Energy the device has delivered to the hand so far (J): the sum over ticks of the
    /// held force times the device's displacement (and torque times rotation). Negative when
    /// the hand has put more in than it got back; a passive loop keeps it at most zero.
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

    /// The contact model in use (the newest complete answer).
    pub fn model(&self) -> &ContactModel {
        self.tool.blend.target()
    }

    /// The pair (its patches after an exact tick: [`Pair::patches`]).
    pub fn pair(&self) -> &Pair {
        &self.pair
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loops_query_has_its_stiffness_patches_and_linearisation() {
        let mut o = HapticOptions::for_device(DeviceClass::Omega);
        o.contact_stiffness = 37.0;
        o.max_patches = 5;
        assert_eq!(
            o.penetration(),
            PenetrationOptions {
                stiffness: 37.0,
                max_patches: 5,
                linearize: true,
                ..Default::default()
            }
        );
    }

    #[test]
    fn the_defaults_at_a_rate_take_its_period_and_coupling() {
        for class in [DeviceClass::Touch, DeviceClass::Omega] {
            let at = HapticOptions::for_device_at(class, 4000.0);
            assert_eq!((at.rate, at.budget), (4000.0, 1.0 / 4000.0));
            assert_eq!(at.coupling, class.coupling_at(4000.0));
            assert_eq!(
                HapticOptions {
                    rate: 1000.0,
                    budget: 1e-3,
                    coupling: class.coupling(),
                    ..at
                },
                HapticOptions::for_device(class)
            );
            assert!(at.check().is_ok());
        }
    }

    type Field = (&'static str, fn(&mut HapticOptions, f64));

    #[test]
    fn every_setting_is_checked_at_its_edges() {
        let base = HapticOptions::for_device(DeviceClass::Omega);
        assert!(base.check().is_ok());
        let refused = |set: fn(&mut HapticOptions, f64), x: f64| {
            let mut o = base;
            set(&mut o, x);
            o.check().is_err()
        };
        // Above 0 and finite.
        let positive: [Field; 7] = [
            ("budget", |o, x| o.budget = x),
            ("model_slew", |o, x| o.model_slew = x),
            ("max_model_age", |o, x| o.max_model_age = x),
            ("max_device_speed", |o, x| o.max_device_speed = x),
            ("max_device_acceleration", |o, x| {
                o.max_device_acceleration = x
            }),
            ("density", |o, x| o.density = x),
            ("angular_stiffness", |o, x| o.coupling.angular_stiffness = x),
        ];
        for (what, set) in positive {
            for x in [0.0, -1.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                assert!(refused(set, x), "{what} = {x}");
            }
            assert!(!refused(set, base_value(&base, what) * 2.0), "{what}");
        }
        // At least 0 and finite.
        let nonneg: [Field; 6] = [
            ("damping", |o, x| o.coupling.damping = x),
            ("angular_damping", |o, x| o.coupling.angular_damping = x),
            ("contact_stiffness", |o, x| o.contact_stiffness = x),
            ("contact_damping", |o, x| o.contact_damping = x),
            ("max_force", |o, x| o.device.max_force = x),
            ("max_torque", |o, x| o.device.max_torque = x),
        ];
        for (what, set) in nonneg {
            for x in [-1.0, f64::NAN, f64::INFINITY] {
                assert!(refused(set, x), "{what} = {x}");
            }
        }
        for set in [
            (|o: &mut HapticOptions, x| o.contact_stiffness = x) as fn(&mut HapticOptions, f64),
            |o, x| o.contact_damping = x,
            |o, x| o.device.max_force = x,
        ] {
            assert!(!refused(set, 0.0));
        }
        // The rate from 100 Hz to 1 MHz (with a coupling for it).
        for (rate, ok) in [(100.0, true), (99.9, false), (1e6, true), (1.1e6, false)] {
            let o = HapticOptions {
                rate,
                ..HapticOptions::for_device_at(DeviceClass::Omega, rate)
            };
            assert_eq!(o.check().is_ok(), ok, "{rate} Hz");
        }
        // The coupling: no stiffer than the device; damped at least k·T/2.
        let c = base.coupling;
        assert!(refused(|o, _| o.coupling.stiffness = 0.0, 0.0));
        let stiff = |o: &mut HapticOptions, k: f64| o.coupling.stiffness = k;
        assert!(!refused(stiff, base.device.max_stiffness));
        assert!(refused(stiff, base.device.max_stiffness * 1.001));
        let least = c.stiffness / (2.0 * base.rate);
        assert!(!refused(|o, b| o.coupling.damping = b, least));
        assert!(refused(|o, b| o.coupling.damping = b, least * 0.999));
        let least = c.angular_stiffness / (2.0 * base.rate);
        assert!(!refused(|o, b| o.coupling.angular_damping = b, least));
        assert!(refused(
            |o, b| o.coupling.angular_damping = b,
            least * 0.999
        ));
    }

    #[test]
    fn a_callers_step_is_zero_or_positive_and_finite() {
        for ok in [0.0, 1e-3, 0.5] {
            assert!(check_step(ok).is_ok(), "{ok}");
        }
        for bad in [-1e-3, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(check_step(bad).is_err(), "{bad}");
        }
    }

    /// A positive setting's value in `o`, by name.
    fn base_value(o: &HapticOptions, what: &str) -> f64 {
        match what {
            "budget" => o.budget,
            "model_slew" => o.model_slew,
            "max_model_age" => o.max_model_age,
            "max_device_speed" => o.max_device_speed,
            "max_device_acceleration" => o.max_device_acceleration,
            "density" => o.density,
            _ => o.coupling.angular_stiffness,
        }
    }
}
