"""Pose sweeps and cohort builds on a Dask cluster (``pip install "innersphere[distributed]"``).

Dask distributed, not Ray: it runs on a laptop (``LocalCluster``), on HPC schedulers
(dask-jobqueue: SLURM, PBS, SGE) and on Kubernetes with the same ``Client``; it ships numpy
arrays without copies, retries failed tasks, replaces lost workers' work, and shows every task
on its dashboard; its futures keep their order. Ray would do the same for this workload but
brings its own object store and runtime to install for what is a map over chunks.

- ``sweep(client, tree_a, tree_b, poses, query=...)``: one query kind over many poses of B,
  in chunks across the workers. Returns exactly what ``Pair(tree_a, tree_b).<query>_many``
  returns on one machine (the same bits: a task's chunk is a whole number of the batch's
  fresh-state chunks).
- ``build_many(client, meshes, out_dir, preset=...)``: one tree per mesh across the workers;
  every item's outcome (tree file or error) is reported.
- ``contact_map_many(client, pairs)``: the occlusion map (``contact_map``) of many arch
  pairs.
- ``occlude_many(client, pairs, from_poses)``: the bite (``occlude``) of many jaw pairs.

A sweep sends its trees once to every worker (``client.scatter(..., broadcast=True)``; a
``Tree`` pickles as its file's bytes, and its mesh's arrays when it carries one), where they stay for all its chunks. To send them once
for many sweeps, scatter them yourself and pass the futures:
``fa, fb = client.scatter([tree_a, tree_b], broadcast=True)``. (Content-keyed scatters,
``hash=True``, are not used: a later sweep re-scattering the key while the scheduler releases
the earlier sweep's copy loses the data, and the tasks fail or wait forever.) Meshes and output
folders of ``build_many`` / ``contact_map_many`` are paths every worker can read and write (a
shared file system), as in a cohort study's data folder.
"""

from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

try:
    from dask.distributed import Client, Future, progress as _dask_progress, wait
except ImportError as e:  # pragma: no cover - exercised only without the extra
    raise ImportError(
        'innersphere.distributed needs Dask distributed: pip install "innersphere[distributed]" '
        '(or pip install "dask[distributed]")'
    ) from e

try:  # what wait raises for cancelled futures (distributed ≥ 2024; asyncio's before)
    from distributed.client import FuturesCancelledError as _Cancelled
except ImportError:  # pragma: no cover
    from asyncio import CancelledError as _Cancelled  # type: ignore[assignment]

from ._innersphere import Pair, Tree, contact_map, occlude

__all__ = ["sweep", "balanced_chunk", "build_many", "contact_map_many", "occlude_many", "QUERIES"]

#: The query kinds of ``sweep`` and the batch method each one runs.
QUERIES = {
    "distance": "distance_many",
    "refined-distance": "refined_distance_many",
    "contact": "contact_many",
    "penetration": "penetration_many",
}

_TreeLike = Union[Tree, str, "os.PathLike[str]", Future]


def _tree(t: _TreeLike) -> Union[Tree, Future]:
    if isinstance(t, (Tree, Future)):
        return t
    if isinstance(t, (str, os.PathLike)):
        return Tree.load(t)
    raise TypeError(f"a tree must be a Tree or a path to a .ist file, not {type(t).__name__}")


def _poses(p: Any, name: str) -> np.ndarray:
    arr = np.ascontiguousarray(np.asarray(p, dtype=np.float64))
    if arr.ndim == 2 and arr.shape[1] == 7 or arr.ndim == 3 and arr.shape[1:] == (4, 4):
        return arr
    raise ValueError(f"{name}: expected an (N, 7) or (N, 4, 4) array, got shape {arr.shape}")


def _sweep_chunk(
    tree_a: Tree,
    tree_b: Tree,
    poses: np.ndarray,
    pose_a: Optional[np.ndarray],
    method: str,
    kwargs: Dict[str, Any],
) -> Any:
    """One task: the local batch call on one chunk of poses (runs on a worker)."""
    return getattr(Pair(tree_a, tree_b), method)(poses, pose_a=pose_a, **kwargs)


def _show(futures: List[Future], progress: bool) -> None:
    if progress:
        _dask_progress(futures)
    wait(futures)


def _each_or_error(futures: List[Future], progress: bool) -> List[Any]:
    """Every task's result in order, or the exception it raised in its place."""
    _show(futures, progress)
    out: List[Any] = []
    for f in futures:
        try:
            out.append(f.result())
        except Exception as e:
            out.append(e)
    return out


DEFAULT_TASK_POSES = 65536
"""The most poses ``balanced_chunk`` puts in one task unless told (about a second of
distance on one core of the jaw pair)."""

TASK_POSES = {
    "distance": DEFAULT_TASK_POSES,
    "refined-distance": 16384,
    "contact": DEFAULT_TASK_POSES,
    "penetration": 1024,
}
"""The most poses ``sweep`` puts in one task by default, per query: about a second of one
core's work on the jaw pair (penetration answers ~700 poses a second, the refined distance
~20,000, distance ~55,000), so that a lost worker's task is cheap to redo."""

MIN_TASK_POSES = 1024
"""The fewest poses ``sweep`` puts in one task by default, where there are poses enough:
below it a task's fixed cost (milliseconds) outweighs its work."""

TASKS_PER_THREAD = 4
"""About how many tasks ``sweep`` gives each worker thread by default: enough that a lost
worker costs little and Dask's stealing can even out a slow core, few enough that per-task
costs (scheduling, sending the chunk and its answers) stay small."""


def balanced_chunk(n: int, threads: int, batch_chunk: int = 1, most: int = DEFAULT_TASK_POSES) -> int:
    """Poses per task that split ``n`` poses into equal tasks, a whole number of rounds of
    ``threads`` worker threads, at most ``most`` each, and none much under ``MIN_TASK_POSES``
    (or ``most``, if smaller) unless ``n`` is (rounded up to a multiple of ``batch_chunk``)."""
    threads, most = max(1, threads), max(1, most)
    need = -(-n // most)
    tasks = max(need, min(threads * TASKS_PER_THREAD, n // min(MIN_TASK_POSES, most)), 1)
    if tasks >= threads:
        down = tasks // threads * threads
        tasks = down if down >= need else -(-tasks // threads) * threads
    per = max(1, -(-n // tasks))
    return -(-per // batch_chunk) * batch_chunk


def sweep(
    client: Client,
    tree_a: _TreeLike,
    tree_b: _TreeLike,
    poses: Any,
    query: str = "distance",
    chunk: Optional[int] = None,
    *,
    pose_a: Any = None,
    stiffness: float = 1.0,
    batch_chunk: int = 1,
    threads: int = 1,
    retries: int = 3,
    progress: bool = False,
) -> Any:
    """``Pair(tree_a, tree_b).<query>_many(poses, pose_a=pose_a, chunk=batch_chunk)`` across
    the cluster of ``client``, the same arrays bit for bit and in input order.

    tree_a, tree_b: ``Tree`` objects or paths of ``.ist`` files (read here, then sent once to
        every worker), or futures of trees already scattered to the cluster (sent by the
        caller once for many sweeps).
    poses: B's poses, ``(N, 7)`` or ``(N, 4, 4)``. pose_a: None, one pose, or N poses.
    query: "distance" (float64 (N,)), "refined-distance" (a dict of arrays, as
        ``Pair.refined_distance_many``; both trees must carry their meshes, ``Tree.with_mesh``,
        which travel with them), "contact" (bool (N,)) or "penetration" (a dict of arrays, as
        ``Pair.penetration_many``; ``stiffness`` applies).
    chunk: poses per task; a multiple of ``batch_chunk`` (each task answers its poses in
        fresh-state chunks of ``batch_chunk``, exactly as the local call does). None (the
        default): equal tasks, as many as a whole number of rounds of the cluster's worker
        threads needs with at most ``TASK_POSES[query]`` poses each and about
        ``TASKS_PER_THREAD`` per thread (so no worker idles through a last, partial round,
        and a lost worker's tasks are small).
    batch_chunk: the local call's ``chunk``: 1 (the default) answers every pose from a fresh
        state, right for scattered poses (a tolerance study, a data set: a state carried
        between unrelated poses costs 1.4× for distance, 9× for penetration on the jaw);
        a motion's poses gain from long chunks (e.g. 1024).
    threads: threads per task (1: one core per Dask worker thread, the cluster's parallelism
        is its workers'; None: all the worker machine's cores).
    retries: how often the engine reruns a failed task (a task of a lost worker is rerun
        elsewhere regardless).
    progress: show Dask's progress bar while the tasks run (the dashboard shows them anyway).
    """
    if query not in QUERIES:
        raise ValueError(f"query must be one of {', '.join(QUERIES)}, not {query!r}")
    if chunk is not None and (not isinstance(chunk, int) or chunk < 1):
        raise ValueError("chunk must be None or a positive integer")
    if not isinstance(batch_chunk, int) or batch_chunk < 1:
        raise ValueError("batch_chunk must be a positive integer")
    if chunk is not None and chunk % batch_chunk:
        raise ValueError(
            f"chunk ({chunk}) must be a multiple of batch_chunk ({batch_chunk}): a task starts a "
            "fresh state where the local batch does"
        )
    b = _poses(poses, "poses")
    n = len(b)
    a_each: Optional[np.ndarray] = None
    a_one: Any = None
    if pose_a is not None:
        pa = np.asarray(pose_a, dtype=np.float64)
        if pa.shape in ((7,), (4, 4)):
            a_one = pa
        else:
            a_each = _poses(pa, "pose_a")
            if len(a_each) != n:
                raise ValueError(f"pose_a: {len(a_each)} poses for a batch of {n}")
    ta, tb = _tree(tree_a), _tree(tree_b)
    if query == "refined-distance" and any(isinstance(t, Tree) and not t.has_mesh for t in (ta, tb)):
        raise ValueError(
            "query 'refined-distance' needs both trees with their meshes: Tree.with_mesh(mesh)"
        )
    kwargs: Dict[str, Any] = {"chunk": batch_chunk, "threads": threads}
    if query == "penetration":
        kwargs["stiffness"] = stiffness
    method = QUERIES[query]
    if n == 0:
        ea = ta.result() if isinstance(ta, Future) else ta
        eb = tb.result() if isinstance(tb, Future) else tb
        return getattr(Pair(ea, eb), method)(b, pose_a=a_one, **kwargs)
    if chunk is None:
        chunk = balanced_chunk(n, sum(client.nthreads().values()), batch_chunk, TASK_POSES[query])
    # Fresh keys per sweep (hash=False): see the module's note on content-keyed scatters.
    def scatter() -> List[Any]:
        return [
            t if isinstance(t, Future) else client.scatter(t, broadcast=True, hash=False)
            for t in (ta, tb)
        ]

    trees = scatter()

    def submit(start: int) -> Future:
        part = b[start : start + chunk]
        pa_part = a_each[start : start + chunk] if a_each is not None else a_one
        return client.submit(
            _sweep_chunk, trees[0], trees[1], part, pa_part, method, kwargs, retries=retries, pure=False
        )

    starts = list(range(0, n, chunk))
    futures = [submit(start) for start in starts]
    if progress:
        _dask_progress(futures)
    # A lost worker can take the last copy of a scattered tree with it (the scheduler may
    # keep fewer replicas than were broadcast): the tasks that needed it are cancelled, and
    # run again on the trees scattered anew.
    for attempt in range(retries + 1):
        try:
            wait(futures)
        except _Cancelled:
            pass
        lost = [k for k, f in enumerate(futures) if f.status == "cancelled"]
        if not lost:
            break
        if attempt == retries or any(isinstance(t, Future) for t in (ta, tb)):
            raise RuntimeError(
                f"{len(lost)} of {len(futures)} chunks were cancelled (a lost worker held the "
                "trees' last copy); sweep again, or scatter the trees anew"
            )
        trees = scatter()
        for k in lost:
            futures[k] = submit(starts[k])
    parts = client.gather(futures)
    for k, (start, part) in enumerate(zip(range(0, n, chunk), parts)):
        want = min(chunk, n - start)
        got = len(next(iter(part.values()))) if isinstance(part, dict) else len(part)
        if got != want:
            raise RuntimeError(f"chunk {k} came back with {got} answers for {want} poses")
    return _concatenate(parts)


def _concatenate(parts: List[Any]) -> Any:
    """The chunks' answers joined in order: arrays end to end, dicts of columns (nested, as a
    batch's answers are) key by key."""
    if isinstance(parts[0], dict):
        return {key: _concatenate([p[key] for p in parts]) for key in parts[0]}
    return np.concatenate(parts)


def _build_one(mesh: str, out: str, preset: Optional[str], options: Dict[str, Any]) -> Dict[str, Any]:
    """One task: build and save one tree; every failure is a reported outcome, not an error."""
    t0 = time.perf_counter()
    item: Dict[str, Any] = {"mesh": mesh, "tree": out, "ok": False, "error": None}
    try:
        import warnings

        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            tree = Tree.build(mesh, preset=preset, **options)
        tree.save(out)
        item.update(
            ok=True,
            spheres=tree.leaf_count,
            nodes=tree.node_count,
            warnings=[str(w.message) for w in caught],
        )
    except (OSError, ValueError) as e:
        item["error"] = f"{type(e).__name__}: {e}"
    item["seconds"] = time.perf_counter() - t0
    return item


def build_many(
    client: Client,
    meshes: Sequence[Union[str, "os.PathLike[str]"]],
    out_dir: Union[str, "os.PathLike[str]"],
    preset: Optional[str] = None,
    *,
    retries: int = 1,
    progress: bool = False,
    **options: Any,
) -> List[Dict[str, Any]]:
    """Builds one tree per mesh across the cluster into ``out_dir/<mesh name>.ist``.

    Returns one dict per mesh, in order: mesh, tree (the output path), ok, error (None, or
    the library's message: a bad mesh is one reported error while the rest build), spheres,
    nodes, warnings, seconds. ``preset`` and ``options`` are ``Tree.build``'s. Meshes and
    ``out_dir`` must be reachable from every worker. Two meshes that would write the same tree
    file are refused before anything runs.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [os.fspath(m) for m in meshes]
    targets = []
    for m in paths:
        name = Path(m).name
        for suffix in (".gz", ".stl", ".obj", ".ply", ".off", ".STL", ".OBJ", ".PLY", ".OFF"):
            if name.endswith(suffix):
                name = name[: -len(suffix)]
        targets.append(os.fspath(out / f"{name}.ist"))
    seen: Dict[str, str] = {}
    for m, t in zip(paths, targets):
        if t in seen:
            raise ValueError(f"{seen[t]} and {m} would both be written to {t}")
        seen[t] = m
    futures = [
        client.submit(_build_one, m, t, preset, options, retries=retries, pure=False)
        for m, t in zip(paths, targets)
    ]
    _show(futures, progress)
    results: List[Dict[str, Any]] = []
    for m, t, f in zip(paths, targets, futures):
        try:
            results.append(f.result())
        except Exception as e:  # the task itself died (a lost worker beyond its retries)
            results.append({"mesh": m, "tree": t, "ok": False, "error": f"{type(e).__name__}: {e}"})
    return results


def _map_one(a: str, b: str, pose_b: Any, pose_a: Any) -> Tuple[np.ndarray, np.ndarray]:
    return contact_map(a, b, pose_b=pose_b, pose_a=pose_a)


def contact_map_many(
    client: Client,
    pairs: Sequence[Tuple[Any, Any]],
    poses_b: Optional[Sequence[Any]] = None,
    *,
    retries: int = 1,
    progress: bool = False,
) -> List[Any]:
    """``contact_map(a, b, pose_b)`` for each mesh pair ``(a, b)`` (paths every worker can
    read), across the cluster, in order: per pair the two gap arrays, or the exception
    raised for that pair (one bad pair does not lose the others)."""
    poses = list(poses_b) if poses_b is not None else [None] * len(pairs)
    if len(poses) != len(pairs):
        raise ValueError(f"{len(poses)} poses for {len(pairs)} pairs")
    futures = [
        client.submit(_map_one, os.fspath(a), os.fspath(b), p, None, retries=retries, pure=False)
        for (a, b), p in zip(pairs, poses)
    ]
    return _each_or_error(futures, progress)


def _occlude_one(a: _TreeLike, b: _TreeLike, from_pose: Any, options: Dict[str, Any]) -> Dict[str, Any]:
    return occlude(_tree(a), _tree(b), from_pose, **options)  # type: ignore[arg-type]


def occlude_many(
    client: Client,
    pairs: Sequence[Tuple[_TreeLike, _TreeLike]],
    from_poses: Any,
    *,
    retries: int = 1,
    progress: bool = False,
    **options: Any,
) -> List[Any]:
    """``occlude(a, b, from_pose, **options)`` for each jaw pair ``(a, b)`` (``Tree``
    objects, or paths of ``.ist`` files every worker can read), across the cluster, in
    order: per pair the bite's dict, or the exception raised for that pair (one bad pair
    does not lose the others; a pair that cannot bite is a ValueError there, and a bite that
    did not converge says so in its ``status``). ``from_poses``: one start per pair, or one
    pose for all. ``options`` are ``occlude``'s (``free=True, starts=…`` runs each free
    closing on one worker's cores)."""
    one = np.asarray(from_poses, dtype=np.float64)
    poses = [one] * len(pairs) if one.shape in ((7,), (4, 4)) else list(one)
    if len(poses) != len(pairs):
        raise ValueError(f"{len(poses)} start poses for {len(pairs)} pairs")
    futures = [
        client.submit(
            _occlude_one,
            a if isinstance(a, (Tree, Future)) else os.fspath(a),
            b if isinstance(b, (Tree, Future)) else os.fspath(b),
            p,
            options,
            retries=retries,
            pure=False,
        )
        for (a, b), p in zip(pairs, poses)
    ]
    return _each_or_error(futures, progress)
