#!/usr/bin/env python3
"""Throughput of the batch queries: the local batch on 1 thread and on all, then
``innersphere.distributed.sweep`` on a LocalCluster of 1, 2, 4, ... worker processes (one
thread each), poses per second; every answer checked bit for bit against the local batch.

    python crates/innersphere-py/benches/sweep_throughput.py maxilla.ist mandible.ist \
        --poses 200000 --query distance --workers 1,2,4,8

The poses: B around the identity (a scanned jaw pair's bite), ±2 mm and ±4° about its centre
of mass, from a fixed seed. Needs ``pip install "./crates/innersphere-py[distributed]"``.
"""

import argparse
import json
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


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--poses", type=int, default=200_000)
    ap.add_argument("--query", default="distance", choices=sorted(isd.QUERIES))
    ap.add_argument("--workers", default="1,2,4,8")
    ap.add_argument("--repeat", type=int, default=2)
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
    for w in [int(x) for x in args.workers.split(",")]:
        cluster = LocalCluster(n_workers=w, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        chunk = max(1024, (args.poses // (8 * w)) // 1024 * 1024)
        # The trees sent once (as a cohort run would), the workers started.
        fa, fb = client.scatter([a, b], broadcast=True)
        isd.sweep(client, fa, fb, p[:2048], query=args.query, chunk=1024)
        t, got = timed(lambda: isd.sweep(client, fa, fb, p, query=args.query, chunk=chunk))
        rows.append({"what": "sweep", "workers": w, "chunk": chunk, "seconds": t, "poses_per_s": args.poses / t, "same": same(got, want)})
        client.close()
        cluster.close()
    base = rows[0]["poses_per_s"]
    for r in rows:
        r["speedup"] = r["poses_per_s"] / base
    if args.json:
        print(json.dumps(rows, indent=1))
    else:
        print("%d poses, %s, %d cores" % (args.poses, args.query, os.cpu_count()))
        for r in rows:
            who = "threads %s" % r["threads"] if "threads" in r else "workers %d" % r["workers"]
            print("%-12s %-11s %8.2f s %10.0f poses/s  %5.2fx  same=%s" % (r["what"], who, r["seconds"], r["poses_per_s"], r["speedup"], r["same"]))


if __name__ == "__main__":
    main()
