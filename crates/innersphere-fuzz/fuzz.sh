#!/usr/bin/env bash
# Coverage-guided fuzzing of innersphere's readers with cargo-fuzz (libFuzzer), one target
# at a time; see docs/RELIABILITY.md, "Fuzzing". Needs a nightly toolchain and
# `cargo install cargo-fuzz`.
#
#   ./fuzz.sh TARGET SECONDS      fuzz one target (names: cargo +nightly fuzz list)
#   ./fuzz.sh cmin TARGET         minimise its corpus in fuzz/corpus/TARGET: `cargo fuzz cmin`
#                                 on edges only (-use_counters=0, not hit-count buckets),
#                                 then a greedy set cover over each file's own edges (the
#                                 file adding most edges not yet covered first, the smaller
#                                 on ties): the same edges, a fraction of the files
#
# Release build with debug assertions and overflow checks (-O -a). New coverage goes into
# fuzz/corpus/TARGET, a crash into fuzz/artifacts/TARGET/; after a crash the target is
# restarted for the rest of its time (at most 5 times), so that SECONDS is the time fuzzed.
set -euo pipefail
cd "$(dirname "$0")"
FLAGS=(-max_len=4096 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1)
if [ "$1" = cmin ]; then
  target=$2
  cargo +nightly fuzz cmin -O -a "$target" -- "${FLAGS[@]}" -use_counters=0
  bin=fuzz/target/x86_64-unknown-linux-gnu/release/$target
  work=$(mktemp -d)
  trap 'rm -rf "$work"' EXIT
  # Each file's full edge set: a merge of that file alone into an empty folder.
  for f in fuzz/corpus/"$target"/*; do
    rm -rf "$work/in" "$work/out" "$work/ctrl"
    mkdir -p "$work/in" "$work/out"
    cp "$f" "$work/in/"
    "$bin" -merge=1 -use_counters=0 -max_len=4096 -merge_control_file="$work/ctrl" \
      "$work/out" "$work/in" > /dev/null 2>&1
    echo "$f $(grep '^COV' "$work/ctrl" | cut -d' ' -f3-)"
  done > "$work/edges"
  python3 - "$work/edges" > "$work/keep" <<'PY'
import os, sys
cov = {}
for line in open(sys.argv[1]):
    path, *edges = line.split()
    cov[path] = set(edges)
left = set().union(*cov.values())
total, keep = len(left), []
while left:
    best = max(cov, key=lambda f: (len(cov[f] & left), -os.path.getsize(f)))
    keep.append(best)
    left -= cov[best]
print(f"{total} edges in {len(keep)} of {len(cov)} files", file=sys.stderr)
print("\n".join(keep))
PY
  mkdir "$work/kept"
  xargs -a "$work/keep" cp -t "$work/kept"
  rm -rf fuzz/corpus/"$target"
  mv "$work/kept" fuzz/corpus/"$target"
  exit 0
fi
target=$1 seconds=$2
cargo +nightly fuzz build -O -a "$target"
end=$(( $(date +%s) + seconds ))
for attempt in 1 2 3 4 5 6; do
  left=$(( end - $(date +%s) ))
  [ "$left" -gt 0 ] || break
  echo "== $target: run $attempt, ${left} s left ($(date -u +%FT%TZ))"
  set +e
  cargo +nightly fuzz run -O -a "$target" -- "${FLAGS[@]}" -max_total_time="$left"
  code=$?
  set -e
  echo "== $target: exit $code ($(date -u +%FT%TZ))"
  [ "$code" -eq 0 ] && break
done
