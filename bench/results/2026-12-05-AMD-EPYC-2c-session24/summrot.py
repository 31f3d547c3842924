# summrot.py OUT BASE: per build, median ns per particle-step and CPU s; against BASE, the median of
# the per-round ratios and in how many rounds the build was faster (ns) and cheaper (CPU).
import sys, statistics as st
runs = {}
for line in open(sys.argv[1]):
    parts = [p.strip() for p in line.split('|')]
    head = parts[0].split()
    runs.setdefault(head[0], {})[int(head[2])] = (float(parts[8]), float(parts[6]))
base = runs[sys.argv[2]]
for label, r in runs.items():
    ns = st.median(v[0] for v in r.values()); cpu = st.median(v[1] for v in r.values())
    line = f"{label}: {len(r)} runs, median {ns:.1f} ns, CPU {cpu:.2f} s"
    if label != sys.argv[2]:
        rs = sorted(set(r) & set(base))
        dn = [r[k][0] / base[k][0] - 1 for k in rs]; dc = [r[k][1] / base[k][1] - 1 for k in rs]
        line += (f"; against {sys.argv[2]}: ns {100 * st.median(dn):+.1f} % (faster in {sum(x < 0 for x in dn)}/{len(dn)}),"
                 f" CPU {100 * st.median(dc):+.1f} % (lower in {sum(x < 0 for x in dc)}/{len(dc)})")
    print(line)
