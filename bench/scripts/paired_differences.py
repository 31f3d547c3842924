#!/usr/bin/python3
"""Paired comparison of filters from a `grove fastslam montecarlo` summary.json: run r of every
filter sees the same simulation (seed S + r), so the per-run difference of two filters' position
MSE means removes the runs' common variation. Prints, for each listed pair A B, the mean of
MSE(A) - MSE(B) over the runs both finished, its 95 % Student-t interval and the share of runs in
which A's error was lower.
  bench/scripts/paired_differences.py SUMMARY.json A:particles B:particles [A B ...]"""
import json
import math
import statistics
import sys

# Two-sided 95 % Student-t quantiles t_{0.975, n-1} for n runs (tables).
T975 = {2: 12.706, 3: 4.303, 4: 3.182, 5: 2.776, 6: 2.571, 8: 2.365, 10: 2.262, 20: 2.093,
        30: 2.045}


def runs(summary, key):
    name, particles = key.split(":")
    for g in summary["groups"]:
        if g["filter"] == name and g["particles"] == int(particles):
            return {r["run"]: r["position_mse_mean"] for r in g["runs"] if r["status"] == "ok"}
    sys.exit(f"no group {key}")


summary = json.load(open(sys.argv[1]))
pairs = sys.argv[2:]
print("| A | B | runs | mean of MSE(A) - MSE(B), m² (95 % CI) | A lower in |")
print("| --- | --- | --- | --- | --- |")
for a, b in zip(pairs[0::2], pairs[1::2]):
    ra, rb = runs(summary, a), runs(summary, b)
    common = sorted(set(ra) & set(rb))
    d = [ra[k] - rb[k] for k in common]
    n = len(d)
    m = statistics.mean(d)
    half = T975[n] * statistics.stdev(d) / math.sqrt(n) if n > 1 else float("nan")
    lower = sum(1 for x in d if x < 0)
    print(f"| {a} | {b} | {n} | {m:.4g} ({m - half:.4g} .. {m + half:.4g}) | {lower} of {n} |")
