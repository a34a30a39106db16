#!/usr/bin/env bash
# blind.sh: the C interface (include/innersphere.h) against `ist query --json`, bit for bit.
#
# Usage: crates/innersphere-c/tests/c/blind.sh A.ist B.ist
#   (written against the header only, by someone who had not read the Rust code; run by
#   run.sh on generated trees, and passes on the real jaw trees built with --preset jaw)
#
# Builds blind_test.c against target/release/libinnersphere_c.a (CARGO_TARGET_DIR honoured),
# then for each pose of B (A at the identity) runs the C program once and
# `ist query A B --pose-b POSE --query KIND --json` for KIND in distance, contact,
# multipoint, penetration, and compares the numbers with == after parsing:
#   distance:    distance, contact flag, point_a, point_b
#   contact:     contact flag
#   multipoint:  number of contacts (k = 16), then each contact's point, normal, depth, leaves
#   penetration: volume, max_depth, normal, force, torque_a, torque_b, number of patches,
#                then each patch's point, normal, depth, volume, pairs
# One line per pose and kind; exit status 1 on any difference.
# BLIND_REUSE=1 runs the C queries on one pair without ist_pair_reset between them.
set -euo pipefail

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
root="$(cd "$here/../../../.." && pwd)"
A="$(realpath "${1:?usage: blind.sh A.ist B.ist}")"
B="$(realpath "${2:?usage: blind.sh A.ist B.ist}")"
cd "$root"

TARGET="${CARGO_TARGET_DIR:-target}"
LIB="$TARGET/release/libinnersphere_c.a"
IST="$TARGET/release/ist"
if [[ ! -f "$LIB" || ! -x "$IST" ]]; then
    echo "blind.sh: building $LIB and $IST" >&2
    cargo build --release -p innersphere-c -p ist
fi

work="$(mktemp -d "${TMPDIR:-/tmp}/ist-blind.XXXXXX")"
trap 'rm -rf "$work"' EXIT

cc -std=c99 -Wall -Wextra -Werror -Iinclude "$here/blind_test.c" -o "$work/blind_test" \
    "$LIB" -lpthread -ldl -lm

reuse=()
if [[ "${BLIND_REUSE:-0}" == 1 ]]; then
    reuse=(reuse)
fi

# name|pose "tx ty tz qw qx qy qz"|stiffness (empty: the defaults of both sides)
poses=(
    "apart_5mm_z|0 0 -5 1 0 0 0|"
    "apart_oblique|4 -3 -6 1 0 0 0|"
    "near_0.3mm|0 0 -0.3 1 0 0 0|"
    "touching_gap_7e-6|0 0 -0.2883 1 0 0 0|"
    "touching|0 0 -0.28829 1 0 0 0|"
    "touching_in|0 0 -0.2882 1 0 0 0|"
    "identity|0 0 0 1 0 0 0|"
    "bite_z+0.1|0 0 0.1 1 0 0 0|"
    "bite_z+0.2|0 0 0.2 1 0 0 0|"
    "bite_z+0.3|0 0 0.3 1 0 0 0|"
    "turned_x|0 0 0 0.99995 0.01 0 0|"
    "turned_xyz_unnormalised|0.05 -0.1 0.15 0.9999 0.005 -0.008 0.003|"
    "turned_apart|0 0 -2 0.9998 0 0.02 0|"
    "deep_z+1|0 0 1 1 0 0 0|"
    "identity_stiffness_0.5|0 0 0 1 0 0 0|0.5"
    "bite_z+0.2_stiffness_1000|0 0 0.2 1 0 0 0|1000"
)

manifest="$work/manifest.txt"
: >"$manifest"
i=0
for entry in "${poses[@]}"; do
    IFS='|' read -r name pose stiff <<<"$entry"
    dir="$work/$i"
    mkdir -p "$dir"
    # shellcheck disable=SC2086 # the pose is seven words on purpose
    cargs=($pose)
    if [[ -n "$stiff" ]]; then
        cargs+=("$stiff")
        kinds=(penetration)
    else
        kinds=(distance contact multipoint penetration)
    fi
    "$work/blind_test" "$A" "$B" "${cargs[@]}" ${reuse[@]+"${reuse[@]}"} >"$dir/c.json"
    for kind in "${kinds[@]}"; do
        extra=()
        if [[ "$kind" == penetration && -n "$stiff" ]]; then
            extra=(--stiffness "$stiff")
        fi
        "$IST" query "$A" "$B" --pose-b "$pose" --query "$kind" --json \
            ${extra[@]+"${extra[@]}"} >"$dir/$kind.json"
    done
    printf '%s|%s|%s|%s|%s\n' "$name" "$pose" "$stiff" "$dir" "${kinds[*]}" >>"$manifest"
    i=$((i + 1))
done

python3 - "$manifest" <<'PY'
import json
import sys

failures = 0


def load(path):
    with open(path) as f:
        return json.load(f)


class Cmp:
    def __init__(self):
        self.n = 0
        self.diffs = []

    def num(self, field, c, r):
        self.n += 1
        # JSON booleans of ist against the C ints 0/1: compare as numbers.
        if isinstance(c, bool):
            c = int(c)
        if isinstance(r, bool):
            r = int(r)
        if not (isinstance(c, (int, float)) and isinstance(r, (int, float))) or not (c == r):
            self.diffs.append("%s: C=%r ist=%r" % (field, c, r))

    def vec(self, field, c, r):
        if len(c) != len(r):
            self.diffs.append("%s: length C=%d ist=%d" % (field, len(c), len(r)))
            return
        for j, (x, y) in enumerate(zip(c, r)):
            self.num("%s[%d]" % (field, j), x, y)


def check_distance(c, r, k):
    d = c["distance"]
    k.num("distance", d["distance"], r["distance"])
    k.num("contact", d["contact"], r["contact"])
    k.vec("point_a", d["point_a"], r["point_a"])
    k.vec("point_b", d["point_b"], r["point_b"])


def check_contact(c, r, k):
    k.num("contact", c["contact"]["contact"], r["contact"])


def check_multipoint(c, r, k):
    m = c["multipoint"]
    k.num("count", m["count"], len(r["contacts"]))
    for j, (x, y) in enumerate(zip(m["contacts"], r["contacts"])):
        for f in ("point", "normal"):
            k.vec("contacts[%d].%s" % (j, f), x[f], y[f])
        for f in ("depth", "leaf_a", "leaf_b"):
            k.num("contacts[%d].%s" % (j, f), x[f], y[f])


def check_penetration(c, r, k):
    p = c["penetration"]
    for f in ("volume", "max_depth"):
        k.num(f, p[f], r[f])
    for f in ("normal", "force", "torque_a", "torque_b"):
        k.vec(f, p[f], r[f])
    k.num("patch_count", p["patch_count"], len(r["patches"]))
    for j, (x, y) in enumerate(zip(p["patches"], r["patches"])):
        for f in ("point", "normal"):
            k.vec("patches[%d].%s" % (j, f), x[f], y[f])
        for f in ("depth", "volume", "pairs"):
            k.num("patches[%d].%s" % (j, f), x[f], y[f])


checks = {
    "distance": check_distance,
    "contact": check_contact,
    "multipoint": check_multipoint,
    "penetration": check_penetration,
}

lines = 0
with open(sys.argv[1]) as manifest:
    for line in manifest:
        name, pose, stiff, d, kinds = line.rstrip("\n").split("|")
        c = load(d + "/c.json")
        for kind in kinds.split():
            r = load("%s/%s.json" % (d, kind))
            k = Cmp()
            checks[kind](c, r, k)
            lines += 1
            label = "%-28s %-12s" % (name, kind)
            if kind == "distance":
                info = "distance=%r contact=%s" % (r["distance"], r["contact"])
            elif kind == "contact":
                info = "contact=%s" % r["contact"]
            elif kind == "multipoint":
                info = "contacts=%d" % len(r["contacts"])
            else:
                info = "volume=%r patches=%d stiffness=%s" % (
                    r["volume"], len(r["patches"]), stiff or "1 (default)")
            if k.diffs:
                failures += 1
                print("%s DIFF  (%d of %d values differ; pose \"%s\"; %s)" % (
                    label, len(k.diffs), k.n, pose, info))
                for x in k.diffs:
                    print("    " + x)
            else:
                print("%s ok    (%d values equal; %s)" % (label, k.n, info))

print("%d pose/kind comparisons, %d with differences" % (lines, failures))
sys.exit(1 if failures else 0)
PY
