"""Inner Sphere Trees: collision detection, proximity and penetration volume between rigid
3D models at haptic rates (1 kHz and more).

Build a tree per model once (``Tree.build`` from a mesh file, ``(vertices, faces)`` arrays or
a ``trimesh.Trimesh``; or ``Tree.load`` a ``.ist`` file), make a ``Pair`` per pair of bodies
and ask it with the pose of body B (and optionally A): ``distance``, ``contact``,
``multipoint``, ``penetration``, and the batch forms ``distance_many``, ``contact_many`` and
``penetration_many`` that loop in Rust. A pose is a 4×4 homogeneous matrix or 7 numbers
``(tx, ty, tz, qw, qx, qy, qz)``. ``load_motion`` reads a motion file, ``Haptic`` runs the
6-DOF haptic loop, ``contact_map`` gives every vertex of two meshes its signed gap to the
other, ``splint`` makes the occlusal splint (surgical wafer) between two arches, ``occlude``
closes a lower jaw (or a free segment) onto the upper into its bite.

The numbers are the Rust library's own: a query on a new (or reset) pair answers what
``ist query`` prints, ``distance_many`` over a motion what ``ist replay`` prints.

Example::

    import numpy as np, innersphere as ist
    box = (np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float),
           np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                     [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]]))
    tree = ist.Tree.build(box, resolution=32)
    pair = ist.Pair(tree, tree)
    print(pair.distance([2.0, 0, 0, 1, 0, 0, 0]).distance)   # ≈ 1: B moved 2 along x

Errors are exceptions with the library's message: ``OSError`` for files that cannot be read
or written, ``ValueError`` for everything else (options, meshes, tree files, poses, shapes).
"""

from ._innersphere import (
    DistanceResult,
    Haptic,
    Pair,
    PenetrationResult,
    Tick,
    Tree,
    __version__,
    arch_pair,
    contact_map,
    load_motion,
    occlude,
    plan,
    splint,
)

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
