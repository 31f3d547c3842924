#!/usr/bin/python3
import sys, statistics, collections
# reads absc.py's printed lines
d = collections.defaultdict(lambda: collections.defaultdict(list))
for line in open(sys.argv[1]):
    f = line.split()
    if len(f) != 8: continue
    r, name, t = f[0], f[1], f[2]
    d[(name, t)]['round'].append(int(r))
    for k, v in zip(['ns', 'cpu', 'busy', 'wait', 'outside'], f[3:]):
        d[(name, t)][k].append(float(v))
names = sorted({k[0] for k in d})
for name in names:
    one, two = d[(name, '1')], d[(name, '2')]
    sp = [a / b for a, b in zip(one['ns'], two['ns'])]
    cp = [b / a - 1 for a, b in zip(one['cpu'], two['cpu'])]
    med = statistics.median
    print(f"{name}: 1t ns {med(one['ns']):.1f} 2t ns {med(two['ns']):.1f} speed-up {med(sp):.3f} "
          f"(range {min(sp):.2f}-{max(sp):.2f}) CPU 2t/1t {100*med(cp):+.1f} % | 2t: cpu {med(two['cpu']):.1f} "
          f"busy {med(two['busy']):.1f} wait {med(two['wait']):.1f} outside {med(two['outside']):.2f} | "
          f"1t: cpu {med(one['cpu']):.1f} busy {med(one['busy']):.1f}")
if len(names) == 2:
    a, b = names
    for t in '12':
        ra = d[(a, t)]['ns']; rb = d[(b, t)]['ns']
        diffs = [y / x - 1 for x, y in zip(ra, rb)]
        wa = d[(a, t)]['wait']; wb = d[(b, t)]['wait']
        print(f"{t}t: {b} vs {a} ns {100*statistics.median(diffs):+.1f} % ({sum(x < 0 for x in diffs)} of {len(diffs)} faster); "
              f"wait {statistics.median(wa):.1f} -> {statistics.median(wb):.1f}; cpu {statistics.median(d[(a,t)]['cpu']):.1f} -> {statistics.median(d[(b,t)]['cpu']):.1f}")
