#!/usr/bin/env bash
# Builds grove's libFuzzer targets (tests/fuzz/: clang, ASan + UBSan, pooling off) and runs each
# one for a bounded time over a scratch copy of its committed corpus (the repository is never
# written to; new inputs and crash files stay in the scratch directory).
#
#   tools/scripts/fuzz.sh [SECONDS [TARGET...]]
#     SECONDS  run time per fuzzer (default 60)
#     TARGET   step_reader, config_json, csv_readers, checkpoint (default: all four)
#
# Environment: BUILD_DIR (default build-fuzz), JOBS (build jobs, default 2), WORK_DIR (scratch
# directory, default a new one under /tmp; kept so the corpora and reproducers can be inspected).
# CLANG_VERSION (default 19). FUZZ_RUNS=N runs N inputs per fuzzer with a fixed seed instead of
# a time limit: the same inputs on every run, so CI is repeatable; FUZZ_RUNS_<TARGET>=N (say
# FUZZ_RUNS_CHECKPOINT) sets one fuzzer's. FUZZ_JOBS=N runs up to N fuzzers at once (default 1:
# one after the other). Installs clang-N, libclang-rt-N-dev (libFuzzer) and llvm-N
# (llvm-symbolizer) from Debian when missing; the project's own dependencies come from
# tools/scripts/setup.sh.
# Exit status: 0 when no fuzzer failed, 1 when one did (its reproducer's path is printed), 2 for a
# usage error.
set -euo pipefail
cd "$(dirname "$0")/../.."

seconds="${1:-60}"
shift || true
if ! [[ "$seconds" =~ ^[0-9]+$ ]] || [ "$seconds" -lt 1 ]; then
  echo "usage: tools/scripts/fuzz.sh [SECONDS [step_reader|config_json|csv_readers|checkpoint ...]]" >&2
  exit 2
fi
jobs_max="${FUZZ_JOBS:-1}"
if ! [[ "$jobs_max" =~ ^[0-9]+$ ]] || [ "$jobs_max" -lt 1 ]; then
  echo "fuzz: FUZZ_JOBS must be a whole number >= 1, not '$jobs_max'" >&2
  exit 2
fi
targets=("$@")
((${#targets[@]})) || targets=(step_reader config_json csv_readers checkpoint)
for t in "${targets[@]}"; do
  if [ ! -d "tests/fuzz/corpus/$t" ]; then
    echo "fuzz: unknown target '$t' (known: step_reader config_json csv_readers checkpoint)" >&2
    exit 2
  fi
done

installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }
install_missing() {
  local missing=()
  for p in "$@"; do installed "$p" || missing+=("$p"); done
  ((${#missing[@]})) || return 0
  echo "fuzz: installing ${missing[*]}" >&2
  local sudo_cmd=()
  [ "$(id -u)" -eq 0 ] || sudo_cmd=(sudo)
  "${sudo_cmd[@]}" apt-get update -qq
  DEBIAN_FRONTEND=noninteractive "${sudo_cmd[@]}" apt-get install -y -qq --no-install-recommends \
    "$@" >/dev/null
}
# clang 19 from Debian 12's main archive: clang 14 (Debian's default) cannot compile grove, which
# captures structured bindings in lambdas (C++20, clang >= 16). libFuzzer ships in the compiler-rt
# package of the same version; llvm-symbolizer (in llvm-N) gives reports with file:line.
llvm="${CLANG_VERSION:-19}"
install_missing "clang-$llvm" "libclang-rt-$llvm-dev" "llvm-$llvm"
symbolizer="/usr/lib/llvm-$llvm/bin/llvm-symbolizer"

build_dir="${BUILD_DIR:-build-fuzz}"
cache="$build_dir/CMakeCache.txt"
if [ -f "$cache" ] && ! grep -q "^CMAKE_CXX_COMPILER:[A-Z]*=.*clang++-$llvm\$" "$cache"; then
  rm -rf "$cache" "$build_dir/CMakeFiles"  # configured with another compiler
fi
CC="clang-$llvm" CXX="clang++-$llvm" cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DGROVE_FUZZ=ON -DGROVE_BUILD_TESTS=OFF -DGROVE_BUILD_BENCHMARKS=OFF -DGROVE_NODE_POOL=OFF \
  >/dev/null
cmake --build "$build_dir" -j "${JOBS:-2}" --target "${targets[@]/%/_fuzzer}" \
  -- --no-print-directory >/dev/null

work="${WORK_DIR:-$(mktemp -d /tmp/grove-fuzz.XXXXXX)}"
mkdir -p "$work"
export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:symbolize=1}:external_symbolizer_path=$symbolizer"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"

# One fuzzer: its scratch corpus, its run, its report. A failure leaves $work/$t.failed.
fuzz_one() {
  local t="$1" dir="$work/$1" status=0 runs_var budget
  rm -rf "$dir" "$work/$t.failed"
  mkdir -p "$dir/corpus" "$dir/artifacts"
  cp -R "tests/fuzz/corpus/$t/." "$dir/corpus/"
  runs_var="FUZZ_RUNS_${t^^}"
  local runs_budget="${!runs_var:-${FUZZ_RUNS:-}}"
  if [ -n "$runs_budget" ]; then
    budget=(-runs="$runs_budget" -seed=1)
    echo "fuzz: $t for $runs_budget inputs (scratch $dir)"
  else
    budget=(-max_total_time="$seconds")
    echo "fuzz: $t for ${seconds} s (scratch $dir)"
  fi
  "$build_dir/tests/fuzz/${t}_fuzzer" "${budget[@]}" -max_len=4096 -timeout=10 \
    -rss_limit_mb=2048 -print_final_stats=1 -artifact_prefix="$dir/artifacts/" \
    "$dir/corpus" >"$dir/log" 2>&1 || status=$?
  local done_line rate runs
  done_line="$(grep -aE '^#[0-9]+[[:space:]]+DONE' "$dir/log" | tail -n 1 || true)"
  rate="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$dir/log" | tail -n 1)"
  runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$dir/log" | tail -n 1)"
  if [ "$status" -eq 0 ]; then
    echo "fuzz: $t ok: ${runs:-?} runs, ${rate:-?} exec/s; ${done_line:-no DONE line}"
    return 0
  fi
  touch "$work/$t.failed"
  echo "fuzz: $t FAILED (exit $status); log $dir/log" >&2
  grep -aE 'fuzz property violated|ERROR: (libFuzzer|AddressSanitizer)|runtime error|SUMMARY' \
    "$dir/log" | head -n 5 >&2 || true
  for f in "$dir"/artifacts/*; do
    [ -e "$f" ] || continue
    echo "fuzz: reproducer $f  (replay: $build_dir/tests/fuzz/${t}_fuzzer $f)" >&2
  done
}

running=0
for t in "${targets[@]}"; do
  if [ "$jobs_max" -eq 1 ]; then
    fuzz_one "$t"
    continue
  fi
  if [ "$running" -ge "$jobs_max" ]; then
    wait -n || true
    running=$((running - 1))
  fi
  fuzz_one "$t" &
  running=$((running + 1))
done
wait || true
failed=0
for t in "${targets[@]}"; do
  [ ! -e "$work/$t.failed" ] || failed=1
done
exit "$failed"
