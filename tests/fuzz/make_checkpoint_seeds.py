#!/usr/bin/python3
"""Writes the FootSLAM checkpoint seeds of the checkpoint fuzzer (tests/fuzz/corpus/checkpoint),
run again whenever the checkpoint format changes. Each is a checkpoint of one of the fuzzer's
configurations (CheckpointConfigs in tests/fuzz/fuzz_checks.h: 3 particles on a 16 x 16 first
grid, one thread) after a short walk; the regression_* files are inputs that once found a bug and
are kept as they are.

    PYTHONPATH=build/python tests/fuzz/make_checkpoint_seeds.py [OUT_DIR]
"""
import os
import sys

import numpy as np

import grove

HERE = os.path.dirname(os.path.abspath(__file__))
BASE = {"particles": 3, "grid_size": 16, "threads": 1}


def bundled_walk(steps):
    path = os.path.join(HERE, "..", "..", "tools", "data", "building_walk_steps.csv")
    return np.loadtxt(path, delimiter=",", skiprows=1)[:steps]


def straight_walk(steps, step_m=0.7):
    """Steps east, one a second: leaves the first grid (16 hexagons, about 14 m) after ~10."""
    return np.array([[k + 1.0, step_m, 0.0] for k in range(steps)])


def seed(config, walk):
    f = grove.FootSlam({**BASE, **config})
    f.run(walk)
    return f.checkpoint(b"seed")


def main():
    out = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "corpus", "checkpoint")
    seeds = {
        "htree_one_step.grove": seed({}, bundled_walk(1)),
        "htree_s16_t5.grove": seed({}, bundled_walk(40)),
        "htree_s4_t0.grove": seed({"degree": 4, "alphabet": 0}, bundled_walk(40)),
        "naive.grove": seed({"map": "naive"}, bundled_walk(40)),
        "htree_grown.grove": seed({}, straight_walk(30)),
        "htree_stored.grove": seed({"store_distance_m": 5}, straight_walk(110)),
    }
    for name, data in seeds.items():
        with open(os.path.join(out, name), "wb") as f:
            f.write(data)
        print(f"{name}: {len(data)} bytes")


if __name__ == "__main__":
    main()
