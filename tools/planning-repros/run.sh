#!/usr/bin/env bash
# The planning tools' hostile and clumsy inputs, run by one or two `ist` binaries side by side
# on generated arches (teeth with roots, open boundaries, metres, +y up, bone): exit code,
# wall seconds, peak memory and the first line of stderr (or what the case checks) per run,
# as a markdown table on stdout. Each run is capped at 60 s and 4 GB of address space, so
# an old binary that runs away cannot take the machine down.
#   bash tools/planning-repros/run.sh NEW_IST [OLD_IST]
# Builds the generated arches with `cargo run --example write_arches` into a temporary folder.
set -uo pipefail
if [ $# -lt 1 ]; then
  echo "usage: bash tools/planning-repros/run.sh NEW_IST [OLD_IST]" >&2
  exit 2
fi
ROOT=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
BINS=()
for b in "$@"; do BINS+=("$(cd "$(dirname "$b")" && pwd)/$(basename "$b")"); done
W=$(mktemp -d)
trap 'rm -rf "$W"' EXIT
(cd "$ROOT" && cargo run --release -q -p innersphere-dental --example write_arches -- "$W/gen" >&2)
G="$W/gen"

# run LABEL CHECK BIN ARGS...: one row. CHECK is a shell snippet run after the command in
# its folder ($OUT the folder); its output replaces the stderr line when not empty.
run() {
  local label=$1 check=$2 bin=$3; shift 3
  local out="$W/run.$RANDOM"; mkdir -p "$out"
  (cd "$out" && IST_CACHE="$out/cache" /usr/bin/time -f "%e %M" -o "$out/time" \
    prlimit --as=4000000000 timeout -k 5 60 "$bin" "$@" > "$out/stdout" 2> "$out/stderr")
  local rc=$?
  local t m; read -r t m < <(tail -1 "$out/time" 2>/dev/null) || { t="?"; m=0; }
  [[ "$m" =~ ^[0-9]+$ ]] || m=0
  [ "$rc" = 124 ] && t=">60"
  local note; note=$(cd "$out" && OUT="$out" bash -c "$check" 2>/dev/null)
  [ -n "$note" ] || note=$(grep -v '^Command ' "$out/stderr" | tail -1 | cut -c1-150)
  echo "| $label | $(basename "$(dirname "$(dirname "$bin")")") | $rc | $t | $((m / 1024)) | ${note//|/\\|} |"
}
json() { python3 -c "import json,sys; d=json.load(open('stdout')); print(', '.join(f'{k} {d.get(k)}' for k in sys.argv[1:]))" "$@"; }
export -f json

echo "| case | binary | exit | s | MB | what it said or wrote |"
echo "|---|---|---|---|---|---|"
for B in "${BINS[@]}"; do
  # 1. The cache pointed at the user's folder of trees.
  U="$W/user.$RANDOM"; mkdir -p "$U"
  "$B" build "$G/upper.stl" -o "$U/my_upper.ist" --preset fast -q > /dev/null 2>&1
  cp "$U/my_upper.ist" "$U/other.ist"
  truncate -s 3G "$U/archive.ist" # a large file of the user's: the cache's 2 GiB bound is passed
  (cd "$U" && IST_CACHE=. timeout 60 "$B" query my_upper.ist "$G/lower.stl" --preset fast --pose-b "0 0 -20 1 0 0 0" > /dev/null 2>&1)
  echo "| 1 cache in a folder of the user's trees | $(basename "$(dirname "$(dirname "$B")")") | | | | user's .ist files left: $(ls "$U"/my_upper.ist "$U"/other.ist "$U"/archive.ist 2>/dev/null | wc -l) of 3 |"
  run "2 teeth file /dev/zero" "" "$B" occlusion-map "$G/upper.stl" "$G/lower.stl" --teeth-b /dev/zero
  run "3 splint voxel 0.012" "" "$B" splint "$G/upper.stl" "$G/lower.stl" --open 3 --voxel 0.012 -o w.stl
  run "4 splint B 100 mm below" "json triangles" "$B" splint "$G/upper.stl" "$G/lower.stl" --pose "0 0 -100 1 0 0 0" -o w.stl --json
  run "4 splint B 200 mm sideways" "json triangles" "$B" splint "$G/upper.stl" "$G/lower.stl" --pose "200 0 0 1 0 0 0" -o w.stl --json
  run "4 splint B turned 180°" "json a_vertices_inside min_thickness" "$B" splint "$G/upper.stl" "$G/lower.stl" --pose "0 50.6 0 0 0 0 1" -o w.stl --json
  run "4 splint metre meshes" "json coverage_a coverage_b" "$B" splint "$G/upper_m.stl" "$G/lower_m.stl" --open 3 -o w.stl --json
  run "4 splint --open -50" "json triangles" "$B" splint "$G/upper.stl" "$G/lower.stl" --open -50 -o w.stl --json
  run "5 splint open boundaries, 4 mm open" "json fit coverage_a coverage_b" "$B" splint "$G/upper_open.stl" "$G/lower_open.stl" --pose "0 0 -4 1 0 0 0" --voxel 0.15 -o w.stl --json
  run "6 occlude --force 0.001" "" "$B" occlude "$G/upper.stl" "$G/lower.stl" --preset jaw-fast --from "0 0 -3 1 0 0 0" --force 0.001
  run "6 occlude --force 2000" "" "$B" occlude "$G/upper.stl" "$G/lower.stl" --preset jaw-fast --from "0 0 -3 1 0 0 0" --force 2000
  run "6 occlude an arch against its copy" "" "$B" occlude "$G/upper.stl" "$G/upper.stl" --preset jaw-fast --from "0 0 -3 1 0 0 0"
  run "6 occlude --free --spread 1000" "" "$B" occlude "$G/upper.stl" "$G/lower.stl" --preset jaw-fast --from "0 0 -3 1 0 0 0" --free --starts 10 --spread 1000
  run "7 occlusion-map at 1e17" "" "$B" occlusion-map "$G/upper.stl" "$G/lower.stl" --pose "1e17 0 0 1 0 0 0" --out-b q.ply
  run "7 occlusion-map at 1e300" "grep -a -c inf q.ply" "$B" occlusion-map "$G/upper.stl" "$G/lower.stl" --pose "1e300 0 0 1 0 0 0" --out-b q.ply
  "$B" build "$G/upper_open.stl" -o "$W/open.ist" --preset jaw-fast -q > /dev/null 2>&1
  run "8 check an open mesh's own tree" "grep -E '^(ok|FAILED)' stdout | cut -c1-90" "$B" check "$W/open.ist" --mesh "$G/upper_open.stl"
  run "9 --out-a q.ply.gz" "head -c2 q.ply.gz | od -An -tx1" "$B" occlusion-map "$G/upper.stl" "$G/lower.stl" --out-a q.ply.gz
  run "9 --out-a q.stl" "head -c3 q.stl" "$B" occlusion-map "$G/upper.stl" "$G/lower.stl" --out-a q.stl
  run "9 splint -o x.obj" "head -c12 x.obj | tr '\n' ' '" "$B" splint "$G/upper.stl" "$G/lower.stl" --open 3 --voxel 0.2 -o x.obj
  run "9 --out-a out/q.ply --out-b ./out/q.ply" "" "$B" occlusion-map "$G/upper.stl" "$G/lower.stl" --out-a "$W/out/q.ply" --out-b "$W/./out/q.ply"
  run "9 a missing output folder" "" "$B" splint "$G/upper.stl" "$G/lower.stl" --open 3 -o nowhere/w.stl
  run "11 teeth files swapped" "" "$B" occlusion-map "$G/upper.stl" "$G/lower.stl" --teeth-a "$G/lower.json" --teeth-b "$G/upper.json"
  run "12 cache path that is a file" "grep -m1 -E 'warning|rror' stderr" "$B" query "$G/upper.stl" "$G/lower.stl" --preset fast --cache "$G/upper.json" --pose-b "0 0 -20 1 0 0 0"
  run "13 jaw preset on metres" "" "$B" build "$G/upper_m.stl" -o t.ist --preset jaw -q
  run "13 splint --unit m" "json fit volume" "$B" splint "$G/upper_m.stl" "$G/lower_m.stl" --unit m --open 3 --voxel 0.2 -o w.stl --json
  run "13 +y up, opened 3 mm" "json fit insertion_axis" "$B" splint "$G/upper_y.stl" "$G/lower_y.stl" --open 3 --voxel 0.2 -o w.stl --json
  run "14 build: teeth alone, jaw" "" "$B" build "$G/teeth_upper.stl" -o t.ist --preset jaw -q
  run "14 build: teeth in bone, jaw" "" "$B" build "$G/upper_bone.stl" -o t.ist --preset jaw -q
  run "14 splint between bone arches" "json fit coverage_a coverage_b min_thickness" "$B" splint "$G/upper_bone.stl" "$G/lower_bone.stl" --open 3 -o w.stl --json
  # The real pair (../shared/data/jaw, or $INNERSPHERE_DATA/jaw), where it is beside the clone.
  J="${INNERSPHERE_DATA:-$ROOT/../shared/data}/jaw"
  if [ -f "$J/ofj_p26_maxilla_teeth.stl.gz" ]; then
    UP="$J/ofj_p26_maxilla_teeth.stl.gz" LO="$J/ofj_p26_mandible_teeth.stl.gz"
    run "P26 4 splint B 100 mm below" "json triangles" "$B" splint "$UP" "$LO" --pose "0 0 -100 1 0 0 0" -o w.stl --json
    run "P26 4 splint --open -50" "json triangles" "$B" splint "$UP" "$LO" --open -50 -o w.stl --json
    run "P26 6 occlude --force 2000" "" "$B" occlude "$UP" "$LO" --preset jaw-fast --from "0 0 -3 1 0 0 0" --force 2000
    run "P26 7 occlusion-map at 1e17" "" "$B" occlusion-map "$UP" "$LO" --pose "1e17 0 0 1 0 0 0" --out-b q.ply
    run "P26 9 --out-a q.stl" "head -c3 q.stl" "$B" occlusion-map "$UP" "$LO" --out-a q.stl
    run "P26 11 teeth files swapped" "" "$B" occlusion-map "$UP" "$LO" --teeth-a "$J/ofj_p26_teeth_axes_mandible.json" --teeth-b "$J/ofj_p26_teeth_axes_maxilla.json"
    run "P26 splint auto" "json fit coverage_a coverage_b min_thickness" "$B" splint "$UP" "$LO" --open auto -o w.stl --json
  fi
done
