#!/usr/bin/env bash
# The C ABI end to end (run by .ci/run): builds the C library and the Rust reference,
# compiles tests/c/abi_test.c against the header and the static library with
# AddressSanitizer and UndefinedBehaviorSanitizer (leak checking on), runs both and diffs
# their answers (bit for bit), then builds and runs the C++ servo-loop example on a short
# motion. Honours CARGO_TARGET_DIR.
set -euo pipefail
cd "$(dirname "$0")/../../../.."
TARGET="${CARGO_TARGET_DIR:-target}"
cargo build --release -q -p innersphere-c --lib --example reference
LIB="$TARGET/release/libinnersphere_c.a"
OUT=$(mktemp -d)
trap 'rm -rf "$OUT"' EXIT
CC="${CC:-cc}"
SAN="-fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all"
$CC -std=c99 -Wall -Wextra -Werror -pedantic -g -O1 $SAN -Iinclude \
    crates/innersphere-c/tests/c/abi_test.c "$LIB" -lpthread -ldl -lm -o "$OUT/abi_test"
"$TARGET/release/examples/reference" make "$OUT"
"$TARGET/release/examples/reference" answer "$OUT" > "$OUT/rust.txt"
ASAN_OPTIONS=detect_leaks=1 "$OUT/abi_test" "$OUT" > "$OUT/c.txt"
if ! cmp -s "$OUT/rust.txt" "$OUT/c.txt"; then
  echo "FAILED: the C answers differ from the Rust answers:" >&2
  diff "$OUT/rust.txt" "$OUT/c.txt" | head -20 >&2
  exit 1
fi
echo "ok: C answers equal the Rust answers bit for bit ($(wc -l < "$OUT/rust.txt") lines), no ASan/UBSan/leak report"

# A C program written against the header alone agrees with `ist query --json`, bit for bit.
cargo build --release -q -p ist
bash crates/innersphere-c/tests/c/blind.sh "$OUT/a.ist" "$OUT/b.ist" | tail -1

# The README's C example compiles and runs (on the generated trees under its file names).
awk '/^```c$/{f=1;next} /^```$/{f=0} f' README.md > "$OUT/readme.c"
$CC -std=c99 -Wall -Wextra -Werror $SAN -Iinclude "$OUT/readme.c" "$LIB" -lpthread -ldl -lm -o "$OUT/readme"
cp "$OUT/a.ist" "$OUT/maxilla.ist"
cp "$OUT/b.ist" "$OUT/mandible.ist"
(cd "$OUT" && ./readme) | grep -q "mm apart" || { echo "FAILED: the README's C example"; exit 1; }
echo "ok: the README's C example"

# The C++ servo-loop example (and its CHAI3D-style adapter, against stubs) on the same trees.
make -s -C examples/cpp TARGET="$(cd "$TARGET" && pwd)" CXXFLAGS="-std=c++17 -O2 -Wall -Wextra -Werror $SAN"
ASAN_OPTIONS=detect_leaks=1 examples/cpp/haptic_loop "$OUT/a.ist" "$OUT/b.ist" "$OUT/device.csv" > "$OUT/cpp.json"
grep -q '"ticks": 600,' "$OUT/cpp.json" || { echo "FAILED: the C++ example"; cat "$OUT/cpp.json"; exit 1; }
grep -q '"over_budget": 0,' "$OUT/cpp.json" || echo "warning: ticks over budget under the sanitizers: $(cat "$OUT/cpp.json")"
echo "ok: C++ example: $(cat "$OUT/cpp.json")"
rm -f examples/cpp/haptic_loop
