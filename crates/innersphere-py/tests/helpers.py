"""Helpers of the tests: generated meshes, poses and motions (no data files needed), the
`ist` CLI."""

import json
import os
import pathlib
import shutil
import subprocess

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[3]


# --- generated meshes -----------------------------------------------------------------------


def box_mesh(lo=(-1.0, -1.0, -1.0), hi=(1.0, 1.0, 1.0)):
    """An axis-aligned box as (vertices (8, 3), faces (12, 3)), faces outward."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    v = np.array(
        [[(hi if x else lo)[0], (hi if y else lo)[1], (hi if z else lo)[2]]
         for x in (0, 1) for y in (0, 1) for z in (0, 1)]
    )
    f = np.array(
        [[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
         [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]],
        dtype=np.int64,
    )
    return orient_outward(v, f)


def icosphere(subdivisions=2, radius=1.0, center=(0.0, 0.0, 0.0)):
    """A geodesic sphere as (vertices, faces), faces outward."""
    t = (1.0 + 5.0 ** 0.5) / 2.0
    v = [[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t],
         [0, -1, -t], [0, 1, -t], [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]]
    v = [list(np.asarray(p, float) / np.linalg.norm(p)) for p in v]
    f = [[0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4],
         [11, 10, 2], [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8],
         [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1]]
    for _ in range(subdivisions):
        cache = {}

        def mid(a, b):
            key = (min(a, b), max(a, b))
            if key not in cache:
                m = (np.asarray(v[a]) + np.asarray(v[b])) / 2.0
                v.append(list(m / np.linalg.norm(m)))
                cache[key] = len(v) - 1
            return cache[key]

        nf = []
        for a, b, c in f:
            ab, bc, ca = mid(a, b), mid(b, c), mid(c, a)
            nf += [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
        f = nf
    v = np.asarray(v) * radius + np.asarray(center, float)
    return orient_outward(v, np.asarray(f, dtype=np.int64))


def orient_outward(v, f):
    """Flips every face when the signed volume is negative."""
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    if np.einsum("ij,ij->", a, np.cross(b, c)) < 0:
        f = f[:, [0, 2, 1]]
    return v, f


def write_obj(path, vertices, faces):
    """An OBJ file with the exact float values (repr round-trips)."""
    with open(path, "w") as out:
        for p in vertices:
            out.write("v %r %r %r\n" % (float(p[0]), float(p[1]), float(p[2])))
        for t in faces:
            out.write("f %d %d %d\n" % (t[0] + 1, t[1] + 1, t[2] + 1))


def quat_axis_angle(axis, angle):
    axis = np.asarray(axis, float)
    axis = axis / np.linalg.norm(axis)
    return [np.cos(angle / 2)] + list(np.sin(angle / 2) * axis)


def pose_text(p):
    """A 7-number pose as `ist query --pose-b` text, every digit kept."""
    return " ".join(repr(float(x)) for x in p)


def pose_matrix(p):
    """The 4×4 matrix of a 7-number pose (quaternion normalised)."""
    t, q = np.asarray(p[:3], float), np.asarray(p[3:], float)
    w, x, y, z = q / np.linalg.norm(q)
    r = np.array(
        [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    )
    m = np.eye(4)
    m[:3, :3], m[:3, 3] = r, t
    return m


# Poses of B (the ellipsoid, semi-axes 0.6, 0.45, 0.35) against A (the box [-1, 1]³): far, near, touching,
# overlapping, deep, rotated, and quaternions that are not unit (normalised as the CLI does).
POSES = [
    [5.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
    [40.0, -12.0, 7.5, 0.7, 0.1, -0.7, 0.2],
    [1.75, 0.1, -0.2, 1.0, 0.0, 0.0, 0.0],
    [1.55, 0.3, 0.2] + quat_axis_angle([0.3, 1.0, -0.2], 0.7),
    [-1.3, 1.25, 0.4, 2.0, 0.2, -0.4, 0.6],
    [0.9, -0.8, 1.1] + quat_axis_angle([1.0, 0.0, 1.0], 2.5),
    [0.2, 0.1, -0.3, 0.9, 0.1, 0.3, -0.2],
    [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
]


def chew_motion(n=400):
    """A generated motion of B: in from afar, through A's face, out and around (times in s)."""
    t = np.arange(n) * 0.001
    s = np.linspace(0.0, 1.0, n)
    x = 3.0 - 2.6 * np.sin(np.pi * s)
    y = 0.4 * np.sin(3 * np.pi * s)
    z = 0.3 * np.cos(2 * np.pi * s)
    ang = 1.5 * s
    axis = np.array([0.2, 1.0, 0.4]) / np.linalg.norm([0.2, 1.0, 0.4])
    q = np.column_stack([np.cos(ang / 2), np.outer(np.sin(ang / 2), axis)])
    return t, np.column_stack([x, y, z, q])


def write_motion(path, t, poses, fmt="%.9f"):
    with open(path, "w") as out:
        out.write("t,tx,ty,tz,qw,qx,qy,qz\n")
        for ti, p in zip(t, poses):
            out.write(",".join(fmt % x for x in [ti, *p]) + "\n")


# --- the CLI --------------------------------------------------------------------------------


def find_ist():
    """The `ist` binary: $IST_BIN, else target/release/ist under $CARGO_TARGET_DIR or the
    repository, else `ist` on the PATH."""
    if os.environ.get("IST_BIN"):
        return os.environ["IST_BIN"]
    dirs = []
    if os.environ.get("CARGO_TARGET_DIR"):
        dirs.append(REPO / os.environ["CARGO_TARGET_DIR"])
    dirs.append(REPO / "target")
    for d in dirs:
        exe = d / "release" / "ist"
        if exe.is_file() and os.access(exe, os.X_OK):
            return str(exe)
    return shutil.which("ist")


class Ist:
    """Runs the `ist` CLI."""

    def __init__(self, exe):
        self.exe = exe

    def run(self, *args):
        r = subprocess.run([self.exe, *map(str, args)], capture_output=True, text=True)
        if r.returncode != 0:
            raise AssertionError("ist %s failed (%d): %s" % (" ".join(map(str, args)), r.returncode, r.stderr))
        return r.stdout

    def query(self, a, b, pose, kind, *extra):
        out = self.run("query", a, b, "--pose-b", pose_text(pose), "--query", kind, "--json", *extra)
        return json.loads(out)

    def replay_csv(self, a, b, motion, kind, out_csv):
        self.run("replay", a, b, "--motion", motion, "--query", kind, "--csv", out_csv)
        return read_csv(out_csv)


def read_csv(path):
    """A CSV as a dict of column name -> list of strings."""
    with open(path) as f:
        head = f.readline().strip().split(",")
        rows = [line.rstrip("\n").split(",") for line in f if line.strip()]
    return {h: [r[i] for r in rows] for i, h in enumerate(head)}
