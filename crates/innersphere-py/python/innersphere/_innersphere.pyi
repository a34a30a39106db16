"""Type stubs of the native module innersphere._innersphere (re-exported by innersphere)."""

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union, final

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = [
    "DistanceResult",
    "Haptic",
    "Pair",
    "PenetrationResult",
    "Tick",
    "Tree",
    "__version__",
    "arch_pair",
    "contact_map",
    "load_motion",
    "occlude",
    "plan",
    "splint",
]

#: A pose: a 4×4 homogeneous matrix (row-major ``m[row, col]``, translation in the last
#: column, last row exactly ``0 0 0 1``) or 7 numbers ``(tx, ty, tz, qw, qx, qy, qz)``
#: (the quaternion is normalised). Applied to a tree's model coordinates as ``p' = R p + t``.
_PoseLike = Union[npt.ArrayLike, Sequence[float]]
#: A batch of poses: an ``(N, 7)`` or ``(N, 4, 4)`` array-like.
_PosesLike = npt.ArrayLike
#: A file path.
_PathLike = Union[str, bytes, "os.PathLike[str]", "os.PathLike[bytes]"]
#: A mesh: a file path, a ``(vertices (n, 3) float, faces (m, 3) int)`` pair, or an object
#: with ``.vertices`` and ``.faces`` (a ``trimesh.Trimesh``).
_MeshLike = Union[_PathLike, Tuple[npt.ArrayLike, npt.ArrayLike], Sequence[npt.ArrayLike], Any]

_FloatArray = npt.NDArray[np.float64]

@final
class Tree:
    """An Inner Sphere Tree: the inner-sphere packing of one rigid model and its
    bounding-sphere hierarchy, ready for queries (shared read-only by every Pair that uses
    it). Lengths are in the mesh's own model units (mm for the jaw scans).

    Make one with ``Tree.build`` or ``Tree.load``. Trees pickle (through the file's bytes).
    """

    @staticmethod
    def build(
        path_or_mesh: _MeshLike,
        *,
        voxel_size: Optional[float] = None,
        resolution: Optional[int] = None,
        min_radius: float = 0.0,
        refine_steps: int = 0,
        fanout: int = 4,
        progress: bool = False,
        preset: Optional[str] = None,
        cache: Union[None, bool, _PathLike] = None,
        unit: str = "mm",
    ) -> "Tree":
        """Builds the Inner Sphere Tree of a closed triangle mesh.

        path_or_mesh: a mesh file (STL, OBJ, PLY or OFF, optionally .gz), a pair
            ``(vertices (n, 3) float, faces (m, 3) int)``, or an object with ``.vertices``
            and ``.faces`` (a ``trimesh.Trimesh``). Arrays are welded as the file loaders
            do, so they give the tree of the same mesh read from a file.
        voxel_size: edge of the voxel grid's cells (model units); exclusive with resolution.
        resolution: cells along the longest side of the bounding box (2..4096); the default
            when neither is given is 128 cells.
        min_radius: no inner sphere smaller than this (model units; 0 = no floor).
        refine_steps: off-grid refinement steps per sphere (0 = the paper's packing; the
            calibrated setting is 8).
        fanout: most children per inner node (2..32).
        progress: print each stage's progress to standard error.
        preset: start from ``ist build --preset NAME``: "fast", "default", "fine", "jaw"
            (0.1 mm voxels, 0.05 mm minimum radius, 8 steps; jaw scans in mm) or
            "jaw-fast"; options given (or differing from their defaults) override it.

        cache: None or False (build), True (the platform's cache folder, e.g.
            ~/.cache/innersphere) or a folder: a tree built before from the same mesh with
            the same options and library is read back instead (checked as a tree file and
            against the mesh; an entry that fails is rebuilt, with a UserWarning saying
            why); ``tree.report["cache"]`` says ``{"outcome": "hit" | "built" |
            "rebuilt", "dir": ...}``. The trees are kept in the cache's own subfolder
            ``innersphere-trees-v1`` of that folder (tagged with a CACHEDIR.TAG), bounded
            to 2 GiB, least recently used first out; nothing else in the folder is read,
            touched or removed. OSError, in a sentence naming the path, when the folder is
            a file or the subfolder's name is taken by something the cache did not make.
        unit: the mesh's unit, "mm", "cm", "m" or "in": converted to mm as it is read
            (everything after, the tree and its answers, is in mm; the tree records the
            unit of its source file).

        Warnings of the build (open mesh, flipped faces, ...) are issued as UserWarnings
        and kept in ``tree.report``. Raises ValueError for a bad option or mesh, OSError
        when the file cannot be read.
        """
    @staticmethod
    def load(path: _PathLike) -> "Tree":
        """Reads a tree file (.ist) written by ``Tree.save`` or ``ist build``. Raises
        OSError when it cannot be read, ValueError when it is no valid tree file."""
    def save(self, path: _PathLike) -> None:
        """Writes the tree file (through a temporary file renamed into place). Raises
        OSError when it cannot be written."""
    def with_mesh(self, mesh: _MeshLike, *, unit: str = "mm") -> "Tree":
        """The same tree with the mesh it was built from (path, (vertices, faces) or a
        trimesh.Trimesh; ``unit`` its unit, converted to mm), for ``Pair.refined_distance``.
        Raises ValueError when the mesh is not the tree's source."""
    @property
    def has_mesh(self) -> bool:
        """True when the tree carries its mesh (``Tree.with_mesh``)."""
    def to_bytes(self) -> bytes:
        """The tree file's bytes."""
    @staticmethod
    def from_bytes(data: bytes, mesh: Optional[_MeshLike] = None) -> "Tree":
        """A tree from a tree file's bytes (checked as ``Tree.load`` checks a file), with
        ``mesh`` attached as ``with_mesh`` does when given. A pickled tree that carries its
        mesh comes back with it."""
    @property
    def spheres(self) -> _FloatArray:
        """The inner spheres (leaves): shape (leaf_count, 4), rows (x, y, z, r)."""
    @property
    def nodes(self) -> _FloatArray:
        """Every node's sphere, breadth first from the root: shape (node_count, 4)."""
    @property
    def node_count(self) -> int:
        """Number of nodes, leaves included."""
    @property
    def leaf_count(self) -> int:
        """Number of inner spheres (leaves)."""
    @property
    def depth(self) -> int:
        """Largest leaf depth (the root is at depth 0)."""
    @property
    def meta(self) -> Dict[str, Any]:
        """Build parameters and facts about the source mesh: fanout, voxel_size, min_radius,
        mesh_volume, center_of_mass, bbox_min, bbox_max, coverage, mesh_closed, built_by,
        inertia, source_volume, source_centroid (what recognises the source mesh, open or
        closed)."""
    @property
    def report(self) -> Optional[Dict[str, Any]]:
        """The build report (spheres, coverage, stage times, warnings, ...) of a tree built
        in this process; None for a loaded tree."""

@final
class DistanceResult:
    """The answer of ``Pair.distance`` (world frame)."""

    @property
    def distance(self) -> float:
        """Minimum distance between the sphere packings (0 when they overlap; with
        ``signed=True`` minus the deepest leaf overlap)."""
    @property
    def contact(self) -> bool:
        """True when the packings overlap."""
    @property
    def point_a(self) -> _FloatArray:
        """Closest point on A's sphere, shape (3,)."""
    @property
    def point_b(self) -> _FloatArray:
        """Closest point on B's sphere, shape (3,)."""
    @property
    def normal(self) -> _FloatArray:
        """Unit direction from A's sphere centre to B's, shape (3,)."""
    @property
    def lower_bound(self) -> float:
        """A proved lower bound on the exact answer (= distance without tolerances)."""
    @property
    def pair_distance(self) -> float:
        """|cb − ca| − ra − rb of the reported leaf pair (negative when it overlaps)."""
    @property
    def leaf_a(self) -> int:
        """A's leaf (node index) of the closest pair."""
    @property
    def leaf_b(self) -> int:
        """B's leaf (node index) of the closest pair."""
    @property
    def visits(self) -> int:
        """Node pairs whose distance was computed."""
    def to_dict(self) -> Dict[str, Any]:
        """The answer's serialized form as a dict: the keys and values of ``ist query
        --json`` (vectors as lists); the attributes are its keys."""

@final
class PenetrationResult:
    """The answer of ``Pair.penetration`` (world frame)."""

    @property
    def volume(self) -> float:
        """Penetration volume (model units³): the volume of the intersection of the two
        sphere unions."""
    @property
    def max_depth(self) -> float:
        """Largest leaf-pair overlap (model units)."""
    @property
    def normal(self) -> _FloatArray:
        """Contact normal (unit, zeros without penetration), shape (3,)."""
    @property
    def force(self) -> _FloatArray:
        """Force on B: stiffness × volume × normal, shape (3,)."""
    @property
    def torque_a(self) -> _FloatArray:
        """Torque on A about A's centre of mass, shape (3,)."""
    @property
    def torque_b(self) -> _FloatArray:
        """Torque on B about B's centre of mass, shape (3,)."""
    @property
    def patches(self) -> List[Dict[str, Any]]:
        """Contact patches: dicts with point (3,), normal (3,), depth, volume, pairs."""
    @property
    def pairs(self) -> int:
        """Number of overlapping leaf pairs."""
    @property
    def contact(self) -> bool:
        """True when at least one leaf pair overlaps."""
    @property
    def distance(self) -> float:
        """0 with penetration, else a proved lower bound on the separation."""
    @property
    def visits(self) -> int:
        """Node pairs tested."""
    @property
    def skipped(self) -> bool:
        """True when the safe-motion bound answered without a traversal."""
    @property
    def patch_count(self) -> int:
        """Number of contact patches."""
    @property
    def area(self) -> float:
        """Contact area (0 unless the query was asked to linearize)."""
    @property
    def stiffness(self) -> Dict[str, _FloatArray]:
        """The linearised wrench: linear, coupling, angular, each 9 numbers column-major
        (zeros unless the query was asked to linearize)."""
    def to_dict(self) -> Dict[str, Any]:
        """The answer's serialized form and its patches as a dict: the keys and values of
        ``ist query --json`` (vectors as lists); the attributes are its keys."""

@final
class Pair:
    """Two trees and all per-pair state of their queries.

    Every query takes B's pose and optionally A's (``pose_a=``, default the identity). The
    pair starts each query from what the last ones found (fast along a motion); call
    ``reset()`` or use a new Pair for a query from scratch (what ``ist query`` runs). One
    thread at a time per pair; trees are shared freely.
    """

    def __new__(cls, tree_a: Tree, tree_b: Tree) -> "Pair": ...
    @property
    def tree_a(self) -> Tree: ...
    @property
    def tree_b(self) -> Tree: ...
    def distance(
        self,
        pose_b: _PoseLike,
        *,
        pose_a: Optional[_PoseLike] = None,
        signed: bool = False,
        abs_tol: float = 0.0,
        rel_tol: float = 0.0,
    ) -> DistanceResult:
        """Exact minimum distance between the inner-sphere packings, with closest points."""
    def contact(self, pose_b: _PoseLike, *, pose_a: Optional[_PoseLike] = None) -> bool:
        """Whether the packings overlap."""
    def multipoint(
        self,
        pose_b: _PoseLike,
        k: int = 16,
        *,
        pose_a: Optional[_PoseLike] = None,
        split_depth: int = 4,
    ) -> _FloatArray:
        """Up to k contact points, shape (count, 3); details in ``pair.contacts``."""
    @property
    def contacts(self) -> Dict[str, npt.NDArray[Any]]:
        """The last multipoint's contacts: point (n, 3), normal (n, 3), depth (n,),
        leaf_a (n,), leaf_b (n,)."""
    def penetration(
        self,
        pose_b: _PoseLike,
        stiffness: float = 1.0,
        *,
        pose_a: Optional[_PoseLike] = None,
        max_patches: int = 8,
    ) -> PenetrationResult:
        """Penetration volume, normal, penalty force, torques and contact patches."""
    def penetration_within(
        self,
        pose_b: _PoseLike,
        budget: int = 8000,
        stiffness: float = 1.0,
        *,
        pose_a: Optional[_PoseLike] = None,
    ) -> Dict[str, Any]:
        """Time-critical penetration volume within budget node-pair tests: the answer's
        serialized form as a dict (``ist query --json --query penetration-within`` without
        its budget): volume, upper_bound, visits, complete, max_depth, normal, force,
        torque_b, area, stiffness."""
    def refined_distance(
        self,
        pose_b: _PoseLike,
        *,
        pose_a: Optional[_PoseLike] = None,
        radius_scale: float = 0.5,
        rel_tol: float = 1e-3,
        max_node_pairs: int = 4096,
    ) -> Dict[str, Any]:
        """The distance between the meshes, refined from the sphere distance by the exact
        distance of the triangles near its closest points (both trees need their meshes:
        ``Tree.with_mesh``): the answer's serialized form as a dict (``ist query --json --query
        refined-distance``): distance, contact, refined, complete, point_a, point_b,
        triangle_a, triangle_b (None unless refined), radius, node_pairs, triangle_pairs,
        and spheres (the sphere distance refined, as ``DistanceResult.to_dict()``)."""
    def mesh_penetration(
        self,
        pose_b: _PoseLike,
        *,
        pose_a: Optional[_PoseLike] = None,
        stiffness: float = 1.0,
        max_patches: int = 8,
    ) -> Dict[str, Any]:
        """The penetration of the meshes themselves (both trees need their meshes:
        ``Tree.with_mesh``): the exact volume of the intersection of the two solids, the
        force and torques from its exact gradient, as the answer's serialized form (``ist
        query --json --query mesh-penetration``): contact, volume, normal, force, torque_a,
        torque_b, gradient, rotation_gradient, area, max_depth, patch_count, stiffness,
        crossing_pairs, and the ``max_patches`` largest connected pieces of the
        intersection as ``patches`` (point: the centre of B's surface inside A, normal,
        depth: the mean thickness along it, volume, pairs)."""
    def distance_traversal(self, pose_b: _PoseLike, *, pose_a: Optional[_PoseLike] = None) -> bool:
        """The paper's distance traversal: whether the packings overlap."""
    def backtracking(self, pose_b: _PoseLike, *, pose_a: Optional[_PoseLike] = None) -> bool:
        """The paper's backtracking traversal: whether the packings overlap."""
    def reset(self) -> None:
        """Forgets all temporal coherence: the next query starts from scratch."""
    def distance_many(
        self,
        poses: _PosesLike,
        *,
        pose_a: Optional[Union[_PoseLike, _PosesLike]] = None,
        threads: Optional[int] = None,
        chunk: int = 1024,
    ) -> _FloatArray:
        """``distance`` for each pose of B in order, on ``threads`` threads (None: all
        cores), in chunks of ``chunk`` poses that each start from a fresh state and carry it
        (``ist replay``'s distances); the answers never depend on ``threads``. Returns shape
        (N,)."""
    def refined_distance_many(
        self,
        poses: _PosesLike,
        *,
        pose_a: Optional[Union[_PoseLike, _PosesLike]] = None,
        threads: Optional[int] = None,
        chunk: int = 1024,
        radius_scale: float = 0.5,
        rel_tol: float = 1e-3,
        max_node_pairs: int = 4096,
    ) -> Dict[str, npt.NDArray[Any]]:
        """``refined_distance`` for each pose of B in order (threads and chunks as
        distance_many; both trees need their meshes): the keys of ``refined_distance``, each a
        column over the poses: numbers (N,), vectors (N, 3), triangle_a and triangle_b (N,)
        int64 (−1 unless refined), spheres a dict of such columns."""
    def contact_many(
        self,
        poses: _PosesLike,
        *,
        pose_a: Optional[Union[_PoseLike, _PosesLike]] = None,
        threads: Optional[int] = None,
        chunk: int = 1024,
    ) -> npt.NDArray[np.bool_]:
        """``contact`` for each pose of B in order (threads and chunks as distance_many):
        shape (N,) bool."""
    def penetration_many(
        self,
        poses: _PosesLike,
        stiffness: float = 1.0,
        *,
        pose_a: Optional[Union[_PoseLike, _PosesLike]] = None,
        threads: Optional[int] = None,
        chunk: int = 1024,
    ) -> Dict[str, npt.NDArray[Any]]:
        """``penetration`` for each pose of B in order: the keys of
        ``PenetrationResult.to_dict()`` but the patches, each a column over the poses:
        numbers (N,), vectors (N, 3) (torque_b on B, torque_a on A), stiffness a dict of
        (N, 9) arrays."""
    def mesh_penetration_many(
        self,
        poses: _PosesLike,
        stiffness: float = 1.0,
        *,
        pose_a: Optional[Union[_PoseLike, _PosesLike]] = None,
        threads: Optional[int] = None,
        chunk: int = 1024,
    ) -> Dict[str, npt.NDArray[Any]]:
        """``mesh_penetration`` for each pose of B in order (both trees need their meshes:
        ``Tree.with_mesh``): its keys but the patches, each a column over the poses."""

@final
class Tick:
    """What one haptic tick did (mm, N, s)."""

    @property
    def force(self) -> _FloatArray:
        """Force to send to the device (N), shape (3,)."""
    @property
    def torque(self) -> _FloatArray:
        """Torque to send to the device (N·mm), shape (3,)."""
    @property
    def tool(self) -> _FloatArray:
        """The tool's pose after the tick: (tx, ty, tz, qw, qx, qy, qz)."""
    @property
    def tool_matrix(self) -> _FloatArray:
        """The tool's pose after the tick as a 4×4 matrix."""
    @property
    def contact_force(self) -> _FloatArray:
        """Penalty force of the contact on the tool (N), shape (3,)."""
    @property
    def volume(self) -> float:
        """Penetration volume (mm³)."""
    @property
    def volume_bound(self) -> float:
        """Upper bound on the penetration volume (= volume unless budgeted)."""
    @property
    def max_depth(self) -> float:
        """Deepest leaf-pair overlap (mm)."""
    @property
    def patches(self) -> int:
        """Contact patches (exact path only)."""
    @property
    def budgeted(self) -> bool:
        """True when the time-critical query answered."""
    @property
    def compute(self) -> float:
        """Time the tick took (s)."""
    @property
    def late(self) -> bool:
        """True when the tick took longer than its budget."""
    @property
    def model_age(self) -> float:
        """Age of the contact model the tick used (s)."""
    def to_dict(self) -> Dict[str, Any]:
        """The fields as a dict."""

@final
class Haptic:
    """The 6-DOF haptic loop: tool B coupled to the device's pose by a spring-damper and
    pushed out of A (fixed at pose_a) by the penalty wrench. Units: mm, N, s, kg."""

    def __new__(
        cls,
        pair: Pair,
        device: str = "omega",
        rate: float = 1000.0,
        start: Optional[_PoseLike] = None,
        *,
        pose_a: Optional[_PoseLike] = None,
        budget: Optional[float] = None,
        collision_thread: bool = False,
        collision_delay: float = 0.0,
        contact: str = "spheres",
    ) -> "Haptic":
        """device: "omega" (12 N) or "touch" (3.3 N); rate in Hz; start: the tool's pose
        at rest (default identity); budget: most seconds per tick (default one period);
        collision_thread: the penetration query in a thread of its own (pace the ticks in
        real time); collision_delay: seconds it sleeps before each query (stress knob);
        contact: "spheres" or "mesh" (the meshes' own exact volume: both trees need their
        meshes, Tree.with_mesh; implies collision_thread)."""
    def tick(self, device_pose: _PoseLike, dt: float = 0.0) -> Tick:
        """One device tick: the device's pose in, the force to send out (dt: seconds since
        the last tick; 0 = one period). A NaN pose raises ValueError."""
    @property
    def energy_to_user(self) -> float:
        """Energy delivered to the hand so far (J); at most zero for a passive loop."""
    @property
    def energy_to_user_max(self) -> float:
        """The largest value energy_to_user has had (J)."""
    @property
    def tool(self) -> _FloatArray:
        """The tool's current pose (tx, ty, tz, qw, qx, qy, qz)."""
    @property
    def rate(self) -> float: ...
    @property
    def budget(self) -> float: ...
    @property
    def collision_queries(self) -> int:
        """Contact models the collision thread has published (0 without one)."""
    @property
    def mass(self) -> float:
        """The tool's mass (kg)."""

def load_motion(path: _PathLike) -> Tuple[_FloatArray, _FloatArray]:
    """Reads a motion file (CSV ``t,tx,ty,tz,qw,qx,qy,qz``, optionally .gz): returns the
    times (N,) and the poses (N, 7) of B in A's frame, as ``ist replay --motion`` reads
    them. Raises OSError when unreadable, ValueError (with the line) when invalid."""

def contact_map(
    a: _MeshLike,
    b: _MeshLike,
    pose_b: Optional[_PoseLike] = None,
    pose_a: Optional[_PoseLike] = None,
    unit: str = "mm",
) -> Tuple[_FloatArray, _FloatArray]:
    """The contact map of meshes ``a`` and ``b`` (each a file path, a ``(vertices, faces)``
    pair or a ``trimesh.Trimesh``) at ``pose_b`` (and ``pose_a``, default the identity): per
    vertex of each, its exact distance to the other's surface, negative inside the other
    (``ist occlusion-map``'s ``gap``). Arrays keep their vertex order; a file's vertices are
    the loader's (welded). ``unit``: the meshes' unit ("mm", "cm", "m", "in"), converted to
    mm; the gaps are in mm. Raises OSError for unreadable files, ValueError for bad meshes or
    poses."""

def arch_pair(
    teeth: int = 12, bone: bool = False
) -> Tuple[Tuple[_FloatArray, npt.NDArray[np.uint32]], Tuple[_FloatArray, npt.NDArray[np.uint32]]]:
    """A generated arch pair in mm, (upper, lower), each (vertices, faces): ``teeth``
    molar-like teeth per arch (2..16) with roots, interlocking at the identity like a bite;
    with ``bone``, the same teeth standing in a solid horseshoe of bone, each arch one closed
    surface (about 0.5 M triangles per arch)."""

def splint(
    a: _MeshLike,
    b: _MeshLike,
    pose_b: Optional[_PoseLike] = None,
    open: Union[float, str, None] = None,
    clearance: Optional[float] = None,
    coverage: Optional[float] = None,
    min_thickness: Optional[float] = None,
    rim: Optional[float] = None,
    voxel: Optional[float] = None,
    max_triangles: Optional[int] = None,
    out: Optional[_PathLike] = None,
    keep_unfit: bool = False,
    unit: str = "mm",
) -> Tuple[_FloatArray, npt.NDArray[np.uint32], Dict[str, Any]]:
    """The occlusal splint (surgical wafer) between arch ``a`` (upper, fixed) and arch ``b``
    at ``pose_b`` (default the identity), each a file path, a ``(vertices, faces)`` pair or a
    ``trimesh.Trimesh``: the vertices (n, 3) and faces (m, 3) of its closed, outward-facing
    surface in A's frame, and a dict of its measurements (the JSON of ``ist splint``, with
    ``opened`` and ``pose``). ``open``: an incisal opening about the hinge (mm) applied after
    the pose, or ``"auto"`` for the least that leaves room for the wafer. The options default
    as in ``ist splint`` (mm: clearance 0.1, coverage 2, min_thickness 1, rim 1.5, voxel
    0.1, max_triangles 300000: simplified down to it, 0 for as extracted). ``out``: also
    write it there, as binary STL (``.stl``) or OBJ (``.obj``), compressed when the name
    ends in ``.gz``, or 3MF (``.3mf``). Every measurement is made on the mesh as
    written; a wafer that fails a guarantee (``checks`` in the dict, ``fit`` false) raises
    ValueError unless ``keep_unfit``. ``unit``: the meshes' unit ("mm", "cm", "m", "in"),
    converted to mm; the wafer is in mm. Raises OSError for unreadable or unwritable files,
    ValueError for bad meshes, poses or options and for inputs that cannot make a wafer."""

def plan(
    case: _PathLike,
    out: _PathLike,
    cache: Union[_PathLike, bool, None] = None,
) -> Dict[str, Any]:
    """Runs the case file ``case`` (JSON, docs/PLAN.md; paths relative to it) into the folder
    ``out`` (new, empty or a previous plan's): the contact map's PLYs, each fit wafer's STL and 3MF,
    ``report.html`` and ``case.json``, the same files as ``ist plan`` writes. Returns the plan
    as a dict (the JSON of ``ist plan --json``: ``bite`` with its ``pose``, ``map``,
    ``splints`` with each wafer's ``file`` and ``report``, ``fit``, ``seconds``). ``cache``:
    the build cache's folder (default the platform's; ``False`` for none). Raises OSError for
    unreadable or unwritable files and ValueError for a case that cannot be planned; a wafer
    that fails a guarantee is in the dict with ``fit`` false and no file, one that cannot be
    made with ``report`` None and its ``error``."""

def occlude(
    tree_a: Tree,
    tree_b: Tree,
    from_pose: _PoseLike,
    *,
    free: bool = False,
    axis: Optional[Sequence[float]] = None,
    force: Optional[float] = None,
    contact_stiffness: Optional[float] = None,
    max_seconds: Optional[float] = None,
    reference: Optional[_PoseLike] = None,
    joint_stiffness: Optional[float] = None,
    starts: Optional[int] = None,
    spread: Optional[float] = None,
    seed: Optional[int] = None,
    contact: str = "spheres",
) -> Dict[str, Any]:
    """B (``tree_b``: the lower jaw or a free cut segment, built by this version so that it
    holds its mass properties) closed onto A (``tree_a``, fixed at the identity) from
    ``from_pose`` (B's pose in A's frame) under ``force`` N (default 5) along ``axis``
    (default the pair's occlusal "up"), its temporomandibular joints (``joint_stiffness``
    N/mm, default 20) held where they are with B at ``reference`` (default the identity); or,
    ``free=True``, no joints and ``starts`` closings (default 120) spread within ``spread``
    mm (default 2.5; yaw twice that in degrees) from ``seed`` (default 1), the rest poses
    ranked. ``contact_stiffness`` defaults to 10 N/mm³ with the joints, 1000 free;
    ``max_seconds`` of simulated time to 30. Limits as in ``ist occlude``: ``force`` 0.5–1000
    N and at most 2 mm³ × ``contact_stiffness``, ``contact_stiffness`` up to 1e5,
    ``joint_stiffness`` 0–1e4, ``max_seconds`` up to 60, ``starts`` 1–1000, ``spread`` up to
    10. Returns ``ist occlude --json``'s dict less its wall time and landmarks: ``pose`` (7
    numbers), ``status`` (``"converged"``: at rest in contact; ``"no_contact"``,
    ``"time_limit"``, ``"passed_through"``, ``"escaped"``), ``converged`` (status is
    ``"converged"``), ``steps``, ``seconds``, ``volume``, ``max_depth``, ``patches``,
    ``axis``, ``force``, ``contact_stiffness``, ``contact``, ``joints``, ``frame``,
    ``candidates``, ``closings`` (free: how many closings ended in each status).
    ``contact="mesh"`` rests B on the meshes' own contact (both trees need their meshes:
    ``Tree.with_mesh``; a free search runs on the spheres, its chosen rest then settles on
    the meshes). Raises ValueError for
    options out of range, poses that cannot bite (far open, beside A, beyond it, turned),
    arches that do not face each other (B is not the lower arch in A's frame), or a tree B
    without mass properties."""
