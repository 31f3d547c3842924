#!/usr/bin/python3
"""Loop closure on Bailey's webmap under unknown association, against known association.

For each simulator seed s (the filter seed is s too, as `grove bench fastslam-accuracy`), the
webmap is simulated (2 loops) and filtered once with the simulator's ids (known association)
and once per association rule given, the ids then only tagging the landmarks they create. Per
seed it prints the path RMSE of the weighted-mean pose, the landmarks mapped twice (the
heaviest map's landmarks whose source id another landmark also has) against the landmarks seen,
what the association did along the heaviest particle's ancestry (new, ignored, removed; under
jcbb the scans whose search stopped at its node budget, when the summary has them), and the
drift at the loop: the weighted-mean position and heading error when the vehicle first comes
back within 10 m of its start, with a lower bound on the squared Mahalanobis distance at which a
landmark of the first loop then appears, |position error|^2 / (2 (r sb)^2) for a landmark at
r = 20 m (the sensor's larger axis doubled for the landmark's own covariance; heading error
adds to it). The augment gate is 25.

  bench/studies/fastslam_loop_closure.py GROVE [--seeds 1-10] [--particles 100]
      [--filter fastslam2] [--associations ml,sampled,jcbb] [-- extra run flags]

Prints Markdown tables: one row per seed, then the mean and the range over seeds.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys
import tempfile


def parse_seeds(text):
    if "-" in text:
        a, b = text.split("-")
        return list(range(int(a), int(b) + 1))
    return [int(s) for s in text.split(",")]


def read_rows(path):
    with open(path, newline="") as f:
        return [{k: float(v) for k, v in row.items()} for row in csv.DictReader(f)]


def loop_time(truth):
    """The first time the vehicle is back within 10 m of its start after 100 m of travel."""
    x0, y0 = truth[0]["x"], truth[0]["y"]
    travelled, px, py = 0.0, x0, y0
    for r in truth:
        travelled += math.hypot(r["x"] - px, r["y"] - py)
        px, py = r["x"], r["y"]
        if travelled > 100 and math.hypot(r["x"] - x0, r["y"] - y0) < 10:
            return r["t"]
    return truth[-1]["t"]


def error_at(trajectory, truth, t):
    est = min(trajectory, key=lambda r: abs(r["t"] - t))
    tru = min(truth, key=lambda r: abs(r["t"] - t))
    dh = (est["heading"] - tru["heading"] + math.pi) % (2 * math.pi) - math.pi
    return math.hypot(est["x"] - tru["x"], est["y"] - tru["y"]), dh


def run(grove, sim, out, association, seed, args, extra):
    cmd = [grove, "fastslam", "run", "--controls", f"{sim}/controls.csv",
           "--observations", f"{sim}/observations.csv", "--truth", f"{sim}/truth.csv",
           "--landmarks-truth", f"{sim}/landmarks_truth.csv", "--association", association,
           "--particles", str(args.particles), "--filter", args.filter, "--seed", str(seed),
           "--threads", "1", "--out", out] + extra
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(f"{out}/summary.json") as f:
        summary = json.load(f)
    truth = read_rows(f"{sim}/truth.csv")
    t_loop = loop_time(truth)
    dp, dh = error_at(read_rows(f"{out}/trajectory.csv"), truth, t_loop)
    la = summary["landmark_accuracy"]
    a = summary.get("association", {})
    sb = summary["config"]["sigma_bearing_rad"]
    return {
        "rmse": summary["accuracy"]["position_rmse_m"],
        "landmarks": summary["landmarks"],
        "seen": la["true"] - la.get("true_without_estimate", 0),
        "twice": la.get("duplicates", 0),
        "new": a.get("created", 0),
        "ignored": a.get("ignored", 0),
        "removed": a.get("removed", 0),
        "truncated": a.get("truncated", 0),
        "dp": dp,
        "dh_deg": math.degrees(dh),
        "d2": dp * dp / (2 * (20 * sb) ** 2),
    }


def stats(values):
    return (sum(values) / len(values), min(values), max(values))


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        extra = argv[argv.index("--") + 1:]
        argv = argv[:argv.index("--")]
    p = argparse.ArgumentParser()
    p.add_argument("grove")
    p.add_argument("--seeds", default="1-10")
    p.add_argument("--particles", type=int, default=100)
    p.add_argument("--filter", default="fastslam2")
    p.add_argument("--associations", default="ml")
    args = p.parse_args(argv)
    grove = os.path.abspath(args.grove)
    if os.path.isdir(grove):
        grove = os.path.join(grove, "tools", "grove")
    associations = args.associations.split(",")
    seeds = parse_seeds(args.seeds)
    results = {a: [] for a in ["known"] + associations}
    with tempfile.TemporaryDirectory() as tmp:
        for seed in seeds:
            sim = f"{tmp}/sim{seed}"
            subprocess.run([grove, "fastslam", "simulate", "--seed", str(seed), "--out", sim],
                           check=True, stdout=subprocess.DEVNULL)
            for a in results:
                results[a].append(run(grove, sim, f"{tmp}/{a}{seed}", a, seed, args, extra))
                print(f"seed {seed} {a}: RMSE {results[a][-1]['rmse']:.2f} m", file=sys.stderr)
    print(f"Webmap, {args.filter}, {args.particles} particles, seeds {args.seeds} "
          f"(simulator and filter){' ' + ' '.join(extra) if extra else ''}\n")
    for a in associations:
        print(f"### association {a} against known\n")
        print("| seed | RMSE known (m) | RMSE unknown (m) | ratio | landmarks | seen | mapped "
              "twice | new | ignored | removed | error at loop, known (m, deg) | unknown (m, "
              "deg) | d2 bound, unknown |")
        print("| --- " * 13 + "|")
        for seed, k, u in zip(seeds, results["known"], results[a]):
            print(f"| {seed} | {k['rmse']:.2f} | {u['rmse']:.2f} | {u['rmse'] / k['rmse']:.2f} | "
                  f"{u['landmarks']} | {u['seen']} | {u['twice']} | {u['new']} | "
                  f"{u['ignored']} | {u['removed']} | {k['dp']:.2f}, {k['dh_deg']:.2f} | "
                  f"{u['dp']:.2f}, {u['dh_deg']:.2f} | {u['d2']:.0f} |")
        km, kl, kh = stats([r["rmse"] for r in results["known"]])
        um, ul, uh = stats([r["rmse"] for r in results[a]])
        twice = sum(r["twice"] for r in results[a])
        seen = sum(r["seen"] for r in results[a])
        print(f"\nmean RMSE known {km:.2f} m ({kl:.2f}..{kh:.2f}), unknown {um:.2f} m "
              f"({ul:.2f}..{uh:.2f}), ratio of means {um / km:.2f} (target <= 1.2); mapped "
              f"twice {twice} of {seen} seen ({100 * twice / seen:.1f} %, target <= 5 %); "
              f"per seed {min(r['twice'] for r in results[a])}.."
              f"{max(r['twice'] for r in results[a])}; scans at the search's node budget "
              f"{sum(r['truncated'] for r in results[a])}\n")


if __name__ == "__main__":
    main()
