#!/usr/bin/python3
"""grove's FastSLAM against Tim Bailey's MATLAB FastSLAM on identical noisy inputs.

For each simulator seed s, `grove fastslam simulate --seed s` writes Bailey's webmap (2 loops,
his noise: sigma V 0.3 m/s, sigma G 3 deg, sigma r 0.1 m, sigma b 1 deg, controls every
0.025 s, a scan every 8 controls). The same controls.csv and observations.csv are filtered by
`grove fastslam run --filter F --particles P --seed s --threads 1` (known association) and by
Bailey's own filter functions under Octave, driven by bailey_parity_driver.m (beside this
script), which replaces only his simulator's loop by the CSV rows; his random streams are
seeded with s. His weights are kept as logarithms (--weights log, the default; see the driver:
his linear products underflow to 0 in every particle at a loop closure). Both weighted-mean paths are scored by one function here: the position RMSE
against truth.csv at every truth time (the estimate after the scan where a scan falls).

  bench/studies/bailey_parity.py GROVE BAILEY_FASTSLAM_DIR --work DIR [--seeds 1-10]
      [--particles 100] [--filters fastslam2,fastslam1] [--jobs 2] [--weights log|linear]

BAILEY_FASTSLAM_DIR is the `fastslam` folder of his code (OpenSLAM's bailey-slam); his
configfile.m must hold the noise above, which the script checks against grove's configuration.
DIR keeps every run: a run whose output exists is not rerun. Needs octave-cli. Prints a
Markdown table per filter: each seed's RMSEs, then the means and the paired difference
(grove - Bailey) with its 95 % Student-t interval.
"""
import argparse
import concurrent.futures
import csv
import json
import math
import os
import statistics
import subprocess
import sys

from fastslam_loop_closure import parse_seeds

# Two-sided 95 % Student-t quantiles by degrees of freedom.
T95 = {1: 12.706, 2: 4.303, 3: 3.182, 4: 2.776, 5: 2.571, 6: 2.447, 7: 2.365, 8: 2.306,
       9: 2.262, 10: 2.228, 11: 2.201, 12: 2.179, 13: 2.160, 14: 2.145, 15: 2.131, 16: 2.120,
       17: 2.110, 18: 2.101, 19: 2.093, 20: 2.086, 25: 2.060, 30: 2.042}


def t95(dof):
    return T95[max(k for k in T95 if k <= dof)]


def time_key(t):
    return round(float(t) * 1e6)


def read_path(path):
    """t -> (x, y); of several rows at one time the last (after the scan) wins."""
    out = {}
    with open(path, newline="") as f:
        for row in csv.DictReader(f):
            out[time_key(row["t"])] = (float(row["x"]), float(row["y"]))
    return out


def position_rmse(truth_csv, path_csv):
    truth, est = read_path(truth_csv), read_path(path_csv)
    sq = [(est[t][0] - x) ** 2 + (est[t][1] - y) ** 2 for t, (x, y) in truth.items()
          if t in est]
    if len(sq) != len(truth):
        sys.exit(f"{path_csv}: {len(truth) - len(sq)} truth times without an estimate")
    return math.sqrt(sum(sq) / len(sq))


def simulate(grove, work, seed):
    sim = os.path.join(work, f"sim_{seed}")
    if not os.path.exists(os.path.join(sim, "truth.csv")):
        subprocess.run([grove, "fastslam", "simulate", "--seed", str(seed), "--out", sim],
                       check=True, stdout=subprocess.DEVNULL)
    return sim


def run_grove(grove, sim, out, filt, particles, seed):
    if not os.path.exists(os.path.join(out, "summary.json")):
        subprocess.run([grove, "fastslam", "run", "--controls", f"{sim}/controls.csv",
                        "--observations", f"{sim}/observations.csv", "--truth",
                        f"{sim}/truth.csv", "--filter", filt, "--particles", str(particles),
                        "--seed", str(seed), "--threads", "1", "--no-progress", "--out", out],
                       check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(os.path.join(out, "summary.json")) as f:
        return json.load(f)


def run_bailey(bailey, sim, out, filt, particles, seed, weights):
    if not os.path.exists(out):
        here = os.path.dirname(os.path.abspath(__file__))
        tmp = out + ".tmp"
        call = (f"addpath('{here}'); bailey_parity_driver('{bailey}', '{sim}', '{filt}', "
                f"{particles}, {seed}, '{tmp}', '{weights}')")
        subprocess.run(["octave-cli", "--no-gui", "-q", "--eval", call], check=True,
                       stdout=subprocess.DEVNULL)
        os.replace(tmp + ".params", out + ".params")
        os.replace(tmp, out)
    with open(out + ".params") as f:
        return dict(line.strip().split("=") for line in f if "=" in line)


def check_settings(params, config):
    """Bailey's settings as his driver used them against grove's filter configuration."""
    for key in ("wheelbase_m", "sigma_speed_mps", "sigma_steer_rad", "sigma_range_m",
                "sigma_bearing_rad"):
        if abs(float(params[key]) - float(config[key])) > 1e-12:
            sys.exit(f"Bailey's {key} = {params[key]}, grove's = {config[key]}")


def one_seed(args, work, filt, seed):
    sim = simulate(args.grove, work, seed)
    summary = run_grove(args.grove, sim, os.path.join(work, f"grove_{filt}_{seed}"), filt,
                        args.particles, seed)
    bailey_csv = os.path.join(work, f"bailey_{args.weights}_{filt}_{seed}.csv")
    params = run_bailey(args.bailey, sim, bailey_csv, filt, args.particles, seed, args.weights)
    check_settings(params, summary["config"])
    grove_rmse = position_rmse(f"{sim}/truth.csv",
                               os.path.join(work, f"grove_{filt}_{seed}", "trajectory.csv"))
    reported = summary["accuracy"]["position_rmse_m"]
    if abs(grove_rmse - reported) > 1e-6 * max(1.0, reported):
        sys.exit(f"seed {seed}: RMSE {grove_rmse} here, {reported} in grove's summary")
    return seed, grove_rmse, position_rmse(f"{sim}/truth.csv", bailey_csv)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("grove")
    p.add_argument("bailey", help="the fastslam folder of Bailey's MATLAB code")
    p.add_argument("--work", required=True)
    p.add_argument("--seeds", default="1-10")
    p.add_argument("--particles", type=int, default=100)
    p.add_argument("--filters", default="fastslam2,fastslam1")
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--weights", choices=("log", "linear"), default="log",
                   help="Bailey's weights as logarithms (default) or his linear products")
    args = p.parse_args()
    args.grove = os.path.abspath(args.grove)
    args.bailey = os.path.abspath(args.bailey)
    work = os.path.abspath(args.work)
    os.makedirs(work, exist_ok=True)
    seeds = parse_seeds(args.seeds)
    for s in seeds:
        simulate(args.grove, work, s)
    for filt in args.filters.split(","):
        with concurrent.futures.ThreadPoolExecutor(args.jobs) as pool:
            rows = sorted(pool.map(lambda s: one_seed(args, work, filt, s), seeds))
        print(f"\n{filt}, {args.particles} particles, known association\n")
        print("| simulator seed | grove RMSE | Bailey RMSE | grove - Bailey |")
        print("| --- | --- | --- | --- |")
        for s, g, b in rows:
            print(f"| {s} | {g:.2f} m | {b:.2f} m | {g - b:+.2f} m |")
        g = [r[1] for r in rows]
        b = [r[2] for r in rows]
        d = [x - y for x, y in zip(g, b)]
        mean = statistics.fmean(d)
        half = t95(len(d) - 1) * statistics.stdev(d) / math.sqrt(len(d)) if len(d) > 1 else 0
        print(f"| mean of {len(rows)} | {statistics.fmean(g):.2f} m | {statistics.fmean(b):.2f} m"
              f" | {mean:+.2f} m ({mean - half:+.2f} .. {mean + half:+.2f}) |")


if __name__ == "__main__":
    main()
