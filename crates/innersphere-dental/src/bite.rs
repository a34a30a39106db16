//! The bite of a jaw pair as a planner asks for it: B (the lower jaw, or a free cut segment)
//! closed onto A (fixed, at the identity) from a start, along the pair's own occlusal "up"
//! (found from the trees' leaf spheres, as [`AnatomicalFrame`] finds it), with the
//! temporomandibular joints held where they are in a reference pose, or free from many
//! starts ([`occlude_free`]). What `ist occlude`, Python's `occlude` and its cluster map
//! `occlude_many` run: one place decides the frame, the joints and the defaults.

use crate::anatomy::{check_opposed, AnatomicalFrame};
use crate::free_occlusion::{occlude_free, Candidate, FreeOcclusionOptions};
use crate::occlusion::{occlude, unit, Joints, Occlusion, OcclusionOptions};
use crate::occlusion_limits::{check_options, check_start};
use crate::occlusion_status::StatusCounts;
use crate::reach::Reach;
use glam::DVec3;
use innersphere::error::{Error, Result};
use innersphere::pose::Pose;
use innersphere::query::{Pair, SharedTree};
use innersphere::tree::SphereTree;
use innersphere_haptic::ContactSource;

/// Half the distance between a human's condyles (mm, at the frame's scale 1).
pub const CONDYLE_HALF_SPAN: f64 = 50.0;

/// How fast B closes in free flight (mm/s): the damping is the force over it, so that a
/// larger force presses harder without closing faster (one 1 ms step moves B 5 µm, a tenth
/// of [`MAX_STEP_TRAVEL`](crate::occlusion_limits::MAX_STEP_TRAVEL)).
pub const CLOSING_SPEED: f64 = 5.0;

/// Settings of [`bite`]. Units: mm, N, s.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BiteOptions {
    /// Closing direction (A's frame); `None`: the pair's occlusal "up" (from B towards A).
    pub axis: Option<DVec3>,
    /// Closing force (N): 0.5 to 1000, and at most 2 mm³ × the contact stiffness
    /// ([`occlusion_limits`](crate::occlusion_limits)).
    pub force: f64,
    /// Penalty force per penetration volume (N/mm³); `None`: 10 with the joints, 1000 free
    /// (stiff, so that a free segment's cusps do not sink into each other and slide over).
    pub contact_stiffness: Option<f64>,
    /// Simulated time before giving up (s), at most 60.
    pub max_seconds: f64,
    /// Where B's condyles are held: where they are with B at this pose (the scanned bite of
    /// a pair scanned in occlusion: the identity).
    pub reference: Pose,
    /// Stiffness of each temporomandibular joint (N/mm).
    pub joint_stiffness: f64,
    /// B is a free segment (no joints): closed from `starts` places around the start, the
    /// rest poses ranked ([`occlude_free`]).
    pub free: bool,
    /// Free: closings in all (1 to 1000).
    pub starts: usize,
    /// Free: how far the starts spread sideways and forwards (mm, at most 10); the yaw
    /// spread is twice this in degrees.
    pub spread: f64,
    /// Free: the seed of the spread.
    pub seed: u64,
    /// Where the contact comes from: the sphere packings (default) or the meshes' own
    /// ([`OcclusionOptions::contact`]; both trees need their meshes).
    pub contact: ContactSource,
}

impl Default for BiteOptions {
    /// `ist occlude`'s defaults: 5 N along the pair's up, 30 s, the joints at 20 N/mm held
    /// at the identity; free: 120 starts within 2.5 mm and 5°, seed 1.
    fn default() -> Self {
        BiteOptions {
            axis: None,
            force: 5.0,
            contact_stiffness: None,
            max_seconds: 30.0,
            reference: Pose::IDENTITY,
            joint_stiffness: 20.0,
            free: false,
            starts: 120,
            spread: 2.5,
            seed: 1,
            contact: ContactSource::Spheres,
        }
    }
}

/// What [`bite`] found.
#[derive(Debug, Clone, PartialEq)]
pub struct Bite {
    /// B's final pose and its closing (status, steps, volume, depth, patches). Free: the
    /// chosen candidate's closing; when no closing converged, the closing from the start
    /// itself, whose status says how it ended.
    pub occlusion: Occlusion,
    /// The pair's anatomical frame (B at the identity) the axis and the joints came from.
    pub frame: AnatomicalFrame,
    /// The settings the closing ran with (the axis and stiffness chosen, the joints).
    pub closing: OcclusionOptions,
    /// Free: the distinct rest poses, best first (empty with the joints).
    pub candidates: Vec<Candidate>,
    /// Free: how many closings ended in each status (`None` with the joints).
    pub closings: Option<StatusCounts>,
}

impl BiteOptions {
    /// Refuses options outside their limits ([`occlusion_limits`](crate::occlusion_limits),
    /// [`FreeOcclusionOptions`]'s) and non-finite poses, before any body is loaded or built:
    /// what [`bite`] checks first, without the pair's frame (its axes stand in by z and x).
    pub fn validate(&self) -> Result<()> {
        let (closing, fo) = self.closing(DVec3::Z, DVec3::X, None);
        check_options(&closing)?;
        if self.free {
            fo.check()?;
        }
        Ok(())
    }

    /// The closing's options with the pair's up and left.
    fn closing(
        &self,
        up: DVec3,
        left: DVec3,
        joints: Option<Joints>,
    ) -> (OcclusionOptions, FreeOcclusionOptions) {
        let closing = OcclusionOptions {
            axis: self.axis.unwrap_or(up),
            force: self.force,
            contact_stiffness: self.contact_stiffness.unwrap_or(if self.free {
                1000.0
            } else {
                10.0
            }),
            damping: self.force / CLOSING_SPEED,
            max_seconds: self.max_seconds,
            joints,
            contact: self.contact,
            ..OcclusionOptions::default()
        };
        let fo = FreeOcclusionOptions {
            closing,
            lateral: left,
            starts: self.starts,
            spread: self.spread,
            spread_angle: (2.0 * self.spread).to_radians(),
            seed: self.seed,
            ..FreeOcclusionOptions::default()
        };
        (closing, fo)
    }
}

impl Joints {
    /// The temporomandibular joints of a lower jaw B: its condyles on the frame's hinge
    /// axis, [`CONDYLE_HALF_SPAN`] either side of the midline (times the frame's scale),
    /// held by springs of `stiffness` (N/mm) where they are when B is at `reference`.
    pub fn temporomandibular(frame: &AnatomicalFrame, reference: &Pose, stiffness: f64) -> Joints {
        let half = frame.left * (CONDYLE_HALF_SPAN * frame.scale);
        let points = [frame.hinge + half, frame.hinge - half];
        Joints {
            points,
            anchors: points.map(|p| reference.transform_point(p)),
            stiffness,
        }
    }
}

/// The anatomical frame of two trees (B at the identity), from their leaf spheres' centres.
pub fn frame_of(a: &SphereTree, b: &SphereTree) -> Result<AnatomicalFrame> {
    let centres =
        |t: &SphereTree| -> Vec<DVec3> { t.leaves().map(|n| t.sphere(n).0.as_dvec3()).collect() };
    AnatomicalFrame::from_points(&centres(a), &centres(b))
}

/// B closed onto A (fixed at the identity) from `from` (B's pose in A's frame): see the
/// [module docs](self). The damping is the force over [`CLOSING_SPEED`]. Refused before any
/// closing: options outside their limits ([`occlusion_limits`](crate::occlusion_limits),
/// [`FreeOcclusionOptions`]'s), arches that do not face each other with B at the identity
/// ([`check_opposed`]), a closing axis far from the pair's up, and a start (or, with the
/// joints, a reference pose) from which B cannot bite A (turned, beyond A, far open, or
/// beside it). Fails too on a B without mass properties, or a pair whose frame cannot be
/// found (e.g. no points).
pub fn bite(a: &SharedTree, b: &SharedTree, from: &Pose, opts: &BiteOptions) -> Result<Bite> {
    let frame = frame_of(a, b)?;
    let joints = (!opts.free)
        .then(|| Joints::temporomandibular(&frame, &opts.reference, opts.joint_stiffness));
    let (closing, fo) = opts.closing(frame.up, frame.left, joints);
    // The options first (what the user typed; the joints' with the pair's frame), then the
    // bodies and the poses.
    opts.validate()?;
    check_options(&closing)?;
    for (what, pose) in [("start", from), ("reference", &opts.reference)] {
        if !pose.translation.is_finite() || !pose.rotation.is_finite() {
            return Err(Error::InvalidOption(format!(
                "the {what} pose must be finite"
            )));
        }
    }
    let axis = unit(closing.axis).expect("checked");
    let reach = Reach::new(a.tree(), b.tree());
    let (ca, cb) = reach.centres();
    check_opposed(&ca, &cb, frame.up)?;
    Reach::check_axis(axis, frame.up)?;
    reach.check_pose("the start", from, axis, frame.left)?;
    if !opts.free {
        reach.check_pose("the reference pose", &opts.reference, axis, frame.left)?;
    }
    check_start(&closing, from)?;
    if !opts.free {
        let mut pair = Pair::new(a, b);
        let occlusion = occlude(&mut pair, &Pose::IDENTITY, from, &closing)?;
        return Ok(Bite {
            occlusion,
            frame,
            closing,
            candidates: vec![],
            closings: None,
        });
    }
    let f = occlude_free(a, b, &Pose::IDENTITY, from, &fo)?;
    Ok(Bite {
        occlusion: f.closing,
        frame,
        closing,
        candidates: f.candidates,
        closings: Some(f.closings),
    })
}

impl Bite {
    /// The answer as JSON, the shape every door gives (`ist occlude --json` adds the wall
    /// time and the landmark errors): `pose` (7 numbers), `status` (the
    /// [`OcclusionStatus`](crate::OcclusionStatus) word), `converged` (status is
    /// `converged`), `steps`, `seconds` (simulated), `volume`, `max_depth`, `patches` (point,
    /// normal, volume, depth), `axis`, `force`, `contact_stiffness`, `joints` (points,
    /// anchors, stiffness; null when free), `frame` (up, left, anterior, incisal, hinge,
    /// scale), `candidates` (free: pose, starts, contacts, contacts_left, contacts_right,
    /// contact_area, volume, lateral_stiffness; null with the joints) and `closings` (free:
    /// how many closings ended in each status, every status named; null with the joints).
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        let o = &self.occlusion;
        let f = &self.frame;
        let candidates = self.closing.joints.is_none().then(|| {
            self.candidates
                .iter()
                .map(|c| {
                    json!({
                        "pose": c.pose.to_array(),
                        "starts": c.starts,
                        "contacts": c.contacts,
                        "contacts_left": c.lateral_side,
                        "contacts_right": c.other_side,
                        "contact_area": c.contact_area,
                        "volume": c.volume,
                        "lateral_stiffness": c.lateral_stiffness,
                    })
                })
                .collect::<Vec<_>>()
        });
        json!({
            "pose": o.pose.to_array(),
            "status": o.status,
            "converged": o.converged(),
            "steps": o.steps,
            "seconds": o.seconds,
            "volume": o.volume,
            "max_depth": o.max_depth,
            "patches": o.patches.iter().map(|p| json!({
                "point": p.point.to_array(),
                "normal": p.normal.to_array(),
                "volume": p.volume,
                "depth": p.depth,
            })).collect::<Vec<_>>(),
            "axis": o.axis.to_array(),
            "force": self.closing.force,
            "contact_stiffness": self.closing.contact_stiffness,
            "contact": self.closing.contact,
            "joints": self.closing.joints.map(|j| json!({
                "points": j.points.map(|p| p.to_array()),
                "anchors": j.anchors.map(|p| p.to_array()),
                "stiffness": j.stiffness,
            })),
            "frame": {
                "up": f.up.to_array(),
                "left": f.left.to_array(),
                "anterior": f.anterior.to_array(),
                "incisal": f.incisal.to_array(),
                "hinge": f.hinge.to_array(),
                "scale": f.scale,
            },
            "candidates": candidates,
            "closings": self.closings,
        })
    }
}
