#!/usr/bin/python3
"""The Python module's overhead: the bundled walk fed to grove.FootSlam.run() in one call against
the same walk fed to the C API (grove_footslam_steps, through ctypes: one foreign call) in the
same process, alternated run by run. Each run: create, every step, read the cumulative map,
release. (The C API against the C++ facade: bench/embedding_benchmark.cc.)

  PYTHONPATH=build/python /usr/bin/python3 bench/embedding_python.py \
      --lib build/engine/libgrove.so --runs 7 --particles 3000 --threads 1
"""

import argparse
import ctypes
import json
import os
import statistics
import time

import numpy as np

import grove

WALK = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tools", "data",
                    "building_walk_steps.csv")
HEX_BYTES = 72  # grove_hex_counts: two int32, eight doubles


def c_api(lib_path):
    lib = ctypes.CDLL(lib_path)
    handle = ctypes.c_void_p
    lib.grove_footslam_create_json.argtypes = [ctypes.c_char_p, ctypes.POINTER(handle),
                                               ctypes.c_char_p, ctypes.c_size_t]
    dp = ctypes.POINTER(ctypes.c_double)
    lib.grove_footslam_steps.argtypes = [handle, dp, dp, dp, ctypes.c_size_t,
                                         ctypes.POINTER(ctypes.c_size_t)]
    lib.grove_footslam_cumulative_map.argtypes = [handle, ctypes.c_void_p, ctypes.c_size_t,
                                                  ctypes.POINTER(ctypes.c_size_t)]
    lib.grove_footslam_destroy.argtypes = [handle]
    lib.grove_footslam_last_error.argtypes = [handle]
    lib.grove_footslam_last_error.restype = ctypes.c_char_p
    return lib


def run_c(lib, config_json, t, dx, dy):
    slam = ctypes.c_void_p()
    error = ctypes.create_string_buffer(512)
    if lib.grove_footslam_create_json(config_json.encode(), ctypes.byref(slam), error, 512) != 0:
        raise RuntimeError(error.value.decode())
    dp = ctypes.POINTER(ctypes.c_double)
    done = ctypes.c_size_t()
    if lib.grove_footslam_steps(slam, t.ctypes.data_as(dp), dx.ctypes.data_as(dp),
                                dy.ctypes.data_as(dp), len(t), ctypes.byref(done)) != 0:
        raise RuntimeError(lib.grove_footslam_last_error(slam).decode())
    count = ctypes.c_size_t()
    lib.grove_footslam_cumulative_map(slam, None, 0, ctypes.byref(count))
    buffer = np.empty(count.value * HEX_BYTES, dtype=np.uint8)
    if lib.grove_footslam_cumulative_map(slam, buffer.ctypes.data, count.value,
                                         ctypes.byref(count)) != 0:
        raise RuntimeError(lib.grove_footslam_last_error(slam).decode())
    lib.grove_footslam_destroy(slam)
    return count.value


def run_python(particles, threads, steps):
    slam = grove.FootSlam(particles=particles, threads=threads)
    slam.run(steps)
    return len(slam.cumulative_map())


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--lib", required=True, help="libgrove.so of the same build")
    parser.add_argument("--runs", type=int, default=7)
    parser.add_argument("--particles", type=int, default=3000)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()

    steps = np.loadtxt(WALK, delimiter=",", skiprows=1)
    t, dx, dy = (np.ascontiguousarray(steps[:, k]) for k in range(3))
    lib = c_api(args.lib)
    config_json = json.dumps({"particles": args.particles, "threads": args.threads})
    times = {"c_api": [], "python": []}
    hexagons = {}
    for run in range(args.runs):
        order = ["c_api", "python"] if run % 2 == 0 else ["python", "c_api"]
        for which in order:
            start = time.perf_counter()
            if which == "c_api":
                hexagons[which] = run_c(lib, config_json, t, dx, dy)
            else:
                hexagons[which] = run_python(args.particles, args.threads, steps)
            times[which].append(time.perf_counter() - start)
    if hexagons["c_api"] != hexagons["python"]:
        raise SystemExit("the two maps differ in size: %s" % hexagons)
    median = {k: statistics.median(v) for k, v in times.items()}
    print("%s, %d particles, %d thread(s), %d steps, %d runs each, alternated" %
          (grove.version()["string"], args.particles, args.threads, len(t), args.runs))
    for k in ("c_api", "python"):
        print("  %-6s median %.3f s  (runs %s)" %
              (k, median[k], " ".join("%.3f" % x for x in times[k])))
    print("  python / c_api = %.4f" % (median["python"] / median["c_api"]))


if __name__ == "__main__":
    main()
