#!/usr/bin/env bash
# Accuracy of FootSLAM against raw odometry on simulated 8-minute building walks, and the
# short-step trap: prints one markdown row per (configuration, seed).
#   bench/studies/footslam_accuracy.sh [build-dir] [particles] [seeds...]
# Needs python3 only to integrate the odometry. Takes about 10 s per run at 30,000 particles.
set -euo pipefail
build="${1:-build}"
particles="${2:-30000}"
shift 2 || true
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3 4 5 6)
grove="$build/tools/grove"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT

configs=(
  "paper, fixed scale (default)|{}"
  "prior_ratio, fixed scale|{\"weighting\":\"prior_ratio\"}"
  "paper, free scale (trap)|{\"scale_sigma\":0.02,\"scale_drift_sigma\":0.002}"
  "prior_ratio, free scale|{\"weighting\":\"prior_ratio\",\"scale_sigma\":0.02,\"scale_drift_sigma\":0.002}"
)
rmse() { "$grove" footslam evaluate --truth "$1" --trajectory "$2" | sed -n 's/.*"aligned_rmse_m": \([0-9.]*\).*/\1/p'; }

echo "| configuration | seed | odometry aligned RMSE (m) | FootSLAM aligned RMSE (m) | ratio | final mean scale |"
echo "| --- | --- | --- | --- | --- | --- |"
for seed in "${seeds[@]}"; do
  sim="$work/sim$seed"
  "$grove" footslam simulate --out "$sim" --seed "$seed" --heading-drift 0.012 2>/dev/null
  python3 - "$sim/steps.csv" "$sim/odometry.csv" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))[1:]
x = y = 0.0
out = ["t,x,y", "0,0,0"]
for t, dx, dy in rows:
    x += float(dx); y += float(dy); out.append(f"{t},{x},{y}")
open(sys.argv[2], "w").write("\n".join(out) + "\n")
PY
  odo=$(rmse "$sim/truth.csv" "$sim/odometry.csv")
  for entry in "${configs[@]}"; do
    name="${entry%%|*}"
    echo "${entry#*|}" >"$work/config.json"
    "$grove" footslam run --no-progress --particles "$particles" --steps "$sim/steps.csv" \
      --config "$work/config.json" --out "$work/out" 2>/dev/null
    est=$(rmse "$sim/truth.csv" "$work/out/trajectory.csv")
    scale=$(sed -n 's/.*"mean_scale": \([0-9.]*\).*/\1/p' "$work/out/summary.json")
    printf "| %s | %s | %.2f | %.2f | %.2f | %.3f |\n" "$name" "$seed" "$odo" "$est" \
      "$(awk -v a="$est" -v b="$odo" 'BEGIN { print a / b }')" "$scale"
  done
done
