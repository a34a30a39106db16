//! The finished Inner Sphere Tree: flat f32 arrays ready for traversal, and its file format
//! ([`file`](mod@file)).

pub mod check;
pub mod export;
pub mod file;

/// Build parameters and facts about the source mesh, kept with the tree.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TreeMeta {
    /// Maximum children per inner node.
    pub fanout: u32,
    /// Voxel edge length used for the packing (model units).
    pub voxel_size: f64,
    /// Smallest inner-sphere radius kept (model units).
    pub min_radius: f64,
    /// Enclosed volume of the source mesh; for an open mesh (not closed, see
    /// [`mesh_closed`](Self::mesh_closed)) the volume of the voxels the build found inside.
    pub mesh_volume: f64,
    /// The volume of the source mesh's triangles by `check::source_shape` (about the centre
    /// of its bounding box): its enclosed volume when closed, a number its triangles fix when
    /// open; with [`source_centroid`](Self::source_centroid), what lets
    /// [`check::source_mismatch`] recognise the mesh a tree was built from, open or closed.
    /// `None` in files written before it was stored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source_volume: Option<f64>,
    /// The centroid of that volume (`check::source_shape`): the centre of mass of a closed
    /// mesh. `None` when the volume is zero and in files written before it was stored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source_centroid: Option<[f64; 3]>,
    /// Centre of mass of the source mesh (uniform density), for torques.
    pub center_of_mass: [f64; 3],
    /// Bounding box of the source mesh.
    pub bbox_min: [f64; 3],
    /// Bounding box of the source mesh.
    pub bbox_max: [f64; 3],
    /// Total inner-sphere volume / mesh volume.
    pub coverage: f64,
    /// True when the source mesh was closed (exact inside test), false when the generalized
    /// winding number decided inside/outside.
    pub mesh_closed: bool,
    /// Which library built the tree, and how; `None` in files written before the stamp
    /// existed (they still load: see [`SphereTree::staleness`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub built_by: Option<BuildStamp>,
    /// Inertia tensor of the solid about [`center_of_mass`](Self::center_of_mass), per unit
    /// density, `[xx, yy, zz, xy, xz, yz]` (model units⁵; see
    /// [`MassProperties`](crate::mesh::MassProperties)): what the haptic tool needs to move
    /// as a rigid body. From the mesh when it is closed, else from the inner spheres. `None`
    /// in files written before it was stored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inertia: Option<[f64; 6]>,
    /// The mesh file the tree was built from, when the builder was given a file (`ist build`,
    /// Python's `Tree.build(path)`): so that a viewer draws its surface without being told,
    /// and can tell whether the file still holds that mesh. `None` for trees built from
    /// arrays and in files written before it was stored.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<MeshSource>,
}

/// The mesh file a tree was built from ([`TreeMeta::source`]).
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct MeshSource {
    /// Its path, absolute where it could be resolved.
    pub path: String,
    /// [`Mesh::content_hash`](crate::mesh::Mesh::content_hash) of the mesh as loaded
    /// (converted to millimetres).
    pub hash: String,
    /// The unit of the file's coordinates, converted to millimetres at load
    /// ([`Mesh::load_in`](crate::mesh::Mesh::load_in)); absent (mm) in trees of millimetre
    /// meshes.
    #[serde(default, skip_serializing_if = "crate::mesh::Unit::is_mm")]
    pub unit: crate::mesh::Unit,
}

impl MeshSource {
    /// The record of `mesh`, loaded from `path` (in millimetres).
    pub fn of(path: &std::path::Path, mesh: &crate::mesh::Mesh) -> MeshSource {
        Self::of_unit(path, mesh, crate::mesh::Unit::Mm)
    }

    /// The record of `mesh`, loaded from `path` in `unit` ([`Mesh::load_in`](crate::mesh::Mesh::load_in)).
    pub fn of_unit(
        path: &std::path::Path,
        mesh: &crate::mesh::Mesh,
        unit: crate::mesh::Unit,
    ) -> MeshSource {
        let abs = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        MeshSource {
            path: abs.to_string_lossy().into_owned(),
            hash: mesh.content_hash(),
            unit,
        }
    }

    /// The mesh at [`path`](Self::path) when it still is the one the tree was built from;
    /// otherwise an error that says which (missing, unreadable, another mesh now).
    pub fn load(&self) -> crate::error::Result<crate::mesh::Mesh> {
        let mesh = crate::mesh::Mesh::load_in(&self.path, self.unit)?;
        if mesh.content_hash() != self.hash {
            return Err(crate::error::Error::InvalidMesh(format!(
                "{} holds another mesh than the tree was built from",
                self.path
            )));
        }
        Ok(mesh)
    }
}

impl TreeMeta {
    /// The meta of spheres that were not packed from a mesh (a hand-made or analytic sphere
    /// set given to [`tree_of_spheres`](crate::build::tree_of_spheres)): its fan-out, voxel size
    /// and box; a mesh volume of 1 (no source volume), the centre of mass at the origin, no
    /// coverage, no stamp, no inertia. Change the fields that matter afterwards.
    pub fn unmeasured(
        fanout: u32,
        voxel_size: f64,
        bbox_min: [f64; 3],
        bbox_max: [f64; 3],
    ) -> TreeMeta {
        TreeMeta {
            fanout,
            voxel_size,
            min_radius: 0.0,
            mesh_volume: 1.0,
            source_volume: None,
            source_centroid: None,
            center_of_mass: [0.0; 3],
            bbox_min,
            bbox_max,
            coverage: 0.0,
            mesh_closed: true,
            built_by: None,
            inertia: None,
            source: None,
        }
    }
}

/// Revision of the tree construction; raised whenever the builder changes the trees it makes
/// (not their file layout), so that a tree, and a build cache entry, from another builder is
/// told apart. Revision 2: every node's sphere encloses the leaves below it (revision 1
/// enclosed the children's spheres: looser, and the jaw replay measured 3× slower on such
/// trees). Revision 3: the packing runs in bands and blocks on all cores (slightly other
/// spheres, the same accuracy).
pub const BUILD_REVISION: u32 = 3;

/// Who built a tree and how, kept in its file's meta block, so that a reader can tell a tree
/// built by an older library (valid, but possibly slower to query) from a current one.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct BuildStamp {
    /// Library name and version, e.g. `innersphere 0.1.0`.
    pub library: String,
    /// [`BUILD_REVISION`] of the builder.
    pub revision: u32,
    /// Off-grid refinement steps of the packing (`--refine-steps`).
    pub refine_steps: u32,
}

impl BuildStamp {
    /// The stamp of this library's builder.
    pub fn current(refine_steps: u32) -> BuildStamp {
        BuildStamp {
            library: format!("innersphere {}", env!("CARGO_PKG_VERSION")),
            revision: BUILD_REVISION,
            refine_steps,
        }
    }
}

/// An Inner Sphere Tree in structure-of-arrays layout.
///
/// Node 0 is the root. The children of node `n` are the contiguous nodes
/// `first_child[n] .. first_child[n] + child_count[n]`; a node with no children is a leaf and
/// its sphere is one inner sphere of the packing (every leaf holds exactly one). Nodes are in
/// breadth-first order, so a child's index is always greater than its parent's.
#[derive(Debug, Clone, PartialEq)]
pub struct SphereTree {
    /// Sphere centre x of each node.
    pub x: Vec<f32>,
    /// Sphere centre y of each node.
    pub y: Vec<f32>,
    /// Sphere centre z of each node.
    pub z: Vec<f32>,
    /// Sphere radius of each node.
    pub r: Vec<f32>,
    /// Index of the first child (meaningless for leaves, stored as 0).
    pub first_child: Vec<u32>,
    /// Number of children; 0 for leaves.
    pub child_count: Vec<u8>,
    /// Parent index; `u32::MAX` for the root.
    pub parent: Vec<u32>,
    /// Depth below the root (root = 0).
    pub depth: Vec<u16>,
    /// Build parameters and mesh facts.
    pub meta: TreeMeta,
}

/// Parent value of the root node.
pub const NO_PARENT: u32 = u32::MAX;

impl SphereTree {
    /// A warning when this tree was not built by the current builder: no stamp (written
    /// before stamps existed), an older [`BUILD_REVISION`] (valid, but node spheres that may
    /// be looser, so queries may run slower than they would on a rebuilt tree), or a newer
    /// one. `None` for a current tree. Queries on any valid tree are correct.
    pub fn staleness(&self) -> Option<String> {
        match &self.meta.built_by {
            None => Some(
                "the tree has no build stamp (written before innersphere stamped its trees); \
                 if it predates build revision 2 its node spheres are looser and queries slower \
                 (measured 3× on the jaws): rebuild it with `ist build` to be sure"
                    .into(),
            ),
            Some(b) if b.revision < 2 => Some(format!(
                "the tree was built by {} at build revision {}, this library builds revision \
                 {BUILD_REVISION}: results are correct, but a rebuilt tree may query faster",
                b.library, b.revision
            )),
            Some(b) if b.revision < BUILD_REVISION => Some(format!(
                "the tree was built by {} at build revision {}, this library builds revision \
                 {BUILD_REVISION} (the packing in bands and blocks on all cores): results are \
                 correct; a rebuilt tree has slightly other spheres of the same accuracy",
                b.library, b.revision
            )),
            Some(b) if b.revision > BUILD_REVISION => Some(format!(
                "the tree was built by {} at build revision {}, newer than this library's \
                 {BUILD_REVISION}: it loads and validates, but the speed figures of this \
                 version may not apply",
                b.library, b.revision
            )),
            Some(_) => None,
        }
    }

    /// Number of nodes.
    #[inline]
    pub fn len(&self) -> usize {
        self.r.len()
    }

    /// True for a tree without nodes (never produced by the builder).
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.r.is_empty()
    }

    /// True when node `n` is a leaf (an inner sphere).
    #[inline]
    pub fn is_leaf(&self, n: usize) -> bool {
        self.child_count[n] == 0
    }

    /// Sphere of node `n` as `(centre, radius)`.
    #[inline]
    pub fn sphere(&self, n: usize) -> (glam::Vec3, f32) {
        (glam::Vec3::new(self.x[n], self.y[n], self.z[n]), self.r[n])
    }

    /// Children of node `n` as an index range.
    #[inline]
    pub fn children(&self, n: usize) -> std::ops::Range<usize> {
        let f = self.first_child[n] as usize;
        f..f + self.child_count[n] as usize
    }

    /// Indices of all leaves (inner spheres), ascending.
    pub fn leaves(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.len()).filter(|&n| self.is_leaf(n))
    }

    /// Number of leaves (inner spheres).
    pub fn leaf_count(&self) -> usize {
        self.child_count.iter().filter(|&&c| c == 0).count()
    }

    /// Largest depth of any node.
    pub fn max_depth(&self) -> u16 {
        self.depth.iter().copied().max().unwrap_or(0)
    }

    /// Checks the structural invariants every query relies on: consistent array lengths,
    /// children contiguous and after their parent, parents and depths consistent, finite
    /// non-negative spheres. Loading a file runs this, so a corrupt file cannot make a
    /// traversal misbehave.
    pub fn validate_structure(&self) -> crate::error::Result<()> {
        let n = self.r.len();
        let bad = |m: String| Err(crate::error::Error::CorruptTree(m));
        if n == 0 {
            return bad("the tree has no nodes".into());
        }
        if [
            self.x.len(),
            self.y.len(),
            self.z.len(),
            self.first_child.len(),
            self.child_count.len(),
            self.parent.len(),
            self.depth.len(),
        ]
        .iter()
        .any(|&l| l != n)
        {
            return bad("node arrays have different lengths".into());
        }
        if self.parent[0] != NO_PARENT || self.depth[0] != 0 {
            return bad("node 0 is not a root".into());
        }
        let mut seen_as_child = vec![false; n];
        for i in 0..n {
            if !(self.x[i].is_finite()
                && self.y[i].is_finite()
                && self.z[i].is_finite()
                && self.r[i].is_finite()
                && self.r[i] >= 0.0)
            {
                return bad(format!("node {i} has a non-finite or negative sphere"));
            }
            let c = self.child_count[i] as usize;
            if c == 0 {
                continue;
            }
            let f = self.first_child[i] as usize;
            if f <= i || f + c > n {
                return bad(format!("node {i} has children out of range"));
            }
            for (ch, seen) in seen_as_child.iter_mut().enumerate().skip(f).take(c) {
                if *seen {
                    return bad(format!("node {ch} has two parents"));
                }
                *seen = true;
                // `checked_add`: node `i` may be an orphan (refused below) of any depth.
                if self.parent[ch] as usize != i
                    || self.depth[i].checked_add(1) != Some(self.depth[ch])
                {
                    return bad(format!("node {ch} disagrees with its parent {i}"));
                }
            }
        }
        if let Some(orphan) = (1..n).find(|&i| !seen_as_child[i]) {
            return bad(format!("node {orphan} is nobody's child"));
        }
        Ok(())
    }
}
