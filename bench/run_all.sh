#!/usr/bin/env bash
# Runs the micro-benchmarks, the FootSLAM step benchmark, `grove bench scaling` and `grove bench
# paper`, and writes their results into bench/results/<machine>/, replacing that machine's
# previous baseline of these four (git keeps the old one). <machine> is the CPU's model name and
# core count, e.g. amd-epyc-2c; MACHINE=name overrides it. machine.md, the machine's description,
# is written only when missing. Run on a quiet machine; about 20 minutes on 2 cores.
#   bench/run_all.sh [build-dir]
set -euo pipefail
cd "$(dirname "$0")/.."
build="${1:-build}"
model=$(sed -n 's/^model name\s*:\s*//p' /proc/cpuinfo | head -1)
slug=$(echo "$model" | sed -e 's/([RrTtMm]*)//g' -e 's/ CPU//' -e 's/@.*//' | tr 'A-Z' 'a-z' |
  tr -cs 'a-z0-9' '-' | sed 's/^-//; s/-$//')
out="bench/results/${MACHINE:-$slug-$(nproc)c}"
mkdir -p "$out"/{micro,footslam_benchmark}
if [ ! -f "$out/machine.md" ]; then
  {
    echo "# Machine: $(basename "$out")"
    echo
    echo "- CPU: $model, $(nproc) cores"
    echo "- memory: $(free -g | awk '/Mem:/ {print $2}') GiB"
    echo "- OS: $(. /etc/os-release; echo "$PRETTY_NAME"), kernel $(uname -r)"
    echo "- compiler: $(c++ --version | head -1)"
    echo "- transparent huge pages: $(cat /sys/kernel/mm/transparent_hugepage/enabled)"
  } >"$out/machine.md"
fi
# Each result records the commit, compiler and build type it was made with.
"$build/bench/grove_micro_benchmark" --benchmark_out="$out/micro/micro.json" \
  --benchmark_out_format=json | tee "$out/micro/micro.txt"
"$build/bench/grove_footslam_benchmark" --benchmark_min_time=2 \
  --benchmark_out="$out/footslam_benchmark/footslam.json" --benchmark_out_format=json \
  | tee "$out/footslam_benchmark/footslam.txt"
"$build/tools/grove" bench scaling --out "$out/scaling"
"$build/tools/grove" bench paper --out "$out/paper"
# The charts are drawn as PNG and SVG; the results keep the PNG.
rm -f "$out"/scaling/*.svg "$out"/paper/*.svg
echo "results in $out; add a row for them to bench/results/README.md"
