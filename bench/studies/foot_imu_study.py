#!/usr/bin/python3
"""The foot IMU front end on simulated walks: step accuracy, heading drift against what the
sensor model predicts, the zero-velocity detectors compared, and FootSLAM on the IMU's steps
against FootSLAM on the simulator's step file of the same walk.

  bench/studies/foot_imu_study.py --grove build/tools/grove --out foot-imu-study

For each walk seed w and sensor seed s: `grove footslam simulate --seed w --imu --imu-seed s`
(a building walk with its step file, truth, imu.csv and the foot's true stances), then
`grove footslam steps` with each detector at its default threshold, then `grove footslam run`
(seed s) on the IMU's steps (SHOE) and on the step file, each scored by `grove footslam
evaluate` against the truth. Prints Markdown tables; writes OUT/study.json.
"""
import argparse
import csv
import json
import math
import os
import subprocess
import sys

import numpy as np

DETECTORS = ["shoe", "are", "mv", "mag"]
# The simulator's default z-gyro scale factor error (tools/sim/foot_imu_simulator.h), 1 sigma.
GYRO_SCALE_SIGMA = 0.005


def run(cmd):
    subprocess.run(cmd, check=True, stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def read_csv(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def wrap(a):
    return (a + math.pi) % (2 * math.pi) - math.pi


def stance_metrics(true_stances, detected, times):
    """Boundary errors (ms), missed and false stances, and per-sample error rates."""
    inner = true_stances[1:-1]  # the first and last are the long rests
    begin_err, end_err, missed = [], [], 0
    for s in inner:
        hits = [d for d in detected if d[0] <= s[1] and d[1] >= s[0]]
        if not hits:
            missed += 1
            continue
        begin_err.append(1000 * (min(d[0] for d in hits) - s[0]))
        end_err.append(1000 * (max(d[1] for d in hits) - s[1]))
    false = sum(1 for d in detected
                if not any(d[0] <= s[1] and d[1] >= s[0] for s in true_stances))
    truth = np.zeros(len(times), bool)
    for s in true_stances:
        truth |= (times >= s[0]) & (times <= s[1])
    found = np.zeros(len(times), bool)
    for d in detected:
        found |= (times >= d[0]) & (times <= d[1])
    # Only between the first and the last stance's end (the detected list has no rests).
    window = (times >= true_stances[0][1]) & (times <= true_stances[-1][0])
    moving = window & ~truth
    still = window & truth
    return {
        "begin_ms": float(np.mean(begin_err)) if begin_err else float("nan"),
        "end_ms": float(np.mean(end_err)) if end_err else float("nan"),
        "abs_boundary_ms": float(np.mean(np.abs(begin_err + end_err))) if begin_err else float("nan"),
        "missed": missed,
        "false": false,
        "false_still_pct": 100.0 * np.sum(found & moving) / max(1, np.sum(moving)),
        "missed_still_pct": 100.0 * np.sum(~found & still) / max(1, np.sum(still)),
    }


def step_metrics(true_stances, steps):
    """Each step matched to the true stance nearest its time: length error (% RMS), heading
    drift at the end, and the final position error of the summed steps."""
    mids = np.array([(s[0] + s[1]) / 2 for s in true_stances])
    length_err, prev = [], 0
    heading_sum = 0.0
    for st in steps:
        k = int(np.argmin(np.abs(mids - float(st["t"]))))
        if abs(mids[k] - float(st["t"])) > 0.2 or k <= prev:
            continue
        a, b = true_stances[prev], true_stances[k]
        true_len = math.hypot(b[2] - a[2], b[3] - a[3])
        est_len = math.hypot(float(st["dx"]), float(st["dy"]))
        if true_len > 0.3:
            length_err.append((est_len - true_len) / true_len)
        heading_sum += float(st["dheading"]) - (b[4] - a[4])
        prev = k
    net_turn = true_stances[prev][4] - true_stances[0][4]
    turned = sum(abs(true_stances[i + 1][4] - true_stances[i][4]) for i in range(prev))
    return {
        "length_rms_pct": 100.0 * math.sqrt(np.mean(np.square(length_err))),
        "heading_drift_deg": math.degrees(heading_sum),
        "net_turn_deg": math.degrees(net_turn),
        "turned_deg": math.degrees(turned),
        "predicted_drift_sigma_deg": math.degrees(GYRO_SCALE_SIGMA * abs(net_turn)),
    }


def evaluate(grove, truth, trajectory):
    out = subprocess.run([grove, "footslam", "evaluate", "--truth", truth, "--trajectory",
                          trajectory], check=True, stdout=subprocess.PIPE).stdout
    return json.loads(out)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grove", required=True)
    parser.add_argument("--out", required=True)
    parser.add_argument("--walks", type=int, default=3)
    parser.add_argument("--seeds", type=int, default=3)
    parser.add_argument("--minutes", type=float, default=10)
    parser.add_argument("--particles", type=int, default=5000)
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    rows = []
    for w in range(1, args.walks + 1):
        for s in range(1, args.seeds + 1):
            d = os.path.join(args.out, f"w{w}s{s}")
            run([args.grove, "footslam", "simulate", "--minutes", str(args.minutes), "--seed",
                 str(w), "--imu", "--imu-seed", str(s), "--out", d])
            true_stances = [[float(r[k]) for k in ("begin", "end", "x", "y", "heading")]
                            for r in read_csv(os.path.join(d, "stances.csv"))]
            times = np.loadtxt(os.path.join(d, "imu.csv"), delimiter=",", skiprows=1, usecols=0)
            row = {"walk": w, "seed": s, "detectors": {}}
            for det in DETECTORS:
                steps_path = os.path.join(d, f"steps_{det}.csv")
                stances_path = os.path.join(d, f"stances_{det}.csv")
                run([args.grove, "footslam", "steps", "--imu", os.path.join(d, "imu.csv"),
                     "--detector", det, "--out", steps_path, "--stances", stances_path,
                     "--no-progress"])
                steps = read_csv(steps_path)
                detected = [(float(r["begin"]), float(r["end"])) for r in read_csv(stances_path)]
                m = stance_metrics(true_stances, detected, times)
                m.update(step_metrics(true_stances, steps))
                m["steps"] = len(steps)
                m["true_steps"] = len(true_stances) - 1
                row["detectors"][det] = m
            for name, flag, path in (("imu", "--steps", os.path.join(d, "steps_shoe.csv")),
                                     ("step_file", "--steps", os.path.join(d, "steps.csv"))):
                run_dir = os.path.join(d, "run_" + name)
                run([args.grove, "footslam", "run", flag, path, "--particles",
                     str(args.particles), "--seed", str(s), "--out", run_dir, "--no-progress"])
                row["footslam_" + name] = evaluate(args.grove, os.path.join(d, "truth.csv"),
                                                   os.path.join(run_dir, "smoothed_trajectory.csv"))
            rows.append(row)
            print(f"walk {w} seed {s}: done", file=sys.stderr)
    with open(os.path.join(args.out, "study.json"), "w") as f:
        json.dump(rows, f, indent=1)

    print("Steps (SHOE, default configuration):\n")
    print("| walk | sensor seed | steps / true | step length error, RMS | heading drift | "
          "net turn | predicted drift, 1 sigma | drift / predicted |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for r in rows:
        m = r["detectors"]["shoe"]
        print(f"| {r['walk']} | {r['seed']} | {m['steps']} / {m['true_steps']} | "
              f"{m['length_rms_pct']:.2f} % | {m['heading_drift_deg']:+.1f} deg | "
              f"{m['net_turn_deg']:+.0f} deg | {m['predicted_drift_sigma_deg']:.1f} deg | "
              f"{abs(m['heading_drift_deg']) / max(1e-9, m['predicted_drift_sigma_deg']):.2f} |")
    print("\nDetectors (means over the walks and seeds):\n")
    print("| detector | missed stances | false stances | stance begins (ms) | stance ends (ms) | "
          "moving samples taken as still | still samples missed | step length error, RMS |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for det in DETECTORS:
        ms = [r["detectors"][det] for r in rows]
        mean = lambda k: float(np.mean([m[k] for m in ms]))
        print(f"| {det} | {mean('missed'):.1f} | {mean('false'):.1f} | {mean('begin_ms'):+.1f} | "
              f"{mean('end_ms'):+.1f} | {mean('false_still_pct'):.2f} % | "
              f"{mean('missed_still_pct'):.2f} % | {mean('length_rms_pct'):.2f} % |")
    print("\nFootSLAM, smoothed path against the truth (aligned RMSE, m):\n")
    print("| walk | seed | on the IMU's steps | on the step file | ratio |")
    print("| --- | --- | --- | --- | --- |")
    imu_all, file_all = [], []
    for r in rows:
        a = r["footslam_imu"]["aligned_rmse_m"]
        b = r["footslam_step_file"]["aligned_rmse_m"]
        imu_all.append(a)
        file_all.append(b)
        print(f"| {r['walk']} | {r['seed']} | {a:.3f} | {b:.3f} | {a / b:.2f} |")
    print(f"| mean | | {np.mean(imu_all):.3f} | {np.mean(file_all):.3f} | "
          f"{np.mean(imu_all) / np.mean(file_all):.2f} |")


if __name__ == "__main__":
    main()
