//! How a new contact model reaches the tool: not at once. Two models (the one in use and a
//! newer one) generally disagree at the tool's pose — a stale model's linearisation, a late
//! query — and switching would step the force. The wrench applied is the convex blend
//! `(1 − s)·old(x) + s·new(x)` of both models evaluated at the tool's current pose `x`, and
//! `s` rises from 0 to 1 no faster than keeps the change it causes per tick under a bound
//! (a slew limit on the switch only: the force still follows the tool's motion at once, through
//! each model's linearisation). Both are pushes (each model is unilateral), so the blend never
//! pulls either.

use super::device::LEVER;
use super::mat6::Mat6;
use super::model::ContactModel;
use super::step::Wrench;
use crate::Pose;
use glam::DVec3;

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

    /// Blends towards `next` from what is applied now at the tool pose `pose` (the blend in
    /// progress is frozen into one model there, so that the wrench stays continuous).
    pub(crate) fn switch_to(&mut self, next: ContactModel, pose: &Pose, com: DVec3) {
        if self.s < 1.0 {
            let (w, k) = self.mix(pose, com, self.s);
            self.from = ContactModel {
                pose: *pose,
                force: w.force,
                torque: w.torque,
                stiffness: k,
                volume: (1.0 - self.s) * self.from.volume + self.s * self.to.volume,
                max_depth: self.from.max_depth.max(self.to.max_depth),
                force_cap: f64::INFINITY,
                ..self.to
            };
        } else {
            self.from = self.to;
        }
        self.to = next;
        self.s = 0.0;
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
