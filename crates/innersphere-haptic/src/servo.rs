//! The servo side of a haptic loop, shared by the single-thread loop and the multi-rate one,
//! and public for applications that run their collision queries themselves: the device's
//! motion and the energy it exchanges with the hand, the tool moved by one implicit step
//! under the coupling and the contact model in use, and the force sent back.

use crate::blend::Blend;
use crate::body::{exp, rotation_between, BodyState, RigidBody};
use crate::device::LEVER;
use crate::mat6::Mat6;
use crate::model::ContactModel;
use crate::render::{HapticOptions, Tick};
use crate::step::{contact_damping, implicit_step, Wrench};
use glam::{DQuat, DVec3};
use innersphere::error::Result;
use innersphere::pose::Pose;
use std::time::Instant;

/// Millijoules per joule: N·mm is mJ.
const MJ: f64 = 1e-3;

/// The device as sensed this tick.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sensed {
    /// The device's centre-of-mass point and rotation (B's centre of mass carried by it).
    x: DVec3,
    q: DQuat,
    /// Its velocities, by backward difference.
    v: DVec3,
    w: DVec3,
    /// The step (s).
    pub h: f64,
}

/// What the servo step sends and applied.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sent {
    /// Force and torque to the device, clamped.
    pub force: DVec3,
    pub torque: DVec3,
    /// The contact wrench applied to the tool this tick.
    pub contact: Wrench,
}

/// The servo side of a haptic loop: the tool (body B) coupled to the device, the contact
/// model in use and the energy exchanged with the hand. [`HapticLoop`](crate::HapticLoop)
/// and [`MultirateLoop`](crate::MultirateLoop) drive one; an application with collision
/// queries of its own feeds it [`ContactModel`]s through [`tick`](Self::tick). A new model
/// is blended in at the options' [`model_slew`](HapticOptions::model_slew), never switched.
#[derive(Debug, Clone)]
pub struct Servo {
    pub(crate) body: RigidBody,
    pub(crate) state: BodyState,
    pub(crate) opts: HapticOptions,
    pub(crate) blend: Blend,
    /// The device's centre-of-mass point and rotation as the loop took them last tick.
    last_device: (DVec3, DQuat),
    /// Their velocities (mm/s, rad/s).
    device_velocity: (DVec3, DVec3),
    /// The force and torque sent at the last tick (held until this one: zero-order hold).
    sent: (DVec3, DVec3),
    energy: f64,
    energy_max: f64,
}

impl Servo {
    /// The tool with mass properties `body` at rest at `start`, no contact known yet.
    /// Fails on bad options or body.
    pub fn new(body: RigidBody, start: Pose, opts: HapticOptions) -> Result<Servo> {
        opts.check()?;
        body.check()?;
        Ok(Servo::start(body, start, opts))
    }

    /// One device tick: the device's pose in (`dt` as in
    /// [`HapticLoop::tick_step`](crate::HapticLoop::tick_step)), with `model` the newest
    /// contact model when one arrived since the last tick; the force to send out and the
    /// tool's new pose. Allocates nothing, takes no lock.
    pub fn tick(&mut self, device: &Pose, dt: f64, model: Option<&ContactModel>) -> Tick {
        let start = Instant::now();
        let sensed = self.sense(device, dt);
        if let Some(m) = model {
            self.new_model(*m);
        }
        let sent = self.step(&sensed);
        let compute = start.elapsed().as_secs_f64();
        self.tick_of(&sent, compute, start)
    }

    /// The [`Tick`] of a servo step whose model came from the collision thread's side.
    pub(crate) fn tick_of(&self, sent: &Sent, compute: f64, now: Instant) -> Tick {
        let model = self.blend.target();
        let volume_bound = if model.force_cap.is_finite() {
            model.force_cap / self.opts.contact_stiffness
        } else {
            model.volume
        };
        Tick {
            force: sent.force,
            torque: sent.torque,
            tool: self.state.pose,
            contact_force: sent.contact.force,
            volume: model.volume,
            volume_bound,
            max_depth: model.max_depth,
            patches: model.patches,
            budgeted: model.force_cap.is_finite(),
            compute,
            late: compute > self.opts.budget,
            model_age: model.age(now),
        }
    }

    /// Energy the device has delivered to the hand so far (J; see
    /// [`HapticLoop::energy_to_user`](crate::HapticLoop::energy_to_user)).
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

    /// The newest contact model.
    pub fn model(&self) -> &ContactModel {
        self.blend.target()
    }

    pub(crate) fn start(body: RigidBody, start: Pose, opts: HapticOptions) -> Servo {
        Servo {
            body,
            state: BodyState::at_rest(start),
            opts,
            blend: Blend::new(ContactModel::none(start)),
            last_device: (start.transform_point(body.center_of_mass), start.rotation),
            device_velocity: (DVec3::ZERO, DVec3::ZERO),
            sent: (DVec3::ZERO, DVec3::ZERO),
            energy: 0.0,
            energy_max: 0.0,
        }
    }

    /// Reads the device's pose: the step (`dt` when positive, finite and at most ten
    /// periods, else one period), the device's velocity, and the energy the held force did
    /// on the hand since the last tick (zero-order hold: constant over the tick).
    pub(crate) fn sense(&mut self, device: &Pose, dt: f64) -> Sensed {
        let period = 1.0 / self.opts.rate;
        let h = if dt.is_finite() && dt > 0.0 && dt <= 10.0 * period {
            dt
        } else {
            period
        };
        // The device as the loop takes it: it follows the pose read exactly while that moves
        // within `max_device_speed` and `max_device_acceleration` (rotations at the same at
        // the coupling's lever), else it goes there as fast as those allow without
        // overshooting; so a glitch, a jump or a far or non-finite pose moves the tool, and
        // steps the coupling's force, no more than a hand could.
        let (x0, q0) = self.last_device;
        let (vmax, amax) = (
            self.opts.max_device_speed,
            self.opts.max_device_acceleration,
        );
        let xr = device.transform_point(self.body.center_of_mass);
        let (x, v) = follow(xr - x0, self.device_velocity.0, vmax, amax, h);
        let x = x.map_or(xr, |dx| x0 + dx);
        let (turn, w) = follow(
            rotation_between(q0, device.rotation),
            self.device_velocity.1,
            vmax / LEVER,
            amax / LEVER,
            h,
        );
        let (q, dth) = match turn {
            None => (device.rotation, rotation_between(q0, device.rotation)),
            Some(t) => ((exp(t) * q0).normalize(), t),
        };
        self.device_velocity = (v, w);
        let dx = x - x0;
        self.energy += (self.sent.0.dot(dx) + self.sent.1.dot(dth)) * MJ;
        self.energy_max = self.energy_max.max(self.energy);
        self.last_device = (x, q);
        Sensed { x, q, v, w, h }
    }

    /// Starts blending towards a new contact model.
    pub(crate) fn new_model(&mut self, m: ContactModel) {
        self.blend.switch_to(m);
    }

    /// One implicit step of the tool under the coupling to the sensed device and the contact
    /// model in use; the force to send.
    pub(crate) fn step(&mut self, d: &Sensed) -> Sent {
        let com = self.body.center_of_mass;
        let c = self.opts.coupling;
        let max_step = self.opts.model_slew * d.h;
        let (contact, kc) = self.blend.wrench_at(&self.state.pose, com, max_step);
        let xt = self.state.pose.transform_point(com);
        let err = rotation_between(self.state.pose.rotation, d.q);
        let spring = (d.x - xt) * c.stiffness + (d.v - self.state.velocity) * c.damping;
        let twist =
            err * c.angular_stiffness + (d.w - self.state.angular_velocity) * c.angular_damping;
        // Contact damping β·K on the tool's own velocity (A is fixed).
        let (cd, mut damping) = contact_damping(&kc, self.opts.contact_damping, &self.state);
        let w = Wrench {
            force: spring + contact.force + cd.force,
            torque: twist + contact.torque + cd.torque,
        };
        let mut stiffness: Mat6 = kc;
        for i in 0..6 {
            let (k, b) = if i < 3 {
                (c.stiffness, c.damping)
            } else {
                (c.angular_stiffness, c.angular_damping)
            };
            stiffness[i][i] += k;
            damping[i][i] += b;
        }
        if !implicit_step(&self.body, &mut self.state, d.h, w, &stiffness, &damping) {
            // Non-finite input (a NaN device pose): the tool stays where it was, at rest.
            self.state.velocity = DVec3::ZERO;
            self.state.angular_velocity = DVec3::ZERO;
        }
        // What the hand feels: the coupling after the step, pulling the device towards the
        // tool, clamped to the device's limits.
        let xt = self.state.pose.transform_point(com);
        let err = rotation_between(self.state.pose.rotation, d.q);
        let f = -((d.x - xt) * c.stiffness + (d.v - self.state.velocity) * c.damping);
        let t =
            -(err * c.angular_stiffness + (d.w - self.state.angular_velocity) * c.angular_damping);
        let force = clamp(f, self.opts.device.max_force);
        let torque = clamp(t, self.opts.device.max_torque);
        self.sent = (force, torque);
        Sent {
            force,
            torque,
            contact,
        }
    }
}

/// One step of a follower at velocity `v0` towards a target `d` away, in `h`: `None` (and
/// the velocity `d / h`) when it can be there now within the speed `vmax` and the
/// acceleration `amax`; else the displacement it makes at the best speed that still stops
/// on the target (`√(2·amax·|d|)`, at most `vmax`), reached within `amax`, and its new
/// velocity. A non-finite `d` is a target in its direction, infinitely far; a NaN one, none.
fn follow(d: DVec3, v0: DVec3, vmax: f64, amax: f64, h: f64) -> (Option<DVec3>, DVec3) {
    let need = d / h;
    if need.is_finite() && need.length() <= vmax && (need - v0).length() <= amax * h {
        return (None, need);
    }
    let dist = d.length();
    let dir = towards(d, 1.0);
    let speed = if dist.is_finite() {
        (2.0 * amax * dist).sqrt().min(vmax)
    } else {
        vmax
    };
    let v = v0 + towards(dir * speed - v0, amax * h);
    let mut step = v * h;
    if dist.is_finite() && step.length() > dist {
        step = d;
    }
    (Some(step), step / h)
}

/// `d` shortened to at most `max` (its direction kept), robust to huge and non-finite
/// vectors: zero when `d` has no direction (zero, NaN).
fn towards(d: DVec3, max: f64) -> DVec3 {
    let scale = d.abs().max_element();
    if d.is_nan() || scale <= 0.0 {
        return DVec3::ZERO;
    }
    if scale.is_infinite() {
        // An infinite component: its direction alone.
        let u = DVec3::new(
            if d.x.is_infinite() { d.x.signum() } else { 0.0 },
            if d.y.is_infinite() { d.y.signum() } else { 0.0 },
            if d.z.is_infinite() { d.z.signum() } else { 0.0 },
        );
        return u.normalize() * max;
    }
    let u = d / scale;
    let len = u.length() * scale;
    if len <= max {
        d
    } else {
        u / u.length() * max
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Follows a target `dist` mm away along x from rest, tick by tick, until `follow` says
    /// it is there; the ticks taken and the largest position and velocity change seen.
    fn chase(dist: f64, vmax: f64, amax: f64, h: f64) -> (usize, f64, f64) {
        let (mut x, mut v) = (0.0f64, DVec3::ZERO);
        let (mut peak, mut dv_max) = (0.0f64, 0.0f64);
        for tick in 1..100_000 {
            let (step, v1) = follow(DVec3::new(dist - x, 0.0, 0.0), v, vmax, amax, h);
            match step {
                None => {
                    dv_max = dv_max.max((v1 - v).length());
                    return (tick, peak.max(dist), dv_max);
                }
                Some(s) => {
                    assert!(s.y == 0.0 && s.z == 0.0, "{s}");
                    // Landing on the target (the overshoot guard) may stop at once.
                    if s.x != dist - x {
                        dv_max = dv_max.max((v1 - v).length());
                    }
                    x += s.x;
                    v = v1;
                    peak = peak.max(x);
                    assert!(v.length() <= vmax * (1.0 + 1e-12), "{v} over {vmax}");
                }
            }
        }
        panic!("never got there");
    }

    #[test]
    fn the_follower_brakes_onto_the_target_in_the_least_time_the_limits_allow() {
        let h = 1e-3;
        for (dist, vmax, amax) in [
            (10.0, 1e9, 5e3),
            (50.0, 1e9, 2e4),
            (200.0, 300.0, 5e3),
            (3.0, 1e9, 1e4),
        ] {
            let (ticks, peak, dv) = chase(dist, vmax, amax, h);
            // Never past the target, never accelerating beyond the limit on the way.
            assert!(peak <= dist * (1.0 + 1e-12), "{dist}: overshot to {peak}");
            assert!(
                dv <= amax * h * (1.0 + 1e-9),
                "{dist}: Δv {dv} over {}",
                amax * h
            );
            // Bang-bang: accelerate, cruise at vmax if it is reached, brake; a follower that
            // brakes too early or too late takes longer.
            let t_acc = (vmax / amax).min((dist / amax).sqrt());
            let cruise = (dist - amax * t_acc * t_acc) / vmax;
            let best = 2.0 * t_acc + cruise.max(0.0);
            let took = ticks as f64 * h;
            assert!(
                took >= best * 0.9,
                "{dist}: {took} s, the limits allow {best}"
            );
            assert!(
                took <= best * 1.05 + 3.0 * h,
                "{dist}: {took} s, the limits allow {best}"
            );
        }
    }

    #[test]
    fn the_follower_cruises_at_the_speed_limit_and_goes_for_an_infinite_target() {
        // A target at infinity: full speed after the ramp, never NaN.
        let (mut v, h) = (DVec3::ZERO, 1e-3);
        for _ in 0..1000 {
            let (step, v1) = follow(DVec3::new(f64::INFINITY, 0.0, 0.0), v, 250.0, 5e3, h);
            let s = step.expect("an infinite target is never reached");
            assert!(s.is_finite() && (v1 - v).length() <= 5e3 * h * (1.0 + 1e-12));
            v = v1;
        }
        assert!((v.x - 250.0).abs() < 1e-9 && v.y == 0.0, "{v}");
        // A NaN target: no motion.
        let (step, v1) = follow(DVec3::NAN, DVec3::ZERO, 250.0, 5e3, h);
        assert_eq!((step, v1), (Some(DVec3::ZERO), DVec3::ZERO));
    }

    #[test]
    fn towards_keeps_the_direction_and_shortens_to_the_limit() {
        let d = DVec3::new(3.0, 4.0, 0.0);
        assert_eq!(towards(d, 5.1), d);
        assert_eq!(towards(d, 5.0), d);
        let s = towards(d, 2.5);
        assert!((s - DVec3::new(1.5, 2.0, 0.0)).length() < 1e-12, "{s}");
        let big = towards(DVec3::new(1e300, -1e300, 0.0), 2.0);
        assert!(
            (big - DVec3::new(1.0, -1.0, 0.0) * 2f64.sqrt()).length() < 1e-12,
            "{big}"
        );
        let inf = towards(DVec3::new(f64::INFINITY, 0.0, f64::NEG_INFINITY), 4.0);
        assert!(
            (inf - DVec3::new(1.0, 0.0, -1.0) * 8f64.sqrt()).length() < 1e-12,
            "{inf}"
        );
        assert_eq!(
            towards(DVec3::new(0.0, f64::INFINITY, 1.0), 0.5),
            DVec3::new(0.0, 0.5, 0.0)
        );
        assert_eq!(towards(DVec3::ZERO, 1.0), DVec3::ZERO);
        assert_eq!(towards(DVec3::new(f64::NAN, 1.0, 0.0), 1.0), DVec3::ZERO);
    }
}
