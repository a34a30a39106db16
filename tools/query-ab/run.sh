#!/usr/bin/env bash
# Interleaved A/B of `ist replay --query "${QUERY:-all}" --passes P` (best-of-passes p99 per kind): OLD and
# NEW alternated per motion, ROUNDS rounds. Usage: run.sh OLD_IST NEW_IST TREE_A TREE_B MOTION...
set -euo pipefail
OLD=$1 NEW=$2 A=$3 B=$4; shift 4
ROUNDS=${ROUNDS:-3} PASSES=${PASSES:-3}
for m in "$@"; do
  for r in $(seq 1 "$ROUNDS"); do
    for which in OLD NEW; do
      bin=$OLD; [ $which = NEW ] && bin=$NEW
      $bin replay "$A" "$B" --motion "$m" --query "${QUERY:-all}" --passes "$PASSES" --json 2>/dev/null \
        | python3 -c "
import json,sys
v=json.load(sys.stdin)
print('$which', '$(basename "$m" .csv)', $r, ' '.join(f\"{k['kind']}={k['best_of_passes_p99_us']:.2f}\" for k in v['kinds']))"
    done
  done
done
