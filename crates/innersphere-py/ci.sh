#!/usr/bin/env bash
# The Python module's CI: a fresh virtual environment in a temporary folder, the module
# installed the way a user installs it (`pip install ./crates/innersphere-py`, a release
# build by maturin), imported, its type stubs checked against it (mypy stubtest), and its
# pytest suite run against the `ist` CLI.
#
# Run from anywhere (it works from the repository root). Builds where cargo puts them:
# CARGO_TARGET_DIR is honoured (by cargo for `ist`, by maturin for the module); without it
# the module builds in crates/innersphere-py/target, so that a second run is incremental.
# The tests on the real models run when ../shared/data is beside the repository (or
# INNERSPHERE_DATA points to it), and are skipped otherwise. IST_BIN=path uses that `ist`
# instead of building it (`cargo build --release -p ist`, a no-op when it is current).
# Fails when pytest fails or collects no test.
set -euo pipefail
cd "$(dirname "$0")/../.."
REPO=$(pwd)
PYTHON=${PYTHON:-python3}

# The `ist` the tests compare with.
if [ -z "${IST_BIN:-}" ]; then
  echo "== ist (the CLI the tests compare with)"
  cargo build --release -q -p ist
  TARGET=${CARGO_TARGET_DIR:-target}
  case "$TARGET" in /*) ;; *) TARGET="$REPO/$TARGET" ;; esac
  IST_BIN="$TARGET/release/ist"
fi
export IST_BIN INNERSPHERE_REQUIRE_IST=1
if [ -z "${INNERSPHERE_DATA:-}" ] && [ -d "$REPO/../shared/data/jaw" ]; then
  INNERSPHERE_DATA=$(cd "$REPO/../shared/data" && pwd)
fi
if [ -n "${INNERSPHERE_DATA:-}" ]; then export INNERSPHERE_DATA; fi

TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
echo "== virtual environment in $TMP ($($PYTHON --version))"
$PYTHON -m venv "$TMP/venv"
PY="$TMP/venv/bin/python"
"$PY" -m pip install -q --disable-pip-version-check --upgrade pip
"$PY" -m pip install -q --disable-pip-version-check maturin pytest numpy trimesh networkx manifold3d cgal mypy "dask[distributed]"

echo "== pip install ./crates/innersphere-py (maturin, release build)"
start=$(date +%s)
"$PY" -m pip install --disable-pip-version-check ./crates/innersphere-py
echo "built and installed in $(( $(date +%s) - start )) s"

echo "== import"
# From the temporary folder, so that the installed package is imported, not the source tree.
(cd "$TMP" && "$PY" -c "import innersphere; print('innersphere', innersphere.__version__, 'from', innersphere.__file__)")

echo "== type stubs match the module (mypy stubtest)"
(cd "$TMP" && "$PY" -m mypy.stubtest innersphere._innersphere --allowlist "$REPO/crates/innersphere-py/stubtest-allowlist.txt")

echo "== pytest"
set +e
# Each test has a time limit (conftest.py); the whole run has one more, as a last guard.
(cd "$TMP" && timeout -k 30 1500 "$PY" -m pytest -p no:cacheprovider -q -rs "$REPO/crates/innersphere-py/tests" 2>&1) | tee "$TMP/pytest.log"
rc=${PIPESTATUS[0]}
set -e
if [ "$rc" -eq 5 ]; then
  echo "FAILED: pytest collected no test" >&2; exit 1
fi
if [ "$rc" -ne 0 ]; then
  echo "FAILED: pytest exited with $rc" >&2; exit "$rc"
fi
if ! grep -Eq "[1-9][0-9]* passed" "$TMP/pytest.log"; then
  echo "FAILED: pytest passed no test" >&2; exit 1
fi
if [ -d "$REPO/../shared/data/jaw" ]; then
  echo "== the README's Python example, as written (from the repository root)"
  awk '/^```python$/{f=1;next} /^```$/{f=0} f' "$REPO/README.md" > "$TMP/readme_example.py"
  (cd "$REPO" && "$PY" "$TMP/readme_example.py")
fi
echo "innersphere-py CI: all passed"
