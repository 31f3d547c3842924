#!/usr/bin/python3
# Rotated A/B rounds of `grove bench scaling --grid fixed --steps 1418 --max-particles 1`
# (the 30,000-particle thread sweep: 1 and 2 threads); order A B, B A, ... ; prints per-round rows.
import csv, subprocess, sys, os, statistics
rounds = int(sys.argv[1]); out = sys.argv[2]; bins = dict(a.split('=') for a in sys.argv[3:])
os.makedirs(out, exist_ok=True)
names = list(bins)
rows = []
for r in range(rounds):
    order = names if r % 2 == 0 else names[::-1]
    for name in order:
        d = f"{out}/r{r}_{name}"
        subprocess.run([bins[name], 'bench', 'scaling', '--out', d, '--grid', 'fixed', '--steps', '1418',
                        '--max-particles', '1'], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        for row in csv.DictReader(open(f"{d}/scaling.csv")):
            rows.append((r, name, row))
            print(r, name, row['threads'], row['ns per particle-step'], row['process CPU ns'],
                  row['loop bodies ns'], row['waiting in loops ns'], row['outside loops ns'], flush=True)
