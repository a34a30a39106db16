//! Whether B can bite A from a pose: the checks [`bite`](fn@crate::bite) makes before any
//! closing, each refusal a sentence a surgeon understands. A closing from a pose that fails
//! them ends far from any bite (through A, beside it, or nowhere near), so such poses are
//! refused rather than closed.
//!
//! The bodies are judged by their leaf spheres (A at the identity, B at the pose), as the
//! pair's frame is found.

use crate::occlusion_limits::short;
use glam::DVec3;
use innersphere::error::{num, Error, Result};
use innersphere::pose::Pose;
use innersphere::tree::SphereTree;

/// The widest start a bite closes from (mm along the closing axis, from B's highest point
/// to A's lowest): a bite search starts a few millimetres open; the mouth opens 40–60 mm
/// at the incisors, less at the molars. Farther is a start in another frame or unit.
pub const MAX_OPENING: f64 = 30.0;
/// The most a start (or the reference pose) may turn B from A's frame (degrees): the widest
/// opening turns the jaw about 25–30° about its hinge. More is B upside down, back to
/// front, or in another frame.
pub const MAX_TURN_DEGREES: f64 = 30.0;
/// The most the closing axis may lean from the pair's occlusal "up" (degrees): a bite closes
/// along up; an axis across it pushes B sideways along A.
pub const MAX_AXIS_TILT_DEGREES: f64 = 45.0;

/// The leaf spheres of A and B (centre, radius; model frames) and their centroids.
pub(super) struct Reach {
    a: Vec<(DVec3, f64)>,
    b: Vec<(DVec3, f64)>,
    ca: DVec3,
    cb: DVec3,
}

impl Reach {
    pub(super) fn new(a: &SphereTree, b: &SphereTree) -> Reach {
        let spheres = |t: &SphereTree| -> Vec<(DVec3, f64)> {
            t.leaves()
                .map(|n| {
                    let (c, r) = t.sphere(n);
                    (c.as_dvec3(), r as f64)
                })
                .collect()
        };
        let centroid =
            |s: &[(DVec3, f64)]| s.iter().map(|x| x.0).sum::<DVec3>() / (s.len().max(1) as f64);
        let (a, b) = (spheres(a), spheres(b));
        let (ca, cb) = (centroid(&a), centroid(&b));
        Reach { a, b, ca, cb }
    }

    /// The leaf spheres' centres of A, and of B (model frames).
    pub(super) fn centres(&self) -> (Vec<DVec3>, Vec<DVec3>) {
        let c = |s: &[(DVec3, f64)]| s.iter().map(|x| x.0).collect();
        (c(&self.a), c(&self.b))
    }

    /// Refuses a closing axis (unit) more than [`MAX_AXIS_TILT_DEGREES`] from `up`.
    pub(super) fn check_axis(axis: DVec3, up: DVec3) -> Result<()> {
        let tilt = axis.dot(up).clamp(-1.0, 1.0).acos().to_degrees();
        if tilt <= MAX_AXIS_TILT_DEGREES {
            return Ok(());
        }
        Err(Error::InvalidOption(format!(
            "the closing axis is {}° from the arches' occlusal axis; a bite closes along it \
             (within {}°): is the axis in A's frame, towards A?",
            short(tilt),
            num(MAX_AXIS_TILT_DEGREES)
        )))
    }

    /// Refuses a pose of B (`what`: "the start", "the reference pose") from which B cannot
    /// bite A closing along the unit `axis` (`lateral`: a direction across the arch):
    /// turned more than [`MAX_TURN_DEGREES`] from A's frame, level with or beyond A along
    /// the axis, more than [`MAX_OPENING`] open, or beside A (B's centre outside A's outline
    /// across the axis).
    pub(super) fn check_pose(
        &self,
        what: &str,
        pose: &Pose,
        axis: DVec3,
        lateral: DVec3,
    ) -> Result<()> {
        let turn = (2.0 * pose.rotation.w.abs().min(1.0).acos()).to_degrees();
        if turn > MAX_TURN_DEGREES {
            return Err(Error::InvalidOption(format!(
                "{what} turns B {}° from A's frame; a bite closes from B turned at most {}° (a \
                 wide opening turns the jaw about 25° about its hinge): is {what} in A's frame?",
                short(turn),
                num(MAX_TURN_DEGREES)
            )));
        }
        let cb = pose.transform_point(self.cb);
        let below = (self.ca - cb).dot(axis);
        if below <= 0.0 {
            return Err(Error::InvalidOption(format!(
                "{what} puts B's centre {} mm beyond A's along the closing axis: closing would \
                 push B away from A or through it. Is B the lower arch, and is {what} below A?",
                short(-below)
            )));
        }
        let a_low = self
            .a
            .iter()
            .map(|(c, r)| c.dot(axis) - r)
            .fold(f64::INFINITY, f64::min);
        let b_high = self
            .b
            .iter()
            .map(|(c, r)| pose.transform_point(*c).dot(axis) + r)
            .fold(f64::NEG_INFINITY, f64::max);
        let open = a_low - b_high;
        if open.is_nan() || open > MAX_OPENING {
            return Err(Error::InvalidOption(format!(
                "{what} puts B {} mm below A along the closing axis; a bite closes from at most \
                 {} mm open: is {what} in A's frame, in millimetres?",
                short(open),
                num(MAX_OPENING)
            )));
        }
        // Across the axis: B's centre within A's outline (its extent along the lateral
        // direction and the one across both).
        let side = (lateral - axis * lateral.dot(axis)).normalize_or_zero();
        let front = axis.cross(side);
        let across = |p: DVec3| {
            let d = p - self.ca;
            (d.dot(side), d.dot(front))
        };
        let (mut lo, mut hi) = (
            (f64::INFINITY, f64::INFINITY),
            (f64::NEG_INFINITY, f64::NEG_INFINITY),
        );
        for (c, _) in &self.a {
            let (s, f) = across(*c);
            lo = (lo.0.min(s), lo.1.min(f));
            hi = (hi.0.max(s), hi.1.max(f));
        }
        let (s, f) = across(cb);
        if !(lo.0..=hi.0).contains(&s) || !(lo.1..=hi.1).contains(&f) {
            return Err(Error::InvalidOption(format!(
                "{what} puts B's centre {} mm to the side of A's across the closing axis, beyond \
                 A's outline: the arches lie side by side and would not meet. Is {what} in A's \
                 frame?",
                short(s.hypot(f))
            )));
        }
        Ok(())
    }
}
