//! One linearly implicit (backward) Euler step of a rigid body (Baraff & Witkin 1998; Otaduy
//! & Lin 2006 for 6-DOF haptics): the forces are linearised about the current state, so that
//! a contact far stiffer than `mass / step²` stays stable with one collision query per step.

use crate::body::{exp, BodyState, RigidBody};
use crate::mat6::{solve_spd, Mat6};
use glam::{DMat3, DVec3};
use innersphere::pose::Pose;

/// Kilograms times mm/s² per newton: `F = m·a` with `a` in mm/s² needs `m` in kg / 1000.
const KG_MM: f64 = 1e-3;

/// A force and a torque about the body's centre of mass (N, N·mm; world frame).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Wrench {
    /// Force (N).
    pub force: DVec3,
    /// Torque about the body's centre of mass (N·mm).
    pub torque: DVec3,
}

/// Writes the 3×3 block `m` at (`r`, `c`) of `a`, adding.
pub fn add_block(a: &mut Mat6, r: usize, c: usize, m: &DMat3) {
    let cols = m.to_cols_array_2d();
    for (j, col) in cols.iter().enumerate() {
        for (i, v) in col.iter().enumerate() {
            a[r + i][c + j] += v;
        }
    }
}

/// Contact damping proportional to the contact stiffness `k`: the wrench `−β·K·[v; ω]` on
/// the body's own velocity (the other body is fixed) and the damping matrix `β·K`.
pub fn contact_damping(k: &Mat6, beta: f64, state: &BodyState) -> (Wrench, Mat6) {
    let (v, w) = (state.velocity, state.angular_velocity);
    let kv = crate::mat6::mul(k, [v.x, v.y, v.z, w.x, w.y, w.z]);
    let mut d = [[0.0; 6]; 6];
    for (drow, krow) in d.iter_mut().zip(k) {
        for (dij, kij) in drow.iter_mut().zip(krow) {
            *dij = beta * kij;
        }
    }
    let wrench = Wrench {
        force: -(DVec3::new(kv[0], kv[1], kv[2]) * beta),
        torque: -(DVec3::new(kv[3], kv[4], kv[5]) * beta),
    };
    (wrench, d)
}

/// Advances `state` by `h` seconds under `w` (evaluated at the current state), with
/// `stiffness = −∂w/∂x` and `damping = −∂w/∂v` (6×6, symmetric positive semi-definite,
/// world frame, about the centre of mass). Returns false (and leaves the state alone) when
/// the system cannot be solved (non-finite input).
pub fn implicit_step(
    body: &RigidBody,
    state: &mut BodyState,
    h: f64,
    w: Wrench,
    stiffness: &Mat6,
    damping: &Mat6,
) -> bool {
    let r = DMat3::from_quat(state.pose.rotation);
    let inertia = r * body.inertia * r.transpose() * KG_MM;
    let (v, om) = (state.velocity, state.angular_velocity);
    // Gyroscopic torque −ω × Iω, explicit (small at haptic speeds).
    let torque = w.torque - om.cross(inertia * om);
    // (M + hB + h²K) v⁺ = M v + h F + h B v.
    let mut a = [[0.0f64; 6]; 6];
    let m = body.mass * KG_MM;
    for (i, row) in a.iter_mut().enumerate().take(3) {
        row[i] = m;
    }
    add_block(&mut a, 3, 3, &inertia);
    for i in 0..6 {
        for j in 0..6 {
            a[i][j] += h * damping[i][j] + h * h * stiffness[i][j];
        }
    }
    let x = [v.x, v.y, v.z, om.x, om.y, om.z];
    let bv = crate::mat6::mul(damping, x);
    let iw = inertia * om;
    let rhs = [
        m * v.x + h * (w.force.x + bv[0]),
        m * v.y + h * (w.force.y + bv[1]),
        m * v.z + h * (w.force.z + bv[2]),
        iw.x + h * (torque.x + bv[3]),
        iw.y + h * (torque.y + bv[4]),
        iw.z + h * (torque.z + bv[5]),
    ];
    let Some(n) = solve_spd(&a, rhs) else {
        return false;
    };
    if n.iter().any(|x| !x.is_finite()) {
        return false;
    }
    let v1 = DVec3::new(n[0], n[1], n[2]);
    let w1 = DVec3::new(n[3], n[4], n[5]);
    // Move the centre of mass and turn about it.
    let com = state.pose.transform_point(body.center_of_mass) + v1 * h;
    let rot = (exp(w1 * h) * state.pose.rotation).normalize();
    let t = com - rot * body.center_of_mass;
    state.pose = Pose {
        rotation: rot,
        translation: t,
    };
    state.velocity = v1;
    state.angular_velocity = w1;
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DMat3;

    #[test]
    fn a_free_body_spinning_off_its_axes_keeps_its_angular_momentum() {
        // No wrench: the world angular momentum R I Rᵀ ω stays put while ω and the body turn
        // (the gyroscopic term). One explicit step errs by O(h²); the term's sign flipped,
        // it would turn L by 2h·ω×L a step.
        let body = RigidBody {
            mass: 0.01,
            center_of_mass: DVec3::new(1.0, -2.0, 0.5),
            inertia: DMat3::from_diagonal(DVec3::new(1.0, 2.0, 3.0)),
        };
        let mut s = BodyState::at_rest(Pose::IDENTITY);
        s.angular_velocity = DVec3::new(10.0, 5.0, 0.0);
        let momentum = |s: &BodyState| {
            let r = DMat3::from_quat(s.pose.rotation);
            r * body.inertia * r.transpose() * s.angular_velocity
        };
        let (l0, h) = (momentum(&s), 1e-3);
        let zero = [[0.0; 6]; 6];
        for _ in 0..10 {
            assert!(implicit_step(
                &body,
                &mut s,
                h,
                Wrench::default(),
                &zero,
                &zero
            ));
        }
        let flipped = 10.0 * 2.0 * h * s.angular_velocity.cross(l0).length();
        assert!(
            (momentum(&s) - l0).length() < 0.05 * flipped,
            "{} vs {l0}",
            momentum(&s)
        );
        // And the centre of mass stays where it was.
        assert!(
            (s.pose.transform_point(body.center_of_mass) - body.center_of_mass).length() < 1e-12
        );
    }
}
