#!/bin/sh
# One FootSLAM filter across MPI ranks (grove_ranks_benchmark): the digest of every particle's final
# state (weight, pose, error states, path, map) is the same for one process and for 2 and 4
# ranks (oversubscribed on any machine), at 1 and 2 threads per rank; too few particles for the
# ranks, or ranks given other options, is refused on every rank with exit code 2.
# Usage: mpi_filter_test.sh RANKS_BENCHMARK_BINARY MPIEXEC
set -eu
bench=$1
mpiexec=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Open MPI refuses root unless told; the tests may run as root in a container.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
digest() { sed -n 's/.*"digest": "\([0-9a-f]*\)".*/\1/p' "$1/ranks.json"; }
args="--particles 16500 --minutes 0.5"
"$bench" $args --threads 2 --out "$work/one" >/dev/null
want=$(digest "$work/one")
[ -n "$want" ] || { echo "FAIL: no digest from one process"; exit 1; }
fail=0
for run in "2 1" "2 2" "4 1"; do
  set -- $run
  "$mpiexec" --oversubscribe --bind-to none -np "$1" "$bench" $args --threads "$2" \
    --out "$work/np$1t$2" >/dev/null 2>"$work/err" || { echo "FAIL: -np $1: exit $?"; cat "$work/err"; fail=1; continue; }
  got=$(digest "$work/np$1t$2")
  if [ "$got" = "$want" ]; then
    echo "ok: -np $1, $2 threads per rank: digest $got"
  else
    echo "FAIL: -np $1, $2 threads per rank: digest $got, one process $want"; fail=1
  fi
  grep -q '"sent_bytes_per_resampling": 0.0' "$work/np$1t$2/ranks.json" &&
    { echo "FAIL: -np $1: no particle moved"; fail=1; }
done
status=0
"$mpiexec" --oversubscribe --bind-to none -np 2 "$bench" --particles 4096 \
  --minutes 0.5 --out "$work/few" >/dev/null 2>"$work/few.err" || status=$?
[ "$status" -eq 2 ] || { echo "FAIL: too few particles exited $status"; fail=1; }
n=$(grep -c 'every rank needs a block' "$work/few.err" || true)
[ "$n" = 2 ] || { echo "FAIL: $n of 2 ranks explained the refusal"; cat "$work/few.err"; fail=1; }
# Ranks given other options (an MPMD launch): every rank refuses with exit 2.
status=0
"$mpiexec" --oversubscribe --bind-to none -np 1 "$bench" $args --out "$work/mpmd" : \
  -np 1 "$bench" --particles 16500 --minutes 0.6 --out "$work/mpmd" \
  >/dev/null 2>"$work/mpmd.err" || status=$?
[ "$status" -eq 2 ] || { echo "FAIL: ranks with other options exited $status"; fail=1; }
n=$(grep -c 'rank 1 was given' "$work/mpmd.err" || true)
[ "$n" = 2 ] || { echo "FAIL: $n of 2 ranks named the difference"; cat "$work/mpmd.err"; fail=1; }
exit $fail
