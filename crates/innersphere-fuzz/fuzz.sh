#!/usr/bin/env bash
# Coverage-guided fuzzing of innersphere's readers with cargo-fuzz (libFuzzer), one target
# at a time; see docs/RELIABILITY.md, "Fuzzing". Needs a nightly toolchain and
# `cargo install cargo-fuzz`.
#
#   ./fuzz.sh TARGET SECONDS      fuzz one target (names: cargo +nightly fuzz list)
#   ./fuzz.sh cmin TARGET         minimise its corpus in fuzz/corpus/TARGET
#
# Release build with debug assertions and overflow checks (-O -a). New coverage goes into
# fuzz/corpus/TARGET, a crash into fuzz/artifacts/TARGET/; after a crash the target is
# restarted for the rest of its time (at most 5 times), so that SECONDS is the time fuzzed.
set -euo pipefail
cd "$(dirname "$0")"
FLAGS=(-max_len=4096 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1)
if [ "$1" = cmin ]; then
  exec cargo +nightly fuzz cmin -O -a "$2" -- "${FLAGS[@]}"
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
