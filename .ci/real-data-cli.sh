#!/usr/bin/env bash
# The `ist` binary on every real model: closed meshes build and pass `ist check`; every bad
# input gives a tree with a warning or a clear error, never a panic (exit code 101).
# Honours CARGO_TARGET_DIR like cargo does (relative to the repository root).
set -euo pipefail
DATA="$(cd "$1" && pwd)"
cd "$(dirname "$0")/.."
IST="${CARGO_TARGET_DIR:-target}/release/ist"
cargo build --release -q -p ist
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT

for f in "$DATA"/small/*.stl "$DATA"/classic/*.stl "$DATA"/jaw/*molar.stl; do
  name=$(basename "$f")
  "$IST" inspect "$f" | tail -1 | grep -q "^verdict: closed and consistently oriented" || {
    echo "FAILED: ist inspect's verdict on $name"; "$IST" inspect "$f" | tail -1; exit 1; }
  "$IST" build "$f" -o "$OUT/$name.ist" --resolution 96 --quiet > /dev/null
  "$IST" check "$OUT/$name.ist" --mesh "$f" --json > "$OUT/check.json" || {
    echo "FAILED: ist check on $name"; cat "$OUT/check.json"; exit 1; }
  echo "ok: $name"
done

# A real molar with the jaw preset (0.1 mm voxels, 0.05 mm minimum radius, 8 refinement steps).
f="$DATA/jaw/ofj_p26_tooth03_upper_first_molar.stl"
"$IST" build "$f" -o "$OUT/molar.ist" --preset jaw --quiet --json > "$OUT/molar.json"
grep -q '"preset": "jaw"' "$OUT/molar.json" || { echo "FAILED: --preset jaw"; cat "$OUT/molar.json"; exit 1; }
"$IST" check "$OUT/molar.ist" --mesh "$f" --json > "$OUT/check.json" || {
  echo "FAILED: ist check on the molar built with --preset jaw"; cat "$OUT/check.json"; exit 1; }
echo "ok: molar with --preset jaw"

# One real jaw arch at 0.15 mm voxels (the fast jaw preset's).
f="$DATA/jaw/ofj_p26_mandible_teeth.stl.gz"
"$IST" build "$f" -o "$OUT/mandible.ist" --voxel-size 0.15 --json > "$OUT/mandible.json"
grep -E '"(spheres|seconds|coverage)"' "$OUT/mandible.json"
"$IST" check "$OUT/mandible.ist" --mesh "$f" --json > "$OUT/check.json" || {
  echo "FAILED: ist check on the mandible"; cat "$OUT/check.json"; exit 1; }
echo "ok: mandible arch"

# The contact map of the jaw pair at the scanned bite, per tooth (the scans overlap by ≈ 0.3 mm
# at the molars: contacts on both sides).
J="$DATA/jaw"
"$IST" occlusion-map "$J/ofj_p26_maxilla_teeth.stl.gz" "$J/ofj_p26_mandible_teeth.stl.gz" \
  --out-a "$OUT/map_a.ply" --out-b "$OUT/map_b.ply" \
  --teeth-a "$J/ofj_p26_teeth_axes_maxilla.json" --teeth-b "$J/ofj_p26_teeth_axes_mandible.json" \
  --json > "$OUT/map.json"
python3 - "$OUT/map.json" <<'PY' || { echo "FAILED: ist occlusion-map on the jaws"; cat "$OUT/map.json"; exit 1; }
import json, sys
m = json.load(open(sys.argv[1]))
for k, molars in (("a", (3, 14)), ("b", (19, 30))):
    teeth = {t["tooth"]: t for t in m[k]["teeth"]}
    assert len(teeth) >= 14, teeth.keys()
    for n in molars:
        assert teeth[n]["spots"] >= 1 and teeth[n]["area_within_0_1"] > 1, teeth[n]
print("contact map:", {k: m[k]["vertices_within_0_1"] for k in ("a", "b")}, "vertices within 0.1 mm,", round(m["seconds_map"], 2), "s")
PY
[ -s "$OUT/map_a.ply" ] && [ -s "$OUT/map_b.ply" ] || { echo "FAILED: the contact map PLYs"; exit 1; }
echo "ok: occlusion map of the jaw pair"

# The intermediate splint: the mandible opened 3 mm about the hinge (docs/SPLINT.md), with its
# wall time and peak memory where /usr/bin/time is installed.
TIME=""; [ -x /usr/bin/time ] && TIME="/usr/bin/time -f %e,%M -o $OUT/splint.time"
$TIME "$IST" splint "$J/ofj_p26_maxilla_teeth.stl.gz" "$J/ofj_p26_mandible_teeth.stl.gz" --open 3 \
  -o "$OUT/splint.stl" --json > "$OUT/splint.json"
python3 - "$OUT/splint.json" "$OUT/splint.time" <<'PY' || { echo "FAILED: ist splint on the jaws"; cat "$OUT/splint.json"; exit 1; }
import json, os, sys
s = json.load(open(sys.argv[1]))
assert s["watertight"] and s["manifold"] and s["winding_consistent"] and s["bodies"] == 1, s
assert s["volume"] > 0 and s["a_vertices_inside"] == 0 and s["b_vertices_inside"] == 0, s
assert min(s["min_distance_a"], s["min_distance_b"]) >= 0.1 - 0.02, s
assert min(s["coverage_a"], s["coverage_b"]) >= 0.85, s
line = f"splint: {s['triangles']} triangles, coverage {s['coverage_a']:.3f}/{s['coverage_b']:.3f}, {s['seconds']:.1f} s"
if os.path.exists(sys.argv[2]):
    wall, kb = open(sys.argv[2]).read().strip().splitlines()[-1].split(",")
    assert int(kb) <= 1_000_000, f"peak memory {kb} KB"
    line += f"; ist splint {wall} s wall, {int(kb) / 1e6:.2f} GB peak"
print(line)
PY
echo "ok: intermediate splint of the jaw pair"

for f in "$DATA"/bad/*.stl; do
  name=$(basename "$f")
  set +e
  "$IST" inspect "$f" | tail -1 | grep -q "^verdict: " || { echo "FAILED: no verdict from ist inspect on $name"; exit 1; }
  "$IST" build "$f" -o "$OUT/$name.ist" --resolution 64 --quiet > "$OUT/out.txt" 2> "$OUT/err.txt"
  code=$?
  set -e
  if [ $code -eq 101 ] || grep -q "panicked" "$OUT/err.txt"; then
    echo "FAILED: $name panicked"; cat "$OUT/err.txt"; exit 1
  fi
  if [ $code -eq 0 ]; then
    grep -q "warning" "$OUT/err.txt" || { echo "FAILED: $name built without a warning"; exit 1; }
    echo "ok (built, with warning): $name: $(head -1 "$OUT/err.txt")"
  else
    grep -q "error" "$OUT/err.txt" || { echo "FAILED: $name failed without a clear error"; exit 1; }
    echo "ok (clear error): $name: $(head -1 "$OUT/err.txt")"
  fi
done
# Corrupt tree files are clear errors.
head -c 1000 "$OUT/mandible.ist" > "$OUT/truncated.ist"
if "$IST" check "$OUT/truncated.ist" --mesh "$f" 2> "$OUT/err.txt"; then echo "FAILED: truncated tree accepted"; exit 1; fi
grep -q "corrupt tree file" "$OUT/err.txt" || { echo "FAILED: no clear error for a truncated tree"; cat "$OUT/err.txt"; exit 1; }
echo "ok: truncated tree rejected"
