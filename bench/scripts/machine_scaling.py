#!/usr/bin/python3
"""How much faster two threads run than one, on this machine, in paired rounds: every round runs
each case on 1 thread and on 2, back to back (the order swapped every round), so a pair sees the
same host load and the speedup of a round is the ratio within the pair. The cases are
grove_machine_benchmark's (work that shares nothing, and locked increments on one shared set) and,
with --grove, the engine itself on the paper walk (`grove bench paper --only 'htree s=16 T=5'`, one
run a round).
Prints a Markdown table: per case the median 1- and 2-thread rate, the median speedup over rounds
and its range, the rounds reaching 1.85x, and the 2-thread run's CPU time per unit of work over
the 1-thread run's (1.00: no CPU lost to sharing; the engine's target for 2 threads is at least
1.85x at no more than 1.05).

  bench/scripts/machine_scaling.py BUILD_DIR [--rounds N] [--grove] [--particles N] [--raw FILE]
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile


def machine_cases(binary):
    out = subprocess.run([binary, "--benchmark_list_tests=true"], check=True, capture_output=True,
                         text=True).stdout.split()
    cases = []
    for name in out:
        if name.endswith("/threads:1"):
            cases.append(name[: -len("/threads:1")])
    return cases


def run_machine(binary, case, threads):
    """Returns (items per second, process CPU seconds per item)."""
    with tempfile.NamedTemporaryFile(suffix=".json") as f:
        subprocess.run([binary, f"--benchmark_filter=^{re.escape(case)}/threads:{threads}$",
                        "--benchmark_min_time=0.3", f"--benchmark_out={f.name}",
                        "--benchmark_out_format=json"], check=True, capture_output=True)
        b = json.load(open(f.name))["benchmarks"][0]
    rate = b["items_per_second"]
    # cpu_time and real_time are per iteration, in the same unit; items per iteration (over all
    # threads) = rate * real time per iteration.
    return rate, b["cpu_time"] / b["real_time"] / rate


def run_engine(grove, threads, particles):
    """Returns (particle-steps per second, CPU seconds per particle-step) of the paper walk."""
    with tempfile.TemporaryDirectory() as d:
        subprocess.run([grove, "bench", "paper", "--only", "htree s=16 T=5", "--threads",
                        str(threads), "--particles", str(particles), "--repeat", "1", "--out", d],
                       check=True, capture_output=True)
        row = next(l for l in open(os.path.join(d, "paper.md")) if l.startswith("| htree"))
    cells = [c.strip() for c in row.strip().strip("|").split("|")]
    steps, run_s, cpu_s = int(cells[1]), float(cells[3]), float(cells[5])
    work = steps * particles
    return work / run_s, cpu_s / work


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("build")
    p.add_argument("--rounds", type=int, default=7)
    p.add_argument("--grove", action="store_true", help="add the engine's paper walk")
    p.add_argument("--particles", type=int, default=30000)
    p.add_argument("--raw", help="also write every run here, one line each")
    a = p.parse_args()
    binary = os.path.join(a.build, "bench", "grove_machine_benchmark")
    grove = os.path.join(a.build, "tools", "grove")
    cases = [(c, lambda t, c=c: run_machine(binary, c, t)) for c in machine_cases(binary)]
    if a.grove:
        cases.append((f"engine: paper walk, htree s=16 T=5, {a.particles} particles",
                      lambda t: run_engine(grove, t, a.particles)))
    results = {name: [] for name, _ in cases}
    raw = open(a.raw, "w") if a.raw else None
    for r in range(a.rounds):
        for name, run in cases:
            order = (1, 2) if r % 2 == 0 else (2, 1)
            got = {t: run(t) for t in order}
            results[name].append(got)
            if raw:
                print(f"round {r + 1} {name} " + " ".join(
                    f"t{t} rate {got[t][0]:.6g} cpu_per_item {got[t][1]:.6g}" for t in (1, 2)),
                    file=raw, flush=True)
    print(f"{a.rounds} paired rounds.\n")
    print("| case | 1 thread, M/s | 2 threads, M/s | speedup, median (range) | rounds >= 1.85x "
          "| CPU per item, 2 threads / 1 |")
    print("| --- | --- | --- | --- | --- | --- |")
    for name, _ in cases:
        rs = results[name]
        speedup = [g[2][0] / g[1][0] for g in rs]
        cpu = [g[2][1] / g[1][1] for g in rs]
        print(f"| {name} | {statistics.median(g[1][0] for g in rs) / 1e6:.1f} "
              f"| {statistics.median(g[2][0] for g in rs) / 1e6:.1f} "
              f"| {statistics.median(speedup):.2f} ({min(speedup):.2f}-{max(speedup):.2f}) "
              f"| {sum(s >= 1.85 for s in speedup)} of {len(rs)} | {statistics.median(cpu):.2f} |")


if __name__ == "__main__":
    sys.exit(main())
