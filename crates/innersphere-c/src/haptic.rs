//! The library's haptic loop: virtual coupling, implicit step, deadline (docs/HAPTICS.md).

use crate::error::{pointer, status, Fail};
use crate::query::ist_pair;
use crate::types::ist_pose;
use crate::{mutable, reference};
use innersphere::Pair;
use innersphere_haptic::{
    CollisionOptions, ContactSource, Coupling, DeviceClass, DeviceLimits, HapticLoop,
    HapticOptions, MultirateLoop, Tick,
};
use std::ffi::c_int;

/// A desktop pen device (Geomagic Touch class: 3.3 N, rotations sensed only).
pub const IST_DEVICE_TOUCH: c_int = 0;
/// A parallel device (Force Dimension omega.6 class: 12 N, rotations sensed only).
pub const IST_DEVICE_OMEGA: c_int = 1;

/// Settings of a haptic loop. Units: mm, N, s, kg; torques in N·mm.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ist_haptic_params {
    /// Device ticks per second (Hz).
    pub rate: f64,
    /// Most time one tick may take (s); the exact query gives way to the time-critical one
    /// when it would not fit.
    pub budget: f64,
    /// Largest force sent (N).
    pub max_force: f64,
    /// Largest torque sent (N·mm); 0 for a device that does not actuate rotations.
    pub max_torque: f64,
    /// Stiffest spring the device renders (N/mm).
    pub max_stiffness: f64,
    /// Coupling stiffness (N/mm).
    pub coupling_stiffness: f64,
    /// Coupling damping (N·s/mm).
    pub coupling_damping: f64,
    /// Rotational coupling stiffness (N·mm/rad).
    pub angular_stiffness: f64,
    /// Rotational coupling damping (N·mm·s/rad).
    pub angular_damping: f64,
    /// Penalty force per penetration volume (N/mm³).
    pub contact_stiffness: f64,
    /// Contact damping (s), proportional to the contact stiffness.
    pub contact_damping: f64,
    /// Density of the tool (kg/mm³).
    pub density: f64,
    /// How fast a new contact model may take over from the one in use (N/s): bounds the
    /// force step a model update causes.
    pub model_slew: f64,
    /// Oldest a contact model may get (s) before the single-thread loop runs the exact query
    /// whatever it costs.
    pub max_model_age: f64,
    /// Fastest the loop lets the device move (mm/s; rotations alike at a 20 mm lever): a
    /// jump, a glitch or a far pose is approached no faster.
    pub max_device_speed: f64,
    /// Largest acceleration the loop lets the device have (mm/s²).
    pub max_device_acceleration: f64,
    /// 1: the penetration query runs in a collision thread of its own, started by
    /// ist_haptic_new and joined by ist_haptic_free, and each tick uses the newest contact
    /// model it published (the multi-rate loop, for 4–10 kHz servo rates or contacts whose
    /// query exceeds a tick); 0: the query runs inside ist_haptic_tick.
    pub collision_thread: c_int,
    /// With collision_thread: seconds the collision thread sleeps before each query (0; a
    /// stress knob standing for a slow machine).
    pub collision_delay: f64,
    /// With collision_thread: most time one collision query may take (s) before the
    /// time-critical query bounds the model in use instead.
    pub collision_budget: f64,
    /// 1: the contact is the meshes' own (ist_mesh_penetration; needs collision_thread 1
    /// and both trees' meshes, ist_tree_with_mesh); 0: the sphere packings' (default).
    pub mesh_contact: c_int,
    /// World pose of body A (fixed).
    pub pose_a: ist_pose,
    /// Where the tool (body B) starts, at rest.
    pub start: ist_pose,
}

/// A haptic loop (opaque). ist_haptic_tick and ist_haptic_energy are called from one thread
/// at a time: the device's servo thread. With a collision thread, that thread is the
/// library's own; the caller never calls into it.
pub struct ist_haptic {
    hl: Loop,
}

/// Either loop.
enum Loop {
    Single(Box<HapticLoop>),
    Multirate(Box<MultirateLoop>),
}

/// What one tick did (world frame).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ist_haptic_output {
    /// Force to send to the device (N), clamped to max_force.
    pub force: [f64; 3],
    /// Torque to send to the device (N·mm), clamped to max_torque.
    pub torque: [f64; 3],
    /// The tool's pose after the tick: draw this.
    pub tool: ist_pose,
    /// Penalty force on the tool (N).
    pub contact_force: [f64; 3],
    /// Penetration volume (mm³): exact, or what the time-critical query found.
    pub volume: f64,
    /// Upper bound on the volume (= volume unless budgeted).
    pub volume_bound: f64,
    /// Deepest leaf-sphere overlap (mm).
    pub max_depth: f64,
    /// Time the tick took (s).
    pub compute_seconds: f64,
    /// 1 when the time-critical query answered.
    pub budgeted: c_int,
    /// 1 when the tick took longer than its budget.
    pub late: c_int,
    /// Age of the contact model the tick used (s): since the tool pose its query answered
    /// for was taken (simulated time without a collision thread, real time with one).
    pub model_age_seconds: f64,
}

/// The defaults of a device class (IST_DEVICE_TOUCH or IST_DEVICE_OMEGA) at 1 kHz, with A
/// at the identity and the tool starting at the identity.
///
/// # Safety
/// `out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_haptic_params_default(
    device_class: c_int,
    out: *mut ist_haptic_params,
) -> c_int {
    unsafe { ist_haptic_params_for_rate(device_class, 1000.0, out) }
}

/// The defaults of a device class for a loop at `rate` Hz (budget one period): below 1 kHz
/// the coupling's damping grows with the period and, past the device's damping limit, its
/// stiffness drops, so that the loop stays passive (ist_haptic_new refuses a damping below
/// k·T/2).
///
/// # Safety
/// `out` is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_haptic_params_for_rate(
    device_class: c_int,
    rate: f64,
    out: *mut ist_haptic_params,
) -> c_int {
    status(|| {
        let out = unsafe { mutable(out, "out") }?;
        if !(rate.is_finite() && rate > 0.0) {
            return Err(Fail::arg(format!(
                "the rate must be positive and finite, not {} Hz",
                innersphere::error::num(rate)
            )));
        }
        let class = match device_class {
            IST_DEVICE_TOUCH => DeviceClass::Touch,
            IST_DEVICE_OMEGA => DeviceClass::Omega,
            c => {
                return Err(Fail::arg(format!(
                    "unknown device class {c} (IST_DEVICE_TOUCH or IST_DEVICE_OMEGA)"
                )))
            }
        };
        let o = HapticOptions::for_device_at(class, rate);
        let id = crate::query::ist_pose_identity();
        *out = ist_haptic_params {
            rate: o.rate,
            budget: o.budget,
            max_force: o.device.max_force,
            max_torque: o.device.max_torque,
            max_stiffness: o.device.max_stiffness,
            coupling_stiffness: o.coupling.stiffness,
            coupling_damping: o.coupling.damping,
            angular_stiffness: o.coupling.angular_stiffness,
            angular_damping: o.coupling.angular_damping,
            contact_stiffness: o.contact_stiffness,
            contact_damping: o.contact_damping,
            density: o.density,
            model_slew: o.model_slew,
            max_model_age: o.max_model_age,
            max_device_speed: o.max_device_speed,
            max_device_acceleration: o.max_device_acceleration,
            collision_thread: 0,
            collision_delay: 0.0,
            collision_budget: CollisionOptions::default().budget,
            mesh_contact: 0,
            pose_a: id,
            start: id,
        };
        Ok(())
    })
}

/// A haptic loop on the trees of `pair` (it keeps its own pair: `pair` stays yours), with
/// B as the tool. B's tree must hold mass properties (built by this version). NULL on error.
///
/// # Safety
/// `pair` and `params` are NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_haptic_new(
    pair: *const ist_pair,
    params: *const ist_haptic_params,
) -> *mut ist_haptic {
    pointer(|| {
        let p = unsafe { reference(pair, "pair") }?;
        let c = unsafe { reference(params, "params") }?;
        let opts = HapticOptions {
            rate: c.rate,
            budget: c.budget,
            device: DeviceLimits {
                max_force: c.max_force,
                max_torque: c.max_torque,
                max_stiffness: c.max_stiffness,
                max_damping: f64::INFINITY,
            },
            coupling: Coupling {
                stiffness: c.coupling_stiffness,
                damping: c.coupling_damping,
                angular_stiffness: c.angular_stiffness,
                angular_damping: c.angular_damping,
            },
            contact_stiffness: c.contact_stiffness,
            contact_damping: c.contact_damping,
            density: c.density,
            max_patches: 8,
            model_slew: c.model_slew,
            max_model_age: c.max_model_age,
            max_device_speed: c.max_device_speed,
            max_device_acceleration: c.max_device_acceleration,
        };
        let own = Pair::new(p.pair.tree_a().clone(), p.pair.tree_b().clone());
        let (pose_a, start) = (c.pose_a.to_pose()?, c.start.to_pose()?);
        let contact = match c.mesh_contact {
            0 => ContactSource::Spheres,
            1 => ContactSource::Mesh,
            n => return Err(Fail::arg(format!("mesh_contact must be 0 or 1, not {n}"))),
        };
        let hl = match c.collision_thread {
            0 if contact == ContactSource::Mesh => {
                return Err(Fail::arg(
                    "mesh_contact 1 needs collision_thread 1 (the meshes' query takes milliseconds in deep contact)"
                        .to_string(),
                ))
            }
            0 => Loop::Single(Box::new(HapticLoop::new(own, pose_a, start, opts)?)),
            1 => {
                let collision = CollisionOptions {
                    delay: c.collision_delay,
                    budget: c.collision_budget,
                    contact,
                    ..Default::default()
                };
                Loop::Multirate(Box::new(MultirateLoop::spawn(
                    own, pose_a, start, opts, collision,
                )?))
            }
            n => {
                return Err(Fail::arg(format!(
                    "collision_thread must be 0 or 1, not {n}"
                )))
            }
        };
        Ok(Box::new(ist_haptic { hl }))
    })
}

/// One device tick: the device's pose in (B's pose in the world), `dt` the seconds between
/// this pose's sample and the previous one (0: one period; it must be the interval the pose
/// moved over, or the device's velocity comes out wrong; over ten periods counts as one);
/// the force and torque to send and the tool's pose out.
/// Never allocates, never blocks. A NaN device pose (IST_ERR_POSE) and a negative, NaN or
/// infinite dt (IST_ERR_INVALID_ARGUMENT) are refused and the tool stays where it was.
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_haptic_tick(
    haptic: *mut ist_haptic,
    device: *const ist_pose,
    dt: f64,
    out: *mut ist_haptic_output,
) -> c_int {
    status(|| {
        let h = unsafe { mutable(haptic, "haptic") }?;
        let d = unsafe { reference(device, "device") }?.to_pose()?;
        let out = unsafe { mutable(out, "out") }?;
        innersphere_haptic::check_step(dt)?;
        let t: Tick = match &mut h.hl {
            Loop::Single(l) => l.tick_step(&d, dt),
            Loop::Multirate(l) => l.tick_step(&d, dt),
        };
        *out = ist_haptic_output {
            force: t.force.to_array(),
            torque: t.torque.to_array(),
            tool: ist_pose::from_pose(&t.tool),
            contact_force: t.contact_force.to_array(),
            volume: t.volume,
            volume_bound: t.volume_bound,
            max_depth: t.max_depth,
            compute_seconds: t.compute,
            budgeted: t.budgeted as c_int,
            late: t.late as c_int,
            model_age_seconds: t.model_age,
        };
        Ok(())
    })
}

/// The energy the device has given the hand so far (J; at most 0 for a passive loop), and
/// its largest value, through `now` and `max` (either may be NULL).
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_haptic_energy(
    haptic: *const ist_haptic,
    now: *mut f64,
    max: *mut f64,
) -> c_int {
    status(|| {
        let h = unsafe { reference(haptic, "haptic") }?;
        let (e, e_max) = match &h.hl {
            Loop::Single(l) => (l.energy_to_user(), l.energy_to_user_max()),
            Loop::Multirate(l) => (l.energy_to_user(), l.energy_to_user_max()),
        };
        if let Some(n) = unsafe { now.as_mut() } {
            *n = e;
        }
        if let Some(m) = unsafe { max.as_mut() } {
            *m = e_max;
        }
        Ok(())
    })
}

/// The contact models the collision thread has published so far, through `out` (0 without
/// a collision thread). Never waits; from the servo thread or any other.
///
/// # Safety
/// Every pointer is NULL or valid.
#[no_mangle]
pub unsafe extern "C" fn ist_haptic_collision_queries(
    haptic: *const ist_haptic,
    out: *mut u64,
) -> c_int {
    status(|| {
        let h = unsafe { reference(haptic, "haptic") }?;
        let out = unsafe { mutable(out, "out") }?;
        *out = match &h.hl {
            Loop::Single(_) => 0,
            Loop::Multirate(l) => l.collision_queries(),
        };
        Ok(())
    })
}

/// Frees a haptic loop (NULL is accepted); with a collision thread, stops and joins it
/// first (waiting for its query in progress to end).
///
/// # Safety
/// `haptic` is NULL or from ist_haptic_new, not freed before.
#[no_mangle]
pub unsafe extern "C" fn ist_haptic_free(haptic: *mut ist_haptic) {
    if !haptic.is_null() {
        let free = || drop(unsafe { Box::from_raw(haptic) });
        let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(free));
    }
}
