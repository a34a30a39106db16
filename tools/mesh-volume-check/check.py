"""The meshes' exact intersection volume of `mesh_volume_replay`'s CSV against manifold3d's
mesh boolean (an independent library), and its gradient against central differences of
manifold3d's volumes.

    python3 check.py A.stl B.stl OUT.csv [--gradient N]
    python3 check.py A.stl B.stl --motion MOTION.csv --reference REF.csv [--every K] [--gradient N]

The first form prints per frame class (apart, touching < 0.05 mm³, overlapping) how the volumes agree, the
frames where one says contact and the other not, and for N frames the angle between our
gradient and the reference's. The second writes the reference itself for every K-th frame of
a motion (`frame,volume,gx,gy,gz`; the gradient by central differences on N of the
overlapping frames, blank elsewhere), which `ist replay --query mesh-penetration --reference`
compares with."""
import argparse, csv, math
import numpy as np
import trimesh
import manifold3d as m3d


def manifold(mesh):
    m = m3d.Manifold(m3d.Mesh(vert_properties=np.asarray(mesh.vertices, dtype=np.float32),
                              tri_verts=np.asarray(mesh.faces, dtype=np.uint32)))
    if m.status() != m3d.Error.NoError:
        raise SystemExit(f"manifold3d refuses the mesh: {m.status()}")
    return m


def matrix(row):
    t = [float(row[k]) for k in ("tx", "ty", "tz")]
    w, x, y, z = (float(row[k]) for k in ("qw", "qx", "qy", "qz"))
    r = trimesh.transformations.quaternion_matrix([w, x, y, z])
    r[:3, 3] = t
    return r


def overlap(a, mb, m):
    b = mb.copy()
    b.apply_transform(m)
    return (a ^ manifold(b)).volume()


def gradient(a, mb, m, h=1e-3):
    """Central differences of the reference volume along B's translation."""
    g = []
    for e in np.eye(3):
        mp, mm = m.copy(), m.copy()
        mp[:3, 3] += e * h
        mm[:3, 3] -= e * h
        g.append((overlap(a, mb, mp) - overlap(a, mb, mm)) / (2 * h))
    return np.array(g)


def reference(a, mb, args):
    """The reference CSV of every K-th frame of the motion."""
    rows = [r for r in csv.reader(open(args.motion)) if r and not r[0].startswith("t")]
    frames = list(range(0, len(rows), args.every))
    poses = {}
    for i in frames:
        t = [float(x) for x in rows[i][1:8]]
        poses[i] = matrix(dict(zip(("tx", "ty", "tz", "qw", "qx", "qy", "qz"), t)))
    volumes = {i: overlap(a, mb, poses[i]) for i in frames}
    touching = [i for i in frames if volumes[i] > 1e-3]
    picked = set(touching[:: max(1, len(touching) // max(1, args.gradient))][: args.gradient])
    with open(args.reference, "w") as out:
        out.write("frame,volume,gx,gy,gz\n")
        for i in frames:
            g = ",".join(repr(float(x)) for x in gradient(a, mb, poses[i])) if i in picked else ",,"
            out.write(f"{i},{float(volumes[i])!r},{g}\n")
    print(f"{len(frames)} frames, {sum(v > 0 for v in volumes.values())} overlapping, "
          f"{len(picked)} gradients: {args.reference}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("a"); ap.add_argument("b"); ap.add_argument("csv", nargs="?")
    ap.add_argument("--gradient", type=int, default=0)
    ap.add_argument("--motion"); ap.add_argument("--reference")
    ap.add_argument("--every", type=int, default=1)
    args = ap.parse_args()
    # Merged vertices (STL stores each triangle's own): manifold3d needs a closed manifold.
    ma, mb = (trimesh.load(p, force="mesh", process=True) for p in (args.a, args.b))
    # manifold3d's Mesh holds f32 positions: B is moved in f64, then rounded (≈ 1e-6 mm at
    # the jaw's 50 mm), far below the bars.
    a = manifold(ma)
    if args.reference:
        if not args.motion:
            raise SystemExit("--reference needs --motion")
        return reference(a, mb, args)
    if not args.csv:
        raise SystemExit("give OUT.csv of mesh_volume_replay, or --motion and --reference")
    rows = list(csv.DictReader(open(args.csv)))
    spheres = bool(rows and rows[0].get("sphere_volume"))
    sphere_ratios, sphere_silent = [], 0
    ratios, missed, ghost, worst = [], [], [], (0, None)
    for r in rows:
        ours, ref = float(r["volume"]), overlap(a, mb, matrix(r))
        if ref >= 1e-4 and ours == 0:
            missed.append(r["frame"])
        if ours > 1e-4 and ref == 0:
            ghost.append(r["frame"])
        if ref > 0:
            err = abs(ours - ref) / ref if ref >= 5e-3 else abs(ours - ref) / 5e-3
            ratios.append(ours / ref)
            if spheres:
                sv = float(r["sphere_volume"])
                sphere_ratios.append(sv / ref)
                sphere_silent += ref >= 1e-4 and sv == 0
            if err > worst[0]:
                worst = (err, r["frame"])
    ratios = np.array(ratios)
    print(f"{len(rows)} frames, {len(ratios)} overlapping by the reference")
    if len(ratios):
        within = np.mean(np.abs(ratios - 1) <= 0.02)
        print(f"ours / reference: median {np.median(ratios):.5f}, p5 {np.percentile(ratios, 5):.5f}, "
              f"p95 {np.percentile(ratios, 95):.5f}; within 2 %: {100 * within:.1f} %; worst frame {worst}")
    if spheres and sphere_ratios:
        s = np.array(sphere_ratios)
        print(f"the spheres' volume / reference: median {np.median(s):.4f}, p5 {np.percentile(s, 5):.4f}, "
              f"p95 {np.percentile(s, 95):.4f}; no contact at all on {sphere_silent} of {len(s)} overlapping frames")
    print(f"contact missed (reference ≥ 1e-4 mm³, ours 0): {missed}")
    print(f"contact invented (ours > 1e-4 mm³, reference 0): {ghost}")
    if args.gradient:
        h, angles, sphere_angles = 1e-3, [], []
        picked = [r for r in rows if float(r["volume"]) > 1e-3][:: max(1, len(rows) // args.gradient)][: args.gradient]
        for r in picked:
            m = matrix(r)
            g = []
            for e in np.eye(3):
                mp, mm = m.copy(), m.copy()
                mp[:3, 3] += e * h
                mm[:3, 3] -= e * h
                g.append((overlap(a, mb, mp) - overlap(a, mb, mm)) / (2 * h))
            ours = np.array([float(r[k]) for k in ("gx", "gy", "gz")])
            c = np.dot(ours, g) / (np.linalg.norm(ours) * np.linalg.norm(g) + 1e-300)
            angles.append(math.degrees(math.acos(max(-1, min(1, c)))))
            if spheres:
                sn = np.array([float(r[k]) for k in ("snx", "sny", "snz")])
                if np.linalg.norm(sn) > 0:
                    # The spheres' normal pushes B out: against the volume's gradient.
                    c = -np.dot(sn, g) / (np.linalg.norm(sn) * np.linalg.norm(g) + 1e-300)
                    sphere_angles.append(math.degrees(math.acos(max(-1, min(1, c)))))
        print(f"gradient direction against the reference's central differences (h = {h}): "
              f"median {np.median(angles):.3f}°, max {max(angles):.3f}° over {len(angles)} frames")
        if sphere_angles:
            print(f"the spheres' normal against the same: median {np.median(sphere_angles):.2f}°, "
                  f"max {max(sphere_angles):.2f}° over {len(sphere_angles)} frames")


main()
