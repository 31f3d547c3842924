#!/usr/bin/env bash
# Prior maps: a second walk through the same building with and without a prior map, one markdown
# row per walk. Two priors: the true map of a first walk (its true path's crossings, counted by
# one noiseless particle) and FootSLAM's own cumulative map of that walk (the realistic case).
# Errors are the smoothed path's against the truth, not aligned (a prior map fixes the frame):
# over the first quarter of the walk (how fast the filter finds the map) and over all of it.
#   bench/studies/footslam_prior_map.sh [build-dir] [particles]   (seeds: SEEDS="2 3 4 5 6 7 8 9")
# About 5 s per run at 5,000 particles on 2 cores.
set -euo pipefail
build="${1:-build}"
particles="${2:-5000}"
read -r -a seeds <<<"${SEEDS:-2 3 4 5 6 7 8 9}"
grove="$build/tools/grove"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# First-quarter and whole-walk RMSE (m) of trajectory $2 against truth $1, matched by time.
errors() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import csv, math, sys
def load(path):
    return [(round(float(r["t"]), 3), float(r["x"]), float(r["y"])) for r in csv.DictReader(open(path))]
truth = {t: (x, y) for t, x, y in load(sys.argv[1])}
err = [math.hypot(x - truth[t][0], y - truth[t][1]) for t, x, y in load(sys.argv[2]) if t in truth]
rms = lambda e: math.sqrt(sum(v * v for v in e) / len(e))
print(f"{rms(err[: len(err) // 4]):.2f} | {rms(err):.2f}")
PY
}
ns() { sed -n 's/.*"ns_per_particle_step": \([0-9.]*\).*/\1/p' "$1/summary.json" | cut -d. -f1; }
run() { "$grove" footslam run --no-progress --particles "$particles" "$@" >/dev/null 2>&1; }

"$grove" footslam simulate --out "$work/sim1" --seed 1 --heading-drift 0.012 >/dev/null 2>&1
"$grove" footslam run --no-progress --particles 1 --steps "$work/sim1/truth.csv" \
  --heading-drift-sigma-rad 0 --heading-sigma-rad 0 --step-length-sigma-m 0 \
  --out "$work/true1" >/dev/null 2>&1
run --steps "$work/sim1/steps.csv" --out "$work/run1"
echo "Prior maps from walk 1 (seed 1): $(($(wc -l <"$work/true1/map.csv") - 1)) hexagons in the true map, $(($(wc -l <"$work/run1/map.csv") - 1)) in FootSLAM's; $particles particles; RMSE of the smoothed path (m) over the first quarter and the whole walk"
echo
echo "| walk (seed) | no prior: first quarter | whole | true map: first quarter | whole | FootSLAM's map of walk 1: first quarter | whole | ns per particle-step: none, true, FootSLAM's |"
echo "| --- | --- | --- | --- | --- | --- | --- | --- |"
for seed in "${seeds[@]}"; do
  sim="$work/sim$seed"
  "$grove" footslam simulate --out "$sim" --seed "$seed" --heading-drift 0.012 >/dev/null 2>&1
  run --steps "$sim/steps.csv" --out "$work/none"
  run --steps "$sim/steps.csv" --out "$work/true" --prior-map "$work/true1/map.csv"
  run --steps "$sim/steps.csv" --out "$work/own" --prior-map "$work/run1/map.csv"
  printf "| %s | %s | %s | %s | %s, %s, %s |\n" "$seed" \
    "$(errors "$sim/truth.csv" "$work/none/smoothed_trajectory.csv")" \
    "$(errors "$sim/truth.csv" "$work/true/smoothed_trajectory.csv")" \
    "$(errors "$sim/truth.csv" "$work/own/smoothed_trajectory.csv")" \
    "$(ns "$work/none")" "$(ns "$work/true")" "$(ns "$work/own")"
done
