#!/usr/bin/python3
"""Does the engine's loop-body inflation on 2 threads follow the host? Every round runs, back to
back (order swapped every round), grove_machine_benchmark's arithmetic and 8 MiB random-read
cases on 1 and 2 threads (machine_scaling.py's paired runs) and `grove bench scaling --grid fixed
--steps 1418 --max-particles 1` (the 30,000-particle points on 1 and 2 threads, with the split of
their CPU). Prints per round: the 2-thread CPU per item over the 1-thread one for both machine
cases, the engine's 2-thread loop-body time over its 1-thread one, its waiting in loops, and the
engine's speedup; then the medians and the correlation over rounds.

  host_probe.py BUILD_DIR ROUNDS > out.txt
"""
import csv
import importlib.util
import os
import statistics
import subprocess
import sys
import tempfile

here = os.path.dirname(os.path.abspath(__file__))
spec = importlib.util.spec_from_file_location(
    "machine_scaling", os.path.join(here, "..", "..", "scripts", "machine_scaling.py"))
ms = importlib.util.module_from_spec(spec)
spec.loader.exec_module(ms)

build, rounds = sys.argv[1], int(sys.argv[2])
machine = os.path.join(build, "bench", "grove_machine_benchmark")
grove = os.path.join(build, "tools", "grove")
cases = ["BM_MachineArithmetic/process_time/real_time",
         "BM_MachineRandomRead/kib_per_thread:8192/process_time/real_time"]


def machine_ratio(case, swap):
    order = [2, 1] if swap else [1, 2]
    cpu = {t: ms.run_machine(machine, case, t)[1] for t in order}
    return cpu[2] / cpu[1]


def engine():
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([grove, "bench", "scaling", "--out", d, "--grid", "fixed", "--steps", "1418",
                        "--max-particles", "1"], check=True, capture_output=True)
        rows = {r["threads"]: r for r in csv.DictReader(open(os.path.join(d, "scaling.csv")))}
    one, two = rows["1"], rows["2"]
    return (float(two["loop bodies ns"]) / float(one["loop bodies ns"]),
            float(two["waiting in loops ns"]),
            float(one["ns per particle-step"]) / float(two["ns per particle-step"]),
            float(two["process CPU ns"]) / float(one["process CPU ns"]))


cols = {"arith": [], "read8": [], "bodies": [], "wait": [], "speedup": [], "cpu": []}
print("round arithmetic_cpu_2t/1t randread8MiB_cpu_2t/1t engine_bodies_2t/1t engine_wait_ns "
      "engine_speedup engine_cpu_2t/1t", flush=True)
for r in range(rounds):
    swap = r % 2 == 1
    if swap:
        b, w, s, c = engine()
    a = machine_ratio(cases[0], swap)
    m = machine_ratio(cases[1], swap)
    if not swap:
        b, w, s, c = engine()
    for k, v in zip(cols, (a, m, b, w, s, c)):
        cols[k].append(v)
    print(f"{r} {a:.3f} {m:.3f} {b:.3f} {w:.1f} {s:.3f} {c:.3f}", flush=True)
print("medians: " + " ".join(f"{k} {statistics.median(v):.3f}" for k, v in cols.items()))
print(f"rounds with speedup >= 1.85 and CPU within 5 %: "
      f"{sum(s >= 1.85 and c <= 1.05 for s, c in zip(cols['speedup'], cols['cpu']))} of {rounds}")
for k in ("arith", "read8"):
    print(f"correlation of engine bodies with {k}: "
          f"{statistics.correlation(cols['bodies'], cols[k]):.2f}")
