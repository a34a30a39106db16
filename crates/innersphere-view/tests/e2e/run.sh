#!/usr/bin/env bash
# End-to-end test of the `ist view` page: starts `ist view --demo` (with a tooth per body for
# the contact map's list) on a free port, drives the page with a headless Chromium
# (software WebGL) through playwright-core, and stops the server on exit.
#
#   cargo build --release -p ist                  # the caller builds the binary
#   bash crates/innersphere-view/tests/e2e/run.sh [OUTDIR]
#
# Environment: IST (default ${CARGO_TARGET_DIR:-target}/release/ist, relative to the
# workspace root), CHROMIUM (default /usr/bin/chromium), OUTDIR (default
# ${CARGO_TARGET_DIR:-target}/e2e-view; also the first argument): screenshots and the
# server's log go there.
set -euo pipefail

HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../../../.." && pwd)"
TARGET="${CARGO_TARGET_DIR:-target}"
case "$TARGET" in /*) ;; *) TARGET="$ROOT/$TARGET" ;; esac
IST="${IST:-$TARGET/release/ist}"
OUTDIR="${1:-${OUTDIR:-$TARGET/e2e-view}}"
export CHROMIUM="${CHROMIUM:-/usr/bin/chromium}"

[ -x "$IST" ] || { echo "run.sh: no ist binary at $IST (cargo build --release -p ist)" >&2; exit 2; }
[ -x "$CHROMIUM" ] || { echo "run.sh: no chromium at $CHROMIUM" >&2; exit 2; }
command -v node >/dev/null || { echo "run.sh: node is not installed" >&2; exit 2; }
mkdir -p "$OUTDIR"
OUTDIR="$(cd "$OUTDIR" && pwd)"

# playwright-core (the pinned version in package.json) into this folder's node_modules;
# it downloads no browser: the test uses the system Chromium.
(cd "$HERE" && npm install --no-audit --no-fund --loglevel=error)

# The server: --port 0 picks a free port; it prints its URL on stdout.
LOG="$OUTDIR/server.log"
# The demo's teeth (one molar each, crown centres of the generated pair) give the contact
# map's per-tooth list something to show.
"$IST" view --demo --port 0 --teeth-a "$HERE/demo_teeth_a.json" --teeth-b "$HERE/demo_teeth_b.json" >"$LOG" 2>&1 &
SERVER=$!
cleanup() {
  if kill -0 "$SERVER" 2>/dev/null; then
    kill "$SERVER" 2>/dev/null || true
    wait "$SERVER" 2>/dev/null || true
  fi
}
trap cleanup EXIT INT TERM

# Wait for the URL (the demo builds two trees first: allow two minutes).
URL=""
for _ in $(seq 1 1200); do
  URL="$(grep -oE 'http://127\.0\.0\.1:[0-9]+/' "$LOG" | head -n1 || true)"
  [ -n "$URL" ] && break
  if ! kill -0 "$SERVER" 2>/dev/null; then
    echo "run.sh: the server exited before printing its URL:" >&2
    cat "$LOG" >&2
    exit 1
  fi
  sleep 0.1
done
[ -n "$URL" ] || { echo "run.sh: no URL from the server in 120 s:" >&2; cat "$LOG" >&2; exit 1; }
echo "server: $URL (log: $LOG)"

node "$HERE/e2e.mjs" "$URL" "$OUTDIR"
