#!/usr/bin/env python3
"""Throughput of the batch queries: the local batch on 1 thread and on all, then
``innersphere.distributed.sweep`` on a LocalCluster of 1, 2, 4, ... worker processes (one
thread each), poses per second; every answer checked bit for bit against the local batch.

    python crates/innersphere-py/benches/sweep_throughput.py maxilla.ist mandible.ist \
        --poses 200000 --query distance --workers 1,2,4,8,2x8

``--independent 1,8,16`` adds K lone processes answering a batch each at once: the
machine's own ceiling for K cores, the linear a sweep is held to.

``--workers`` lists cluster layouts: ``W`` is W worker processes of one thread each, every
task on one core; ``WxT`` is W workers whose tasks each use T threads (``sweep(threads=T)``),
the layout of one worker per machine (or per socket) that lets the Rust batch share one copy
of the trees among its cores.

The poses: B around the identity (a scanned jaw pair's bite), ±2 mm and ±4° about its centre
of mass, from a fixed seed. Needs ``pip install "./crates/innersphere-py[distributed]"``.
"""

import argparse
import json
import multiprocessing as mp
import os
import time

import numpy as np
from dask.distributed import Client, LocalCluster

import innersphere
from innersphere import distributed as isd


def poses(n, centre, seed=1, mm=2.0, deg=4.0):
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    half = np.radians(rng.uniform(-deg, deg, n)) / 2
    w, (x, y, z) = np.cos(half), (np.sin(half)[:, None] * axis).T
    rot = np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], 1)
    t = centre - rot @ centre + rng.uniform(-mm, mm, (n, 3))
    return np.hstack([t, np.stack([w, x, y, z], -1)])


def same(a, b):
    if isinstance(a, dict):
        return all(same(a[k], b[k]) for k in a)
    return a.tobytes() == b.tobytes()


def _alone(a, b, n, query, barrier, out):
    """One process of --independent: the local batch on one thread, started with the others."""
    ta, tb = innersphere.Tree.load(a), innersphere.Tree.load(b)
    p = poses(n, np.asarray(tb.meta["center_of_mass"], float))
    method = getattr(innersphere.Pair(ta, tb), isd.QUERIES[query])
    method(p[:1024], threads=1, chunk=1)
    barrier.wait()
    t0 = time.perf_counter()
    method(p, threads=1, chunk=1)
    out.put(time.perf_counter() - t0)


def independent(args, k):
    """K processes answering the same batch each, none sharing anything: the machine's own
    ceiling for K cores (clock, caches and memory shared), the "linear" a sweep can reach."""
    ctx = mp.get_context("spawn")
    barrier, out = ctx.Barrier(k), ctx.Queue()
    n = max(1, args.poses // 16)
    procs = [ctx.Process(target=_alone, args=(args.a, args.b, n, args.query, barrier, out)) for _ in range(k)]
    for p in procs:
        p.start()
    times = [out.get() for _ in procs]
    for p in procs:
        p.join()
    return k * n / max(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--poses", type=int, default=200_000)
    ap.add_argument("--query", default="distance", choices=sorted(isd.QUERIES))
    ap.add_argument("--workers", default="1,2,4,8")
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--independent", default="", help="also K lone processes, e.g. 1,8,16")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args()
    a, b = innersphere.Tree.load(args.a), innersphere.Tree.load(args.b)
    p = poses(args.poses, np.asarray(b.meta["center_of_mass"], float))
    method = getattr(innersphere.Pair(a, b), isd.QUERIES[args.query])
    rows = []

    def timed(f):
        best, out = float("inf"), None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            out = f()
            best = min(best, time.perf_counter() - t0)
        return best, out

    # Scattered poses: every pose from a fresh state (chunk=1), the sweep's default.
    t1, want = timed(lambda: method(p, threads=1, chunk=1))
    rows.append({"what": "local batch", "threads": 1, "seconds": t1, "poses_per_s": args.poses / t1, "same": True})
    t, got = timed(lambda: method(p, chunk=1))
    rows.append({"what": "local batch", "threads": os.cpu_count(), "seconds": t, "poses_per_s": args.poses / t, "same": same(got, want)})
    for layout in args.workers.split(","):
        w, _, t = layout.partition("x")
        w, t = int(w), int(t or 1)
        cluster = LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        chunk = isd.balanced_chunk(args.poses, w)
        opts = {"query": args.query, "threads": t}
        # The trees sent once (as a cohort run would), the workers started.
        fa, fb = client.scatter([a, b], broadcast=True)
        isd.sweep(client, fa, fb, p[: 1024 * w], chunk=1024, **opts)
        s, got = timed(lambda: isd.sweep(client, fa, fb, p, **opts))  # the default chunk
        rows.append({"what": "sweep", "workers": w, "task_threads": t, "chunk": chunk, "seconds": s, "poses_per_s": args.poses / s, "same": same(got, want)})
        client.close()
        cluster.close()
    for k in [int(x) for x in args.independent.split(",") if x]:
        rows.append({"what": "independent", "processes": k, "poses_per_s": independent(args, k), "same": True})
    base = rows[0]["poses_per_s"]
    for r in rows:
        r["speedup"] = r["poses_per_s"] / base
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        print("%d poses, %s, %d cores" % (args.poses, args.query, os.cpu_count()))
        for r in rows:
            if "processes" in r:
                print("%-12s %-11s %10.0f poses/s  %5.2fx" % (r["what"], "processes %d" % r["processes"], r["poses_per_s"], r["speedup"]))
                continue
            who = "threads %s" % r["threads"] if "threads" in r else "workers %dx%d" % (r["workers"], r["task_threads"])
            print("%-12s %-11s %8.2f s %10.0f poses/s  %5.2fx  same=%s" % (r["what"], who, r["seconds"], r["poses_per_s"], r["speedup"], r["same"]))


if __name__ == "__main__":
    main()
