//! `ist view`: a local web server with a live 3D view of two bodies. A 1 kHz loop thread runs
//! the library's queries (and, in haptic mode, its haptic loop) on body B's target pose and
//! hands its state to the HTTP side through a lock-free triple buffer; the page (three.js,
//! vendored and embedded) draws it at screen rate. In contact-map mode a worker thread of
//! its own colours both meshes by their gap to each other as B moves. The server holds no
//! collision logic of its own: every answer comes from [`innersphere::Pair`],
//! [`innersphere_haptic::MultirateLoop`] and [`innersphere_dental::contact_map`].
//! `docs/VIEWER.md` describes the page and the API.

mod assets;
mod contact;
mod encode;
mod http;
mod sim;

pub use contact::CAP as CONTACT_MAP_CAP;
pub use http::{
    serve, ServeOptions, BODY_TIMEOUT, HEADER_TIMEOUT, MAX_BODY, MAX_CONNECTIONS, MAX_HEADER,
    WRITE_TIMEOUT,
};
pub use sim::{LoopState, Mode};

use innersphere::{BuildOptions, Mesh, Resolution, SharedTree, SphereTree};
use innersphere_dental::contact_map::Teeth;
use innersphere_motion::Motion;

/// What the viewer shows: two trees, optionally their meshes, optionally a motion of B.
#[derive(Debug, Clone)]
pub struct Scene {
    /// Body A's tree (fixed at the identity).
    pub a: SharedTree,
    /// Body B's tree (moved).
    pub b: SharedTree,
    /// Body A's mesh, drawn when given.
    pub mesh_a: Option<Mesh>,
    /// Body B's mesh, drawn when given.
    pub mesh_b: Option<Mesh>,
    /// A motion of B in A's frame to play.
    pub motion: Option<Motion>,
    /// A's teeth (its mesh's frame), for the contact map's per-tooth list.
    pub teeth_a: Option<Teeth>,
    /// B's teeth (its mesh's own frame).
    pub teeth_b: Option<Teeth>,
    /// A splint to draw between the arches (fixed in A's frame, as `ist splint` writes it).
    pub splint: Option<Mesh>,
    /// Where B starts (default: where the motion starts, else beside A); a splint's pose
    /// shows it seated between the arches.
    pub start: Option<innersphere::Pose>,
}

impl Scene {
    /// The built-in scene: the generated tooth pair (meshes and trees at 64 cells) with a
    /// generated 6 s chew, so that `ist view --demo` needs no file.
    pub fn demo() -> innersphere::Result<Scene> {
        let (upper, lower) = innersphere::shapes::tooth_pair(4);
        let opts = BuildOptions {
            resolution: Resolution::Cells(64),
            ..Default::default()
        };
        let a = SphereTree::build(&upper, &opts)?;
        let b = SphereTree::build(&lower, &opts)?;
        let motion = innersphere_motion::generate(
            innersphere_motion::Scenario::Chew,
            6.0,
            1,
            &upper,
            &lower,
        )?;
        let scene = Scene {
            a: SharedTree::new(a),
            b: SharedTree::new(b),
            mesh_a: Some(upper),
            mesh_b: Some(lower),
            motion: Some(motion),
            teeth_a: None,
            teeth_b: None,
            splint: None,
            start: None,
        };
        Ok(scene.refining_with_meshes().0)
    }

    /// Checks the teeth files against the drawn meshes as `ist occlusion-map` does
    /// ([`innersphere_dental::contact_map::check_pair`], B at its start pose, else at the identity:
    /// the frame the arches were scanned in): an error when a file does not fit its arch,
    /// else the warnings (a tooth that labels no vertex). Teeth without both meshes are an
    /// error: the per-tooth list is made on the meshes.
    pub fn check_teeth(&self) -> innersphere::Result<Vec<String>> {
        if self.teeth_a.is_none() && self.teeth_b.is_none() {
            return Ok(Vec::new());
        }
        let (Some(a), Some(b)) = (&self.mesh_a, &self.mesh_b) else {
            return Err(innersphere::Error::InvalidOption(
                "teeth files need both meshes: the per-tooth list is made on the drawn meshes"
                    .into(),
            ));
        };
        let pose = self.start.unwrap_or(innersphere::Pose::IDENTITY);
        let (fa, fb) = innersphere_dental::contact_map::check_pair(
            a,
            self.teeth_a.as_ref(),
            b,
            self.teeth_b.as_ref(),
            &pose,
        )?;
        Ok(fa.into_iter().chain(fb).flat_map(|f| f.warnings).collect())
    }

    /// The scene whose trees carry the drawn meshes when both are the trees' own, so that
    /// the distance shown is the refined distance between the meshes
    /// ([`innersphere::Pair::refined_distance`]); else unchanged, with a sentence that says
    /// the distance falls back to the sphere packings and why (meshes missing, or which body's
    /// mesh is not the one its tree was built from), for the caller to show as a warning.
    /// Prepares both meshes for exact queries (about a second per jaw arch).
    pub fn refining_with_meshes(mut self) -> (Scene, Option<String>) {
        const FALLBACK: &str = "the distance shown is between the sphere packings, not the meshes";
        let (Some(ma), Some(mb)) = (&self.mesh_a, &self.mesh_b) else {
            return (
                self,
                Some(format!(
                    "{FALLBACK}: the meshes of both bodies are needed (--mesh-a, --mesh-b)"
                )),
            );
        };
        match (self.a.clone().with_mesh(ma), self.b.clone().with_mesh(mb)) {
            (Ok(a), Ok(b)) => {
                self.a = a;
                self.b = b;
                (self, None)
            }
            (Err(e), _) => (self, Some(format!("{FALLBACK}: body A's mesh: {e}"))),
            (_, Err(e)) => (self, Some(format!("{FALLBACK}: body B's mesh: {e}"))),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use innersphere::glam::DVec3;

    fn scene(a: &Mesh, b: &Mesh, drawn_b: &Mesh) -> Scene {
        let opts = BuildOptions {
            resolution: Resolution::Cells(24),
            ..Default::default()
        };
        Scene {
            a: SharedTree::new(SphereTree::build(a, &opts).unwrap()),
            b: SharedTree::new(SphereTree::build(b, &opts).unwrap()),
            mesh_a: Some(a.clone()),
            mesh_b: Some(drawn_b.clone()),
            motion: None,
            teeth_a: None,
            teeth_b: None,
            splint: None,
            start: None,
        }
    }

    /// A tree of an open mesh was refused its own mesh, and the view fell back to the
    /// spheres' distance with a line that did not say it was a fallback. Now an open mesh's
    /// tree takes its mesh (the distance is the meshes'), and a fallback (B drawn with
    /// another mesh) says so, naming the body.
    #[test]
    fn open_meshes_refine_and_a_fallback_says_so() {
        let a = innersphere::shapes::icosphere(3);
        let mut b = a.clone();
        b.triangles
            .retain(|t| t.iter().all(|&i| a.vertices[i as usize].z < 0.8));
        for v in &mut b.vertices {
            *v += DVec3::new(3.0, 0.0, 0.0);
        }
        let (s, why) = scene(&a, &b, &b).refining_with_meshes();
        assert_eq!(why, None);
        assert!(s.b.mesh().is_some());
        let mut other = b.clone();
        for v in &mut other.vertices {
            v.y += 0.5;
        }
        let (s, why) = scene(&a, &b, &other).refining_with_meshes();
        let why = why.unwrap();
        assert!(
            why.starts_with(
                "the distance shown is between the sphere packings, not the meshes: body B's mesh:"
            ) && why.contains("not the mesh this tree was built from"),
            "{why}"
        );
        assert!(s.b.mesh().is_none());
    }
}
