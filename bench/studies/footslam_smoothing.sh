#!/usr/bin/env bash
# The smoothed path against the filtered mean and the heaviest particle's path: aligned RMSE
# against the truth on simulated 8-minute building walks, one markdown row per (particles, seed).
#   bench/studies/footslam_smoothing.sh [build-dir] [particles...]   (seeds: SEEDS="1 2 3 4", the default)
# About 10 s per run at 30,000 particles.
set -euo pipefail
build="${1:-build}"
shift || true
counts=("$@")
[ ${#counts[@]} -gt 0 ] || counts=(1000 5000 30000)
read -r -a seeds <<<"${SEEDS:-1 2 3 4}"
grove="$build/tools/grove"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
rmse() { "$grove" footslam evaluate --truth "$1" --trajectory "$2" | sed -n 's/.*"aligned_rmse_m": \([0-9.]*\).*/\1/p'; }

echo "| particles | seed | heaviest (m) | filtered mean (m) | smoothed (m) |"
echo "| --- | --- | --- | --- | --- |"
for seed in "${seeds[@]}"; do
  "$grove" footslam simulate --out "$work/sim$seed" --seed "$seed" --heading-drift 0.012 2>/dev/null
done
for particles in "${counts[@]}"; do
  for seed in "${seeds[@]}"; do
    sim="$work/sim$seed"
    "$grove" footslam run --no-progress --particles "$particles" --steps "$sim/steps.csv" \
      --out "$work/out" 2>/dev/null
    printf "| %s | %s | %.2f | %.2f | %.2f |\n" "$particles" "$seed" \
      "$(rmse "$sim/truth.csv" "$work/out/trajectory.csv")" \
      "$(rmse "$sim/truth.csv" "$work/out/mean_trajectory.csv")" \
      "$(rmse "$sim/truth.csv" "$work/out/smoothed_trajectory.csv")"
  done
done
