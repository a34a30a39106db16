//! [`Frame`]: B's local frame mapped into A's, with the node shapes of B mapped along and
//! the box helpers of the traversals.

use super::bound;
use crate::mesh::bvh::{BvhNode, TriangleBvh};
use crate::pose::Pose;
use glam::{DMat3, DVec3};

/// B's local frame mapped into A's: `p_A = r · p_B + t`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Frame {
    pub(super) r: DMat3,
    pub(super) abs_r: DMat3,
    pub(super) t: DVec3,
    /// Absolute slack added to transformed boxes (covers rounding of the transform).
    pub(super) pad: f64,
}

impl Frame {
    /// The frame of `rel` (B in A), with the padding sized for the two trees' coordinates.
    pub(crate) fn new(rel: &Pose, a: &TriangleBvh, b: &TriangleBvh) -> Frame {
        let r = DMat3::from_quat(rel.rotation);
        let abs_r = DMat3::from_cols(r.x_axis.abs(), r.y_axis.abs(), r.z_axis.abs());
        let mag = |t: &TriangleBvh| {
            t.bounds()
                .map_or(0.0, |(lo, hi)| lo.abs().max(hi.abs()).max_element())
        };
        let scale = mag(a) + mag(b) + rel.translation.abs().max_element();
        Frame {
            r,
            abs_r,
            t: rel.translation,
            pad: 1e-13 * scale,
        }
    }

    /// False for a non-finite pose (the queries then answer "no result").
    pub(crate) fn is_finite(&self) -> bool {
        self.r.is_finite() && self.t.is_finite() && self.pad.is_finite()
    }

    #[inline]
    pub(crate) fn point(&self, p: DVec3) -> DVec3 {
        self.r * p + self.t
    }

    #[inline]
    pub(crate) fn tri(&self, t: &[DVec3; 3]) -> [DVec3; 3] {
        [self.point(t[0]), self.point(t[1]), self.point(t[2])]
    }

    /// A node shape of B mapped into A's frame.
    #[inline]
    pub(super) fn shape<'s>(&self, s: &'s bound::Shape) -> MappedShape<'s> {
        MappedShape {
            c: self.point(s.c),
            h: self.abs_r * s.h + DVec3::splat(self.pad),
            n: self.r * s.n,
            s,
        }
    }

    /// Squared lower bound on the distance between A's node `a` and B's node `b`.
    #[inline]
    pub(super) fn lower_bound_sq(&self, a: &bound::Shape, b: &bound::Shape) -> f64 {
        self.shape(b).lower_bound_sq(a, self.pad)
    }
}

/// A node shape of B in A's frame.
pub(super) struct MappedShape<'s> {
    c: DVec3,
    h: DVec3,
    n: DVec3,
    s: &'s bound::Shape,
}

impl MappedShape<'_> {
    #[inline]
    pub(super) fn lower_bound_sq(&self, a: &bound::Shape, pad: f64) -> f64 {
        bound::lower_bound_sq(a, self.c, self.h, self.n, self.s, pad)
    }
}

/// The bounding box `(lo, hi)` of a triangle.
#[inline]
pub(super) fn tri_box(t: &[DVec3; 3]) -> (DVec3, DVec3) {
    (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]))
}

/// Squared length of a node's box diagonal (the larger node is split first).
#[inline]
pub(super) fn size_sq(n: &BvhNode) -> f64 {
    (n.hi - n.lo).length_squared()
}
