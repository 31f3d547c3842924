#!/usr/bin/python3
"""grove's FastSLAM 1.0 against FasterSLAM's optimised one on the same webmap input.

FasterSLAM (ETH's optimised single-core C FastSLAM 1.0, public as RomeoV/FasterSLAM) is built
from its repository (cmake -S src -B BUILD -DCMAKE_BUILD_TYPE=Release; -march=native by default).
This script compiles fasterslam_timer.cc against that build, then runs alternating rounds: per
round and particle count, FasterSLAM's timed call `fastslam1_sim_active` (one call in a fresh
process, timed in process) and `grove fastslam run --filter fastslam1 --association known` on
the controls and observations FasterSLAM's own run simulates (17,382 control steps, 1,473 scans),
once per thread count; the order of the two sides flips every round. grove's figure is
`filter_time_s` from summary.json (reading the CSVs and writing outputs excluded). FasterSLAM's
call also simulates the drive and its noisy controls and observations, a small share of its time.

Prints, per particle count and thread count, the medians (and per particle-step: over particles
times the 17,382 control steps), the per-round ratio grove / FasterSLAM (min / median / max),
grove's 2-thread speed-up, the load average before and after, and the round trip of one cache
line between two threads after every round (grove_machine_benchmark's LineRoundTrip, found
beside GROVE's build or given by --round-trip): on a virtual machine two threads' speed can
depend on where the host placed the two virtual CPUs, and that round trip tells the placements
apart.

Usage: fasterslam_rounds.py FASTERSLAM_BUILD GROVE [--data DIR] [--rounds N] [--particles N ...]
           [--threads T ...] [--fastslam2] [--round-trip BENCHMARK] [--out DIR]
"""
import argparse
import json
import os
import pathlib
import statistics
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
CONTROL_STEPS = 17382


def source_dir(build):
    for line in (build / "CMakeCache.txt").read_text().splitlines():
        if line.startswith("CMAKE_HOME_DIRECTORY:"):
            return pathlib.Path(line.split("=", 1)[1])
    sys.exit(f"{build}: no CMAKE_HOME_DIRECTORY in CMakeCache.txt (not a FasterSLAM build?)")


def build_timer(build, out):
    src = source_dir(build)
    timer = out / "fasterslam_timer"
    libs = [build / "fastslam1/libFasterSlamLib.a", build / "core/libFasterSlamCore.a",
            build / "utils/libFasterSlamUtils.a"]
    for lib in libs:
        if not lib.exists():
            sys.exit(f"{lib} is missing: build FasterSLAM first (cmake --build {build})")
    subprocess.run(["c++", "-O3", "-march=native", f"-I{src / 'core'}", f"-I{src / 'fastslam1'}",
                    f"-I{src / 'utils'}", str(HERE / "fasterslam_timer.cc"), *map(str, libs),
                    "-o", str(timer)], check=True)
    return timer, src / "input_data/example_webmap.mat"


def fasterslam_once(timer, webmap, particles):
    out = subprocess.run([str(timer), str(webmap), str(particles)], check=True,
                         capture_output=True, text=True).stdout
    return float(out.split()[-1])


def grove_once(grove, data, out, filt, particles, threads):
    run = out / f"grove_{filt}_{particles}_{threads}"
    subprocess.run([grove, "fastslam", "run", "--controls", str(data / "controls.csv"),
                    "--observations", str(data / "observations.csv"), "--filter", filt,
                    "--association", "known", "--particles", str(particles),
                    "--threads", str(threads), "--no-progress", "--out", str(run)],
                   check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return json.loads((run / "summary.json").read_text())["filter_time_s"]


def load():
    return "load average %.2f %.2f %.2f" % os.getloadavg()


def machine():
    info = pathlib.Path("/proc/cpuinfo").read_text()
    model = next((line.split(":", 1)[1].strip() for line in info.splitlines()
                  if line.startswith("model name")), "unknown CPU")
    virtual = ", virtual machine" if " hypervisor" in info else ""
    return f"{model}, {os.cpu_count()} hardware threads{virtual}"


def round_trip_ns(benchmark):
    """The LineRoundTrip benchmark's round_trip counter, in ns (None without the benchmark)."""
    if benchmark is None:
        return None
    run = subprocess.run([str(benchmark), "--benchmark_filter=LineRoundTrip",
                          "--benchmark_min_time=0.1", "--benchmark_format=json"],
                         capture_output=True, text=True, check=True)
    return json.loads(run.stdout)["benchmarks"][0]["round_trip"] * 1e9


def spread(values):
    return (f"{min(values):.2f} / {statistics.median(values):.2f} / {max(values):.2f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("fasterslam_build", type=pathlib.Path)
    ap.add_argument("grove")
    ap.add_argument("--data", type=pathlib.Path,
                    default=HERE.parents[1] / "../shared/data/fasterslam-webmap",
                    help="controls.csv and observations.csv (default: ../shared/data/"
                    "fasterslam-webmap beside the checkout)")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--particles", type=int, nargs="+", default=[100, 1000])
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--fastslam2", action="store_true",
                    help="also time grove's FastSLAM 2.0 (known association) on 1 thread")
    ap.add_argument("--round-trip", type=pathlib.Path,
                    help="grove_machine_benchmark (default: bench/grove_machine_benchmark of "
                    "the build GROVE is in, when there)")
    ap.add_argument("--out", type=pathlib.Path, help="keep the runs here (default: a temporary "
                    "directory)")
    args = ap.parse_args()
    if args.round_trip is None:
        beside = pathlib.Path(args.grove).resolve().parents[1] / "bench/grove_machine_benchmark"
        args.round_trip = beside if beside.exists() else None
    if not (args.data / "controls.csv").exists():
        sys.exit(f"{args.data}: no controls.csv (give --data)")
    with tempfile.TemporaryDirectory() as tmp:
        out = args.out or pathlib.Path(tmp)
        out.mkdir(parents=True, exist_ok=True)
        timer, webmap = build_timer(args.fasterslam_build.resolve(), out)
        version = subprocess.run([args.grove, "--version"], capture_output=True,
                                 text=True).stdout.strip()
        print(f"- machine: {machine()}\n- {version}\n- {load()} before", flush=True)
        runs = [("grove", "fastslam1", t) for t in args.threads]
        if args.fastslam2:
            runs.append(("grove", "fastslam2", 1))
        times = {}
        trips = []
        for r in range(args.rounds):
            for n in args.particles:
                order = [("fasterslam", None, 1)] + runs
                for side in (order if r % 2 == 0 else order[::-1]):
                    kind, filt, threads = side
                    t = (fasterslam_once(timer, webmap, n) if kind == "fasterslam" else
                         grove_once(args.grove, args.data, out, filt, n, threads))
                    times.setdefault((n, side), []).append(t)
            trip = round_trip_ns(args.round_trip)
            if trip is not None:
                trips.append(trip)
            print(f"round {r + 1} of {args.rounds} done, {load()}"
                  + ("" if trip is None else f", line round trip {trip:.0f} ns"), file=sys.stderr)
        print(f"- {load()} after; {args.rounds} rounds, sides alternated")
        if trips:
            print("- line round trip between two threads after each round (ns): "
                  + ", ".join(f"{t:.0f}" for t in trips))
        print()
        print("| particles | threads | grove filter time | ns per particle-step | FasterSLAM "
              "(1 core) | ns per particle-step | ratio grove / FasterSLAM, min / median / max "
              "| grove speed-up over 1 thread |")
        print("| --- | --- | --- | --- | --- | --- | --- | --- |")
        for n in args.particles:
            fs = times[(n, ("fasterslam", None, 1))]
            one = times.get((n, ("grove", "fastslam1", 1)))
            for side in runs:
                g = times[(n, side)]
                name = side[2] if side[1] == "fastslam1" else f"{side[2]} (FastSLAM 2.0)"
                ratios = [a / b for a, b in zip(g, fs)]
                speedup = ("" if one is None or side[1] != "fastslam1" or side[2] == 1 else
                           spread([a / b for a, b in zip(one, g)]))
                if side[1] == "fastslam2" and one is not None:
                    speedup = "FastSLAM 2.0 / 1.0: " + spread([a / b for a, b in zip(g, one)])
                print(f"| {n:,} | {name} | {statistics.median(g) * 1e3:.1f} ms | "
                      f"{statistics.median(g) / (n * CONTROL_STEPS) * 1e9:.1f} | "
                      f"{statistics.median(fs) * 1e3:.1f} ms | "
                      f"{statistics.median(fs) / (n * CONTROL_STEPS) * 1e9:.1f} | "
                      f"{spread(ratios)} | {speedup} |")


if __name__ == "__main__":
    main()
