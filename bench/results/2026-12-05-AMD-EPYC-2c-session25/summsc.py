#!/usr/bin/python3
"""summsc.py FILE: absc.sh's rows, A against B per thread count and phase (ns per particle-step):
medians and the median of the per-round ratio B/A - 1."""
import statistics as st
import sys

data = {}
for line in open(sys.argv[1]):
    cells = line.split("|")
    label, _, rnd = cells[0].split()[:3]
    data[(label, int(rnd), int(cells[3]))] = [float(x) for x in cells[7:13]]
rounds = sorted({k[1] for k in data})
names = ["total", "advance", "normalise", "resample", "release", "bookkeeping"]
for t in (1, 2):
    for i, n in enumerate(names):
        a = [data[("A", r, t)][i] for r in rounds]
        b = [data[("B", r, t)][i] for r in rounds]
        d = [y / x - 1 for x, y in zip(a, b) if x > 0]
        if d:
            print(f"t{t} {n:11s} A {st.median(a):7.1f} B {st.median(b):7.1f} "
                  f"B/A-1 median {100 * st.median(d):+5.1f} % (B lower in {sum(x < 0 for x in d)}/{len(d)})")
