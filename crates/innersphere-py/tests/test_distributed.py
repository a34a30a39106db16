"""innersphere.distributed on a Dask LocalCluster of 2 worker processes, and the local
batches' threads: the same arrays bit for bit as the local batch call, a worker killed
mid-sweep, a bad mesh among good ones."""

import os
import threading
import time

import numpy as np
import pytest

import innersphere
from helpers import box_mesh, icosphere, write_obj

distributed = pytest.importorskip("dask.distributed")
from innersphere import distributed as isd  # noqa: E402


def random_poses(n, seed, spread=1.6):
    """Poses of B around A: overlapping, touching and apart (random unit quaternions)."""
    rng = np.random.default_rng(seed)
    t = rng.uniform(-spread, spread, (n, 3))
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    return np.hstack([t, q])


def same(a, b):
    """Equal bit for bit (arrays, or dicts of arrays)."""
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    return a.dtype == b.dtype and a.shape == b.shape and a.tobytes() == b.tobytes()


@pytest.fixture(scope="module")
def client():
    if os.environ.get("INNERSPHERE_NO_CLUSTER"):
        # The mutation harness (tests/python_suite.rs) runs the local batches only.
        pytest.skip("INNERSPHERE_NO_CLUSTER is set")
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    c = distributed.Client(cluster)
    c.wait_for_workers(2, timeout=120)
    yield c
    c.close()
    cluster.close()


@pytest.mark.parametrize("query", ["distance", "contact", "penetration"])
def test_local_batches_give_the_same_bits_on_any_number_of_threads(trees, query):
    poses = random_poses(3000, 1)
    pair = innersphere.Pair(*trees)
    method = getattr(pair, isd.QUERIES[query])
    one = method(poses, threads=1, chunk=100)
    for threads in (2, 4, None):
        assert same(method(poses, threads=threads, chunk=100), one)
    # A chunk holding the whole batch is the single query pose after pose on a new pair.
    whole = method(poses[:500], threads=3, chunk=500)
    fresh = innersphere.Pair(*trees)
    if query == "distance":
        assert np.array_equal(whole, [fresh.distance(p).distance for p in poses[:500]])
    elif query == "contact":
        assert np.array_equal(whole, [fresh.contact(p) for p in poses[:500]])
    else:
        assert np.array_equal(whole["volume"], [fresh.penetration(p).volume for p in poses[:500]])


def test_bad_batch_options_are_errors(trees):
    pair = innersphere.Pair(*trees)
    with pytest.raises(ValueError, match="chunk"):
        pair.distance_many(random_poses(3, 2), chunk=0)
    with pytest.raises(ValueError, match="threads"):
        pair.distance_many(random_poses(3, 2), threads=1 << 20)
    with pytest.raises(OverflowError):
        pair.distance_many(random_poses(3, 2), threads=-1)


@pytest.mark.parametrize("query", ["distance", "contact", "penetration"])
def test_sweep_equals_the_local_batch(client, trees, tree_files, query):
    poses = random_poses(5000, 3)
    local = getattr(innersphere.Pair(*trees), isd.QUERIES[query])(poses, chunk=64)
    got = isd.sweep(client, *trees, poses, query=query, chunk=640, batch_chunk=64)
    assert same(got, local)
    # The defaults: every pose from a fresh state, as the local call with chunk=1.
    local1 = getattr(innersphere.Pair(*trees), isd.QUERIES[query])(poses, chunk=1)
    assert same(isd.sweep(client, *trees, poses, query=query, chunk=1000), local1)
    assert same(isd.sweep(client, *trees, poses, query=query), local1)  # the balanced chunk
    assert same(isd.sweep(client, *trees, poses, query=query, batch_chunk=64), local)
    # Trees as paths, 4×4 matrices, a moving A.
    pa = random_poses(5000, 4, spread=0.1)
    local = getattr(innersphere.Pair(*trees), isd.QUERIES[query])(poses, pose_a=pa, chunk=64)
    got = isd.sweep(client, *tree_files, poses, query=query, chunk=1280, batch_chunk=64, pose_a=pa)
    assert same(got, local)


@pytest.mark.time_limit(120)
def test_sweeps_of_the_same_trees_one_after_another(client, trees):
    # Each sweep scatters the trees anew: a content-keyed scatter raced the release of the
    # previous sweep's copy, and a sweep failed with lost data or waited forever.
    poses = random_poses(400, 8)
    local = innersphere.Pair(*trees).distance_many(poses)
    for _ in range(25):
        assert same(isd.sweep(client, *trees, poses, chunk=40), local)
    # Trees scattered once by the caller serve many sweeps.
    fa, fb = client.scatter(list(trees), broadcast=True)
    for _ in range(5):
        assert same(isd.sweep(client, fa, fb, poses, chunk=40), local)
    assert same(isd.sweep(client, fa, fb, poses[:0]), local[:0])


def test_the_default_chunk_fills_whole_rounds_of_the_workers():
    # 65 tasks on 8 workers ran a ninth round of one task while seven workers idled
    # (docs/results/sweep_scaling_16core.txt, run B); the default chunk leaves no such round.
    for n in [0, 1, 7, 1000, 1023, 1024, 5000, 40_000, 100_000, 10**6, 10**8 + 7]:
        for threads in [1, 2, 3, 8, 16, 64]:
            for batch in [1, 64, 1000]:
                for most in [isd.DEFAULT_TASK_POSES, 1024, 100]:
                    per = isd.balanced_chunk(n, threads, batch, most)
                    tasks = -(-n // per)
                    assert per % batch == 0 and per >= 1
                    if batch == 1:
                        assert per <= most or n < 2
                        if n >= min(most, isd.MIN_TASK_POSES):
                            assert per >= min(most, isd.MIN_TASK_POSES) // 2
                        if n >= threads * min(most, isd.MIN_TASK_POSES):
                            # Whole rounds of equal tasks: the threads' time in rounds is
                            # spent on poses (the old 65 tasks on 8 workers: 0.90).
                            rounds = -(-tasks // threads)
                            assert n / (rounds * threads * per) >= 0.95, (n, threads, per)


def test_sweep_refuses_bad_input(client, trees):
    poses = random_poses(10, 5)
    with pytest.raises(ValueError, match="query"):
        isd.sweep(client, *trees, poses, query="volume")
    with pytest.raises(ValueError, match="multiple"):
        isd.sweep(client, *trees, poses, chunk=100, batch_chunk=64)
    with pytest.raises(ValueError, match="chunk"):
        isd.sweep(client, *trees, poses, chunk=0)
    with pytest.raises(ValueError, match="batch_chunk"):
        isd.sweep(client, *trees, poses, batch_chunk=0)
    with pytest.raises(ValueError, match="shape"):
        isd.sweep(client, *trees, poses[:, :5])
    with pytest.raises(ValueError, match="pose_a"):
        isd.sweep(client, *trees, poses, pose_a=poses[:3])
    assert isd.sweep(client, *trees, poses[:0]).shape == (0,)


def sweep_killing(client, trees, poses, pick):
    """A penetration sweep of `poses` (chunks of 160, batch chunks of 16) that kills worker
    `pick(busy)` (`busy`: the workers running a chunk) as soon as a chunk runs; its nanny
    starts a new one. Returns (what the sweep returned, or None if it raised; the victim)."""
    out = {}

    def run():
        out["got"] = isd.sweep(client, *trees, poses, query="penetration", chunk=160, batch_chunk=16)

    th = threading.Thread(target=run)
    th.start()
    victim = None
    deadline = time.time() + 60
    while victim is None and time.time() < deadline:
        busy = [w for w, tasks in client.processing().items() if tasks]
        if busy:
            victim = pick(busy)
        else:
            time.sleep(0.01)
    assert victim is not None, "no task ran"
    try:
        client.run(os._exit, 1, workers=[victim])
    except Exception:
        pass  # the worker died under the call
    th.join(timeout=300)
    assert not th.is_alive()
    return out.get("got"), victim


def test_a_worker_killed_mid_sweep_loses_nothing(client, trees):
    poses = random_poses(40000, 6)
    local = innersphere.Pair(*trees).penetration_many(poses, chunk=16)
    before = set(client.scheduler_info()["workers"])
    got, victim = sweep_killing(client, trees, poses, lambda busy: busy[0])
    assert got is not None and same(got, local)
    client.wait_for_workers(2, timeout=60)
    assert victim not in set(client.scheduler_info()["workers"]) and victim in before


def test_build_many_reports_a_bad_mesh_and_builds_the_rest(client, tmp_path):
    good = []
    for k, (v, f) in enumerate([box_mesh(), icosphere(2, 0.8), box_mesh(hi=(2.0, 1.0, 0.5))]):
        p = tmp_path / f"m{k}.obj"
        write_obj(p, v, f)
        good.append(p)
    bad = tmp_path / "broken.stl"
    bad.write_bytes(b"solid x\nfacet normal 0 0 1\n outer loop\n vertex 0 0")
    missing = tmp_path / "missing.obj"
    out = tmp_path / "trees"
    res = isd.build_many(client, [good[0], bad, good[1], missing, good[2]], out, preset="fast")
    assert [r["ok"] for r in res] == [True, False, True, False, True]
    assert "broken.stl" in res[1]["mesh"] and res[1]["error"].startswith("ValueError")
    assert res[3]["error"].startswith(("OSError", "FileNotFoundError"))
    for r, m in zip([res[0], res[2], res[4]], good):
        t = innersphere.Tree.load(r["tree"])
        assert t.leaf_count == r["spheres"] > 0
        assert same(t.spheres, innersphere.Tree.build(str(m), preset="fast").spheres)
    with pytest.raises(ValueError, match="both"):
        isd.build_many(client, [good[0], tmp_path / "sub" / "m0.obj"], out)


def test_contact_map_many_keeps_order_and_reports_a_bad_pair(client, tmp_path):
    a, b = tmp_path / "a.obj", tmp_path / "b.obj"
    write_obj(a, *box_mesh())
    write_obj(b, *icosphere(2, 0.5))
    poses = [[1.2, 0, 0, 1, 0, 0, 0], [3.0, 0, 0, 1, 0, 0, 0]]
    res = isd.contact_map_many(client, [(a, b), (a, tmp_path / "none.obj"), (a, b)], [poses[0], None, poses[1]])
    for got, p in [(res[0], poses[0]), (res[2], poses[1])]:
        want = innersphere.contact_map(str(a), str(b), pose_b=p)
        assert all(same(x, y) for x, y in zip(got, want))
    assert isinstance(res[1], OSError)


def test_occlude_many_keeps_order_and_reports_a_bad_pair(client, tmp_path):
    from test_occlude import START, arch

    a = innersphere.Tree.build(arch(8.0, n=4), resolution=64)
    b = innersphere.Tree.build(arch(0.0, n=4), resolution=64)
    pa, pb = tmp_path / "a.ist", tmp_path / "b.ist"
    a.save(pa)
    b.save(pb)
    lower = [0.0, 0.0, -1.0, 1.0, 0.0, 0.0, 0.0]
    pairs = [(pa, pb), (pa, tmp_path / "none.ist"), (a, b)]
    res = isd.occlude_many(client, pairs, [START, START, lower])
    assert res[0] == innersphere.occlude(a, b, START)
    assert isinstance(res[1], OSError)
    assert res[2] == innersphere.occlude(a, b, lower)
    # One start for all; options reach every pair.
    free = isd.occlude_many(client, [(pa, pb)] * 2, START, free=True, starts=3)
    assert free[0] == free[1] == innersphere.occlude(a, b, START, free=True, starts=3)
    with pytest.raises(ValueError, match="start poses"):
        isd.occlude_many(client, [(pa, pb)] * 3, [START, START])


def test_a_tree_with_its_mesh_pickles_with_it(trees, meshes):
    import pickle

    am = trees[0].with_mesh(meshes["box"])
    back = pickle.loads(pickle.dumps(am))
    assert back.has_mesh and not pickle.loads(pickle.dumps(trees[0])).has_mesh
    assert back.to_bytes() == am.to_bytes()
    bm = trees[1].with_mesh(meshes["ellipsoid"])
    poses = random_poses(40, 7)
    want = innersphere.Pair(am, bm).refined_distance_many(poses)
    assert same(innersphere.Pair(back, bm).refined_distance_many(poses), want)


def test_sweep_of_the_refined_distance_equals_the_local_batch(client, trees, tree_files, meshes):
    am, bm = trees[0].with_mesh(meshes["box"]), trees[1].with_mesh(meshes["ellipsoid"])
    poses = random_poses(2000, 5)
    local = innersphere.Pair(am, bm).refined_distance_many(poses, chunk=1)
    got = isd.sweep(client, am, bm, poses, query="refined-distance", chunk=500)
    assert same(got, local)
    assert got["contact"].any() and not got["contact"].all()
    with pytest.raises(ValueError, match="with_mesh"):
        isd.sweep(client, *trees, poses, query="refined-distance")
    with pytest.raises(ValueError, match="with_mesh"):
        isd.sweep(client, *tree_files, poses, query="refined-distance")


def test_the_trees_only_holder_killed_mid_sweep_loses_nothing(client, trees, monkeypatch):
    """The trees' only copy on a worker killed as the sweep starts (as when the scheduler
    keeps fewer replicas than were broadcast): the answers are the local batch's. Whether the
    other worker fetched a copy before the kill is a race; when it did not, its chunks are
    cancelled and must run again on trees scattered anew (before that, the sweep raised
    FuturesCancelledError)."""
    poses = random_poses(20000, 8)
    local = innersphere.Pair(*trees).penetration_many(poses, chunk=16)
    holder = sorted(client.scheduler_info()["workers"])[0]
    real = client.scatter
    calls = []

    def scatter(data, **kw):
        calls.append(kw)
        if len(calls) <= 2:  # the first sweep's two trees: on one worker only
            return real(data, workers=[holder], hash=False)
        return real(data, **kw)

    monkeypatch.setattr(client, "scatter", scatter)
    got, _ = sweep_killing(client, trees, poses, lambda busy: holder)
    assert got is not None, "the sweep raised"
    assert len(calls) in (2, 4), calls  # scattered again at most once
    assert same(got, local)
    client.wait_for_workers(2, timeout=60)
