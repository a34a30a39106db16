#!/usr/bin/env python3
"""A cohort run on Dask: build trees for several scans across the workers, then a seating
tolerance sweep of a million poses of the lower arch around the bite.

1. ``build_many``: one tree per mesh (the jaw pair and the two molars of ../shared/data by
   default, ``--meshes`` otherwise), every mesh's outcome reported.
2. ``sweep``: the mandible (B) placed at the bite (the scans' own frame) plus a random error of
   up to ±2 mm and ±4° (``--poses`` of them); per pose the exact gap (``distance``) and the
   penetration volume, force and torque. Prints how much misplacement the arches tolerate
   before they collide, and the throughput.
3. ``occlude_many``: the bite found again from several open starts (the lower arch 1 to 4 mm
   below the scanned bite), each closing on a worker: how far each bite is from the scan's.

Runs on a local cluster (``--workers`` processes, one thread each) unless ``--scheduler``
gives the address of a running one (``dask scheduler`` / ``dask worker``, dask-jobqueue,
Kubernetes); there the meshes and ``--out`` must be on a file system every worker sees.

    pip install "./crates/innersphere-py[distributed]"
    python examples/python/cohort_sweep.py                   # 1e6 poses on a local cluster
    python examples/python/cohort_sweep.py --scheduler tcp://10.0.0.5:8786 --out /shared/trees

Data: ../shared/data beside the repository, or $INNERSPHERE_DATA.
"""

import argparse
import os
import pathlib
import tempfile
import time

import numpy as np
from dask.distributed import Client, LocalCluster

import innersphere
from innersphere import distributed as isd

REPO = pathlib.Path(__file__).resolve().parents[2]
DATA = pathlib.Path(os.environ.get("INNERSPHERE_DATA", REPO.parent / "shared" / "data"))
JAW = [DATA / "jaw" / n for n in ("ofj_p26_maxilla_teeth.stl.gz", "ofj_p26_mandible_teeth.stl.gz",
                                  "ofj_p26_tooth03_upper_first_molar.stl",
                                  "ofj_p26_tooth30_lower_first_molar.stl")]


def perturbed(n, seed, mm, deg, center):
    """n poses of B: a rotation of up to `deg` degrees about a random axis through `center`
    and a translation of up to `mm` along each axis. Returns the (N, 7) poses (tx ty tz qw qx
    qy qz), each pose's largest translation error and its rotation angle (degrees)."""
    rng = np.random.default_rng(seed)
    axis = rng.normal(size=(n, 3))
    axis /= np.linalg.norm(axis, axis=1, keepdims=True)
    angle = np.radians(rng.uniform(-deg, deg, n))
    q = np.hstack([np.cos(angle / 2)[:, None], np.sin(angle / 2)[:, None] * axis])
    w, x, y, z = q.T
    rot = np.stack([
        np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
        np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
        np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
    ], 1)
    shift = rng.uniform(-mm, mm, (n, 3))
    t = center - rot @ center + shift
    return np.hstack([t, q]), np.abs(shift).max(axis=1), np.degrees(np.abs(angle))


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--meshes", nargs="+", type=pathlib.Path, default=JAW,
                    help="meshes to build; the first two are the sweep's A and B")
    ap.add_argument("--preset", default="jaw", help="build preset (default: jaw)")
    ap.add_argument("--poses", type=int, default=1_000_000)
    ap.add_argument("--mm", type=float, default=2.0, help="largest translation error (mm)")
    ap.add_argument("--deg", type=float, default=4.0, help="largest rotation error (degrees)")
    ap.add_argument("--chunk", type=int, default=None, help="poses per task (default: equal tasks in whole rounds of the workers)")
    ap.add_argument("--workers", type=int, default=os.cpu_count(), help="local cluster size")
    ap.add_argument("--scheduler", help="address of a running Dask scheduler")
    ap.add_argument("--out", type=pathlib.Path, help="folder for the trees (default: a temporary one)")
    args = ap.parse_args()

    if args.scheduler:
        client = Client(args.scheduler)
    else:
        client = Client(LocalCluster(n_workers=args.workers, threads_per_worker=1))
    print("cluster:", client.dashboard_link or "(no dashboard)", "-", len(client.scheduler_info()["workers"]), "workers")
    out = args.out or pathlib.Path(tempfile.mkdtemp(prefix="innersphere-trees-"))

    t0 = time.perf_counter()
    built = isd.build_many(client, args.meshes, out, preset=args.preset, progress=True)
    print("\nbuilt %d of %d trees in %.1f s" % (sum(b["ok"] for b in built), len(built), time.perf_counter() - t0))
    for b in built:
        what = "%d spheres, %.1f s" % (b["spheres"], b["seconds"]) if b["ok"] else b["error"]
        print("  %s -> %s: %s" % (pathlib.Path(b["mesh"]).name, b["tree"], what))
    if not (built[0]["ok"] and built[1]["ok"]):
        raise SystemExit("the sweep needs the first two trees")
    a, b = innersphere.Tree.load(built[0]["tree"]), innersphere.Tree.load(built[1]["tree"])

    center = np.asarray(b.meta["center_of_mass"], float)
    poses, shift, turn = perturbed(args.poses, 1, args.mm, args.deg, center)
    # The trees sent to every worker once, for both sweeps.
    fa, fb = client.scatter([a, b], broadcast=True)
    t0 = time.perf_counter()
    gap = isd.sweep(client, fa, fb, poses, query="distance", chunk=args.chunk, progress=True)
    td = time.perf_counter() - t0
    t0 = time.perf_counter()
    pen = isd.sweep(client, fa, fb, poses, query="penetration", chunk=args.chunk, progress=True)
    tp = time.perf_counter() - t0
    print("\n%d poses: distance %.1f s (%.0f poses/s), penetration %.1f s (%.0f poses/s)"
          % (len(poses), td, len(poses) / td, tp, len(poses) / tp))

    collide = pen["contact"]
    print("in contact: %.1f %% of the poses; penetration volume p50/p99 %.3f / %.3f mm^3"
          % (100 * collide.mean(), *np.percentile(pen["volume"], [50, 99])))
    for lim in (0.25, 0.5, 1.0, 2.0):
        sel = (shift <= lim) & (turn <= 2 * lim)
        if sel.any():
            print("  error <= %.2f mm and %.1f deg: %5.1f %% in contact, gap p50 %.3f mm (%d poses)"
                  % (lim, 2 * lim, 100 * collide[sel].mean(), np.median(gap[sel]), sel.sum()))

    starts = [[0.0, 0.0, -dz, 1.0, 0.0, 0.0, 0.0] for dz in (1.0, 2.0, 3.0, 4.0)]
    t0 = time.perf_counter()
    bites = isd.occlude_many(client, [(built[0]["tree"], built[1]["tree"])] * len(starts), starts)
    print("\n%d bites in %.1f s" % (len(bites), time.perf_counter() - t0))
    for s, r in zip(starts, bites):
        if isinstance(r, Exception):
            print("  from %.0f mm below: %s" % (-s[2], r))
            continue
        incisal = np.asarray(r["frame"]["incisal"])
        p = np.asarray(r["pose"])
        w, v = p[3], p[4:]
        moved = incisal + 2 * w * np.cross(v, incisal) + 2 * np.cross(v, np.cross(v, incisal)) + p[:3]
        print("  from %.0f mm below: %s, incisal point %.3f mm from the scanned bite, %d contacts"
              % (-s[2], "at rest" if r["converged"] else "NOT at rest", np.linalg.norm(moved - incisal),
                 len(r["patches"])))
    client.close()


if __name__ == "__main__":
    main()
