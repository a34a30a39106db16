//! The haptic loop: one call per device tick turns the device's pose into the force to
//! send, moving a virtual tool that the contact stops at the other body's surface.

use super::body::{rotation_between, BodyState, RigidBody, TOOTH_DENSITY};
use super::contact::Deadline;
use super::device::{Coupling, DeviceClass, DeviceLimits};
use super::mat6::Mat6;
use super::step::{contact_damping, implicit_step, Wrench};
use crate::{Error, Pair, PenetrationOptions, Pose, Result};
use glam::{DQuat, DVec3};
use std::time::{Duration, Instant};

/// Millijoules per joule: N·mm is mJ.
const MJ: f64 = 1e-3;

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
        }
    }

    /// Refuses settings no loop can run with: a rate or budget that is not positive and
    /// finite, negative or non-finite stiffness, damping or limits, a coupling stiffer
    /// than the device renders.
    pub fn check(&self) -> Result<()> {
        let bad = |what: &str, x: f64| {
            Err(Error::InvalidOption(format!(
                "{what} must be positive and finite, not {x}"
            )))
        };
        if !(self.rate.is_finite() && self.rate > 0.0 && self.rate <= 1e6) {
            return Err(Error::InvalidOption(format!(
                "the rate must be in (0, 1e6] Hz, not {}",
                self.rate
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
        for (what, x) in nonneg {
            if !(x.is_finite() && x >= 0.0) {
                return Err(Error::InvalidOption(format!(
                    "{what} must be finite and not negative, not {x}"
                )));
            }
        }
        if !(self.coupling.stiffness > 0.0 && self.coupling.angular_stiffness > 0.0) {
            return bad("the coupling stiffness", self.coupling.stiffness);
        }
        if self.coupling.stiffness > self.device.max_stiffness * (1.0 + 1e-12) {
            return Err(Error::InvalidOption(format!(
                "a coupling of {} N/mm is stiffer than the device renders ({} N/mm)",
                self.coupling.stiffness, self.device.max_stiffness
            )));
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad("the density", self.density);
        }
        Ok(())
    }
}

/// What one tick did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tick {
    /// Force to send to the device (N, world frame): the coupling's pull on the hand,
    /// clamped to the device's maximum.
    pub force: DVec3,
    /// Torque to send to the device (N·mm, world frame), clamped likewise.
    pub torque: DVec3,
    /// The tool's pose after the tick: what to draw.
    pub tool: Pose,
    /// Penalty force on the tool (N).
    pub contact_force: DVec3,
    /// Penetration volume (mm³): exact, or what the time-critical query found.
    pub volume: f64,
    /// Upper bound on the penetration volume (mm³); equals `volume` unless budgeted.
    pub volume_bound: f64,
    /// Deepest leaf-pair overlap (mm).
    pub max_depth: f64,
    /// Contact patches (exact path only).
    pub patches: usize,
    /// True when the time-critical query answered because the exact one would not fit.
    pub budgeted: bool,
    /// Time the tick took (s).
    pub compute: f64,
    /// True when the tick took longer than its budget.
    pub late: bool,
}

/// The 6-DOF haptic loop: a virtual tool (body B of the pair) coupled to the device's pose by
/// a spring-damper and pushed out of body A (fixed at its pose) by the penalty wrench of the
/// penetration query. Call [`tick`](Self::tick) once per device tick, from one thread; it
/// allocates nothing and takes no lock.
#[derive(Debug)]
pub struct HapticLoop {
    pair: Pair,
    pose_a: Pose,
    body: RigidBody,
    state: BodyState,
    opts: HapticOptions,
    penetration: PenetrationOptions,
    deadline: Deadline,
    /// The device's centre-of-mass point and rotation at the last tick.
    last_device: Option<(DVec3, DQuat)>,
    /// The force and torque sent at the last tick (held until this one: zero-order hold).
    sent: (DVec3, DVec3),
    energy: f64,
    energy_max: f64,
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
            body,
            state: BodyState::at_rest(start),
            penetration: PenetrationOptions {
                stiffness: opts.contact_stiffness,
                max_patches: opts.max_patches,
                linearize: true,
                ..Default::default()
            },
            opts,
            deadline: Deadline::new(),
            last_device: None,
            sent: (DVec3::ZERO, DVec3::ZERO),
            energy: 0.0,
            energy_max: 0.0,
        })
    }

    /// One device tick: the device's pose in (B's pose in the world, as read from the device
    /// this tick), the force and torque to send out, with the tool's new pose.
    pub fn tick(&mut self, device: &Pose) -> Tick {
        self.tick_step(device, 1.0 / self.opts.rate)
    }

    /// [`tick`](Self::tick) with the time since the last tick measured by the caller
    /// (`dt` seconds, e.g. from the device's clock when its servo loop jitters): the step
    /// and the device's velocity use it. A `dt` that is not positive and finite, or more
    /// than ten periods, is replaced by one period.
    pub fn tick_step(&mut self, device: &Pose, dt: f64) -> Tick {
        let start = Instant::now();
        let period = 1.0 / self.opts.rate;
        let h = if dt.is_finite() && dt > 0.0 && dt <= 10.0 * period {
            dt
        } else {
            period
        };
        let com = self.body.center_of_mass;
        let xd = device.transform_point(com);
        let qd = device.rotation;
        // Device velocity by backward difference; the energy the held force and torque did
        // on the hand since the last tick (zero-order hold: constant over the tick).
        let (vd, wd) = match self.last_device {
            Some((x0, q0)) => {
                let dx = xd - x0;
                let dth = rotation_between(q0, qd);
                self.energy += (self.sent.0.dot(dx) + self.sent.1.dot(dth)) * MJ;
                self.energy_max = self.energy_max.max(self.energy);
                (dx / h, dth / h)
            }
            None => (DVec3::ZERO, DVec3::ZERO),
        };
        self.last_device = Some((xd, qd));

        let budget = Duration::from_secs_f64(self.opts.budget);
        let contact = self.deadline.sample(
            &mut self.pair,
            &self.pose_a,
            &self.state.pose,
            &self.penetration,
            start + budget,
            Duration::from_micros(3),
        );

        let c = self.opts.coupling;
        let xt = self.state.pose.transform_point(com);
        let err = rotation_between(self.state.pose.rotation, qd);
        let spring = (xd - xt) * c.stiffness + (vd - self.state.velocity) * c.damping;
        let twist =
            err * c.angular_stiffness + (wd - self.state.angular_velocity) * c.angular_damping;
        // Contact damping β·K on the tool's own velocity (A is fixed).
        let (cd, mut damping) =
            contact_damping(&contact.stiffness, self.opts.contact_damping, &self.state);
        let w = Wrench {
            force: spring + contact.wrench.force + cd.force,
            torque: twist + contact.wrench.torque + cd.torque,
        };
        let mut stiffness: Mat6 = contact.stiffness;
        for i in 0..6 {
            let (k, b) = if i < 3 {
                (c.stiffness, c.damping)
            } else {
                (c.angular_stiffness, c.angular_damping)
            };
            stiffness[i][i] += k;
            damping[i][i] += b;
        }
        if !implicit_step(&self.body, &mut self.state, h, w, &stiffness, &damping) {
            // Non-finite input (a NaN device pose): the tool stays where it was, at rest.
            self.state.velocity = DVec3::ZERO;
            self.state.angular_velocity = DVec3::ZERO;
        }

        // What the hand feels: the coupling after the step, pulling the device towards the
        // tool, clamped to the device's limits.
        let xt = self.state.pose.transform_point(com);
        let err = rotation_between(self.state.pose.rotation, qd);
        let f = -((xd - xt) * c.stiffness + (vd - self.state.velocity) * c.damping);
        let t =
            -(err * c.angular_stiffness + (wd - self.state.angular_velocity) * c.angular_damping);
        let force = clamp(f, self.opts.device.max_force);
        let torque = clamp(t, self.opts.device.max_torque);
        self.sent = (force, torque);
        let compute = start.elapsed().as_secs_f64();
        Tick {
            force,
            torque,
            tool: self.state.pose,
            contact_force: contact.wrench.force,
            volume: contact.volume,
            volume_bound: contact.volume_bound,
            max_depth: contact.max_depth,
            patches: contact.patches,
            budgeted: contact.budgeted,
            compute,
            late: compute > self.opts.budget,
        }
    }

    /// Energy the device has delivered to the hand so far (J): the sum over ticks of the
    /// held force times the device's displacement (and torque times rotation). Negative when
    /// the hand has put more in than it got back; a passive loop keeps it at most zero.
    pub fn energy_to_user(&self) -> f64 {
        self.energy
    }

    /// The largest value [`energy_to_user`](Self::energy_to_user) has had.
    pub fn energy_to_user_max(&self) -> f64 {
        self.energy_max
    }

    /// The tool's state.
    pub fn state(&self) -> &BodyState {
        &self.state
    }

    /// The tool's mass properties.
    pub fn body(&self) -> &RigidBody {
        &self.body
    }

    /// The options.
    pub fn options(&self) -> &HapticOptions {
        &self.opts
    }

    /// The pair (its patches after an exact tick: [`Pair::patches`]).
    pub fn pair(&self) -> &Pair {
        &self.pair
    }
}

/// `v` shortened to at most `max` (its direction kept).
fn clamp(v: DVec3, max: f64) -> DVec3 {
    let l = v.length();
    if l > max && l > 0.0 {
        v * (max / l)
    } else if l.is_finite() {
        v
    } else {
        DVec3::ZERO
    }
}
