"""Per motion and kind: OLD and NEW p99 ranges and the NEW/OLD ratio of medians."""
import sys, statistics, collections
d = collections.defaultdict(list)
for line in open(sys.argv[1]):
    w, m, r, *kv = line.split()
    for x in kv:
        k, v = x.split("=")
        d[(m, k, w)].append(float(v))
for (m, k) in sorted({(m, k) for (m, k, _) in d}):
    o, n = d[(m, k, "OLD")], d[(m, k, "NEW")]
    ratio = statistics.median(n) / statistics.median(o)
    print(f"| {m} | {k} | {min(o):.1f}–{max(o):.1f} | {min(n):.1f}–{max(n):.1f} | {ratio:.3f} |")
