#!/usr/bin/env python3
"""distance_many against `ist replay --query distance`: the same distances on every frame,
and the time per pose of each, in interleaved rounds.

    python examples/python/replay_parity.py TREE_A TREE_B [--motion M] [--ist BIN] [--rounds 3]

The replay's time per pose is the mean of its per-frame timings (`distance_us_1pass` of its
--csv: each query timed alone, in motion order, on one pair whose state is carried from
frame to frame, from a fresh pair). The module's is the wall time of one
`Pair(a, b).distance_many(poses)` call (the same queries in the same order on a fresh pair,
plus turning the numpy poses into poses and the distances into an array) divided by the
number of poses. Both exclude loading the trees and the motion.
"""

import argparse
import csv
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

import innersphere

HERE = pathlib.Path(__file__).resolve().parent
REPO = HERE.parents[1]


def default_ist():
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", REPO / "target"))
    if not target.is_absolute():
        target = REPO / target
    return str(target / "release" / "ist")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a", help="tree of body A (.ist)")
    ap.add_argument("b", help="tree of body B (.ist)")
    ap.add_argument("--motion", default=str(REPO.parent / "shared/data/motion/jaw_chew_demo.csv"))
    ap.add_argument("--ist", default=default_ist(), help="the ist binary")
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()

    ta, tb = innersphere.Tree.load(args.a), innersphere.Tree.load(args.b)
    _, poses = innersphere.load_motion(args.motion)
    n = len(poses)
    rust, py = [], []
    with tempfile.TemporaryDirectory() as tmp:
        out = pathlib.Path(tmp, "replay.csv")
        for r in range(args.rounds):
            subprocess.run(
                [args.ist, "replay", args.a, args.b, "--motion", args.motion, "--query", "distance",
                 "--csv", str(out)],
                check=True, stdout=subprocess.DEVNULL,
            )
            with open(out) as f:
                rows = list(csv.DictReader(f))
            want = np.array([float(x["distance"]) for x in rows])
            rust.append(sum(float(x["distance_us_1pass"]) for x in rows) / n)

            pair = innersphere.Pair(ta, tb)
            t0 = time.perf_counter()
            got = pair.distance_many(poses)
            py.append((time.perf_counter() - t0) * 1e6 / n)
            if not np.array_equal(got, want):
                bad = np.flatnonzero(got != want)
                sys.exit("round %d: %d distances differ from ist replay, first at frame %d: %r vs %r"
                         % (r + 1, len(bad), bad[0], got[bad[0]], want[bad[0]]))
            print("round %d: ist replay %.3f µs/pose, distance_many %.3f µs/pose (%+.1f %%), "
                  "%d distances identical" % (r + 1, rust[-1], py[-1], 100 * (py[-1] / rust[-1] - 1), n))
    mr, mp = statistics.median(rust), statistics.median(py)
    print("median of %d rounds: ist replay %.3f µs/pose, distance_many %.3f µs/pose (%+.1f %%)"
          % (args.rounds, mr, mp, 100 * (mp / mr - 1)))


if __name__ == "__main__":
    main()
