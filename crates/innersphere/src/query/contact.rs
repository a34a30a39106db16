//! First contact (ours, beyond the paper): the paper's contact answer from a kinetic front,
//! at the cost of what the motion changed.

use super::kernel::geometry::{make_contact, Contact};
use super::kernel::info::TreeInfo;
use super::kernel::Ctx;
use super::search::block_front::BlockFront;
use super::search::descent::blocked;
use super::search::front::Front;

/// Result of [`Pair::contact`](crate::Pair::contact) and of the paper's traversals.
///
/// Its serde form is the answer every door prints: flat, `contact` a bool and the contact's
/// `point`, `normal`, `depth`, `leaf_a`, `leaf_b` beside it (null without a contact), then
/// `distance`, `visits`, `skipped`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(into = "ContactForm")]
pub struct ContactResult {
    /// The first overlapping leaf pair found, if any.
    pub contact: Option<Contact>,
    /// 0 with a contact; otherwise a proved lower bound on the distance between the two
    /// inner-sphere packings (the minimum over the separated pairs where the descent stopped,
    /// or the safe-motion bound when skipped).
    pub distance: f64,
    /// Node pairs tested.
    pub visits: u64,
    /// True when the safe-motion bound answered without a traversal.
    pub skipped: bool,
}

impl ContactResult {
    /// True when the packings overlap.
    pub fn in_contact(&self) -> bool {
        self.contact.is_some()
    }

    /// This answer, found in A's frame, in the world frame (A at `pose_a`).
    pub(crate) fn in_world(self, pose_a: &crate::pose::Pose) -> ContactResult {
        ContactResult {
            contact: self.contact.map(|c| c.in_world(pose_a)),
            ..self
        }
    }
}

/// The serialized form of [`ContactResult`]: one flat record, as scripts read it.
#[derive(serde::Serialize)]
struct ContactForm {
    contact: bool,
    point: Option<glam::DVec3>,
    normal: Option<glam::DVec3>,
    depth: Option<f64>,
    leaf_a: Option<u32>,
    leaf_b: Option<u32>,
    distance: f64,
    visits: u64,
    skipped: bool,
}

impl From<ContactResult> for ContactForm {
    fn from(r: ContactResult) -> ContactForm {
        // Destructured whole, so that a new field cannot be left out of the form.
        let ContactResult {
            contact,
            distance,
            visits,
            skipped,
        } = r;
        ContactForm {
            contact: contact.is_some(),
            point: contact.map(|c| c.point),
            normal: contact.map(|c| c.normal),
            depth: contact.map(|c| c.depth),
            leaf_a: contact.map(|c| c.leaf_a),
            leaf_b: contact.map(|c| c.leaf_b),
            distance,
            visits,
            skipped,
        }
    }
}

/// Steps of the block front per contact frame of [`contact`] (`BlockFront::tend`): the
/// lowest p99 of 0 / 32 / 64 / 128 on the jaw chew (BENCHMARKS.md, "Tried and did not pay")).
const TEND: usize = 64;

/// First contact from a kinetic front (ours, beyond the paper): the same contact answer as
/// the paper's distance and backtracking traversals on every frame, at the cost of what the motion
/// changed.
///
/// On trees of fan-out ≤ 4 (the default): the newest contact leaf pair (after a contact
/// frame, the last four) is tested first; if none overlaps, the block front re-runs the 4×4
/// steps of the overlap traversal whose outcome the motion since could have changed, up to
/// the first overlapping leaf pair: shallow first after a frame without contact, deepest
/// first after a contact frame (the deepest expired steps lie next to the overlaps that just
/// ended; when none is left, the front has proved the separation in the same frame). While
/// the recent pairs answer, a few expired steps a frame (shallow first) keep the front close
/// to current, so that the frame where contact ends has less to catch up; its clock runs on,
/// so it stays valid. Other fan-outs use the pair-by-pair front of the tracked queries.
/// The first frame, and a frame after a jump, builds the front by a full traversal. The
/// front subsumes the safe-motion skip.
pub(crate) fn contact(
    ctx: &Ctx,
    ib: &TreeInfo,
    front: &mut Front,
    bfront: &mut BlockFront,
) -> ContactResult {
    let mut visits = 0;
    let distance;
    let found = if blocked(ctx) {
        let f = bfront;
        f.advance(ctx, ib);
        // Contact mostly persists, or comes back, where it was: a leaf test or a few decide
        // most frames in contact.
        let was = f.in_contact();
        let found = match f.recall(ctx, was, &mut visits) {
            // While the contact lasts, a few steps a frame keep the front near current, so
            // that the frame where it ends has less to catch up.
            Some(hit) => {
                visits += f.tend(ctx, TEND);
                Some(hit)
            }
            // After a contact frame the deepest expired steps first; a climb from the newest
            // pair (as `backtracking`) cost a second slow frame when the contact had ended:
            // the front's catch-up on the next one.
            None => {
                visits += f.catch_up(ctx, was);
                f.hit()
            }
        };
        // Without a contact the front is complete, so its margin bounds the separation.
        distance = f.margin().max(0.0);
        f.set_answer(found);
        found
    } else {
        visits += front.update(ctx, ib);
        distance = front.margin().max(0.0);
        front.hits.first().map(|h| (h.a, h.b, h.c))
    };
    match found {
        Some((la, lb, c)) => ContactResult {
            contact: Some(make_contact(ctx.a, la, ctx.b, lb, c)),
            distance: 0.0,
            visits,
            skipped: false,
        },
        None => ContactResult {
            contact: None,
            distance,
            visits,
            skipped: false,
        },
    }
}

/// The answer at a far pose ([`far`](super::kernel::far)): no contact, the bodies at least
/// the root spheres' separation apart.
pub(crate) fn separated(separation: f64) -> ContactResult {
    ContactResult {
        contact: None,
        distance: separation,
        visits: 1,
        skipped: false,
    }
}
