#!/usr/bin/env python3
"""Old (2141ece) and new `ist query --json` on the same trees and poses: every old key's value
equal bit for bit under its new name; the keys added listed."""
import json, subprocess, sys
OLD, NEW, A, B = sys.argv[1:5]
MESHES = sys.argv[5:7]
poses = ["0 0 0 1 0 0 0", "0 0 1.5 1 0 0 0", "0.3 -0.2 0.4 1 0.05 0 0", "0 0 -0.3 1 0 0.02 0",
         "2 1 3 1 0.1 0.1 0", "0 0 0.2 1 0 0 0"]
kinds = ["distance", "contact", "multipoint", "penetration", "penetration-within", "distance-traversal",
         "backtracking", "refined-distance"]
RENAMED = {"refined-distance": {"sphere_distance": ("spheres", "distance"), "visits": ("spheres", "visits")},
           "penetration": {"torque": ("torque_b",)}, "penetration-within": {"torque": ("torque_b",)}}
def q(bin, kind, pose):
    extra = ["--meshes", *MESHES] if kind == "refined-distance" else []
    out = subprocess.run([bin, "query", A, B, "--query", kind, "--pose-b", pose, "--json", *extra],
                         capture_output=True, text=True, check=True).stdout
    v = json.loads(out); v.pop("seconds"); return v
def get(v, path):
    for p in path: v = v[p]
    return v
added = {}
n = 0
for kind in kinds:
    for pose in poses:
        o, w = q(OLD, kind, pose), q(NEW, kind, pose)
        for k, val in o.items():
            path = RENAMED.get(kind, {}).get(k, (k,))
            assert get(w, path) == val, (kind, pose, k, val, get(w, path))
            n += 1
        added.setdefault(kind, set()).update(set(w) - set(o))
        if kind != "refined-distance" and not RENAMED.get(kind):
            assert set(o) <= set(w), (kind, set(o) - set(w))
for kind in kinds:
    print(f"{kind}: all old values equal; keys added: {sorted(added[kind]) or 'none'}; renamed: {RENAMED.get(kind, {})}")
print(f"{n} values compared over {len(poses)} poses")
