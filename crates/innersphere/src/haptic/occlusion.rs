//! Automatic occlusion: body B closed onto body A under a constant force, moved as a damped
//! rigid body with the penalty contact of the haptic loop until it rests — the bite a
//! surgeon looks for by closing plaster casts (maximal intercuspation).

use super::body::{rotation_between, BodyState, RigidBody, TOOTH_DENSITY};
use super::mat6::Mat6;
use super::step::{add_block, contact_damping, implicit_step, Wrench};
use crate::error::{num, vec3};
use crate::error::{Error, Result};
use crate::pose::Pose;
use crate::query::{Pair, Patch, PenetrationOptions};
use glam::{DMat3, DVec3};

/// `[r]×`.
fn cross(r: DVec3) -> DMat3 {
    DMat3::from_cols(
        DVec3::new(0.0, r.z, -r.y),
        DVec3::new(-r.z, 0.0, r.x),
        DVec3::new(r.y, -r.x, 0.0),
    )
}

/// Settings of [`occlude`]. Units: mm, N, s, kg.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct OcclusionOptions {
    /// Unit direction B is pushed (world), e.g. A's occlusal "up" for a lower jaw.
    pub axis: DVec3,
    /// Closing force (N), applied at B's centre of mass.
    pub force: f64,
    /// Penalty force per unit of penetration volume (N/mm³).
    pub contact_stiffness: f64,
    /// Contact damping (s), as [`HapticOptions::contact_damping`](super::HapticOptions::contact_damping).
    pub contact_damping: f64,
    /// Viscous damping of B's motion (N·s/mm); rotations get `damping × r²` N·mm·s/rad,
    /// `r` B's radius of gyration. It sets how fast B closes (`force / damping` mm/s in free
    /// flight).
    pub damping: f64,
    /// Density of B (kg per model unit³).
    pub density: f64,
    /// Integration step (s).
    pub step: f64,
    /// Rest: B's centre of mass moved less than this (mm) and B turned less than
    /// `rest_distance / r` rad (`r` its radius of gyration) over the last `rest_window` steps.
    pub rest_distance: f64,
    /// Steps over which rest is judged.
    pub rest_window: usize,
    /// Give up after this much simulated time (s).
    pub max_seconds: f64,
    /// Joints that hold points of B near points of A (see [`Joints`]); `None`: B is a free
    /// body.
    pub joints: Option<Joints>,
}

/// Compliant joints of B: each point of B (its model frame) is pulled towards an anchor in
/// A's frame by a spring. For a mandible these are its condyles in the temporomandibular
/// joints, which keep a closing jaw from sliding sideways or forwards where no patient's
/// jaw can go.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Joints {
    /// The points of B (model frame).
    pub points: [DVec3; 2],
    /// Where they are held (world frame).
    pub anchors: [DVec3; 2],
    /// Spring stiffness per joint (N/mm).
    pub stiffness: f64,
}

impl Default for OcclusionOptions {
    /// Closing along +z with 5 N, the haptic loop's contact (10 N/mm³, 1 ms), 1 N·s/mm of
    /// damping (5 mm/s closing speed), 1 ms steps, rest at 0.1 µm over 100 steps, at most
    /// 30 s of simulated time.
    fn default() -> Self {
        OcclusionOptions {
            axis: DVec3::Z,
            force: 5.0,
            contact_stiffness: 10.0,
            contact_damping: 1e-3,
            damping: 1.0,
            density: TOOTH_DENSITY,
            step: 1e-3,
            rest_distance: 1e-4,
            rest_window: 100,
            max_seconds: 30.0,
            joints: None,
        }
    }
}

/// Where B came to rest.
#[derive(Debug, Clone, PartialEq)]
pub struct Occlusion {
    /// B's final pose.
    pub pose: Pose,
    /// True when B came to rest within the time allowed.
    pub converged: bool,
    /// Integration steps taken.
    pub steps: usize,
    /// Simulated time (s).
    pub seconds: f64,
    /// Penetration volume at rest (mm³).
    pub volume: f64,
    /// Deepest leaf-pair overlap at rest (mm).
    pub max_depth: f64,
    /// Contact regions at rest (world).
    pub patches: Vec<Patch>,
    /// The unit direction B was pushed (the options' axis, normalised).
    pub axis: DVec3,
}

/// Closes B (at `from`) onto A (fixed at `pose_a`) under `opts.force` along `opts.axis` until
/// it rests. Fails on bad options or a tree of B without mass properties.
pub fn occlude(
    pair: &mut Pair,
    pose_a: &Pose,
    from: &Pose,
    opts: &OcclusionOptions,
) -> Result<Occlusion> {
    check(opts)?;
    let body = RigidBody::from_tree(pair.tree_b(), opts.density)?;
    let axis = unit(opts.axis).expect("checked");
    let mut state = BodyState::at_rest(*from);
    let popts = PenetrationOptions {
        stiffness: opts.contact_stiffness,
        max_patches: 16,
        linearize: true,
        ..Default::default()
    };
    let h = opts.step;
    let max_steps = (opts.max_seconds / h).ceil() as usize;
    let window = opts.rest_window.max(1);
    // The centre of mass and rotation `window` steps ago, in a ring.
    let mut ring = vec![(DVec3::ZERO, glam::DQuat::IDENTITY); window];
    // Rotations are damped as the body's mass at its radius of gyration would be by the
    // linear damping, so that a small body and a large one settle alike.
    let i = &body.inertia;
    let gyration2 = (i.x_axis.x + i.y_axis.y + i.z_axis.z) / (3.0 * body.mass);
    let (b, br) = (opts.damping, opts.damping * gyration2);
    let mut steps = 0;
    let mut converged = false;
    while steps < max_steps {
        let p = pair.penetration_with(pose_a, &state.pose, &popts);
        let com = state.pose.transform_point(body.center_of_mass);
        ring[steps % window] = (com, state.pose.rotation);
        if steps >= window {
            let (c0, q0) = ring[(steps + 1) % window];
            let moved = (com - c0).length();
            let turned = rotation_between(q0, state.pose.rotation).length();
            if moved < opts.rest_distance && turned < opts.rest_distance / gyration2.sqrt() {
                converged = true;
                break;
            }
        }
        // The contact's stiffness, then the joints' springs added to it.
        let kc: Mat6 = p.stiffness.to_matrix6();
        let mut k = kc;
        let (mut jf, mut jt) = (DVec3::ZERO, DVec3::ZERO);
        if let Some(j) = &opts.joints {
            for (pb, anchor) in j.points.iter().zip(&j.anchors) {
                let at = state.pose.transform_point(*pb);
                let f = (*anchor - at) * j.stiffness;
                let r = at - com;
                jf += f;
                jt += r.cross(f);
                // A point spring at lever r: K = k·[[I, −[r]×], [[r]×, −[r]×[r]×]].
                let c = cross(r);
                let ks = j.stiffness;
                add_block(&mut k, 0, 0, &(DMat3::IDENTITY * ks));
                add_block(&mut k, 0, 3, &(c * -ks));
                add_block(&mut k, 3, 0, &(c * ks));
                add_block(&mut k, 3, 3, &(c * c * -ks));
            }
        }
        // The contact's damping only: β·K of the contact, not of the joints.
        let (cd, mut d) = contact_damping(&kc, opts.contact_damping, &state);
        let w = Wrench {
            force: axis * opts.force + jf + p.force - state.velocity * b + cd.force,
            torque: p.torque_b + jt - state.angular_velocity * br + cd.torque,
        };
        for (i, row) in d.iter_mut().enumerate() {
            row[i] += if i < 3 { b } else { br };
        }
        if !implicit_step(&body, &mut state, h, w, &k, &d) {
            return Err(Error::InvalidOption(
                "the occlusion's dynamics became non-finite (a non-finite pose or option?)".into(),
            ));
        }
        steps += 1;
    }
    let p = pair.penetration_with(pose_a, &state.pose, &popts);
    Ok(Occlusion {
        pose: state.pose,
        converged,
        steps,
        seconds: steps as f64 * h,
        volume: p.volume,
        max_depth: p.max_depth,
        patches: pair.patches().to_vec(),
        axis,
    })
}

/// `v` scaled to length 1, robustly (a huge or tiny vector too); `None` when it has no
/// direction (zero or non-finite).
fn unit(v: DVec3) -> Option<DVec3> {
    let scale = v.abs().max_element();
    if !(scale.is_finite() && scale > 0.0) {
        return None;
    }
    let u = v / scale;
    Some(u / u.length())
}

fn check(o: &OcclusionOptions) -> Result<()> {
    let positive = [
        ("the closing force", o.force),
        ("the contact stiffness", o.contact_stiffness),
        ("the damping", o.damping),
        ("the density", o.density),
        ("the step", o.step),
        ("the rest distance", o.rest_distance),
        ("the time limit", o.max_seconds),
    ];
    for (what, x) in positive {
        if !(x.is_finite() && x > 0.0) {
            return Err(Error::InvalidOption(format!(
                "{what} must be positive and finite, not {}",
                num(x)
            )));
        }
    }
    if !(o.contact_damping.is_finite() && o.contact_damping >= 0.0) {
        return Err(Error::InvalidOption(format!(
            "the contact damping must be finite and not negative, not {}",
            num(o.contact_damping)
        )));
    }
    if unit(o.axis).is_none() {
        return Err(Error::InvalidOption(format!(
            "the closing axis must be a finite non-zero vector, not {}",
            vec3(o.axis)
        )));
    }
    if let Some(j) = &o.joints {
        if !j.points.iter().chain(&j.anchors).all(|p| p.is_finite()) {
            return Err(Error::InvalidOption(
                "the joints' points and anchors must be finite".into(),
            ));
        }
        if !(j.stiffness.is_finite() && j.stiffness >= 0.0) {
            return Err(Error::InvalidOption(format!(
                "the joint stiffness must be finite and at least 0, not {} N/mm",
                num(j.stiffness)
            )));
        }
    }
    if o.max_seconds / o.step > 1e8 {
        return Err(Error::InvalidOption(format!(
            "{} s in steps of {} s is more than 10⁸ steps",
            num(o.max_seconds),
            num(o.step)
        )));
    }
    Ok(())
}
