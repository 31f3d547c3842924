#!/bin/sh
# `grove footslam run` as one filter across MPI ranks: the outputs rank 0 writes (maps, the
# heaviest, mean and smoothed paths, the images) are byte-identical to one process's for 2 ranks
# at 1 and 2 threads and for 4 ranks (oversubscribed on any machine), and so are island mode's on
# 1, 2 and 4 ranks, and so are storage of diversity's on 2 ranks and those of a run resumed from
# a checkpoint per rank. Ranks that read different steps, a resume on another rank count, too
# few particles for the ranks and islands that do not divide among them are refused on every
# rank.
# Usage: mpi_run_test.sh GROVE_BINARY MPIEXEC BUNDLED_STEPS_CSV
set -eu
grove=$1
mpiexec=$2
steps=$3
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Open MPI refuses root unless told; the tests may run as root in a container.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mpi() { "$mpiexec" --oversubscribe --bind-to none "$@"; }
head -n 301 "$steps" >"$work/steps.csv"  # the bundled walk's first 300 steps
common="--steps $work/steps.csv --no-progress"
args="$common --particles 12805"
outputs="map.csv map_best.csv trajectory.csv mean_trajectory.csv smoothed_trajectory.csv map.png map.svg"
"$grove" footslam run $args --threads 2 --out "$work/one" 2>/dev/null
fail=0
for run in "2 1" "2 2" "4 1"; do
  set -- $run
  dir="$work/np$1t$2"
  mpi -np "$1" "$grove" footslam run $args --threads "$2" --out "$dir" 2>"$work/err" ||
    { echo "FAIL: -np $1: exit $?"; cat "$work/err"; fail=1; continue; }
  for f in $outputs; do
    cmp -s "$work/one/$f" "$dir/$f" || { echo "FAIL: -np $1, $2 threads: $f differs"; fail=1; }
  done
  grep -q "\"ranks\": $1" "$dir/summary.json" || { echo "FAIL: -np $1: no ranks in summary"; fail=1; }
  echo "ok: -np $1, $2 threads per rank: the outputs of one process"
done
# Island mode: the islands decide the results, not the ranks.
islands="$args --islands 4 --island-exchange-steps 5 --island-exchange-fraction 0.2"
"$grove" footslam run $islands --threads 2 --out "$work/islands" 2>/dev/null
cmp -s "$work/one/trajectory.csv" "$work/islands/trajectory.csv" &&
  { echo "FAIL: island mode gave the global mode's path"; fail=1; }
for np in 2 4; do
  dir="$work/islands$np"
  mpi -np "$np" "$grove" footslam run $islands --threads 1 --out "$dir" 2>"$work/err" ||
    { echo "FAIL: islands -np $np: exit $?"; cat "$work/err"; fail=1; continue; }
  for f in $outputs; do
    cmp -s "$work/islands/$f" "$dir/$f" || { echo "FAIL: islands -np $np: $f differs"; fail=1; }
  done
  echo "ok: 4 islands on -np $np: the outputs of one process"
done
# Storage of diversity: the ranks fold every rank's far blocks into one stored map.
stored="$args --store-distance-m 10"
"$grove" footslam run $stored --threads 2 --out "$work/stored" 2>/dev/null
[ -s "$work/stored/stored_map.csv" ] || { echo "FAIL: nothing was stored"; fail=1; }
mpi -np 2 "$grove" footslam run $stored --threads 1 --out "$work/stored2" 2>"$work/err" ||
  { echo "FAIL: storage -np 2: exit $?"; cat "$work/err"; fail=1; }
for f in $outputs stored_map.csv; do
  cmp -s "$work/stored/$f" "$work/stored2/$f" || { echo "FAIL: storage -np 2: $f differs"; fail=1; }
done
echo "ok: storage of diversity on -np 2: the outputs of one process"
# Checkpoints: each rank writes its own file every 100 steps of the first 200; resumed on as
# many ranks with the whole walk, the run gives the outputs of one uninterrupted process.
head -n 201 "$work/steps.csv" >"$work/first200.csv"
mpi -np 2 "$grove" footslam run --steps "$work/first200.csv" --no-progress --particles 12805 \
  --checkpoint-every 100 --checkpoint "$work/ck/run.grove" --out "$work/part" 2>"$work/err" ||
  { echo "FAIL: a checkpointed run across ranks: exit $?"; cat "$work/err"; fail=1; }
[ -s "$work/ck/run.grove" ] && [ -s "$work/ck/run.grove.rank1" ] ||
  { echo "FAIL: no checkpoint file per rank"; ls "$work/ck"; fail=1; }
mpi -np 2 "$grove" footslam run $args --threads 2 --resume "$work/ck/run.grove" \
  --out "$work/resumed" 2>"$work/err" ||
  { echo "FAIL: a resume across ranks: exit $?"; cat "$work/err"; fail=1; }
for f in $outputs; do
  cmp -s "$work/one/$f" "$work/resumed/$f" || { echo "FAIL: resumed on 2 ranks: $f differs"; fail=1; }
done
echo "ok: -np 2 resumed from a checkpoint per rank: the outputs of one process"
status=0
mpi -np 3 "$grove" footslam run $args --resume "$work/ck/run.grove" --out "$work/bad" \
  >/dev/null 2>"$work/bad.err" || status=$?
[ "$status" -eq 3 ] || { echo "FAIL: a resume on more ranks exited $status"; fail=1; }
grep -q "run.grove.rank2: .*resume on as many ranks as wrote the checkpoint" "$work/bad.err" ||
  { echo "FAIL: the refusal does not say why"; cat "$work/bad.err"; fail=1; }
status=0
"$grove" footslam run $args --resume "$work/ck/run.grove" --out "$work/bad" >/dev/null \
  2>"$work/bad.err" || status=$?
[ "$status" -eq 2 ] || { echo "FAIL: a resume on one process exited $status"; fail=1; }
grep -q "rank 0 of 2's particles, and this is rank 0 of 1" "$work/bad.err" ||
  { echo "FAIL: the refusal does not name the ranks"; cat "$work/bad.err"; fail=1; }
# Every rank must read the same steps: rank 1 reads a walk with one value changed.
sed '100s/^\([0-9.]*\),[-0-9.e]*,/\1,0.5,/' "$work/steps.csv" >"$work/other.csv"
cmp -s "$work/steps.csv" "$work/other.csv" && { echo "FAIL: the other walk is the same"; fail=1; }
status=0
mpi -np 1 "$grove" footslam run $args --out "$work/mpmd" : \
  -np 1 "$grove" footslam run --steps "$work/other.csv" --particles 12805 --no-progress \
  --out "$work/mpmd" >/dev/null 2>"$work/mpmd.err" || status=$?
[ "$status" -eq 3 ] || { echo "FAIL: ranks reading other steps exited $status"; fail=1; }
grep -q 'rank 1 read other values than rank 0 in steps 99' "$work/mpmd.err" ||
  { echo "FAIL: the refusal does not name the step"; cat "$work/mpmd.err"; fail=1; }
[ ! -e "$work/mpmd/map.csv" ] || { echo "FAIL: a refused run wrote outputs"; fail=1; }
for bad in "--particles 4096" "--particles 12805 --islands 3"; do
  status=0
  mpi -np 2 "$grove" footslam run $common $bad --out "$work/bad" >/dev/null 2>"$work/bad.err" ||
    status=$?
  [ "$status" -eq 2 ] || { echo "FAIL: $bad across ranks exited $status"; fail=1; }
  n=$(grep -c 'error' "$work/bad.err" || true)
  [ "$n" = 1 ] || { echo "FAIL: $bad: $n error lines, want rank 0's alone"; cat "$work/bad.err"; fail=1; }
done
exit $fail
