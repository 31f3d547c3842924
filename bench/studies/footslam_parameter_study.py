#!/usr/bin/python3
"""FootSLAM's defaults, swept on simulated walks with a held-out half.

Twelve 8-minute walks: building walks of seeds 1-8 (heading drift 0.012 rad per sqrt step) and
open-area walks of seeds 1-4 (the simulator's defaults). The tuning half is building 1-4 and open
1-2; the held-out half is building 5-8 and open 3-4. Each walk is filtered with FILTER_SEEDS filter
seeds (default "1 2"), and a configuration's score is the mean aligned RMSE of the smoothed path
over the walks and filter seeds. Each parameter is swept one at a time around the current
defaults; the value with the lowest score on the tuning half is chosen per parameter; the chosen
values together are then compared with the current defaults on the held-out half, which no
choice was made on. Every swept value's held-out score is printed too, to show which single
changes carry over.

  bench/studies/footslam_parameter_study.py [build-dir] [particles]   (default: build 5000)

Prints markdown tables. About 550 runs: 40 minutes at 5,000 particles on 2 cores.
"""
import json
import os
import subprocess
import sys
import tempfile

BUILD = sys.argv[1] if len(sys.argv) > 1 else "build"
PARTICLES = sys.argv[2] if len(sys.argv) > 2 else "5000"
GROVE = os.path.join(BUILD, "tools", "grove")

# The current defaults (grove::FootSlamConfig) and the values tried for each.
DEFAULTS = {
    "prior_count": 0.8,
    "heading_sigma_rad": 0.03,
    "heading_drift_sigma_rad": 0.01,
    "step_length_sigma_m": 0.04,
    "resample_threshold": 0.5,
}
SWEEP = {
    "prior_count": [0.2, 0.4, 0.8, 1.6, 3.2],
    "heading_sigma_rad": [0.01, 0.02, 0.03, 0.05, 0.08],
    "heading_drift_sigma_rad": [0.0025, 0.005, 0.01, 0.02, 0.04],
    "step_length_sigma_m": [0.01, 0.02, 0.04, 0.08, 0.16],
    "resample_threshold": [0.2, 0.35, 0.5, 0.75, 1.0],
}
TUNE = [("building", s) for s in (1, 2, 3, 4)] + [("open", s) for s in (1, 2)]
HELD_OUT = [("building", s) for s in (5, 6, 7, 8)] + [("open", s) for s in (3, 4)]
FILTER_SEEDS = os.environ.get("FILTER_SEEDS", "1 2").split()


def run(args):
    subprocess.run([GROVE] + args, check=True, stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL)


def simulate(work, walk):
    scenario, seed = walk
    out = os.path.join(work, f"{scenario}{seed}")
    if not os.path.isdir(out):
        args = ["footslam", "simulate", "--out", out, "--seed", str(seed), "--scenario", scenario]
        if scenario == "building":
            args += ["--heading-drift", "0.012"]
        run(args)
    return out


def error(work, walk, config):
    """Aligned RMSE (m) of the smoothed path, mean over the filter seeds."""
    return sum(error_with_seed(work, walk, config, seed) for seed in FILTER_SEEDS) / len(
        FILTER_SEEDS)


def error_with_seed(work, walk, config, seed):
    sim = simulate(work, walk)
    out = os.path.join(work, "run")
    args = ["footslam", "run", "--no-progress", "--particles", PARTICLES, "--seed", seed,
            "--steps", os.path.join(sim, "steps.csv"), "--out", out]
    for key, value in config.items():
        args += ["--" + key.replace("_", "-"), repr(value)]
    run(args)
    report = subprocess.run(
        [GROVE, "footslam", "evaluate", "--truth", os.path.join(sim, "truth.csv"),
         "--trajectory", os.path.join(out, "smoothed_trajectory.csv")],
        check=True, capture_output=True, text=True).stdout
    return json.loads(report)["aligned_rmse_m"]


def mean_error(work, walks, config, cache):
    key = (tuple(walks), tuple(sorted(config.items())))
    if key not in cache:
        cache[key] = [error(work, w, config) for w in walks]
    errors = cache[key]
    return sum(errors) / len(errors), errors


def main():
    cache = {}
    with tempfile.TemporaryDirectory() as work:
        print(f"Particles: {PARTICLES}; filter seeds {' '.join(FILTER_SEEDS)}. Aligned RMSE of "
              "the smoothed path (m), mean over the walks and filter seeds.")
        print()
        print("One parameter at a time around the defaults; each cell: value: tuning half / "
              "held-out half:")
        print()
        print("| parameter | " + " | ".join(f"value {i + 1}" for i in range(5)) +
              " | chosen on the tuning half |")
        print("| --- |" + " --- |" * 6)
        chosen = dict(DEFAULTS)
        for name, values in SWEEP.items():
            cells, best = [], None
            for v in values:
                config = dict(DEFAULTS)
                config[name] = v
                m, _ = mean_error(work, TUNE, config, cache)
                h, _ = mean_error(work, HELD_OUT, config, cache)
                cells.append(f"{v}: {m:.2f} / {h:.2f}")
                if best is None or m < best[1]:
                    best = (v, m)
            chosen[name] = best[0]
            print(f"| {name} | " + " | ".join(cells) + f" | {best[0]} |", flush=True)
        print()
        print("Chosen values together against the defaults, per walk:")
        print()
        print("| configuration | half | mean | walks (building 1-4, open 1-2 / building 5-8, "
              "open 3-4) |")
        print("| --- | --- | --- | --- |")
        for label, config in (("defaults", DEFAULTS), ("chosen", chosen)):
            for half, walks in (("tuning", TUNE), ("held out", HELD_OUT)):
                m, errors = mean_error(work, walks, config, cache)
                print(f"| {label} | {half} | {m:.2f} | " + ", ".join(f"{e:.2f}" for e in errors) +
                      " |", flush=True)
        print()
        print("Chosen: " + ", ".join(f"{k} = {v}" for k, v in chosen.items()))


if __name__ == "__main__":
    main()
