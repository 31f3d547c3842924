#!/usr/bin/python3
"""The summary tables of README.md from the per-run rows of the islands_*.md files here.

  summarise_islands.py seed1   # islands_walks_*.md and islands_extra_*.md: filter seed 1
  summarise_islands.py seeds   # islands_seeds.md: filter seeds 1-3
A run "over 2 m" is one whose aligned RMSE exceeds 2 m (a loop that did not close: the error is
bimodal, 0.4-1.4 m or 3-4 m).
"""
import glob
import re
import statistics
import sys

which = sys.argv[1] if len(sys.argv) > 1 else "seed1"
files = (sorted(glob.glob("islands_walks_*.md")) + sorted(glob.glob("islands_extra_*.md"))
         if which == "seed1" else ["islands_seeds.md"])
runs, order = {}, []
for f in files:
    for line in open(f):
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) != (5 if which == "seed1" else 6) or not re.fullmatch(r"\d+", cells[1]):
            continue
        if which == "seed1":
            name, key, rmse, secs, rss = cells[0], (cells[1], "1"), *cells[2:5]
        else:
            name, key, rmse, secs, rss = cells[0], (cells[1], cells[2]), *cells[3:6]
        if name not in runs:
            runs[name] = {}
            order.append(name)
        runs[name][key] = (float(rmse), float(secs), int(rss))
base_name = order[0]
base = runs[base_name]
print("| configuration | runs | aligned RMSE (m): mean | median | worst | runs over 2 m | "
      "mean of the others | mean difference from the global mode (m) | runs no worse | "
      "filter s, median | peak RSS MiB, median |")
print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
for name in order:
    r = runs[name]
    keys = sorted(r)
    v = [r[k][0] for k in keys]
    d = [r[k][0] - base[k][0] for k in keys]
    print(f"| {name} | {len(v)} | {statistics.mean(v):.2f} | {statistics.median(v):.2f} | "
          f"{max(v):.2f} | {sum(x > 2 for x in v)} | "
          f"{statistics.mean([x for x in v if x <= 2]):.2f} | {statistics.mean(d):+.2f} | "
          f"{sum(x <= 0 for x in d)} | {statistics.median([r[k][1] for k in keys]):.1f} | "
          f"{statistics.median([r[k][2] for k in keys]):.0f} |")
