"""The batch queries against `ist replay --csv` on a generated motion and against single
calls; load_motion."""

import numpy as np
import pytest

import innersphere
from helpers import chew_motion, pose_matrix, write_motion


@pytest.fixture(scope="module")
def motion(tmp_path_factory):
    """A generated motion file: (path, t, poses as written)."""
    t, poses = chew_motion(400)
    path = tmp_path_factory.mktemp("motion") / "chew.csv"
    write_motion(path, t, poses)
    return path, t, poses


@pytest.fixture(scope="module")
def loaded(motion):
    return innersphere.load_motion(motion[0])


def test_load_motion(motion, loaded):
    path, t, poses = motion
    lt, lp = loaded
    assert lt.shape == (400,) and lp.shape == (400, 7)
    assert lt.dtype == np.float64 and lp.dtype == np.float64
    # The file's numbers, as written with 9 decimals.
    assert np.array_equal(lt, np.round(t, 9))
    assert np.array_equal(lp, np.round(poses, 9))
    assert np.array_equal(innersphere.load_motion(str(path))[1], lp)
    assert np.array_equal(innersphere.load_motion(bytes(path))[1], lp)


def test_load_motion_gz(motion, loaded, tmp_path):
    import gzip

    gz = tmp_path / "chew.csv.gz"
    gz.write_bytes(gzip.compress(motion[0].read_bytes()))
    t, p = innersphere.load_motion(gz)
    assert np.array_equal(t, loaded[0]) and np.array_equal(p, loaded[1])


def test_distance_many_equals_replay(trees, tree_files, ist, motion, loaded, tmp_path):
    csv = ist.replay_csv(*tree_files, motion[0], "distance", tmp_path / "d.csv")
    want = np.array([float(x) for x in csv["distance"]])
    got = innersphere.Pair(*trees).distance_many(loaded[1])
    assert got.shape == (400,) and got.dtype == np.float64
    assert np.array_equal(got, want)
    contact = np.array([x == "true" for x in csv["distance_in_contact"]])
    assert contact.any() and not contact.all()
    assert np.array_equal(got == 0, contact)


def test_penetration_many_equals_replay(trees, tree_files, ist, motion, loaded, tmp_path):
    csv = ist.replay_csv(*tree_files, motion[0], "penetration", tmp_path / "p.csv")
    got = innersphere.Pair(*trees).penetration_many(loaded[1])
    assert np.array_equal(got["volume"], np.array([float(x) for x in csv["penetration_volume"]]))
    assert np.array_equal(got["pairs"], np.array([int(x) for x in csv["penetration_pairs"]]))
    assert np.array_equal(got["contact"], np.array([x == "true" for x in csv["penetration_in_contact"]]))
    n = len(loaded[1])
    for k, shape in [("volume", (n,)), ("max_depth", (n,)), ("force", (n, 3)), ("torque_b", (n, 3)),
                     ("torque_a", (n, 3)), ("normal", (n, 3)), ("pairs", (n,)), ("contact", (n,))]:
        assert got[k].shape == shape, k
    assert got["volume"].max() > 0


def test_contact_many_equals_replay(trees, tree_files, ist, motion, loaded, tmp_path):
    csv = ist.replay_csv(*tree_files, motion[0], "contact", tmp_path / "c.csv")
    got = innersphere.Pair(*trees).contact_many(loaded[1])
    assert got.dtype == np.bool_
    assert np.array_equal(got, np.array([x == "true" for x in csv["contact_in_contact"]]))


def test_batches_equal_single_calls(trees, loaded):
    """A batch is the single query pose after pose on the same pair, state carried."""
    poses = loaded[1]
    one, many = innersphere.Pair(*trees), innersphere.Pair(*trees)
    d = many.distance_many(poses)
    assert np.array_equal(d, [one.distance(p).distance for p in poses])
    one, many = innersphere.Pair(*trees), innersphere.Pair(*trees)
    pen = many.penetration_many(poses, stiffness=3.0)
    singles = [one.penetration(p, stiffness=3.0) for p in poses]
    assert np.array_equal(pen["volume"], [s.volume for s in singles])
    assert np.array_equal(pen["max_depth"], [s.max_depth for s in singles])
    assert np.array_equal(pen["force"], [s.force for s in singles])
    assert np.array_equal(pen["torque_b"], [s.torque_b for s in singles])
    assert np.array_equal(pen["stiffness"]["linear"], [s.stiffness["linear"] for s in singles])
    assert np.array_equal(pen["torque_a"], [s.torque_a for s in singles])
    assert np.array_equal(pen["normal"], [s.normal for s in singles])
    one, many = innersphere.Pair(*trees), innersphere.Pair(*trees)
    assert np.array_equal(many.contact_many(poses), [one.contact(p) for p in poses])


def test_batches_agree_with_fresh_pairs(trees, loaded):
    """Carrying the state does not change the answers near contact."""
    poses = loaded[1][::20]
    d = innersphere.Pair(*trees).distance_many(poses)
    pair = innersphere.Pair(*trees)
    fresh = []
    for p in poses:
        pair.reset()
        fresh.append(pair.distance(p).distance)
    near = d < 1.0
    assert np.array_equal(d[near], np.array(fresh)[near])
    assert np.allclose(d, fresh, atol=1e-3)


def test_matrix_batches(trees, loaded):
    poses = loaded[1][::10]
    mats = np.array([pose_matrix(p) for p in poses])
    d7 = innersphere.Pair(*trees).distance_many(poses)
    d44 = innersphere.Pair(*trees).distance_many(mats)
    assert np.allclose(d7, d44, atol=1e-6)
    v7 = innersphere.Pair(*trees).penetration_many(poses)["volume"]
    v44 = innersphere.Pair(*trees).penetration_many(mats)["volume"]
    assert np.allclose(v7, v44, rtol=1e-5, atol=1e-9)


def test_batch_pose_a(trees, loaded):
    """pose_a: one pose for all, or one per frame; the same rigid motion of both bodies
    leaves the distances as they were."""
    poses = loaded[1][::10]
    base = innersphere.Pair(*trees).distance_many(poses)
    move = [0.5, 1.0, -2.0, 0.0, 1.0, 0.0, 0.0]  # 180° about x, then a translation
    m = pose_matrix(move)
    moved = np.array([m @ pose_matrix(p) for p in poses])
    one = innersphere.Pair(*trees).distance_many(moved, pose_a=move)
    each = innersphere.Pair(*trees).distance_many(moved, pose_a=np.repeat([move], len(poses), axis=0))
    assert np.array_equal(one, each)
    assert np.allclose(one, base, atol=1e-5)
    same_as_identity = innersphere.Pair(*trees).distance_many(poses, pose_a=np.eye(4))
    assert np.array_equal(same_as_identity, base)


def test_empty_batch(trees):
    pair = innersphere.Pair(*trees)
    assert pair.distance_many(np.zeros((0, 7))).shape == (0,)
    assert pair.penetration_many(np.zeros((0, 4, 4)))["force"].shape == (0, 3)


def test_batch_accepts_lists_and_other_dtypes(trees):
    pair = innersphere.Pair(*trees)
    a = pair.distance_many([[3, 0, 0, 1, 0, 0, 0], [2.5, 0, 0, 1, 0, 0, 0]])
    b = pair.distance_many(np.array([[3, 0, 0, 1, 0, 0, 0], [2.5, 0, 0, 1, 0, 0, 0]], dtype=np.float32))
    c = pair.distance_many(np.asfortranarray([[3.0, 0, 0, 1, 0, 0, 0], [2.5, 0, 0, 1, 0, 0, 0]]))
    assert np.array_equal(a, b) and np.array_equal(a, c)
    assert a[0] == pytest.approx(1.4, abs=0.05)


def test_threads(trees, loaded):
    """Batches release the interpreter: pairs query from threads side by side; one pair used
    from two threads at once answers one and refuses the other, never crashes."""
    import threading

    poses = np.tile(loaded[1], (5, 1))
    want = innersphere.Pair(*trees).distance_many(poses)
    out, errors = {}, []

    def run(key, pair):
        try:
            out[key] = pair.distance_many(poses)
        except RuntimeError as e:  # the pair is busy in the other thread
            errors.append(e)

    threads = [threading.Thread(target=run, args=(i, innersphere.Pair(*trees))) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors and all(np.array_equal(out[i], want) for i in range(2))
    shared = innersphere.Pair(*trees)
    out.clear()
    threads = [threading.Thread(target=run, args=(i, shared)) for i in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(out) + len(errors) == 2 and len(out) >= 1
    assert all(v.shape == want.shape and np.isfinite(v).all() for v in out.values())


def test_refined_distance_many_equals_single_calls(trees, meshes, loaded):
    """The refined batch is the single query pose after pose on one pair (one chunk), and
    chunks of 7 on any thread count give the same bits as a pair reset every 7 poses."""
    am, bm = trees[0].with_mesh(meshes["box"]), trees[1].with_mesh(meshes["ellipsoid"])
    poses = loaded[1][::4]
    got = innersphere.Pair(am, bm).refined_distance_many(poses, threads=2)
    one = innersphere.Pair(am, bm)
    singles = [one.refined_distance(p) for p in poses]
    n = len(poses)
    for k, shape in [("distance", (n,)), ("contact", (n,)), ("refined", (n,)), ("complete", (n,)),
                     ("point_a", (n, 3)), ("point_b", (n, 3)), ("triangle_a", (n,)),
                     ("triangle_b", (n,))]:
        assert got[k].shape == shape, k
    assert got["spheres"]["distance"].shape == (n,) and got["spheres"]["point_a"].shape == (n, 3)
    for k in ("distance", "contact", "refined", "complete", "point_a", "point_b"):
        assert np.array_equal(got[k], [s[k] for s in singles]), k
    assert np.array_equal(got["spheres"]["distance"], [s["spheres"]["distance"] for s in singles])
    for k in ("triangle_a", "triangle_b"):
        assert np.array_equal(got[k], [-1 if s[k] is None else s[k] for s in singles]), k
    assert got["contact"].any() and not got["contact"].all()
    assert (got["distance"] <= got["spheres"]["distance"]).all()
    chunked = [innersphere.Pair(am, bm).refined_distance_many(poses, chunk=7, threads=t) for t in (1, 3)]
    reset = innersphere.Pair(am, bm)
    want = []
    for i, p in enumerate(poses):
        if i % 7 == 0:
            reset.reset()
        want.append(reset.refined_distance(p)["distance"])
    for c in chunked:
        assert np.array_equal(c["distance"], want)


def test_refined_distance_many_needs_the_meshes(trees, meshes, loaded):
    with pytest.raises(ValueError, match="with_mesh"):
        innersphere.Pair(*trees).refined_distance_many(loaded[1][:3])
    am, bm = trees[0].with_mesh(meshes["box"]), trees[1].with_mesh(meshes["ellipsoid"])
    with pytest.raises(ValueError, match="rel_tolerance"):
        innersphere.Pair(am, bm).refined_distance_many(loaded[1][:3], rel_tol=2.0)
    assert innersphere.Pair(am, bm).refined_distance_many(np.zeros((0, 7)))["point_a"].shape == (0, 3)


def test_mesh_penetration_many_equals_single_calls(trees, meshes, loaded):
    """The meshes' penetration batch is the single query pose after pose on one pair (one
    chunk), the same bits on any thread count; refused without the meshes."""
    with pytest.raises(ValueError, match="with_mesh"):
        innersphere.Pair(*trees).mesh_penetration_many(loaded[1][:3])
    am, bm = trees[0].with_mesh(meshes["box"]), trees[1].with_mesh(meshes["ellipsoid"])
    poses = loaded[1][::4]
    got = [innersphere.Pair(am, bm).mesh_penetration_many(poses, stiffness=2.0, threads=t) for t in (1, 2)]
    one = innersphere.Pair(am, bm)
    singles = [one.mesh_penetration(p, stiffness=2.0) for p in poses]
    n = len(poses)
    assert got[0]["volume"].shape == (n,) and got[0]["force"].shape == (n, 3)
    for k in ("contact", "volume", "force", "torque_b", "gradient", "max_depth", "patch_count"):
        for g in got:
            assert np.array_equal(g[k], [s[k] for s in singles]), k
    assert got[0]["contact"].any() and not got[0]["contact"].all()
