#!/usr/bin/python3
"""summislands.py FILE: islands_probe.py's runs; per kind, the median per-round speed-up of 2
threads over 1 (filter time) and the 2-thread run's CPU over the 1-thread run's (whole process)."""
import statistics as st
import sys

runs = {}
for line in open(sys.argv[1]):
    kind, threads, rnd, filt, cpu = line.split()
    runs[(kind, int(threads), int(rnd))] = (float(filt), float(cpu))
rounds = sorted({k[2] for k in runs})
for kind in ("filter", "islands"):
    sp = [runs[(kind, 1, r)][0] / runs[(kind, 2, r)][0] for r in rounds]
    cpu = [runs[(kind, 2, r)][1] / runs[(kind, 1, r)][1] for r in rounds]
    t1 = st.median(runs[(kind, 1, r)][0] for r in rounds)
    t2 = st.median(runs[(kind, 2, r)][0] for r in rounds)
    print(f"{kind:8s} 1 thread {t1:.3f} s, 2 threads {t2:.3f} s; speed-up median {st.median(sp):.2f} "
          f"({min(sp):.2f}-{max(sp):.2f}, >= 1.85 in {sum(x >= 1.85 for x in sp)} of {len(sp)}); "
          f"CPU 2/1 median {st.median(cpu):.3f} ({min(cpu):.3f}-{max(cpu):.3f})")
