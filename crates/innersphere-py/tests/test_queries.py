"""Every single query against `ist query --json` on the same trees and poses: identical
numbers (`ist query` runs each query on a fresh pair, so the pair is reset before each)."""

import numpy as np
import pytest

import innersphere
from helpers import POSES, pose_matrix


def same(a, b):
    """Bit-for-bit equal numbers (arrays, lists, scalars)."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    assert np.array_equal(a, b), (a, b)


def assert_is_the_cli_answer(got, want, door=()):
    """A Python dict is the answer `ist query --json` printed: the same keys but the CLI's
    own (the query's name, its time, whether its distance is a bound, and `door`), the same
    values bit for bit (one serialized form, printed by both)."""
    own = {"query", "seconds", "distance_is_lower_bound", *door}
    assert set(got) == set(want) - own, set(got) ^ (set(want) - own)
    for k in got:
        if isinstance(want[k], (bool, int, str)) or want[k] is None:
            assert got[k] == want[k] and type(got[k]) is type(want[k]), k
        elif isinstance(want[k], dict) and not isinstance(got[k], dict):
            raise AssertionError(k)
        elif isinstance(want[k], dict) or (isinstance(want[k], list) and want[k] and isinstance(want[k][0], dict)):
            assert_values_equal(got[k], want[k], k)
        else:
            same(got[k], want[k])


def assert_values_equal(got, want, where):
    """Nested dicts and lists of numbers equal bit for bit."""
    if isinstance(want, dict):
        assert set(got) == set(want), where
        for k in want:
            assert_values_equal(got[k], want[k], f"{where}.{k}")
    elif isinstance(want, list) and want and isinstance(want[0], dict):
        assert len(got) == len(want), where
        for i, (g, w) in enumerate(zip(got, want)):
            assert_values_equal(g, w, f"{where}[{i}]")
    elif isinstance(want, (bool, int, str)) or want is None:
        assert got == want, where
    else:
        same(got, want)


@pytest.fixture(scope="module")
def pair(trees):
    return innersphere.Pair(*trees)


@pytest.mark.parametrize("i", range(len(POSES)))
def test_distance_equals_cli(pair, tree_files, ist, i):
    want = ist.query(*tree_files, POSES[i], "distance")
    pair.reset()
    got = pair.distance(POSES[i])
    same(got.distance, want["distance"])
    assert got.contact == want["contact"]
    same(got.lower_bound, want["lower_bound"])
    same(got.point_a, want["point_a"])
    same(got.point_b, want["point_b"])
    same(got.normal, want["normal"])
    assert (got.leaf_a, got.leaf_b, got.visits) == (want["leaf_a"], want["leaf_b"], want["visits"])
    assert got.point_a.shape == (3,) and got.point_a.dtype == np.float64
    assert_is_the_cli_answer(got.to_dict(), want)


@pytest.mark.parametrize("opts", [("--signed",), ("--abs-tol", "0.05"), ("--rel-tol", "0.1")])
@pytest.mark.parametrize("i", [2, 3, 6])
def test_distance_options_equal_cli(pair, tree_files, ist, opts, i):
    want = ist.query(*tree_files, POSES[i], "distance", *opts)
    kw = {"--signed": {"signed": True}, "--abs-tol": {"abs_tol": 0.05}, "--rel-tol": {"rel_tol": 0.1}}[opts[0]]
    pair.reset()
    got = pair.distance(POSES[i], **kw)
    same(got.distance, want["distance"])
    same(got.lower_bound, want["lower_bound"])
    same(got.point_b, want["point_b"])


@pytest.mark.parametrize("i", range(len(POSES)))
def test_contact_equals_cli(pair, tree_files, ist, i):
    want = ist.query(*tree_files, POSES[i], "contact")
    pair.reset()
    assert pair.contact(POSES[i]) is want["contact"]


@pytest.mark.parametrize("k", [16, 3])
@pytest.mark.parametrize("i", range(len(POSES)))
def test_multipoint_equals_cli(pair, tree_files, ist, i, k):
    want = ist.query(*tree_files, POSES[i], "multipoint", "--k", k)
    pair.reset()
    points = pair.multipoint(POSES[i], k=k)
    assert points.shape == (len(want["contacts"]), 3)
    assert len(points) <= k
    c = pair.contacts
    if want["contacts"]:
        same(points, [w["point"] for w in want["contacts"]])
        same(c["point"], points)
        same(c["normal"], [w["normal"] for w in want["contacts"]])
        same(c["depth"], [w["depth"] for w in want["contacts"]])
        assert list(c["leaf_a"]) == [w["leaf_a"] for w in want["contacts"]]
        assert list(c["leaf_b"]) == [w["leaf_b"] for w in want["contacts"]]
    else:
        assert not want["contact"]


@pytest.mark.parametrize("stiffness", [1.0, 2.5])
@pytest.mark.parametrize("i", range(len(POSES)))
def test_penetration_equals_cli(pair, tree_files, ist, i, stiffness):
    want = ist.query(*tree_files, POSES[i], "penetration", "--stiffness", stiffness)
    pair.reset()
    got = pair.penetration(POSES[i], stiffness=stiffness)
    same(got.volume, want["volume"])
    same(got.max_depth, want["max_depth"])
    same(got.normal, want["normal"])
    same(got.force, want["force"])
    same(got.torque_a, want["torque_a"])
    same(got.torque_b, want["torque_b"])
    same(got.distance, want["distance"])
    assert (got.pairs, got.contact, got.visits) == (want["pairs"], want["contact"], want["visits"])
    assert len(got.patches) == len(want["patches"])
    for p, w in zip(got.patches, want["patches"]):
        same(p["point"], w["point"])
        same(p["normal"], w["normal"])
        same(p["depth"], w["depth"])
        same(p["volume"], w["volume"])
        assert p["pairs"] == w["pairs"]
    assert_is_the_cli_answer(got.to_dict(), want)


@pytest.mark.parametrize("i", range(len(POSES)))
def test_traversals_equal_cli(pair, tree_files, ist, i):
    for kind in ("distance-traversal", "backtracking"):
        want = ist.query(*tree_files, POSES[i], kind)
        pair.reset()
        got = getattr(pair, kind.replace("-", "_"))(POSES[i])
        assert got is want["contact"], kind
    pair.reset()
    assert pair.distance_traversal(POSES[i]) == pair.contact(POSES[i])


@pytest.mark.parametrize("budget", [50, 100_000])
@pytest.mark.parametrize("i", range(len(POSES)))
def test_penetration_within_equals_cli(pair, tree_files, ist, i, budget):
    want = ist.query(*tree_files, POSES[i], "penetration-within", "--budget", str(budget), "--stiffness", "2.5")
    pair.reset()
    got = pair.penetration_within(POSES[i], budget, 2.5)
    assert_is_the_cli_answer(got, want, door=("budget",))
    for k in ("volume", "upper_bound", "max_depth", "normal", "force", "torque_b"):
        same(got[k], want[k])
    assert got["complete"] == want["complete"] and got["visits"] == want["visits"]
    assert got["volume"] <= got["upper_bound"]
    if got["complete"]:
        pair.reset()
        assert got["volume"] == pytest.approx(pair.penetration(POSES[i]).volume, rel=1e-6, abs=1e-12)


def test_some_poses_touch_and_some_do_not(pair):
    """The poses cover both sides of contact (else the tests above prove little)."""
    pair.reset()
    hits = [pair.contact(p) for p in POSES]
    assert any(hits) and not all(hits)
    pair.reset()
    assert pair.penetration(POSES[-1]).volume > 0.1


@pytest.mark.parametrize("i", range(len(POSES)))
def test_matrix_pose_equals_seven_numbers(pair, i):
    pair.reset()
    a = pair.distance(POSES[i])
    pair.reset()
    b = pair.distance(pose_matrix(POSES[i]))
    assert b.distance == pytest.approx(a.distance, abs=1e-6)
    assert b.contact == a.contact
    pair.reset()
    pa = pair.penetration(POSES[i])
    pair.reset()
    pb = pair.penetration(pose_matrix(POSES[i]))
    assert pb.volume == pytest.approx(pa.volume, rel=1e-5, abs=1e-9)


def test_identity_matrix_is_bitwise_the_identity(pair):
    pair.reset()
    a = pair.penetration([0, 0, 0, 1, 0, 0, 0])
    pair.reset()
    b = pair.penetration(np.eye(4))
    assert a.volume == b.volume


def test_pose_a_moves_a(pair):
    """Both bodies moved by the same rigid motion: the same distance, points moved along."""
    move = [0.3, -2.0, 1.0, 0.0, 0.0, 0.0, 1.0]  # 180° about z, then a translation
    m = pose_matrix(move)
    for p in POSES[2:6]:
        pair.reset()
        base = pair.distance(p)
        pair.reset()
        both = pair.distance(m @ pose_matrix(p), pose_a=move)
        assert both.distance == pytest.approx(base.distance, abs=1e-5)
        moved = m[:3, :3] @ base.point_a + m[:3, 3]
        if base.distance > 0:
            assert np.allclose(both.point_a, moved, atol=1e-4)


def test_coherent_answers_equal_fresh_ones(trees):
    """The pair's carried state speeds queries up; it does not change near answers."""
    warm = innersphere.Pair(*trees)
    for p in POSES[2:]:
        fresh = innersphere.Pair(*trees)
        assert warm.distance(p).distance == fresh.distance(p).distance
        assert warm.contact(p) == fresh.contact(p)
        assert warm.penetration(p).volume == fresh.penetration(p).volume


def test_pair_keeps_its_trees(trees):
    pair = innersphere.Pair(*trees)
    assert pair.tree_a is trees[0] and pair.tree_b is trees[1]
    assert "Pair(" in repr(pair)


@pytest.mark.parametrize("i", range(len(POSES)))
def test_refined_distance_equals_cli(trees, tree_files, mesh_files, ist, i):
    want = ist.query(*tree_files, POSES[i], "refined-distance", "--meshes", *mesh_files)
    pair = innersphere.Pair(trees[0].with_mesh(str(mesh_files[0])), trees[1].with_mesh(mesh_files[1]))
    got = pair.refined_distance(POSES[i])
    assert_is_the_cli_answer(got, want)
    for k in ("distance", "radius", "point_a", "point_b"):
        same(got[k], want[k])
    for k in ("contact", "refined", "complete", "triangle_a", "triangle_b", "node_pairs", "triangle_pairs"):
        assert got[k] == want[k], k
    assert got["distance"] <= got["spheres"]["distance"]


def test_refined_distance_needs_the_trees_meshes(trees, meshes):
    a, b = trees
    assert not a.has_mesh
    with pytest.raises(ValueError, match="with_mesh"):
        innersphere.Pair(a, b).refined_distance(POSES[0])
    with pytest.raises(ValueError, match="not the mesh"):
        a.with_mesh(meshes["ellipsoid"])
    am, bm = a.with_mesh(meshes["box"]), b.with_mesh(meshes["ellipsoid"])
    assert am.has_mesh and not a.has_mesh
    with pytest.raises(ValueError, match="radius_scale"):
        innersphere.Pair(am, bm).refined_distance(POSES[0], radius_scale=-1.0)
    r = innersphere.Pair(am, bm).refined_distance(POSES[2])
    assert r["distance"] <= r["spheres"]["distance"] and not r["contact"]


@pytest.mark.parametrize("i", range(len(POSES)))
def test_mesh_penetration_equals_cli(trees, tree_files, mesh_files, ist, i):
    want = ist.query(*tree_files, POSES[i], "mesh-penetration", "--meshes", *mesh_files, "--stiffness", "2.5")
    pair = innersphere.Pair(trees[0].with_mesh(str(mesh_files[0])), trees[1].with_mesh(mesh_files[1]))
    got = pair.mesh_penetration(POSES[i], stiffness=2.5)
    assert_is_the_cli_answer(got, want)
    assert got["contact"] == (got["volume"] > 0)
    if got["contact"]:
        # The force is the stiffness times the volume, along the unit normal.
        assert np.allclose(got["force"], 2.5 * got["volume"] * np.asarray(got["normal"]), rtol=1e-12, atol=0)


def test_mesh_penetration_needs_the_trees_meshes(trees):
    with pytest.raises(ValueError, match="with_mesh"):
        innersphere.Pair(*trees).mesh_penetration(POSES[-1])
