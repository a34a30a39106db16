#!/usr/bin/env python3
"""Contact forces between the upper and lower jaw along a chewing motion.

Loads the two arches' trees (--trees A.ist B.ist), or builds them from the meshes with the
calibrated jaw setting (0.1 mm voxels, 0.05 mm minimum radius, 8 refinement steps: about
half a minute per arch), replays the motion (the pose of the mandible B in the maxilla A's
frame per frame) with Pair.penetration_many, plots the force magnitude and the penetration
volume against time into a PNG and prints a short summary.

    pip install ./crates/innersphere-py matplotlib
    python examples/python/jaw_forces.py --trees maxilla.ist mandible.ist --out jaw_forces.png
    python examples/python/jaw_forces.py --save-trees /tmp/trees   # build, keep the trees

Data: ../shared/data beside the repository, or $INNERSPHERE_DATA.
"""

import argparse
import os
import pathlib
import time

import numpy as np

import innersphere

REPO = pathlib.Path(__file__).resolve().parents[2]
DATA = pathlib.Path(os.environ.get("INNERSPHERE_DATA", REPO.parent / "shared" / "data"))


def load_or_build(args):
    if args.trees:
        return [innersphere.Tree.load(p) for p in args.trees]
    trees = []
    for mesh in args.meshes:
        t0 = time.perf_counter()
        tree = innersphere.Tree.build(mesh, voxel_size=0.1, min_radius=0.05, refine_steps=8,
                                      progress=args.progress)
        print("built %s: %d spheres in %.1f s" % (pathlib.Path(mesh).name, tree.leaf_count,
                                                   time.perf_counter() - t0))
        if args.save_trees:
            out = pathlib.Path(args.save_trees)
            out.mkdir(parents=True, exist_ok=True)
            tree.save(out / (pathlib.Path(mesh).name.split(".")[0] + ".ist"))
        trees.append(tree)
    return trees


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--trees", nargs=2, metavar=("A.ist", "B.ist"),
                    help="the maxilla's and the mandible's trees (else built from --meshes)")
    ap.add_argument("--meshes", nargs=2, metavar=("A", "B"),
                    default=[str(DATA / "jaw/ofj_p26_maxilla_teeth.stl.gz"),
                             str(DATA / "jaw/ofj_p26_mandible_teeth.stl.gz")],
                    help="the meshes to build the trees from (default: the shared jaw scans)")
    ap.add_argument("--save-trees", metavar="DIR", help="keep the built trees in this folder")
    ap.add_argument("--motion", default=str(DATA / "motion/jaw_chew_demo.csv"),
                    help="motion CSV (t,tx,ty,tz,qw,qx,qy,qz: the mandible in the maxilla's frame)")
    ap.add_argument("--stiffness", type=float, default=10.0,
                    help="penalty force per penetration volume, N/mm³ (default 10, the haptic loop's)")
    ap.add_argument("--out", default="jaw_forces.png", help="the PNG to write")
    ap.add_argument("--progress", action="store_true", help="show the build's progress")
    args = ap.parse_args()

    a, b = load_or_build(args)
    t, poses = innersphere.load_motion(args.motion)
    pair = innersphere.Pair(a, b)
    t0 = time.perf_counter()
    r = pair.penetration_many(poses, stiffness=args.stiffness)
    secs = time.perf_counter() - t0
    force = np.linalg.norm(r["force"], axis=1)
    volume = r["volume"]

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(9, 5.5))
    top.plot(t, force, color="tab:red", lw=1)
    top.set_ylabel("force on the mandible (N)")
    top.set_title("Jaw contact along %s (stiffness %g N/mm³)" % (pathlib.Path(args.motion).name, args.stiffness))
    bottom.plot(t, volume, color="tab:blue", lw=1)
    bottom.set_ylabel("penetration volume (mm³)")
    bottom.set_xlabel("time (s)")
    for ax in (top, bottom):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(args.out, dpi=120)

    contact = r["contact"]
    i = int(np.argmax(force))
    print("%d frames over %.2f s: %d in contact (%.0f %%)" % (len(t), t[-1] - t[0], contact.sum(),
                                                              100 * contact.mean()))
    print("peak force %.3f N at t = %.3f s (volume %.4f mm³, deepest overlap %.3f mm, %d leaf pairs)"
          % (force[i], t[i], volume[i], r["max_depth"][i], r["pairs"][i]))
    print("mean force while in contact %.3f N; largest volume %.4f mm³"
          % (force[contact].mean() if contact.any() else 0.0, volume.max()))
    print("penetration_many: %.1f µs per pose (%.3f s for %d poses)" % (secs * 1e6 / len(t), secs, len(t)))
    print("wrote %s" % args.out)


if __name__ == "__main__":
    main()
