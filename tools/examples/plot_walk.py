#!/usr/bin/python3
"""Runs FootSLAM on a walk with the grove Python module and draws the result to a PNG.

The walk is a CSV file with the header t,dx,dy (the bundled tools/data/building_walk_steps.csv
by default), fed to the filter in one run() call. The picture shows the cumulative map (each
hexagon shaded by its weighted edge counts) with the mean and the heaviest particle's paths;
the run's summary line is printed.

  PYTHONPATH=<build>/python /usr/bin/python3 tools/examples/plot_walk.py --out walk.png
"""

import argparse
import os
import sys
import time

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import PolyCollection  # noqa: E402
from matplotlib.colors import LogNorm  # noqa: E402

import grove  # noqa: E402

DEFAULT_WALK = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), "..",
                                             "data", "building_walk_steps.csv"))


def hexagons(centres, radius):
    """The corners of pointy-top hexagons of circumradius `radius` around `centres` (n, 2):
    an array (n, 6, 2)."""
    angles = np.pi / 2 + np.arange(6) * (np.pi / 3)
    corners = radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    return centres[:, None, :] + corners[None, :, :]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("walk", nargs="?", default=DEFAULT_WALK,
                        help="steps CSV with the header t,dx,dy (default: the bundled walk)")
    parser.add_argument("--out", default="walk.png", help="PNG to write (default: walk.png)")
    parser.add_argument("--particles", type=int, default=30000,
                        help="number of particles (default: 30000)")
    parser.add_argument("--seed", type=int, default=1, help="random seed (default: 1)")
    parser.add_argument("--threads", type=int, default=0,
                        help="worker threads, 0 for one per core (default: 0)")
    args = parser.parse_args(argv)

    try:
        steps = np.loadtxt(args.walk, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, ValueError) as e:
        sys.exit("%s: cannot read the steps: %s" % (args.walk, e))
    if steps.shape[1] != 3:
        sys.exit("%s: expected 3 columns t,dx,dy, found %d" % (args.walk, steps.shape[1]))
    slam = grove.FootSlam(particles=args.particles, seed=args.seed, threads=args.threads)
    start = time.perf_counter()
    try:
        slam.run(steps)
    except grove.GroveError as e:
        sys.exit("%s: %s" % (args.walk, e))
    seconds = time.perf_counter() - start
    summary = slam.summary()
    print(summary["report"])
    print("%s: %d steps in %.2f s" % (args.walk, slam.steps, seconds))

    cmap = slam.cumulative_map()
    mean = slam.mean_trajectory()
    heaviest = slam.heaviest_trajectory()
    visits = cmap["counts"].sum(axis=1)

    fig, ax = plt.subplots(figsize=(9, 9), dpi=100)
    cells = PolyCollection(hexagons(np.stack([cmap["x"], cmap["y"]], axis=1),
                                    slam.config["hex_radius_m"]),
                           array=np.maximum(visits, 1e-3), cmap="Greys",
                           norm=LogNorm(vmin=max(visits.min(), 1e-3), vmax=visits.max()),
                           edgecolors="none")
    ax.add_collection(cells)
    fig.colorbar(cells, ax=ax, shrink=0.7, label="weighted edge counts of the hexagon")
    ax.plot(mean[:, 1], mean[:, 2], color="tab:blue", linewidth=1.0, label="mean path")
    ax.plot(heaviest[:, 1], heaviest[:, 2], color="tab:red", linewidth=1.0,
            label="heaviest particle's path")
    ax.plot(mean[0, 1], mean[0, 2], "o", color="black", label="start")
    ax.set_aspect("equal")
    ax.autoscale_view()
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title("FootSLAM, %d particles, %d steps: %d hexagons" %
                 (args.particles, slam.steps, len(cmap)))
    ax.legend(loc="best")
    fig.tight_layout()
    fig.savefig(args.out)
    plt.close(fig)
    print("wrote %s" % args.out)


if __name__ == "__main__":
    main()
