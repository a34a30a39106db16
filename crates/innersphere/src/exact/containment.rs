//! The containment test: whether one body lies entirely inside the other when the surfaces
//! do not cross (a winding number per connected component that may be inside).

use super::frame::Frame;
use super::mesh::ExactMesh;
use crate::pose::Pose;
use glam::DVec3;

impl ExactMesh {
    /// Representatives of the components that may lie inside `outer` (all extreme vertices,
    /// mapped by `to_outer`, inside its bounding box).
    pub(super) fn maybe_inside<'s>(
        &'s self,
        outer: &'s ExactMesh,
        to_outer: &'s Frame,
    ) -> impl Iterator<Item = u32> + 's {
        let (lo, hi) = outer
            .bvh()
            .bounds()
            .map(|(lo, hi)| (lo - to_outer.pad, hi + to_outer.pad))
            .unwrap_or((DVec3::INFINITY, DVec3::NEG_INFINITY));
        self.components.iter().filter_map(move |c| {
            let all_in = self.extremes[c.start as usize..c.end as usize]
                .iter()
                .all(|&v| {
                    let p = to_outer.point(self.mesh.vertices[v as usize]);
                    p.cmpge(lo).all() && p.cmple(hi).all()
                });
            all_in.then_some(c.rep)
        })
    }

    /// True when a connected component of `self` lies inside `outer` (winding number of one
    /// of its vertices); meaningful when the surfaces do not cross.
    pub(super) fn component_inside(
        &self,
        outer: &ExactMesh,
        to_outer: &Frame,
        tests: &mut usize,
    ) -> bool {
        self.maybe_inside(outer, to_outer).any(|v| {
            *tests += 1;
            outer.contains_point(to_outer.point(self.mesh.vertices[v as usize]))
        })
    }
}

/// One body lies entirely inside the other (assuming the surfaces do not cross).
pub(super) fn contained(
    a: &ExactMesh,
    b: &ExactMesh,
    rel: &Pose,
    f: &Frame,
    tests: &mut usize,
) -> bool {
    if b.component_inside(a, f, tests) {
        return true;
    }
    let g = Frame::new(&rel.inverse(), b.bvh(), a.bvh());
    a.component_inside(b, &g, tests)
}
