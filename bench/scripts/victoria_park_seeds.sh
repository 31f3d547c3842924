#!/usr/bin/env bash
# The seed paper's Simulation IV (Victoria Park, Figs. 10-11): every filter with few particles over
# several filter seeds, scored against GPS (grove fastslam victoria-park: the seed's noise of
# Fig. 11 and its 2-sigma gate are the command's defaults). Writes OUT/victoria_park_seeds.csv and
# .md (mean, median and min..max of the mean GPS error over the seeds).
#   bench/scripts/victoria_park_seeds.sh GROVE OUT [PARTICLES] [SEEDS] [FILTERS]
set -euo pipefail
grove="$1"
out="$2"
particles="${3:-3}"
seeds="${4:-10}"
filters="${5:-fastslam1 fastslam2 ufastslam srcd srcd_aided srcd_pf de_srcd}"
mkdir -p "$out/runs"
csv="$out/victoria_park_seeds.csv"
echo "filter,particles,seed,gps_mean_m,gps_median_m,gps_rmse_m,landmarks,filter_time_s,status" >"$csv"
for f in $filters; do
  for s in $(seq 1 "$seeds"); do
    dir="$out/runs/${f}_p${particles}_s${s}"
    if "$grove" fastslam victoria-park --out "$dir" --filter "$f" --particles "$particles" \
      --seed "$s" --threads 1 --no-progress >"$dir.log" 2>&1; then
      /usr/bin/python3 - "$dir/summary.json" "$f" "$particles" "$s" >>"$csv" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
g = d["gps"]
print(f"{sys.argv[2]},{sys.argv[3]},{sys.argv[4]},{g['mean_m']:.3f},{g['median_m']:.3f},"
      f"{g['rmse_m']:.3f},{d['landmarks']},{d['filter_time_s']:.3f},ok")
PY
    else
      echo "$f,$particles,$s,,,,,,failed: $(tail -1 "$dir.log" | tr ',' ';')" >>"$csv"
    fi
  done
done
/usr/bin/python3 - "$csv" >"$out/victoria_park_seeds.md" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| filter | particles | seeds ok | GPS mean error: mean | median | min .. max | landmarks (mean) | filter time (mean) |")
print("| --- | --- | --- | --- | --- | --- | --- | --- |")
seen = []
for r in rows:
    if r["filter"] not in seen:
        seen.append(r["filter"])
for f in seen:
    ok = [r for r in rows if r["filter"] == f and r["status"] == "ok"]
    n = len([r for r in rows if r["filter"] == f])
    if not ok:
        print(f"| {f} | {rows[0]['particles']} | 0 of {n} | | | | | |")
        continue
    e = [float(r["gps_mean_m"]) for r in ok]
    print(f"| {f} | {ok[0]['particles']} | {len(ok)} of {n} | {statistics.mean(e):.2f} m | "
          f"{statistics.median(e):.2f} m | {min(e):.2f} .. {max(e):.2f} m | "
          f"{statistics.mean(float(r['landmarks']) for r in ok):.0f} | "
          f"{statistics.mean(float(r['filter_time_s']) for r in ok):.2f} s |")
PY
cat "$out/victoria_park_seeds.md"
