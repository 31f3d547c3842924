#!/bin/sh
# grove footslam batch and grove fastslam montecarlo under mpirun: the walks dealt to 1, 2 and 3
# ranks (oversubscribed on any machine) give byte-identical outputs to the batch without MPI,
# every rank agrees on the exit code, and rank 0 writes the summary of every walk; the Monte
# Carlo runs dealt to 3 ranks are those of one process.
# Usage: mpi_batch_test.sh GROVE_BINARY MPIEXEC
set -eu
grove=$1
mpiexec=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
# Open MPI refuses root unless told; the tests may run as root in a container.
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
for s in 1 2 3; do
  "$grove" footslam simulate --minutes 1 --seed "$s" --out "$work/w$s" 2>/dev/null
done
cat >"$work/walks.jsonl" <<'JSONL'
{"name": "a", "steps": "w1/steps.csv"}
{"name": "b", "steps": "w2/steps.csv", "config": {"particles": 300}}
{"name": "c", "steps": "w3/steps.csv", "config": {"seed": 5}}
{"name": "d", "steps": "w1/steps.csv", "config": {"alphabet": 0}}
JSONL
"$grove" footslam batch --particles 500 --manifest "$work/walks.jsonl" --out "$work/plain" \
  >/dev/null 2>&1
fail=0
for np in 1 2 3; do
  status=0
  "$mpiexec" --oversubscribe --bind-to none -np "$np" "$grove" footslam batch --particles 500 \
    --manifest "$work/walks.jsonl" --out "$work/np$np" >"$work/np$np.out" 2>"$work/np$np.err" ||
    status=$?
  if [ "$status" -ne 0 ]; then
    echo "FAIL: -np $np exited with $status"; cat "$work/np$np.err"; fail=1; continue
  fi
  for w in a b c d; do
    for f in map.csv map_best.csv trajectory.csv mean_trajectory.csv smoothed_trajectory.csv \
      map.svg map.png; do
      cmp -s "$work/plain/$w/$f" "$work/np$np/$w/$f" || { echo "FAIL: -np $np: $w/$f differs"; fail=1; }
    done
  done
  lines=$(grep -c '"status":"ok"' "$work/np$np/batch_summary.jsonl" || true)
  [ "$lines" = 4 ] || { echo "FAIL: -np $np: $lines of 4 walks ok in batch_summary.jsonl"; fail=1; }
  printed=$(grep -c '"status":"ok"' "$work/np$np.out" || true)
  [ "$printed" = 4 ] || { echo "FAIL: -np $np: $printed result lines on stdout"; fail=1; }
  echo "ok: -np $np"
done
# Run again on 2 ranks: every walk is skipped, whichever rank it lands on now.
"$mpiexec" --oversubscribe --bind-to none -np 2 "$grove" footslam batch --particles 500 \
  --manifest "$work/walks.jsonl" --out "$work/np3" >"$work/again.out" 2>/dev/null
skipped=$(grep -c '"status":"skipped"' "$work/again.out" || true)
[ "$skipped" = 4 ] || { echo "FAIL: rerun skipped $skipped of 4"; fail=1; }
# A bad manifest: every rank exits 2.
echo '{"name": "x"}' >"$work/bad.jsonl"
status=0
"$mpiexec" --oversubscribe --bind-to none -np 2 "$grove" footslam batch \
  --manifest "$work/bad.jsonl" --out "$work/bad" >/dev/null 2>"$work/bad.err" || status=$?
[ "$status" -eq 2 ] || { echo "FAIL: a bad manifest under mpirun exited $status"; cat "$work/bad.err"; fail=1; }
grep -q 'bad.jsonl:1:1: steps: a non-empty path is required' "$work/bad.err" ||
  { echo "FAIL: no file:line:column error"; cat "$work/bad.err"; fail=1; }
# Monte Carlo runs dealt to 3 ranks: every run's series is the one the command writes alone, and
# rank 0 writes the tables.
"$grove" fastslam montecarlo --scenario sim1 --filters fastslam1,fastslam2 --particles 20 \
  --runs 4 --out "$work/mc1" --no-progress >/dev/null 2>&1
status=0
"$mpiexec" --oversubscribe --bind-to none -np 3 "$grove" fastslam montecarlo --scenario sim1 \
  --filters fastslam1,fastslam2 --particles 20 --runs 4 --out "$work/mc3" --no-progress \
  >/dev/null 2>"$work/mc3.err" || status=$?
[ "$status" -eq 0 ] || { echo "FAIL: montecarlo -np 3 exited $status"; cat "$work/mc3.err"; fail=1; }
for f in $(cd "$work/mc1/runs" && find . -name '*.csv' | sort); do
  cmp -s "$work/mc1/runs/$f" "$work/mc3/runs/$f" || { echo "FAIL: montecarlo run $f differs"; fail=1; }
done
[ -s "$work/mc3/table.md" ] || { echo "FAIL: rank 0 wrote no table"; fail=1; }
[ "$fail" -eq 0 ] && echo "ok: montecarlo -np 3"
exit $fail
