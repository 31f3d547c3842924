#!/bin/bash
# abpar_run.sh ROUNDS PARTICLES STEPFILE OUT: A and B (build directories) run `footslam run` on
# 1 thread at the same time, one per core (swapped every round); filter_time_s of each.
rounds=$1; n=$2; steps=$3; out=$4
run() {  # run CORE GROVE LABEL ROUND
  local d; d=$(mktemp -d)
  taskset -c $1 $2 footslam run --steps $steps --particles $n --threads 1 --no-progress --out $d/o >/dev/null 2>&1
  echo "$3 round $4 core $1 $(grep -o '"filter_time_s": [0-9.]*' $d/o/summary.json)" >> $out.$3
  rm -rf $d
}
for r in $(seq 1 $rounds); do
  if [ $((r % 2)) = 1 ]; then ca=0; cb=1; else ca=1; cb=0; fi
  run $ca $A/tools/grove A $r & run $cb $B/tools/grove B $r & wait
done
cat $out.A $out.B > $out; rm $out.A $out.B
