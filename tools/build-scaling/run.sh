#!/usr/bin/env bash
# Build timing on the real jaw arches: one or two `ist` binaries alternated, per thread
# count, beside FCL's OBBRSS build of the same meshes (when tools/fcl-bench can run).
#   bash tools/build-scaling/run.sh NEW_IST [OLD_IST]
# Env: INNERSPHERE_DATA (default ../shared/data beside the repository), THREADS (default
#      "2 16"), ROUNDS (default 3), PRESET (default jaw), NO_FCL=1 to skip FCL.
# Prints CSV on stdout: binary,arch,threads,round,build_s,total_s,field_s,packing_s,
# hierarchy_s,peak_mb; FCL's build times as `# FCL ...` lines. Threads are pinned with
# `taskset -c 0..N-1` and RAYON_NUM_THREADS=N. See README.md beside this file.
set -euo pipefail

if [ $# -lt 1 ]; then
  echo "usage: bash tools/build-scaling/run.sh NEW_IST [OLD_IST]" >&2
  exit 2
fi
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
DATA=${INNERSPHERE_DATA:-$ROOT/../shared/data}
THREADS=${THREADS:-"2 16"}
ROUNDS=${ROUNDS:-3}
PRESET=${PRESET:-jaw}
BINS=("$@")
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT

for b in "${BINS[@]}"; do
  [ -x "$b" ] || { echo "run.sh: $b is not an executable" >&2; exit 1; }
done
for a in maxilla mandible; do
  [ -r "$DATA/jaw/ofj_p26_${a}_teeth.stl.gz" ] || { echo "run.sh: no $DATA/jaw/ofj_p26_${a}_teeth.stl.gz" >&2; exit 1; }
done
command -v python3 >/dev/null || { echo "run.sh: python3 is needed to read the build reports" >&2; exit 1; }
PEAK=""; [ -x /usr/bin/time ] && PEAK="/usr/bin/time -f %M -o $TMP/peak"

fcl() {
  [ -n "${NO_FCL:-}" ] && return 0
  # FCL's bench builds both BVHs before its first frame; two frames of any motion suffice.
  [ -f "$TMP/motion.csv" ] || printf 't,tx,ty,tz,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n0.001,0,0,0,1,0,0,0\n' > "$TMP/motion.csv"
  FCL_BENCH_FRAMES=2 INNERSPHERE_DATA=$DATA bash "$ROOT/tools/fcl-bench/run.sh" "$TMP/motion.csv" 1 2>/dev/null \
    | grep -i "BVH build" | sed "s/^/# FCL $1: /" || echo "# FCL $1: did not run"
}

echo "binary,arch,threads,round,build_s,total_s,field_s,packing_s,hierarchy_s,peak_mb"
fcl start
for r in $(seq 1 "$ROUNDS"); do
  for a in maxilla mandible; do
    for t in $THREADS; do
      for b in "${BINS[@]}"; do
        rm -f "$TMP/peak"
        # shellcheck disable=SC2086
        taskset -c "0-$((t - 1))" env RAYON_NUM_THREADS="$t" $PEAK "$b" build --preset "$PRESET" \
          "$DATA/jaw/ofj_p26_${a}_teeth.stl.gz" -o "$TMP/tree.ist" --json --quiet > "$TMP/report.json"
        peak=$( [ -f "$TMP/peak" ] && echo $(( $(cat "$TMP/peak") / 1024 )) || echo "")
        python3 - "$TMP/report.json" "$b" "$a" "$t" "$r" "$peak" <<'PY'
import json, sys
d = json.load(open(sys.argv[1])); s = d["stage_seconds"]
print(",".join([sys.argv[2], sys.argv[3], sys.argv[4], sys.argv[5]] + ["%.3f" % x for x in (
    d["build_seconds"], d["seconds"], s["distance_field"], s["packing"], s["hierarchy"])] + [sys.argv[6]]))
PY
      done
    done
  done
  [ "$r" = 2 ] && fcl middle
done
fcl end
