#!/usr/bin/python3
"""batch_probe.py GROVE ROUNDS OUT [BATCH ...]: the bundled walk (`grove footslam run`, 32,768
particles, 2 threads) with each --batch in turn, order rotated every round; one line per run:
batch, round, filter s, process CPU s (user + system). Smaller batches leave less to wait for at
each join of the advance, at more per-batch overhead."""
import json
import os
import resource
import subprocess
import sys
import tempfile

grove, rounds, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
batches = sys.argv[4:] or ["128", "512", "2048"]
with open(out, "w") as f:
    for r in range(rounds):
        for k in range(len(batches)):
            b = batches[(k + r) % len(batches)]
            with tempfile.TemporaryDirectory() as d:
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                subprocess.run([grove, "footslam", "run", "--no-progress", "--particles", "32768",
                                "--threads", "2", "--batch", b, "--out", d], check=True,
                               capture_output=True)
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
                s = json.load(open(os.path.join(d, "summary.json")))
            cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            print(f"{b} {r + 1} {s['filter_time_s']:.3f} {cpu:.3f}", file=f, flush=True)
