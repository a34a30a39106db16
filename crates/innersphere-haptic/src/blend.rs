//! How a new contact model reaches the tool: not at once. Two models (the one in use and a
//! newer one) generally disagree at the tool's pose — a stale model's linearisation, a late
//! query — and switching would step the force. The wrench applied is the convex blend
//! `(1 − s)·old(x) + s·new(x)` of both models evaluated at the tool's current pose `x`, and
//! `s` rises from 0 to 1 no faster than keeps the change it causes per tick under a bound
//! (a slew limit on the switch only: the force still follows the tool's motion at once, through
//! each model's linearisation). Models that agree at the tool's pose (consecutive
//! linearisations of one contact) switch at once; the bound acts where they do not: a contact
//! the last model did not know of, a time-critical bound. Both are pushes (each model is
//! unilateral), so the blend never pulls either.

use crate::device::LEVER;
use crate::mat6::Mat6;
use crate::model::ContactModel;
use crate::step::Wrench;
use glam::DVec3;
use innersphere::pose::Pose;

/// The contact in use: a blend from one model to another.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Blend {
    from: ContactModel,
    to: ContactModel,
    /// How far the blend is (1: `to` alone).
    s: f64,
}

/// The size of a wrench change for the slew limit (N): force plus torque at the coupling's
/// lever.
fn size(f: DVec3, t: DVec3) -> f64 {
    f.length() + t.length() / LEVER
}

impl Blend {
    /// Starts with `model` alone.
    pub(crate) fn new(model: ContactModel) -> Blend {
        Blend {
            from: model,
            to: model,
            s: 1.0,
        }
    }

    /// The newest model.
    pub(crate) fn target(&self) -> &ContactModel {
        &self.to
    }

    /// Caps the force of both models (N): a time-critical query's bound on the contact.
    pub(crate) fn set_cap(&mut self, cap: f64) {
        self.from.force_cap = cap;
        self.to.force_cap = cap;
    }

    /// Blends towards `next`: from the model in use when no blend is in progress; else the
    /// blend goes on from where it started, towards `next` instead of the model it was
    /// heading for (each model is a linearisation about its own pose: the newest is the
    /// best target, and the start is what the tool last felt in full).
    pub(crate) fn switch_to(&mut self, next: ContactModel) {
        if self.s >= 1.0 {
            self.from = self.to;
            self.s = 0.0;
        }
        self.to = next;
    }

    /// The wrench (and stiffness) at `pose` for this tick, advancing the blend so that it
    /// changes the wrench by at most `max_step` (N, force plus torque / [`LEVER`]).
    pub(crate) fn wrench_at(&mut self, pose: &Pose, com: DVec3, max_step: f64) -> (Wrench, Mat6) {
        if self.s >= 1.0 {
            return self.to.wrench_at(pose, com);
        }
        let (wf, _) = self.from.wrench_at(pose, com);
        let (wt, kt) = self.to.wrench_at(pose, com);
        let gap = size(wt.force - wf.force, wt.torque - wf.torque);
        let s = if gap <= max_step * (1.0 - self.s) || !gap.is_finite() {
            1.0
        } else {
            (self.s + max_step / gap).min(1.0)
        };
        self.s = s;
        if s >= 1.0 {
            return (wt, kt);
        }
        self.mix(pose, com, s)
    }

    /// `(1 − s)·from + s·to` at `pose`.
    fn mix(&self, pose: &Pose, com: DVec3, s: f64) -> (Wrench, Mat6) {
        let (wf, kf) = self.from.wrench_at(pose, com);
        let (wt, kt) = self.to.wrench_at(pose, com);
        let mut k = [[0.0; 6]; 6];
        for i in 0..6 {
            for j in 0..6 {
                k[i][j] = (1.0 - s) * kf[i][j] + s * kt[i][j];
            }
        }
        (
            Wrench {
                force: wf.force * (1.0 - s) + wt.force * s,
                torque: wf.torque * (1.0 - s) + wt.torque * s,
            },
            k,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::tests::pushing;
    use std::time::Instant;

    #[test]
    fn a_model_that_disagrees_comes_in_at_the_slew_and_one_that_agrees_at_once() {
        let at = Pose::IDENTITY;
        let mut b = Blend::new(ContactModel::none(at));
        b.switch_to(pushing(2.0));
        // 2 N apart at the tool's pose: 0.25 N per tick, in eight ticks.
        let mut last = 0.0;
        for i in 1..=8 {
            let (w, _) = b.wrench_at(&at, DVec3::ZERO, 0.25);
            let step = w.force.z - last;
            assert!(
                step > 0.0 && step <= 0.25 + 1e-12,
                "tick {i}: step {step} N"
            );
            last = w.force.z;
        }
        assert!((last - 2.0).abs() < 1e-12, "{last}");
        // The same contact linearised about a pose 0.01 mm lower: it agrees where the tool
        // is, and is used at once.
        let lower = ContactModel {
            pose: Pose::from_translation(DVec3::new(0.0, 0.0, -0.01)),
            force: DVec3::new(0.0, 0.0, 3.0),
            sampled: Instant::now(),
            ..pushing(3.0)
        };
        b.switch_to(lower);
        let (w, _) = b.wrench_at(&at, DVec3::ZERO, 0.25);
        assert_eq!(w.force, lower.wrench_at(&at, DVec3::ZERO).0.force);
        assert!((w.force.z - 2.0).abs() < 1e-12);
        // A blend in progress goes on towards the newest model.
        b.switch_to(pushing(0.5));
        b.switch_to(pushing(1.0));
        let (w, _) = b.wrench_at(&at, DVec3::ZERO, 0.25);
        assert!((w.force.z - 1.75).abs() < 1e-12, "{}", w.force.z);
    }

    #[test]
    fn a_model_never_pulls() {
        let m = pushing(1.0);
        // 0.02 mm up: the linearised push would be 1 − 100 × 0.02 = −1 N.
        let up = Pose::from_translation(DVec3::new(0.0, 0.0, 0.02));
        let (w, k) = m.wrench_at(&up, DVec3::ZERO);
        assert_eq!(w.force, DVec3::ZERO);
        assert_eq!(k[2][2], 0.0);
        // 0.008 mm up: 0.2 N left of 1, in the fade (below a quarter): 0.2 × 0.8.
        let near = Pose::from_translation(DVec3::new(0.0, 0.0, 0.008));
        let (w, _) = m.wrench_at(&near, DVec3::ZERO);
        assert!((w.force.z - 0.2 * 0.8).abs() < 1e-9, "{}", w.force.z);
        // Deeper pushes harder, uncapped unless a bound says otherwise.
        let down = Pose::from_translation(DVec3::new(0.0, 0.0, -0.01));
        assert!((m.wrench_at(&down, DVec3::ZERO).0.force.z - 2.0).abs() < 1e-12);
        let capped = ContactModel {
            force_cap: 1.5,
            ..m
        };
        assert!((capped.wrench_at(&down, DVec3::ZERO).0.force.z - 1.5).abs() < 1e-12);
    }

    #[test]
    fn a_torque_comes_in_at_the_slew_counted_at_the_lever() {
        // The same push with 2 N·mm of torque, then with 6: 4 / LEVER N of change, at
        // 0.05 N per tick.
        let at = Pose::IDENTITY;
        let torque = |t: f64| ContactModel {
            torque: DVec3::new(0.0, t, 0.0),
            ..pushing(1.0)
        };
        let mut b = Blend::new(torque(2.0));
        b.switch_to(torque(6.0));
        let max_step = 0.05;
        let ticks = (4.0 / LEVER / max_step).ceil() as usize;
        let mut last = 2.0;
        for i in 1..=ticks {
            let (w, _) = b.wrench_at(&at, DVec3::ZERO, max_step);
            let step = (w.torque.y - last) / LEVER;
            assert!(step > 0.0 && step <= max_step + 1e-12, "tick {i}: {step} N");
            assert!((w.torque.y - ((1.0 - b.s) * 2.0 + b.s * 6.0)).abs() < 1e-12);
            assert!((w.force.z - 1.0).abs() < 1e-12);
            last = w.torque.y;
        }
        assert!(
            (last - 6.0).abs() < 1e-12,
            "{last} N·mm after {ticks} ticks"
        );
    }

    #[test]
    fn a_cap_bounds_both_models_of_a_blend() {
        let at = Pose::IDENTITY;
        let mut b = Blend::new(pushing(3.0));
        b.switch_to(pushing(6.0));
        b.set_cap(2.0);
        for _ in 0..100 {
            let (w, _) = b.wrench_at(&at, DVec3::ZERO, 0.25);
            assert!(w.force.length() <= 2.0 + 1e-12, "{}", w.force);
        }
        assert_eq!(b.target().force_cap, 2.0);
    }

    #[test]
    fn a_blends_stiffness_is_the_same_blend_of_the_models_stiffnesses() {
        let at = Pose::IDENTITY;
        let mut b = Blend::new(pushing(2.0));
        let mut stiffer = pushing(3.0);
        stiffer.stiffness[2][2] = 300.0;
        stiffer.stiffness[3][3] = 7.0;
        b.switch_to(stiffer);
        let (_, k) = b.wrench_at(&at, DVec3::ZERO, 0.25);
        let s = b.s;
        assert!(s > 0.0 && s < 1.0, "{s}");
        assert_eq!(k[2][2], (1.0 - s) * 100.0 + s * 300.0);
        assert_eq!(k[3][3], s * 7.0);
        assert_eq!(k[0][0], 0.0);
    }

    #[test]
    fn a_blend_towards_a_model_of_non_finite_wrench_ends_at_once() {
        // No slew can be measured towards an infinite torque: the blend takes it whole (the
        // step then refuses the non-finite wrench) rather than stall at its start for ever.
        let at = Pose::IDENTITY;
        let mut b = Blend::new(pushing(1.0));
        let wild = ContactModel {
            torque: DVec3::new(1e308, 1e308, 0.0),
            ..pushing(1.0)
        };
        b.switch_to(wild);
        b.wrench_at(&at, DVec3::ZERO, 0.25);
        assert_eq!(b.s, 1.0);
    }
}
