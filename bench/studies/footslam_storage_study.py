#!/usr/bin/python3
"""Storage of diversity on the simulator's hour-long campus walks (three buildings 100 m apart).

For each walk seed and store distance (0: no storage) runs `grove footslam run` and reports the
aligned RMSE of the smoothed and filtered-mean paths against the truth, over the whole walk and
over the steps spent in a building the walk had left for at least five minutes (the returns,
where stored areas are restored), the particles' map memory (live at the end and peak), the
blocks stored (and how many folds were exact), the stored map's hexagons, the seconds storing
took and the run time. Prints a Markdown table.

Usage: bench/studies/footslam_storage_study.py GROVE_BINARY OUT_DIR [--particles N] [--seeds 1,2,3]
       [--distances 0,30,60] [--minutes 60]
"""
import argparse
import csv
import json
import math
import os
import subprocess
import time

SPACING = 100.0  # the campus's building spacing (tools/sim/walk_simulator.cc)


def read_points(path):
    with open(path) as f:
        return [(float(r["t"]), float(r["x"]), float(r["y"])) for r in csv.DictReader(f)]


def building_of(x):
    """The building a true x lies in, or None outdoors (buildings span [-1, 37] + 100 k)."""
    k = round((x - 18) / SPACING)
    return k if abs(x - 18 - SPACING * k) <= 19 else None


def return_mask(truth, away_s=300.0):
    """True for the truth points in a building the walk had left for at least away_s seconds."""
    last_in = {}
    returned = set()
    mask = []
    current = None
    for t, x, _ in truth:
        b = building_of(x)
        if b is not None and b != current:
            if b in last_in and t - last_in[b] >= away_s:
                returned.add(b)
            elif b not in last_in:
                returned.discard(b)
        current = b if b is not None else current
        mask.append(b is not None and b in returned)
        if b is not None:
            last_in[b] = t
    return mask


def aligned_rmse(truth, estimate, mask=None):
    """RMSE after the rigid 2-D alignment (least squares) of estimate to truth, over mask."""
    pairs = [(p, q) for k, (p, q) in enumerate(zip(truth, estimate)) if mask is None or mask[k]]
    if not pairs:
        return float("nan")
    n = len(pairs)
    mx = sum(q[1] for _, q in pairs) / n
    my = sum(q[2] for _, q in pairs) / n
    tx = sum(p[1] for p, _ in pairs) / n
    ty = sum(p[2] for p, _ in pairs) / n
    s_cos = s_sin = 0.0
    for p, q in pairs:
        ax, ay = q[1] - mx, q[2] - my
        bx, by = p[1] - tx, p[2] - ty
        s_cos += ax * bx + ay * by
        s_sin += ax * by - ay * bx
    a = math.atan2(s_sin, s_cos)
    c, s = math.cos(a), math.sin(a)
    err = 0.0
    for p, q in pairs:
        ax, ay = q[1] - mx, q[2] - my
        ex = c * ax - s * ay + tx - p[1]
        ey = s * ax + c * ay + ty - p[2]
        err += ex * ex + ey * ey
    return math.sqrt(err / n)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("grove")
    ap.add_argument("out")
    ap.add_argument("--particles", type=int, default=5000)
    ap.add_argument("--seeds", default="1,2,3")
    ap.add_argument("--distances", default="0,30,60")
    ap.add_argument("--minutes", type=float, default=60)
    args = ap.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for seed in [int(s) for s in args.seeds.split(",")]:
        walk = os.path.join(args.out, f"campus{seed}")
        subprocess.run([args.grove, "footslam", "simulate", "--scenario", "campus", "--minutes",
                        str(args.minutes), "--seed", str(seed), "--out", walk], check=True,
                       stderr=subprocess.DEVNULL)
        truth = read_points(os.path.join(walk, "truth.csv"))
        mask = return_mask(truth)
        for d in [float(x) for x in args.distances.split(",")]:
            out = os.path.join(args.out, f"run_s{seed}_d{d:g}")
            start = time.monotonic()
            subprocess.run([args.grove, "footslam", "run", "--steps",
                            os.path.join(walk, "steps.csv"), "--particles", str(args.particles),
                            "--store-distance-m", str(d), "--out", out, "--no-progress"],
                           check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
            seconds = time.monotonic() - start
            with open(os.path.join(out, "summary.json")) as f:
                summary = json.load(f)
            smoothed = read_points(os.path.join(out, "smoothed_trajectory.csv"))
            mean = read_points(os.path.join(out, "mean_trajectory.csv"))
            store = summary.get("storage_of_diversity", {})
            rows.append({
                "seed": seed, "distance": d,
                "smoothed": aligned_rmse(truth, smoothed),
                "smoothed_returns": aligned_rmse(truth, smoothed, mask),
                "mean": aligned_rmse(truth, mean),
                "mean_returns": aligned_rmse(truth, mean, mask),
                "return_steps": sum(mask),
                "live_mib": summary["map_memory"]["live_bytes"] / 2**20,
                "peak_mib": summary["map_memory"]["peak_live_bytes"] / 2**20,
                "blocks": store.get("stored_blocks", 0),
                "exact": store.get("stored_blocks_exact", 0),
                "hexagons": store.get("stored_hexagons", 0),
                "store_s": store.get("seconds", 0.0),
                "run_s": seconds,
            })
            print(json.dumps(rows[-1]), flush=True)
    print()
    print("| seed | store distance | smoothed RMSE (returns) | mean RMSE (returns) | return steps "
          "| map live / peak MiB | blocks (exact) | stored hexagons | storing s | run s |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        distance = "off" if r["distance"] == 0 else f"{r['distance']:g} m"
        print(f"| {r['seed']} | {distance} "
              f"| {r['smoothed']:.2f} ({r['smoothed_returns']:.2f}) "
              f"| {r['mean']:.2f} ({r['mean_returns']:.2f}) | {r['return_steps']} "
              f"| {r['live_mib']:.1f} / {r['peak_mib']:.1f} | {r['blocks']} ({r['exact']}) "
              f"| {r['hexagons']} | {r['store_s']:.2f} | {r['run_s']:.1f} |")


if __name__ == "__main__":
    main()
