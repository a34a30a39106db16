//! `innersphere.Tree`: build, load, save and look at an Inner Sphere Tree.

use crate::convert::{self, error, float_array};
use innersphere::build::cache::DEFAULT_MAX_BYTES;
use innersphere::build::{build_tree, BuildCache, Preset};
use innersphere::glam::DVec3;
use innersphere::progress::{Progress, Silent};
use innersphere::tree::file;
use innersphere::{BuildOptions, Mesh, Resolution, SharedTree, SphereTree};
use numpy::{AllowTypeChange, IxDyn, PyArray2, PyArrayLike};
use pyo3::exceptions::{PyOSError, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyList, PyString, PyTuple};
use std::collections::HashMap;
use std::ffi::CString;
use std::path::Path;
use std::sync::Mutex;

/// An Inner Sphere Tree: the inner-sphere packing of one rigid model and its bounding-sphere
/// hierarchy, ready for queries (shared read-only by every Pair that uses it).
///
/// Make one with Tree.build (from a mesh file, (vertices, faces) arrays or a trimesh.Trimesh)
/// or Tree.load (a .ist file written by Tree.save or `ist build`). Lengths are in the mesh's
/// own model units (mm for the jaw scans).
#[pyclass(module = "innersphere", name = "Tree", frozen)]
pub struct Tree {
    pub(crate) shared: SharedTree,
    /// The build report (JSON), for a tree built in this process.
    report: Option<serde_json::Value>,
}

impl Tree {
    fn new(tree: SphereTree, report: Option<serde_json::Value>) -> Tree {
        Tree {
            shared: SharedTree::new(tree),
            report,
        }
    }
}

/// Issues a Python `UserWarning` (shown once per place by Python's default filter).
fn warn(py: Python<'_>, message: &str) -> PyResult<()> {
    let text = CString::new(message.replace('\0', " ")).expect("no NUL left");
    PyErr::warn(py, &py.get_type::<PyUserWarning>(), &text, 2)
}

/// A path argument: `str`, `bytes` or `os.PathLike`.
fn is_path(obj: &Bound<'_, PyAny>) -> PyResult<bool> {
    Ok(obj.is_instance_of::<PyString>()
        || obj.is_instance_of::<PyBytes>()
        || obj.hasattr("__fspath__")?)
}

/// Welds an indexed mesh as the library's file loaders do: vertices with bit-identical
/// coordinates merged (`-0.0` == `0.0`), in order of first use; vertices no face uses are
/// dropped. A mesh given as arrays therefore builds the same tree as the same mesh written to
/// a file and given by its path.
fn weld(vertices: &[DVec3], faces: &[[u32; 3]]) -> Mesh {
    let mut remap = vec![u32::MAX; vertices.len()];
    let mut index: HashMap<[u64; 3], u32> = HashMap::with_capacity(vertices.len());
    let mut out = Vec::with_capacity(vertices.len());
    let triangles = faces
        .iter()
        .map(|f| {
            f.map(|i| {
                let slot = &mut remap[i as usize];
                if *slot == u32::MAX {
                    let v = vertices[i as usize];
                    let key = [
                        (v.x + 0.0).to_bits(),
                        (v.y + 0.0).to_bits(),
                        (v.z + 0.0).to_bits(),
                    ];
                    *slot = *index.entry(key).or_insert_with(|| {
                        out.push(v);
                        (out.len() - 1) as u32
                    });
                }
                *slot
            })
        })
        .collect();
    Mesh {
        vertices: out,
        triangles,
    }
}

/// A mesh from `(vertices (n, 3) float, faces (m, 3) int)` arrays, welded ([`weld`]) when
/// `welded`, else with the vertices as given.
fn mesh_from_arrays(
    py: Python<'_>,
    vertices: &Bound<'_, PyAny>,
    faces: &Bound<'_, PyAny>,
    welded: bool,
) -> PyResult<Mesh> {
    let v = float_array(vertices, "vertices", "an (n, 3) array of floats")?;
    let v = v.as_array();
    if !matches!(v.shape(), [_, 3]) {
        return Err(PyValueError::new_err(format!(
            "vertices: expected an (n, 3) array of floats, got shape {}",
            convert::shape(v.shape())
        )));
    }
    let verts: Vec<DVec3> = v
        .rows()
        .into_iter()
        .map(|r| DVec3::new(r[0], r[1], r[2]))
        .collect();
    // Integers only: numpy would silently truncate float indices.
    let np = py.import("numpy")?;
    let f = np.call_method1("asarray", (faces,)).map_err(|e| {
        PyValueError::new_err(format!(
            "faces: expected an (m, 3) array of integer vertex indices ({e})"
        ))
    })?;
    let kind: String = f.getattr("dtype")?.getattr("kind")?.extract()?;
    let size: usize = f.getattr("size")?.extract()?;
    if !(kind == "i" || kind == "u" || size == 0) {
        let dtype = f.getattr("dtype")?.str()?.to_string();
        return Err(PyValueError::new_err(format!(
            "faces: expected an (m, 3) array of integer vertex indices, got dtype {dtype}"
        )));
    }
    let f: PyArrayLike<'_, i64, IxDyn, AllowTypeChange> = f.extract()?;
    let f = f.as_array();
    if !(matches!(f.shape(), [_, 3]) || size == 0) {
        return Err(PyValueError::new_err(format!(
            "faces: expected an (m, 3) array of integer vertex indices, got shape {}",
            convert::shape(f.shape())
        )));
    }
    let n = verts.len();
    let mut tris = Vec::with_capacity(f.len() / 3);
    for (t, r) in f.rows().into_iter().enumerate() {
        let mut tri = [0u32; 3];
        for (slot, &i) in tri.iter_mut().zip(r.iter()) {
            if i < 0 || i as u64 >= n as u64 {
                return Err(PyValueError::new_err(format!(
                    "faces[{t}] refers to vertex {i}, but there are {n} vertices"
                )));
            }
            *slot = i as u32;
        }
        tris.push(tri);
    }
    if welded {
        Ok(weld(&verts, &tris))
    } else {
        Ok(Mesh {
            vertices: verts,
            triangles: tris,
        })
    }
}

/// A mesh given as a file path (loaded, welded by the loader), a `(vertices, faces)` pair or
/// an object with `.vertices` and `.faces` (a `trimesh.Trimesh`; welded when `welded`);
/// `what` names the argument in errors.
pub(crate) fn mesh_like(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    what: &str,
    welded: bool,
    unit: &str,
) -> PyResult<Mesh> {
    let unit = convert::unit(unit)?;
    if is_path(obj)? {
        let path = convert::path(obj)?;
        return py.detach(|| Mesh::load_in(&path, unit)).map_err(error);
    }
    let mut mesh = mesh_arrays(py, obj, what, welded)?;
    mesh.scale(unit.to_mm());
    mesh.validate().map_err(error)?;
    Ok(mesh)
}

/// A mesh given as arrays: a (vertices, faces) pair or an object with .vertices and .faces.
fn mesh_arrays(py: Python<'_>, obj: &Bound<'_, PyAny>, what: &str, welded: bool) -> PyResult<Mesh> {
    if obj.hasattr("vertices")? && obj.hasattr("faces")? {
        mesh_from_arrays(
            py,
            &obj.getattr("vertices")?,
            &obj.getattr("faces")?,
            welded,
        )
    } else if (obj.is_instance_of::<PyTuple>() || obj.is_instance_of::<PyList>()) && obj.len()? == 2
    {
        mesh_from_arrays(py, &obj.get_item(0)?, &obj.get_item(1)?, welded)
    } else {
        let ty = obj.get_type().name()?.to_string();
        Err(PyValueError::new_err(format!(
            "{what}: expected a mesh file path, a (vertices, faces) pair or an object with .vertices and .faces (a trimesh.Trimesh), got a {ty}"
        )))
    }
}

/// Build progress on standard error: the stage and its percentage.
struct StderrProgress {
    /// Stage name, total, done so far, last percentage printed.
    state: Mutex<(String, u64, u64, u64)>,
}

impl Progress for StderrProgress {
    fn start(&self, stage: &str, total: u64) {
        let mut s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        *s = (stage.to_string(), total, 0, 0);
        eprint!("{stage}: 0%");
    }
    fn advance(&self, n: u64) {
        let mut s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        s.2 += n;
        let pct = (s.2 * 100).checked_div(s.1).map_or(100, |p| p.min(100));
        if pct != s.3 {
            s.3 = pct;
            eprint!("\r{}: {pct}%", s.0);
        }
    }
    fn finish(&self) {
        let s = self.state.lock().unwrap_or_else(|p| p.into_inner());
        eprintln!("\r{}: done", s.0);
    }
}

/// A count argument within `lo..=hi`, or `ValueError`.
fn count(x: i64, what: &str, lo: i64, hi: i64) -> PyResult<u32> {
    if (lo..=hi).contains(&x) {
        Ok(x as u32)
    } else {
        Err(PyValueError::new_err(format!(
            "invalid option: {what} must be between {lo} and {hi}, got {x}"
        )))
    }
}

/// Loads a tree file, naming a mesh given instead (as `ist` does).
fn load_tree(path: &Path) -> Result<SphereTree, innersphere::Error> {
    match SphereTree::load(path) {
        Err(innersphere::Error::CorruptTree(_))
            if innersphere::mesh::Format::from_path(path).is_ok() =>
        {
            Err(innersphere::Error::CorruptTree(format!(
                "{} is a mesh, not a tree file: build its tree first (Tree.build(path), or `ist build MESH -o TREE.ist`)",
                path.display()
            )))
        }
        other => other,
    }
}

#[pymethods]
impl Tree {
    /// Builds the Inner Sphere Tree of a closed triangle mesh (lengths in its model units)
    /// and returns it as a Tree.
    ///
    /// path_or_mesh: a mesh file (STL, OBJ, PLY or OFF, optionally .gz), a pair
    ///     (vertices (n, 3) float, faces (m, 3) int), or an object with .vertices and .faces
    ///     (a trimesh.Trimesh). Arrays are welded as the file loaders do (bit-identical
    ///     vertices merged, unused ones dropped), so they give the tree of the same mesh
    ///     read from a file.
    /// voxel_size: edge of the voxel grid's cells (model units). Exclusive with resolution.
    /// resolution: cells along the longest side of the bounding box (2..4096); the default
    ///     when neither is given is 128 cells.
    /// min_radius: no inner sphere smaller than this (model units; 0 = no floor).
    /// refine_steps: off-grid refinement steps of each sphere's centre (0 = the paper's
    ///     packing; the calibrated setting is 8).
    /// fanout: most children per inner node (2..32).
    /// progress: print each stage's progress to standard error.
    /// preset: start from a named setting of `ist build --preset`: "fast", "default",
    ///     "fine", "jaw" (0.1 mm voxels, 0.05 mm min radius, 8 steps: the jaw scans in mm),
    ///     "jaw-fast"; the other options override it where they are given (voxel_size,
    ///     resolution) or differ from their defaults.
    ///
    /// The build's warnings (an open mesh, inward faces flipped, ...) are issued as Python
    /// UserWarnings and kept in tree.report. Raises ValueError for a bad option or mesh,
    /// OSError when the file cannot be read. Runs with the interpreter released (a jaw arch
    /// at 0.1 mm takes about half a minute).
    #[staticmethod]
    #[pyo3(signature = (path_or_mesh, *, voxel_size=None, resolution=None, min_radius=0.0, refine_steps=0, fanout=4, progress=false, preset=None, cache=None, unit="mm"))]
    #[allow(clippy::too_many_arguments)]
    fn build(
        py: Python<'_>,
        path_or_mesh: &Bound<'_, PyAny>,
        voxel_size: Option<f64>,
        resolution: Option<i64>,
        min_radius: f64,
        refine_steps: i64,
        fanout: i64,
        progress: bool,
        preset: Option<&str>,
        cache: Option<&Bound<'_, PyAny>>,
        unit: &str,
    ) -> PyResult<Tree> {
        let cache = build_cache(cache)?;
        let mesh = mesh_like(py, path_or_mesh, "path_or_mesh", true, unit)?;
        let mut opts = match preset {
            Some(name) => {
                let p: Preset = name.parse().map_err(error)?;
                BuildOptions::preset(p, &mesh).map_err(error)?
            }
            None => BuildOptions::default(),
        };
        match (voxel_size, resolution) {
            (Some(_), Some(_)) => {
                return Err(PyValueError::new_err(
                    "invalid option: give voxel_size or resolution, not both",
                ))
            }
            (Some(h), None) => opts.resolution = Resolution::VoxelSize(h),
            (None, Some(n)) => {
                opts.resolution = Resolution::Cells(count(n, "resolution", 2, 4096)?)
            }
            (None, None) => {}
        }
        if preset.is_none() || min_radius != 0.0 {
            opts.packing.min_radius = min_radius;
        }
        if preset.is_none() || refine_steps != 0 {
            opts.packing.refine_steps = count(refine_steps, "refine_steps", 0, 1 << 20)?;
        }
        if preset.is_none() || fanout != 4 {
            opts.hierarchy.fanout = count(fanout, "fanout", 2, 32)?;
        }
        let printer = StderrProgress {
            state: Mutex::new((String::new(), 0, 0, 0)),
        };
        let source = if is_path(path_or_mesh)? {
            Some(innersphere::tree::MeshSource::of_unit(
                &convert::path(path_or_mesh)?,
                &mesh,
                convert::unit(unit)?,
            ))
        } else {
            None
        };
        let (mut tree, report, outcome) = py
            .detach(|| {
                let sink: &dyn Progress = if progress { &printer } else { &Silent };
                match &cache {
                    Some(c) => c
                        .get_or_build(&mesh, &opts, sink)
                        .map(|(t, o, r)| (t, r, Some(o))),
                    None => build_tree(&mesh, &opts, sink).map(|(t, r)| (t, Some(r), None)),
                }
            })
            .map_err(error)?;
        for w in report.iter().flat_map(|r| &r.warnings) {
            warn(py, &format!("Tree.build: {w}"))?;
        }
        // A tree built from a file remembers it (as `ist build` does).
        tree.meta.source = source;
        let mut report = report.and_then(|r| serde_json::to_value(&r).ok());
        if let (Some(o), Some(c)) = (outcome, &cache) {
            let r = report.get_or_insert_with(|| serde_json::json!({}));
            r["cache"] = serde_json::json!({"outcome": o, "dir": c.dir().to_string_lossy()});
        }
        Ok(Tree::new(tree, report))
    }

    /// Reads a tree file (.ist) written by Tree.save or `ist build`, checking its size,
    /// checksum and structure. Raises OSError when it cannot be read, ValueError when it is
    /// no valid tree file. A tree built by an older library version loads with a
    /// UserWarning (its queries are correct, maybe slower).
    #[staticmethod]
    fn load(py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<Tree> {
        let path = convert::path(path)?;
        let tree = py.detach(|| load_tree(&path)).map_err(error)?;
        if let Some(w) = tree.staleness() {
            warn(py, &format!("{}: {w}", path.display()))?;
        }
        Ok(Tree::new(tree, None))
    }

    /// The same tree with the mesh it was built from (a mesh file path, a (vertices, faces)
    /// pair or a trimesh.Trimesh), for Pair.refined_distance; this tree is unchanged. About
    /// a second per jaw arch. Raises ValueError when the mesh is not this tree's source
    /// (bounding box, volume and its centroid against the tree's meta).
    #[pyo3(signature = (mesh, *, unit="mm"))]
    fn with_mesh(&self, py: Python<'_>, mesh: &Bound<'_, PyAny>, unit: &str) -> PyResult<Tree> {
        let mesh = mesh_like(py, mesh, "mesh", true, unit)?;
        let shared = self.shared.clone();
        let shared = py.detach(|| shared.with_mesh(&mesh)).map_err(error)?;
        Ok(Tree {
            shared,
            report: self.report.clone(),
        })
    }

    /// True when the tree carries its mesh (Tree.with_mesh).
    #[getter]
    fn has_mesh(&self) -> bool {
        self.shared.mesh().is_some()
    }

    /// Writes the tree file (the same tree always gives the same bytes), through a temporary
    /// file renamed into place. Raises OSError when it cannot be written.
    fn save(&self, py: Python<'_>, path: &Bound<'_, PyAny>) -> PyResult<()> {
        let path = convert::path(path)?;
        let tree = &self.shared;
        py.detach(|| tree.save(&path)).map_err(error)
    }

    /// The tree file's bytes (what save writes).
    fn to_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyBytes>> {
        let bytes = file::to_checked_bytes(&self.shared).map_err(error)?;
        Ok(PyBytes::new(py, &bytes))
    }

    /// A tree from the bytes of a tree file (checked as Tree.load checks a file), with
    /// `mesh` attached as Tree.with_mesh does when given.
    #[staticmethod]
    #[pyo3(signature = (data, mesh=None))]
    fn from_bytes(py: Python<'_>, data: &[u8], mesh: Option<&Bound<'_, PyAny>>) -> PyResult<Tree> {
        let tree = py.detach(|| file::from_bytes(data)).map_err(error)?;
        let tree = Tree::new(tree, None);
        match mesh {
            // The mesh a pickled tree carries is already in mm.
            Some(m) => tree.with_mesh(py, m, "mm"),
            None => Ok(tree),
        }
    }

    /// Pickling goes through the tree file's bytes, and the mesh's vertices and faces when
    /// the tree carries its mesh (the receiver prepares it again, as Tree.with_mesh does).
    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let ctor = py.get_type::<Tree>().getattr("from_bytes")?;
        let bytes = self.to_bytes(py)?.into_any();
        let args = match self.shared.mesh() {
            None => PyTuple::new(py, [bytes])?,
            Some(m) => {
                let m = m.mesh();
                let v: Vec<Vec<f64>> = m.vertices.iter().map(|p| p.to_array().to_vec()).collect();
                let f: Vec<Vec<u32>> = m.triangles.iter().map(|t| t.to_vec()).collect();
                let v = PyArray2::from_vec2(py, &v)
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                let f = PyArray2::from_vec2(py, &f)
                    .map_err(|e| PyValueError::new_err(e.to_string()))?;
                let mesh = PyTuple::new(py, [v.into_any(), f.into_any()])?;
                PyTuple::new(py, [bytes, mesh.into_any()])?
            }
        };
        Ok((ctor, args))
    }

    /// The inner spheres (the leaves): a float64 array of shape (leaf_count, 4), one row
    /// (x, y, z, r) per sphere, in model coordinates (the values stored as float32).
    #[getter]
    fn spheres<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let t: &SphereTree = &self.shared;
        let rows: Vec<[f64; 4]> = t
            .leaves()
            .map(|n| [t.x[n] as f64, t.y[n] as f64, t.z[n] as f64, t.r[n] as f64])
            .collect();
        sphere_array(py, rows)
    }

    /// Every node's sphere (inner nodes and leaves, breadth first, the root first): a
    /// float64 array of shape (node_count, 4), rows (x, y, z, r).
    #[getter]
    fn nodes<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let t: &SphereTree = &self.shared;
        let rows: Vec<[f64; 4]> = (0..t.len())
            .map(|n| [t.x[n] as f64, t.y[n] as f64, t.z[n] as f64, t.r[n] as f64])
            .collect();
        sphere_array(py, rows)
    }

    /// Number of nodes, leaves included.
    #[getter]
    fn node_count(&self) -> usize {
        self.shared.len()
    }

    /// Number of inner spheres (leaves).
    #[getter]
    fn leaf_count(&self) -> usize {
        self.shared.leaf_count()
    }

    /// Largest leaf depth (the root is at depth 0).
    #[getter]
    fn depth(&self) -> u16 {
        self.shared.max_depth()
    }

    /// Build parameters and facts about the source mesh, as a dict: fanout, voxel_size,
    /// min_radius, mesh_volume, center_of_mass, bbox_min, bbox_max, coverage, mesh_closed,
    /// built_by (library, revision, refine_steps), inertia, source_volume and source_centroid
    /// (what recognises the source mesh, open or closed) when known.
    #[getter]
    fn meta<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = serde_json::to_value(&self.shared.meta)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        convert::to_python(py, &v)
    }

    /// The build report as a dict (sphere count, coverage, stage times, warnings, ...) for a
    /// tree built by Tree.build in this process; None for a loaded tree.
    #[getter]
    fn report<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        match &self.report {
            Some(v) => convert::to_python(py, v),
            None => Ok(py.None().into_bound(py)),
        }
    }

    fn __repr__(&self) -> String {
        let t: &SphereTree = &self.shared;
        format!(
            "Tree(node_count={}, leaf_count={}, depth={}, voxel_size={})",
            t.len(),
            t.leaf_count(),
            t.max_depth(),
            t.meta.voxel_size
        )
    }
}

/// Rows of 4 numbers as an (n, 4) float64 array.
fn sphere_array(py: Python<'_>, rows: Vec<[f64; 4]>) -> Bound<'_, PyArray2<f64>> {
    let n = rows.len();
    let flat: Vec<f64> = rows.into_iter().flatten().collect();
    numpy::ndarray::Array2::from_shape_vec((n, 4), flat)
        .map(|a| PyArray2::from_owned_array(py, a))
        .expect("n rows of 4")
}

/// The build cache of `Tree.build(cache=...)`: None or False (none), True (the platform's
/// cache folder), or a folder (whose subfolder `innersphere-trees-v1` holds the trees).
fn build_cache(cache: Option<&Bound<'_, PyAny>>) -> PyResult<Option<BuildCache>> {
    let Some(c) = cache.filter(|c| !c.is_none()) else {
        return Ok(None);
    };
    let dir = match c.extract::<bool>() {
        Ok(false) => return Ok(None),
        Ok(true) => BuildCache::default_dir().ok_or_else(|| {
            PyValueError::new_err(
                "cache=True: this platform has no cache folder; give one (cache=\"/path\")",
            )
        })?,
        Err(_) => convert::path(c)?,
    };
    let cache = BuildCache::new(dir, DEFAULT_MAX_BYTES);
    // A folder that cannot be the cache's: the library's sentence, and what to give instead.
    match cache.prepare() {
        Ok(()) => Ok(Some(cache)),
        Err(innersphere::Error::Io { path, source }) if source.raw_os_error().is_none() => {
            Err(PyOSError::new_err(format!(
                "{}: {source}; give cache= a folder, or cache=None to build without one",
                path.display()
            )))
        }
        Err(e) => Err(error(e)),
    }
}
