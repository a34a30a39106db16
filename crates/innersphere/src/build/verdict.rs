//! [`MeshVerdict`]: what the build does with a mesh, from its defect report alone.

use crate::mesh::MeshReport;

#[cfg(doc)]
use {super::pipeline::build_tree, crate::error::Error};

/// What the build does with a mesh, decided from its defect report alone; `ist inspect`
/// prints it as its verdict, and [`build_tree`] acts on the same value, so the two cannot
/// disagree.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MeshVerdict {
    /// Every edge is used equally often in each direction
    /// ([`MeshReport::oriented_closed`]; non-manifold edges allowed) and the volume is
    /// positive: the exact inside test (signed ray crossings with exact predicates).
    Closed,
    /// Closed as above, but the signed volume is negative (normals point inward): the build
    /// flips every triangle, warns, then uses the exact inside test.
    ClosedInward,
    /// Holes, open boundaries or inconsistent orientation, with at most half the edges
    /// open: inside/outside decided by the generalized winding number (≥ 0.5, which closes
    /// small holes); the build warns, and the coverage is relative to the inside-voxel volume
    /// instead of the mesh volume.
    Open,
    /// More than half the edges are open boundary edges: a triangle soup that bounds
    /// nothing; the build refuses it ([`Error::InvalidMesh`]).
    Soup,
}

impl MeshVerdict {
    /// The verdict for a mesh with this defect report.
    pub fn of(report: &MeshReport) -> MeshVerdict {
        if report.oriented_closed {
            if report.volume < 0.0 {
                MeshVerdict::ClosedInward
            } else {
                MeshVerdict::Closed
            }
        } else if report.boundary_edges * 2 > report.edges {
            // The winding number fills holes in a surface; it cannot invent a surface. When
            // most edges are open the triangles bound nothing, and any "inside" would be noise.
            MeshVerdict::Soup
        } else {
            MeshVerdict::Open
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::build::{BuildOptions, Preset};
    use crate::error::Error;
    use crate::field::InsideMethod;
    use crate::mesh::Mesh;
    use crate::shapes;
    use crate::tree::SphereTree;
    use glam::DVec3;

    #[test]
    fn the_verdict_is_what_the_build_does() {
        let ball = shapes::icosphere(2);
        assert_eq!(MeshVerdict::of(&ball.report()), MeshVerdict::Closed);
        let mut inward = ball.clone();
        inward.flip();
        assert_eq!(MeshVerdict::of(&inward.report()), MeshVerdict::ClosedInward);
        let mut holed = ball.clone();
        holed.triangles.pop();
        assert_eq!(MeshVerdict::of(&holed.report()), MeshVerdict::Open);
        let soup = Mesh::from_soup(
            &(0..20)
                .map(|i| {
                    let o = DVec3::splat(i as f64 * 3.0);
                    [o, o + DVec3::X, o + DVec3::Y]
                })
                .collect::<Vec<_>>(),
        );
        assert_eq!(MeshVerdict::of(&soup.report()), MeshVerdict::Soup);

        let opts = BuildOptions::preset(Preset::Fast, &ball).unwrap();
        let (_, r) =
            SphereTree::build_with_progress(&inward, &opts, &crate::progress::Silent).unwrap();
        assert!(r.warnings.iter().any(|w| w.contains("flipped")), "{r:?}");
        assert_eq!(r.inside_method, InsideMethod::ClosedExact);
        let (_, r) =
            SphereTree::build_with_progress(&holed, &opts, &crate::progress::Silent).unwrap();
        assert_eq!(r.inside_method, InsideMethod::WindingNumber);
        assert!(matches!(
            SphereTree::build(&soup, &opts),
            Err(Error::InvalidMesh(_))
        ));
    }
}
