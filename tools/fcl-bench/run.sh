#!/usr/bin/env bash
# Peer benchmark: FCL 0.7 on the real jaw pair along a motion.
#   bash tools/fcl-bench/run.sh MOTION.csv [PASSES]
# Env: INNERSPHERE_DATA (default ../shared/data beside the repository), FCL_BENCH_FRAMES=N,
#      FCL_BENCH_STRIDE=K, FCL_BENCH_CSV=path. See README.md beside this file.
set -euo pipefail

if [ $# -lt 1 ]; then
  echo "usage: bash tools/fcl-bench/run.sh MOTION.csv [PASSES]" >&2
  exit 2
fi
MOTION=$1
PASSES=${2:-3}

HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
DATA=${INNERSPHERE_DATA:-$ROOT/../shared/data}
MESH_A=$DATA/jaw/ofj_p26_maxilla_teeth.stl.gz
MESH_B=$DATA/jaw/ofj_p26_mandible_teeth.stl.gz
BUILD=$ROOT/target/fcl-bench
BIN=$BUILD/fcl_bench

for f in "$MESH_A" "$MESH_B" "$MOTION"; do
  [ -r "$f" ] || { echo "run.sh: cannot read $f" >&2; exit 1; }
done

# ---- dependencies (Debian: libfcl-dev 0.7 pulls in Eigen, libccd, octomap)
need=()
[ -f /usr/include/fcl/fcl.h ] || need+=(libfcl-dev)
[ -f /usr/include/zlib.h ] || need+=(zlib1g-dev)
command -v g++ >/dev/null || need+=(g++)
command -v pkg-config >/dev/null || need+=(pkg-config)
if [ ${#need[@]} -gt 0 ]; then
  echo "run.sh: installing ${need[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  if ! apt-get install -y -qq "${need[@]}" >&2; then
    apt-get update -qq >&2
    apt-get install -y -qq "${need[@]}" >&2
  fi
fi

# ---- build (only when the source or this script is newer than the binary)
mkdir -p "$BUILD"
if [ ! -x "$BIN" ] || [ "$HERE/fcl_bench.cpp" -nt "$BIN" ] || [ "$HERE/run.sh" -nt "$BIN" ]; then
  if pkg-config --exists fcl 2>/dev/null; then
    # fcl.pc carries -std=c++11, which would override -std=c++17: drop it
    FCL_CFLAGS=$(pkg-config --cflags fcl | sed -E 's/(^| )-std=[^ ]*//g')
    FCL_LIBS=$(pkg-config --libs fcl)
  else
    FCL_CFLAGS="-I/usr/include/eigen3"
    FCL_LIBS="-lfcl -lccd"
  fi
  echo "run.sh: compiling $BIN" >&2
  # shellcheck disable=SC2086
  g++ -O2 -std=c++17 $FCL_CFLAGS -o "$BIN.tmp" "$HERE/fcl_bench.cpp" $FCL_LIBS -lz
  mv "$BIN.tmp" "$BIN"
fi

exec "$BIN" "$MESH_A" "$MESH_B" "$MOTION" "$PASSES"
