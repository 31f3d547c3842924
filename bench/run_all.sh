#!/usr/bin/env bash
# Runs every benchmark and writes the results, with the machine they came from, to
# bench/results/<date>-<cpu>-<cores>c/. Run on a quiet machine; takes about 20 minutes on 2 cores.
#   bench/run_all.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
cpu=$(sed -n 's/^model name\s*:\s*//p' /proc/cpuinfo | head -1 | tr -cs 'A-Za-z0-9' '-' | sed 's/-$//')
out="bench/results/$(date +%Y-%m-%d)-${cpu}-$(nproc)c"
mkdir -p "$out"
{
  echo "# Machine"
  echo
  echo "- CPU: $(sed -n 's/^model name\s*:\s*//p' /proc/cpuinfo | head -1), $(nproc) cores"
  echo "- memory: $(free -g | awk '/Mem:/ {print $2}') GiB"
  echo "- OS: $(. /etc/os-release; echo "$PRETTY_NAME"), kernel $(uname -r)"
  echo "- compiler: $(c++ --version | head -1)"
  echo "- build type: $(sed -n 's/^CMAKE_BUILD_TYPE:STRING=//p' "$build/CMakeCache.txt")"
  echo "- commit: $(git rev-parse --short HEAD)$(git diff --quiet || echo ' (with uncommitted changes)')"
  echo "- transparent huge pages: $(cat /sys/kernel/mm/transparent_hugepage/enabled)"
} >"$out/machine.md"
"$build/bench/grove_micro_benchmark" --benchmark_out="$out/micro.json" --benchmark_out_format=json \
  | tee "$out/micro.txt"
"$build/bench/grove_footslam_benchmark" --benchmark_min_time=2 \
  --benchmark_out="$out/footslam.json" --benchmark_out_format=json | tee "$out/footslam.txt"
"$build/tools/grove" bench scaling --out "$out/scaling"
"$build/tools/grove" bench paper --out "$out/paper"
echo "results in $out"
