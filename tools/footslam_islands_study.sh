#!/usr/bin/env bash
# The statistical price of island mode: FootSLAM on simulated 8-minute building walks, one filter
# of N particles resampled as a whole (the global mode) against the same N in islands that
# resample alone, with and without exchanges, and against one island's particles alone.
# Prints one markdown row per (configuration, walk) and a mean row per configuration.
#   tools/footslam_islands_study.sh [build-dir] [particles] [walk seeds...]
# Island mode's results depend on the islands, not on the ranks (tested), so one process
# stands for any rank count. Takes about 10-25 s per run at 32,768 particles on 2 cores.
set -euo pipefail
build="${1:-build}"
particles="${2:-32768}"
shift 2 || true
seeds=("$@")
[ ${#seeds[@]} -gt 0 ] || seeds=(1 2 3 4 5 6)
grove="$build/tools/grove"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
block=4096

configs=(
  "global, $particles particles|--particles $particles"
  "global, $block particles (one island alone)|--particles $block"
)
for islands in 2 4 8; do
  [ $((islands * block)) -le "$particles" ] || continue
  configs+=(
    "$islands islands, no exchange|--particles $particles --islands $islands --island-exchange-fraction 0"
    "$islands islands, 10 % every 10 steps|--particles $particles --islands $islands"
    "$islands islands, 10 % every step|--particles $particles --islands $islands --island-exchange-steps 1"
  )
done
rmse() { "$grove" footslam evaluate --truth "$1" --trajectory "$2" | sed -n 's/.*"aligned_rmse_m": \([0-9.]*\).*/\1/p'; }

echo "| configuration | walk | aligned RMSE (m) | filter (s) | peak RSS (MiB) |"
echo "| --- | --- | --- | --- | --- |"
for seed in "${seeds[@]}"; do
  sim="$work/sim$seed"
  "$grove" footslam simulate --out "$sim" --seed "$seed" --heading-drift 0.012 2>/dev/null
done
for entry in "${configs[@]}"; do
  name="${entry%%|*}"
  for seed in "${seeds[@]}"; do
    sim="$work/sim$seed"
    # shellcheck disable=SC2086  # the flags are words
    "$grove" footslam run --no-progress ${entry#*|} --steps "$sim/steps.csv" --out "$work/out" \
      2>/dev/null
    est=$(rmse "$sim/truth.csv" "$work/out/trajectory.csv")
    run=$(sed -n 's/.*"filter_time_s": \([0-9.]*\).*/\1/p' "$work/out/summary.json")
    rss=$(sed -n 's/.*"peak_rss_bytes": \([0-9]*\).*/\1/p' "$work/out/summary.json")
    printf "| %s | %s | %.2f | %.1f | %d |\n" "$name" "$seed" "$est" "$run" $((rss >> 20))
    echo "$name|$est" >>"$work/all"
  done
done
echo
echo "| configuration | mean aligned RMSE over ${#seeds[@]} walks (m) | worst (m) |"
echo "| --- | --- | --- |"
for entry in "${configs[@]}"; do
  name="${entry%%|*}"
  awk -F'|' -v n="$name" '$1 == n { s += $2; if ($2 > w) w = $2; k++ }
    END { printf "| %s | %.2f | %.2f |\n", n, s / k, w }' "$work/all"
done
