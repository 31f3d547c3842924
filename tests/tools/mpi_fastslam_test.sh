#!/bin/sh
# `grove fastslam run` as one filter across MPI ranks: the outputs rank 0 writes (the mean and
# heaviest paths, the heaviest particle's landmarks, the images) are byte-identical to one
# process's for 2 ranks at 1 and 2 threads and for 4 ranks (oversubscribed on any machine), for
# FastSLAM 2.0 under unknown association and for DE-SRCD-FastSLAM, whose differential evolution
# draws from every rank's poses; so are those of a run resumed from a checkpoint per rank. Too
# few particles for the ranks is refused on every rank.
# Usage: mpi_fastslam_test.sh GROVE_BINARY MPIEXEC
set -eu
grove=$1
mpiexec=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Open MPI refuses root unless told; the tests may run as root in a container.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpi() { "$mpiexec" --oversubscribe --bind-to none "$@"; }
"$grove" fastslam simulate --out "$work/sim" >/dev/null 2>&1
# The first 30 s of the drive (1,200 controls, 150 scans), its first 15 s and its first 6 s.
for t in 30 15 6; do
  awk -F, -v t=$t 'NR == 1 || $1 < t' "$work/sim/controls.csv" >"$work/controls$t.csv"
  awk -F, -v t=$t 'NR == 1 || $1 < t' "$work/sim/observations.csv" >"$work/observations$t.csv"
done
outputs="trajectory.csv heaviest_trajectory.csv landmarks.csv map.png map.svg"
fail=0
# FastSLAM 2.0 on 30 s, DE-SRCD-FastSLAM (six times slower) on 6 s.
for case in "fastslam2 30" "de_srcd 6"; do
  set -- $case
  filter=$1
  args="--controls $work/controls$2.csv --observations $work/observations$2.csv --no-progress
    --particles 12300 --filter $filter --association ml"
  "$grove" fastslam run $args --threads 2 --out "$work/$filter" 2>/dev/null
  for run in "2 1" "2 2" "4 1"; do
    set -- $run
    dir="$work/$filter-np$1t$2"
    mpi -np "$1" "$grove" fastslam run $args --threads "$2" --out "$dir" 2>"$work/err" ||
      { echo "FAIL: $filter -np $1: exit $?"; cat "$work/err"; fail=1; continue; }
    for f in $outputs; do
      cmp -s "$work/$filter/$f" "$dir/$f" || { echo "FAIL: $filter -np $1, $2 threads: $f differs"; fail=1; }
    done
    grep -q "\"ranks\": $1" "$dir/summary.json" || { echo "FAIL: -np $1: no ranks in summary"; fail=1; }
    echo "ok: $filter -np $1, $2 threads per rank: the outputs of one process"
  done
done
# Checkpoints: each rank writes its own file every 300 input rows of the first 15 s; resumed on
# as many ranks with the whole input, the run gives the outputs of one uninterrupted process.
args="--no-progress --particles 12300 --filter fastslam2 --association ml"
mpi -np 2 "$grove" fastslam run $args --controls "$work/controls15.csv" \
  --observations "$work/observations15.csv" --checkpoint-every 300 \
  --checkpoint "$work/ck/run.grove" --out "$work/part" 2>"$work/err" ||
  { echo "FAIL: a checkpointed run across ranks: exit $?"; cat "$work/err"; fail=1; }
[ -s "$work/ck/run.grove" ] && [ -s "$work/ck/run.grove.rank1" ] ||
  { echo "FAIL: no checkpoint file per rank"; ls "$work/ck"; fail=1; }
mpi -np 2 "$grove" fastslam run $args --controls "$work/controls30.csv" \
  --observations "$work/observations30.csv" --resume "$work/ck/run.grove" \
  --out "$work/resumed" 2>"$work/err" ||
  { echo "FAIL: a resume across ranks: exit $?"; cat "$work/err"; fail=1; }
for f in $outputs; do
  cmp -s "$work/fastslam2/$f" "$work/resumed/$f" || { echo "FAIL: resumed on 2 ranks: $f differs"; fail=1; }
done
echo "ok: -np 2 resumed from a checkpoint per rank: the outputs of one process"
status=0
mpi -np 2 "$grove" fastslam run --no-progress --controls "$work/controls15.csv" \
  --observations "$work/observations15.csv" --particles 4096 --out "$work/bad" >/dev/null \
  2>"$work/bad.err" || status=$?
[ "$status" -eq 2 ] || { echo "FAIL: too few particles across ranks exited $status"; fail=1; }
n=$(grep -c 'error' "$work/bad.err" || true)
[ "$n" = 1 ] || { echo "FAIL: $n error lines, want rank 0's alone"; cat "$work/bad.err"; fail=1; }
echo "ok: too few particles for 2 ranks: refused with one error line"
exit $fail
