#!/usr/bin/python3
"""islands_probe.py GROVE ROUNDS OUT: the bundled walk (`grove footslam run`, 32,768 particles) as
one filter and as 2 islands that never exchange (--islands 2 --island-exchange-steps 100000), on 1
and 2 threads, the four runs of a round in an order rotated every round. With 2 islands of 16,384
particles each worker's home half is one island, so the two cores share no nodes (but stolen
chunks). Writes one line per run: kind, threads, round, filter s, CPU s (user + system)."""
import json
import os
import resource
import subprocess
import sys
import tempfile

grove, rounds, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
kinds = [("filter", 1, []), ("filter", 2, []),
         ("islands", 1, ["--islands", "2", "--island-exchange-steps", "100000"]),
         ("islands", 2, ["--islands", "2", "--island-exchange-steps", "100000"])]
with open(out, "w") as f:
    for r in range(rounds):
        for k in range(len(kinds)):
            name, threads, extra = kinds[(k + r) % len(kinds)]
            with tempfile.TemporaryDirectory() as d:
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                subprocess.run([grove, "footslam", "run", "--no-progress", "--particles", "32768",
                                "--threads", str(threads), "--out", d] + extra, check=True,
                               capture_output=True)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                s = json.load(open(os.path.join(d, "summary.json")))
            cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            print(f"{name} {threads} {r + 1} {s['filter_time_s']:.3f} {cpu:.3f}", file=f, flush=True)
