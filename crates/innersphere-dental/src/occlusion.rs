//! Automatic occlusion: body B closed onto body A under a constant force, moved as a damped
//! rigid body with the penalty contact of the haptic loop until it rests — the bite a
//! surgeon looks for by closing plaster casts (maximal intercuspation).

use crate::occlusion_limits::{check, short};
use crate::occlusion_status::{OcclusionStatus, BALANCE};
use glam::{DMat3, DQuat, DVec3};
use innersphere::error::{num, Error, Result};
use innersphere::pose::Pose;
use innersphere::query::{Pair, Patch, PenetrationOptions};
use innersphere_haptic::body::{rotation_between, BodyState, RigidBody, TOOTH_DENSITY};
use innersphere_haptic::mat6::Mat6;
use innersphere_haptic::step::{add_block, contact_damping, implicit_step, Wrench};
use innersphere_haptic::ContactSource;

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
    /// Closing force (N), applied at B's centre of mass: 0.5 to 1000 N, and at most
    /// 2 mm³ × `contact_stiffness` (the overlap that carries it at rest; see
    /// [`occlusion_limits`](crate::occlusion_limits)).
    pub force: f64,
    /// Penalty force per unit of penetration volume (N/mm³), at most 1e5.
    pub contact_stiffness: f64,
    /// Contact damping (s), as [`HapticOptions::contact_damping`](innersphere_haptic::HapticOptions::contact_damping).
    pub contact_damping: f64,
    /// Viscous damping of B's motion (N·s/mm); rotations get `damping × r²` N·mm·s/rad,
    /// `r` B's radius of gyration. It sets how fast B closes (`force / damping` mm/s in free
    /// flight; one step moves B at most 0.05 mm in free flight).
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
    /// Give up after this much simulated time (s), at most 60.
    pub max_seconds: f64,
    /// Joints that hold points of B near points of A (see [`Joints`]); `None`: B is a free
    /// body.
    pub joints: Option<Joints>,
    /// Where the contact comes from: the sphere packings' volume (default), or the meshes'
    /// own (both trees need their meshes). With the meshes B first closes on the spheres,
    /// then settles on the meshes from that rest: a mesh query costs milliseconds in
    /// contact, and the spheres bring B within a fraction of a millimetre of it in
    /// microseconds a step.
    pub contact: ContactSource,
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
            contact: ContactSource::Spheres,
        }
    }
}

/// Where the closing left B, and how it ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Occlusion {
    /// B's final pose.
    pub pose: Pose,
    /// How the closing ended: [`OcclusionStatus::Converged`] only when B rests in contact
    /// with A, held there by the contact.
    pub status: OcclusionStatus,
    /// Integration steps taken.
    pub steps: usize,
    /// Simulated time (s).
    pub seconds: f64,
    /// Penetration volume at the final pose (mm³).
    pub volume: f64,
    /// Deepest leaf-pair overlap at the final pose (mm); with mesh contact the largest mean
    /// depth of a patch of the meshes' intersection.
    pub max_depth: f64,
    /// Contact regions at the final pose (world).
    pub patches: Vec<Patch>,
    /// The unit direction B was pushed (the options' axis, normalised).
    pub axis: DVec3,
}

impl Occlusion {
    /// True exactly when the closing converged: B at rest in contact.
    pub fn converged(&self) -> bool {
        self.status == OcclusionStatus::Converged
    }
}

/// Closes B (at `from`) onto A (fixed at `pose_a`) under `opts.force` along `opts.axis` until
/// it rests, and says how it ended ([`OcclusionStatus`]): at rest in contact (converged), at
/// rest open, out of time, through A, or away from it (the last two stop the closing at
/// once). Fails on options outside their limits ([`occlusion_limits`](crate::occlusion_limits)),
/// a tree of B without mass properties, or dynamics that fail (the error says at which step
/// and why).
pub fn occlude(
    pair: &mut Pair,
    pose_a: &Pose,
    from: &Pose,
    opts: &OcclusionOptions,
) -> Result<Occlusion> {
    check(opts, from)?;
    if opts.contact == ContactSource::Spheres {
        return close(pair, pose_a, from, opts, 0);
    }
    if pair.tree_a().mesh().is_none() || pair.tree_b().mesh().is_none() {
        return Err(Error::InvalidOption(
            "mesh contact needs both trees' meshes (SharedTree::with_mesh)".into(),
        ));
    }
    // The spheres first: a rest, or how that closing failed (through A, away, out of time).
    let spheres = OcclusionOptions {
        contact: ContactSource::Spheres,
        ..*opts
    };
    let near = close(pair, pose_a, from, &spheres, 0)?;
    if near.status != OcclusionStatus::Converged {
        return Ok(near);
    }
    close(pair, pose_a, &near.pose, opts, near.steps)
}

/// One step's contact, of the spheres or the meshes (`source`).
struct StepContact {
    volume: f64,
    max_depth: f64,
    force: DVec3,
    torque: DVec3,
    stiffness: Mat6,
}

fn contact_at(
    pair: &mut Pair,
    pose_a: &Pose,
    pose: &Pose,
    popts: &PenetrationOptions,
    source: ContactSource,
) -> Result<StepContact> {
    Ok(match source {
        ContactSource::Spheres => {
            let p = pair.penetration_with(pose_a, pose, popts);
            StepContact {
                volume: p.volume,
                max_depth: p.max_depth,
                force: p.force,
                torque: p.torque_b,
                stiffness: p.stiffness.to_matrix6(),
            }
        }
        ContactSource::Mesh => {
            let m = pair.mesh_penetration_with(pose_a, pose, popts)?;
            StepContact {
                volume: m.volume,
                max_depth: m.max_depth,
                force: m.force,
                torque: m.torque_b,
                stiffness: m.stiffness.to_matrix6(),
            }
        }
    })
}

/// [`occlude`] on the options' contact alone, from `from`, `steps_before` steps already
/// taken (they count against the time limit and in the answer).
// Over 120 lines: the step loop reads the contact, the joints, the rest test and the
// bounds in one place, in the order the implicit step needs them.
fn close(
    pair: &mut Pair,
    pose_a: &Pose,
    from: &Pose,
    opts: &OcclusionOptions,
    steps_before: usize,
) -> Result<Occlusion> {
    let body = RigidBody::from_tree(pair.tree_b(), opts.density)?;
    let axis = unit(opts.axis).expect("checked");
    let mut state = BodyState::at_rest(*from);
    let popts = contact_options(opts);
    let h = opts.step;
    let max_steps = (opts.max_seconds / h).ceil() as usize;
    // Rotations are damped as the body's mass at its radius of gyration would be by the
    // linear damping, so that a small body and a large one settle alike.
    let gyration2 = gyration_squared(&body);
    let (b, br) = own_damping(opts.damping, gyration2);
    let mut rest = RestWatch::new(opts.rest_window, opts.rest_distance, gyration2.sqrt());
    let bounds = Bounds::new(pair, pose_a, from, body.center_of_mass, axis);
    let balance = (
        BALANCE * opts.force,
        BALANCE * opts.force * gyration2.sqrt(),
    );
    let mut steps = steps_before;
    let status = loop {
        let p = contact_at(pair, pose_a, &state.pose, &popts, opts.contact)?;
        let com = state.pose.transform_point(body.center_of_mass);
        if let Some(gone) = bounds.left(com) {
            break gone;
        }
        // The contact's stiffness, then the joints' springs added to it.
        let kc: Mat6 = p.stiffness;
        let mut k = kc;
        let joints = match &opts.joints {
            Some(j) => add_joints(j, &state.pose, com, &mut k),
            None => Wrench::default(),
        };
        // What pushes B, but for its damping: balanced at rest.
        let pushed = Wrench {
            force: axis * opts.force + joints.force + p.force,
            torque: p.torque + joints.torque,
        };
        let still = rest.at_rest(com, state.pose.rotation);
        if still && pushed.force.length() <= balance.0 && pushed.torque.length() <= balance.1 {
            let touching = p.volume > 0.0 && !pair.patches().is_empty();
            break if touching {
                OcclusionStatus::Converged
            } else {
                OcclusionStatus::NoContact
            };
        }
        if steps >= max_steps {
            break OcclusionStatus::TimeLimit;
        }
        // The damping: B's own, and the contact's (β·K of the contact, not of the joints).
        let (dw, d) = damping(&kc, opts.contact_damping, b, br, &state);
        let w = Wrench {
            force: pushed.force + dw.force,
            torque: pushed.torque + dw.torque,
        };
        if !implicit_step(&body, &mut state, h, w, &k, &d) {
            return Err(diverged(
                steps,
                h,
                (com - bounds.start).length(),
                &w,
                &k,
                &d,
            ));
        }
        steps += 1;
    };
    let p = contact_at(pair, pose_a, &state.pose, &popts, opts.contact)?;
    Ok(Occlusion {
        pose: state.pose,
        status,
        steps,
        seconds: steps as f64 * h,
        volume: p.volume,
        max_depth: p.max_depth,
        patches: pair.patches().to_vec(),
        axis,
    })
}

/// Where B may go: A's centre of mass (world), B's start, on which side of A it started
/// along the closing axis, and how far it may move before it can no longer touch A.
struct Bounds {
    /// A's centre of mass (world).
    a: DVec3,
    /// B's centre of mass at the start (world).
    start: DVec3,
    /// The unit closing axis.
    axis: DVec3,
    /// B started on the near side of A's centre of mass along the axis.
    near: bool,
    /// The farthest B's centre of mass may move from its start: its start's distance to A's
    /// centre of mass plus both bodies' radii about their centres of mass. Farther, their
    /// bounding spheres are apart and B, pushed on along the axis, cannot touch A again.
    reach: f64,
}

impl Bounds {
    fn new(pair: &Pair, pose_a: &Pose, from: &Pose, com_b: DVec3, axis: DVec3) -> Bounds {
        let radius = |t: &innersphere::query::SharedTree| {
            let i = t.info();
            (i.root_center - i.center_of_mass).length() + i.radius
        };
        let a = pose_a.transform_point(pair.tree_a().info().center_of_mass);
        let start = from.transform_point(com_b);
        Bounds {
            a,
            start,
            axis,
            near: (start - a).dot(axis) < 0.0,
            reach: (start - a).length() + radius(pair.tree_a()) + radius(pair.tree_b()),
        }
    }

    /// Whether B (its centre of mass at `com`) has gone through A or away from it.
    fn left(&self, com: DVec3) -> Option<OcclusionStatus> {
        if self.near && (com - self.a).dot(self.axis) > 0.0 {
            Some(OcclusionStatus::PassedThrough)
        } else if (com - self.start).length() > self.reach {
            Some(OcclusionStatus::Escaped)
        } else {
            None
        }
    }
}

/// The error of a step that could not be taken: at which step, how far B had moved, and
/// what failed (forces that overflowed, or a contact too stiff for B's mass at this step).
fn diverged(steps: usize, h: f64, moved: f64, w: &Wrench, k: &Mat6, d: &Mat6) -> Error {
    let finite = w.force.is_finite()
        && w.torque.is_finite()
        && k.iter().chain(d).flatten().all(|x| x.is_finite());
    let what = if finite {
        let largest = k.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        format!(
            "the contact's stiffness there (up to {} N/mm) cannot be stepped with B's mass in              steps of {} s (the step's equations have no solution); a softer contact or a              shorter step avoids it",
            num(largest),
            num(h)
        )
    } else {
        "the forces on B overflowed".to_string()
    };
    Error::InvalidOption(format!(
        "the closing failed at step {steps} ({} s simulated), B {} mm from its start: {what}",
        num(steps as f64 * h),
        short(moved)
    ))
}

/// Up to this many contact patches are reported at rest.
const PATCHES: usize = 16;

/// The contact query of every step: the penetration at the options' stiffness, linearised
/// (the implicit step needs the contact's stiffness), with up to [`PATCHES`] patches.
fn contact_options(opts: &OcclusionOptions) -> PenetrationOptions {
    PenetrationOptions {
        stiffness: opts.contact_stiffness,
        max_patches: PATCHES,
        linearize: true,
        ..Default::default()
    }
}

/// B's own damping, linear (N·s/mm) and rotational (N·mm·s/rad): `damping`, and `damping`
/// at the radius of gyration (`gyration2` its square), so that B's mass at that radius is
/// damped as the linear damping damps it.
fn own_damping(damping: f64, gyration2: f64) -> (f64, f64) {
    (damping, damping * gyration2)
}

/// The square of B's radius of gyration about its centre of mass (mm²): the mean of its
/// principal moments over its mass.
fn gyration_squared(body: &RigidBody) -> f64 {
    let i = &body.inertia;
    (i.x_axis.x + i.y_axis.y + i.z_axis.z) / (3.0 * body.mass)
}

/// B's damping: its own viscous damping (`b` on the velocity, `br` on the spin) and the
/// contact's (`β·K_c`, of the contact stiffness `kc`): the wrench on B's velocity, and the
/// damping matrix `D` (the wrench is `−D·[v; ω]`).
fn damping(kc: &Mat6, beta: f64, b: f64, br: f64, state: &BodyState) -> (Wrench, Mat6) {
    let (cd, mut d) = contact_damping(kc, beta, state);
    for (i, row) in d.iter_mut().enumerate() {
        row[i] += if i < 3 { b } else { br };
    }
    let w = Wrench {
        force: cd.force - state.velocity * b,
        torque: cd.torque - state.angular_velocity * br,
    };
    (w, d)
}

/// Judges when B rests: its centre of mass moved less than `distance` and it turned less
/// than `angle` since the oldest of the last `window` steps (`window − 1` steps ago).
struct RestWatch {
    /// The centre of mass and rotation of the last `window` steps, by step modulo `window`.
    ring: Vec<(DVec3, DQuat)>,
    /// Steps seen.
    seen: usize,
    distance: f64,
    angle: f64,
}

impl RestWatch {
    /// Rest within `distance` (mm) and `distance / gyration` (rad) over `window` steps (at
    /// least 1).
    fn new(window: usize, distance: f64, gyration: f64) -> RestWatch {
        RestWatch {
            ring: vec![(DVec3::ZERO, DQuat::IDENTITY); window.max(1)],
            seen: 0,
            distance,
            angle: distance / gyration,
        }
    }

    /// Records this step's centre of mass and rotation; true when B rests.
    fn at_rest(&mut self, com: DVec3, rotation: DQuat) -> bool {
        let (step, window) = (self.seen, self.ring.len());
        self.seen += 1;
        self.ring[step % window] = (com, rotation);
        if step < window {
            return false;
        }
        let (c0, q0) = self.ring[(step + 1) % window];
        let moved = (com - c0).length();
        let turned = rotation_between(q0, rotation).length();
        moved < self.distance && turned < self.angle
    }
}

/// The joints' springs on B at `pose` (`com` its centre of mass, world): their wrench about
/// `com`, with their stiffness added to `k` (the wrench changes by `−K·Δ` for a small motion
/// `Δ` of the centre of mass and a rotation about it; exact where the springs are slack,
/// their geometric term `[f]×` being left out).
fn add_joints(j: &Joints, pose: &Pose, com: DVec3, k: &mut Mat6) -> Wrench {
    let mut w = Wrench::default();
    for (pb, anchor) in j.points.iter().zip(&j.anchors) {
        let at = pose.transform_point(*pb);
        let f = (*anchor - at) * j.stiffness;
        let r = at - com;
        w.force += f;
        w.torque += r.cross(f);
        // A point spring at lever r: K = k·[[I, −[r]×], [[r]×, −[r]×[r]×]].
        let c = cross(r);
        let ks = j.stiffness;
        add_block(k, 0, 0, &(DMat3::IDENTITY * ks));
        add_block(k, 0, 3, &(c * -ks));
        add_block(k, 3, 0, &(c * ks));
        add_block(k, 3, 3, &(c * c * -ks));
    }
    w
}

/// `v` scaled to length 1, robustly (a huge or tiny vector too); `None` when it has no
/// direction (zero or non-finite).
pub(super) fn unit(v: DVec3) -> Option<DVec3> {
    // `max_element` passes a NaN component over: test every component.
    let scale = v.abs().max_element();
    if !(v.is_finite() && scale > 0.0) {
        return None;
    }
    let u = v / scale;
    Some(u / u.length())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `pose` moved by `d`: its centre of mass `com` by `d[..3]`, and turned by `d[3..]`
    /// (rotation vector) about it.
    fn moved(pose: &Pose, com: DVec3, d: [f64; 6]) -> Pose {
        let turn = DQuat::from_scaled_axis(DVec3::new(d[3], d[4], d[5]));
        let c = com + DVec3::new(d[0], d[1], d[2]);
        Pose {
            rotation: (turn * pose.rotation).normalize(),
            translation: turn * (pose.translation - com) + c,
        }
    }

    #[test]
    fn the_joints_stiffness_is_the_derivative_of_their_wrench() {
        let points = [DVec3::new(40.0, -5.0, 12.0), DVec3::new(-38.0, -4.0, 10.0)];
        let pose = Pose::new(
            DVec3::new(1.0, -2.0, 3.0),
            DQuat::from_euler(glam::EulerRot::XYZ, 0.2, -0.1, 0.3),
        )
        .unwrap();
        let com = pose.transform_point(DVec3::new(0.5, 20.0, -3.0));
        // Slack: the anchors where the points are.
        let j = Joints {
            points,
            anchors: points.map(|p| pose.transform_point(p)),
            stiffness: 7.0,
        };
        let mut k = [[0.0; 6]; 6];
        let w0 = add_joints(&j, &pose, com, &mut k);
        assert!(w0.force.length() < 1e-9 && w0.torque.length() < 1e-9);
        let eps = 1e-6;
        for c in 0..6 {
            let mut d = [0.0; 6];
            d[c] = eps;
            let p = moved(&pose, com, d);
            let w = add_joints(
                &j,
                &p,
                com + DVec3::new(d[0], d[1], d[2]),
                &mut [[0.0; 6]; 6],
            );
            let dw = [w.force, w.torque].map(|v| v.to_array()).concat();
            for r in 0..6 {
                let fd = -dw[r] / eps;
                assert!(
                    (fd - k[r][c]).abs() <= 1e-4 * (1.0 + k[r][c].abs()),
                    "K[{r}][{c}] = {} but the wrench changes by {fd}",
                    k[r][c]
                );
            }
        }
        // Stretched: the pull towards the anchors and its moment about the centre of mass.
        let stretched = Joints {
            anchors: [j.anchors[0] + DVec3::X, j.anchors[1] - DVec3::Z],
            ..j
        };
        let w = add_joints(&stretched, &pose, com, &mut [[0.0; 6]; 6]);
        let f = [DVec3::X * 7.0, -DVec3::Z * 7.0];
        let r = [j.anchors[0] - com, j.anchors[1] - com];
        assert!((w.force - (f[0] + f[1])).length() < 1e-9);
        assert!((w.torque - (r[0].cross(f[0]) + r[1].cross(f[1]))).length() < 1e-9);
    }

    #[test]
    fn unit_directions_are_robust_and_refuse_no_direction() {
        assert_eq!(unit(DVec3::new(0.0, 0.0, 3.0)), Some(DVec3::Z));
        let huge = unit(DVec3::new(1e300, 1e300, 0.0)).unwrap();
        assert!((huge - DVec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-15);
        let tiny = unit(DVec3::new(0.0, -1e-310, 0.0)).unwrap();
        assert_eq!(tiny, -DVec3::Y);
        for none in [DVec3::ZERO, DVec3::new(f64::NAN, 1.0, 0.0), DVec3::INFINITY] {
            assert_eq!(unit(none), None, "{none}");
        }
    }

    #[test]
    fn cross_is_the_cross_product_matrix() {
        let (r, v) = (DVec3::new(1.0, -2.0, 3.0), DVec3::new(-0.5, 4.0, 2.0));
        assert_eq!(cross(r) * v, r.cross(v));
    }

    #[test]
    fn the_radius_of_gyration_is_the_mean_moment_over_the_mass() {
        let body = RigidBody {
            mass: 2.0,
            center_of_mass: DVec3::new(1.0, 2.0, 3.0),
            inertia: DMat3::from_diagonal(DVec3::new(1.0, 2.0, 6.0)),
        };
        assert_eq!(gyration_squared(&body), 1.5);
    }

    #[test]
    fn the_damping_wrench_is_minus_its_matrix_times_the_velocity() {
        // A contact stiffness, symmetric positive definite with couplings.
        let mut kc = [[0.0; 6]; 6];
        for (r, row) in kc.iter_mut().enumerate() {
            for (c, x) in row.iter_mut().enumerate() {
                *x = if r == c {
                    10.0 + r as f64
                } else {
                    1.0 / (1.0 + (r + c) as f64)
                };
            }
        }
        let state = BodyState {
            pose: Pose::IDENTITY,
            velocity: DVec3::new(0.3, -1.2, 2.0),
            angular_velocity: DVec3::new(-0.7, 0.4, 0.9),
        };
        let (beta, b, br) = (0.25, 3.0, 5.0);
        let (w, d) = damping(&kc, beta, b, br, &state);
        let v = [0.3, -1.2, 2.0, -0.7, 0.4, 0.9];
        let mut power = 0.0;
        for r in 0..6 {
            for c in 0..6 {
                let own = if r != c {
                    0.0
                } else if r < 3 {
                    b
                } else {
                    br
                };
                assert_eq!(d[r][c], beta * kc[r][c] + own, "D[{r}][{c}]");
            }
            let dv: f64 = (0..6).map(|c| d[r][c] * v[c]).sum();
            let got = if r < 3 { w.force[r] } else { w.torque[r - 3] };
            assert!((got + dv).abs() < 1e-12, "row {r}: {got} against {}", -dv);
            power += got * v[r];
        }
        // It takes energy out.
        assert!(power < 0.0);
    }

    #[test]
    fn rest_is_judged_over_the_window_strictly_within_both_thresholds() {
        let still = (DVec3::new(1.0, 2.0, 3.0), DQuat::from_rotation_z(0.3));
        // Still: rest from the step after the window fills, not before.
        let mut watch = RestWatch::new(4, 0.25, 2.0);
        for step in 0..4 {
            assert!(!watch.at_rest(still.0, still.1), "step {step}");
        }
        assert!(watch.at_rest(still.0, still.1));
        // A window of 0 is one step.
        let mut watch = RestWatch::new(0, 0.25, 2.0);
        assert!(!watch.at_rest(still.0, still.1));
        assert!(watch.at_rest(still.0, still.1));
        // Moved by exactly the distance since the window's oldest step: not at rest; by less:
        // at rest.
        for (moved, rests) in [(0.25, false), (0.125, true)] {
            let mut watch = RestWatch::new(3, 0.25, 2.0);
            for _ in 0..3 {
                assert!(!watch.at_rest(still.0, still.1));
            }
            let at = still.0 + DVec3::X * moved;
            assert_eq!(watch.at_rest(at, still.1), rests, "moved {moved}");
        }
        // Turned by exactly the angle (the distance over the radius of gyration): not at
        // rest; by less: at rest; the angle is the distance over the radius, not times it.
        let turn = DQuat::from_rotation_x(0.2) * still.1;
        let angle = rotation_between(still.1, turn).length();
        for (gyration, rests) in [(1.0, false), (0.5, true), (2.0, false)] {
            let mut watch = RestWatch::new(2, angle, gyration);
            for _ in 0..2 {
                assert!(!watch.at_rest(still.0, still.1));
            }
            assert_eq!(watch.at_rest(still.0, turn), rests, "gyration {gyration}");
        }
    }

    #[test]
    fn each_step_asks_for_the_linearised_contact_with_its_patches() {
        let opts = OcclusionOptions {
            contact_stiffness: 123.0,
            ..Default::default()
        };
        assert_eq!(
            contact_options(&opts),
            PenetrationOptions {
                stiffness: 123.0,
                max_patches: 16,
                linearize: true,
                ..Default::default()
            }
        );
    }

    #[test]
    fn rotations_are_damped_as_the_mass_at_the_radius_of_gyration() {
        assert_eq!(own_damping(3.0, 4.0), (3.0, 12.0));
        assert_eq!(own_damping(0.5, 0.25), (0.5, 0.125));
    }
}
