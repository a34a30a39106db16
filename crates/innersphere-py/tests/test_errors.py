"""Errors are Python exceptions with the library's message, never a crash: OSError for
files, ValueError for bad arguments, NaN poses refused."""

import errno
import math

import numpy as np
import pytest

import innersphere
from helpers import box_mesh, write_motion

NAN = float("nan")


@pytest.fixture(scope="module")
def pair(trees):
    return innersphere.Pair(*trees)


# --- files ---------------------------------------------------------------------------------


def test_missing_tree_file(tmp_path):
    path = tmp_path / "nope.ist"
    with pytest.raises(OSError) as e:
        innersphere.Tree.load(path)
    assert isinstance(e.value, FileNotFoundError)
    assert e.value.errno == errno.ENOENT and e.value.filename == str(path)


def test_missing_mesh_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        innersphere.Tree.build(tmp_path / "nope.stl")
    with pytest.raises(FileNotFoundError):
        innersphere.Tree.build(bytes(tmp_path / "nope.stl"))


def test_missing_motion_file(tmp_path):
    with pytest.raises(FileNotFoundError):
        innersphere.load_motion(tmp_path / "nope.csv")


def test_directory_is_not_a_tree(tmp_path):
    with pytest.raises(OSError):
        innersphere.Tree.load(tmp_path)


def test_unwritable_save(trees, tmp_path):
    with pytest.raises(OSError):
        trees[0].save(tmp_path / "no" / "such" / "dir" / "t.ist")


def test_corrupt_tree_file(trees, tmp_path):
    path = tmp_path / "bad.ist"
    data = bytearray(trees[0].to_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(ValueError, match="corrupt tree file"):
        innersphere.Tree.load(path)
    path.write_bytes(b"not a tree")
    with pytest.raises(ValueError, match="corrupt tree file") as e:
        innersphere.Tree.load(path)
    # A tree file, not a mesh: not told to build it.
    assert "is a mesh" not in str(e.value)
    with pytest.raises(ValueError, match="corrupt tree file"):
        innersphere.Tree.from_bytes(b"\x00" * 100)


def test_mesh_given_as_tree(tmp_path):
    path = tmp_path / "m.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(ValueError, match="is a mesh, not a tree file"):
        innersphere.Tree.load(path)


def test_bad_mesh_files(tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("v 0 0 zero\n")
    with pytest.raises(ValueError, match="parse error"):
        innersphere.Tree.build(bad)
    with pytest.raises(ValueError, match="unsupported mesh format"):
        innersphere.Tree.build(tmp_path / "mesh.xyz")


def test_bad_motion_files(tmp_path):
    path = tmp_path / "m.csv"
    path.write_text("t,tx,ty,tz,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n0.001,0,0,0,2,0,0,0\n")
    with pytest.raises(ValueError, match=":3: the quaternion"):
        innersphere.load_motion(path)
    path.write_text("time,x\n")
    with pytest.raises(ValueError, match="expected the header"):
        innersphere.load_motion(path)
    write_motion(path, [0.0, 0.0], [[0, 0, 0, 1, 0, 0, 0]] * 2)
    with pytest.raises(ValueError, match="does not increase"):
        innersphere.load_motion(path)


# --- poses ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "bad",
    [
        [NAN, 0, 0, 1, 0, 0, 0],
        [0, 0, 0, NAN, 0, 0, 0],
        [0, 0, math.inf, 1, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 0],  # a zero quaternion
    ],
)
def test_bad_seven_numbers(pair, bad):
    for call in (pair.distance, pair.contact, pair.multipoint, pair.penetration):
        with pytest.raises(ValueError, match="pose_b: invalid pose"):
            call(bad)
    with pytest.raises(ValueError, match="pose_a: invalid pose"):
        pair.distance([3, 0, 0, 1, 0, 0, 0], pose_a=bad)


def test_bad_matrices(pair):
    m = np.eye(4)
    m[0, 3] = NAN
    with pytest.raises(ValueError, match="NaN"):
        pair.distance(m)
    with pytest.raises(ValueError, match="not a rotation"):
        pair.distance(np.diag([2.0, 1, 1, 1]))  # a scale
    with pytest.raises(ValueError, match="reflection"):
        pair.distance(np.diag([-1.0, 1, 1, 1]))
    m = np.eye(4)
    m[3, 0] = 1.0
    with pytest.raises(ValueError, match="last row"):
        pair.distance(m)


@pytest.mark.parametrize(
    "bad", [[1, 2, 3], np.eye(3), np.zeros((4, 3)), np.zeros((2, 7)), 5.0, "0 0 0 1 0 0 0", object(), None]
)
def test_bad_pose_shapes(pair, bad):
    with pytest.raises(ValueError, match="pose_b"):
        pair.distance(bad)


def test_bad_batches(pair):
    with pytest.raises(ValueError, match=r"got shape \(7,\)"):
        pair.distance_many([0, 0, 0, 1, 0, 0, 0])
    with pytest.raises(ValueError, match=r"got shape \(2, 5\)"):
        pair.distance_many(np.zeros((2, 5)))
    with pytest.raises(ValueError, match=r"got shape \(4, 4\)"):
        pair.penetration_many(np.eye(4))
    poses = np.tile([3.0, 0, 0, 1, 0, 0, 0], (5, 1))
    poses[3, 1] = NAN
    with pytest.raises(ValueError, match=r"poses\[3\]: invalid pose"):
        pair.distance_many(poses)
    mats = np.tile(np.eye(4), (3, 1, 1))
    mats[2] *= 2
    with pytest.raises(ValueError, match=r"poses\[2\]"):
        pair.penetration_many(mats)
    with pytest.raises(ValueError, match="pose_a: 2 poses for a batch of 5"):
        pair.distance_many(np.tile([3.0, 0, 0, 1, 0, 0, 0], (5, 1)), pose_a=np.tile([0.0, 0, 0, 1, 0, 0, 0], (2, 1)))
    with pytest.raises(ValueError, match="poses"):
        pair.contact_many("no")


# --- options and meshes --------------------------------------------------------------------


def test_bad_query_options(pair):
    p = [3, 0, 0, 1, 0, 0, 0]
    with pytest.raises(ValueError, match="stiffness"):
        pair.penetration(p, stiffness=-1)
    with pytest.raises(ValueError, match="stiffness"):
        pair.penetration_many([p], stiffness=NAN)
    with pytest.raises(ValueError, match="k must be at least 1"):
        pair.multipoint(p, k=0)
    with pytest.raises(ValueError, match="split_depth"):
        pair.multipoint(p, split_depth=-1)
    with pytest.raises(ValueError, match="abs_tol"):
        pair.distance(p, abs_tol=-0.1)
    with pytest.raises(ValueError, match="max_patches"):
        pair.penetration(p, max_patches=-1)


def test_bad_build_options(meshes):
    m = meshes["box"]
    for kw, msg in [
        (dict(voxel_size=0.1, resolution=10), "not both"),
        (dict(voxel_size=-1.0), "voxel size must be a positive number"),
        (dict(voxel_size=NAN), "voxel size"),
        (dict(resolution=1), "resolution"),
        (dict(min_radius=-1.0), "minimum radius"),
        (dict(fanout=1), "fanout"),
        (dict(fanout=99), "fanout"),
        (dict(refine_steps=-2), "refine_steps"),
        (dict(preset="nope"), "unknown preset"),
        (dict(resolution=16, min_radius=10.0), "no inner sphere"),
    ]:
        with pytest.raises(ValueError, match=msg):
            innersphere.Tree.build(m, **kw)
    with pytest.raises(ValueError, match="preset jaw is in millimetres"):
        innersphere.Tree.build(box_mesh((0, 0, 0), (1e-3, 1e-3, 1e-3)), preset="jaw")


def test_bad_meshes():
    v, f = box_mesh()
    for mesh, msg in [
        ((v[:, :2], f), r"vertices: expected an \(n, 3\) array"),
        ((v, f.astype(float)), "integer vertex indices, got dtype float64"),
        ((v, f[:, :2]), r"got shape \(12, 2\)"),
        ((v, f + 10), r"faces\[0\] refers to vertex 10, but there are 8 vertices"),
        ((v, -f - 1), "refers to vertex -1"),
        ((v, np.zeros((0, 3), int)), "no triangles"),
        ((np.where(v > 0, NAN, v), f), "non-finite"),
        ((v, [[0, 0, 0]] * 12), "invalid mesh"),
        ((v, f[:2]), "encloses no volume"),
        ((v, f, f), "expected a mesh file path"),
        (42, "expected a mesh file path"),
        (("abc", f), "vertices"),
    ]:
        with pytest.raises(ValueError, match=msg):
            innersphere.Tree.build(mesh, resolution=8)


def test_bad_haptic_options(trees):
    pair = innersphere.Pair(*trees)
    with pytest.raises(ValueError, match='unknown device "joystick"'):
        innersphere.Haptic(pair, device="joystick")
    with pytest.raises(ValueError, match="rate"):
        innersphere.Haptic(pair, rate=0.0)
    with pytest.raises(ValueError, match="budget"):
        innersphere.Haptic(pair, budget=-1.0)
    with pytest.raises(ValueError, match="start"):
        innersphere.Haptic(pair, start=[NAN, 0, 0, 1, 0, 0, 0])


# --- what a hostile caller feeds the haptic loop and the pair -----------------------------


def test_a_stiffness_whose_force_would_overflow_is_refused(pair):
    p = [1.3, 0, 0, 1, 0, 0, 0]
    with pytest.raises(ValueError, match="stiffness must be from 0 to 1e30"):
        pair.penetration(p, stiffness=1e308)
    with pytest.raises(ValueError, match="stiffness must be from 0 to 1e30"):
        pair.penetration_many([p], stiffness=1e31)
    assert np.all(np.isfinite(pair.penetration(p, stiffness=1e30).force))


@pytest.mark.parametrize("dt", [NAN, -1.0, math.inf])
def test_a_bad_tick_step_is_refused(trees, dt):
    h = innersphere.Haptic(innersphere.Pair(*trees), start=[3, 0, 0, 1, 0, 0, 0])
    h.tick([3, 0, 0, 1, 0, 0, 0])
    before = h.tool.copy()
    with pytest.raises(ValueError, match="dt must be 0"):
        h.tick([3, 0, 0, 1, 0, 0, 0], dt=dt)
    assert np.array_equal(h.tool, before)


def test_a_huge_device_pose_does_not_fling_the_tool(trees):
    h = innersphere.Haptic(innersphere.Pair(*trees), start=[3, 0, 0, 1, 0, 0, 0])
    h.tick([3, 0, 0, 1, 0, 0, 0])
    h.tick([1e200, 0, 0, 1, 0, 0, 0])
    for _ in range(20):
        t = h.tick([3, 0, 0, 1, 0, 0, 0])
    assert abs(t.tool[0] - 3.0) < 0.01 and np.all(np.isfinite(t.force))
    assert h.energy_to_user_max <= 1e-9


def test_a_low_rate_is_refused_clearly(trees):
    with pytest.raises(ValueError, match="the rate must be from 100 Hz"):
        innersphere.Haptic(innersphere.Pair(*trees), rate=10.0)
    # Below 1 kHz the default coupling is made passive for the rate.
    h = innersphere.Haptic(innersphere.Pair(*trees), rate=100.0)
    assert h.rate == 100.0


def test_a_resolution_too_fine_is_said_in_cells(meshes):
    with pytest.raises(ValueError, match="a resolution of 4096 cells along the longest side"):
        innersphere.Tree.build(meshes["box"], resolution=4096)


def test_a_pair_used_from_two_threads_says_so(trees):
    import threading

    pair = innersphere.Pair(*trees)
    pose = [1.3, 0, 0, 1, 0, 0, 0]
    errors = []

    def other():
        while worker.is_alive():
            try:
                pair.distance([5, 0, 0, 1, 0, 0, 0])
            except RuntimeError as e:
                errors.append(str(e))
                return

    # Single queries hold the pair (the batches use pairs of their own).
    worker = threading.Thread(target=lambda: [pair.penetration(pose) for _ in range(50_000)])
    worker.start()
    other()
    worker.join()
    assert errors, "the second thread never met the busy pair"
    assert "another thread" in errors[0] and "one Pair per thread" in errors[0]
    # Free again afterwards.
    assert pair.distance([5, 0, 0, 1, 0, 0, 0]).distance > 0
