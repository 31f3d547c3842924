#!/bin/bash
# abpar_args.sh ROUNDS OUT ARGS...: A and B (environment: build directories) run `bench paper`
# on 1 thread at the same time, one per core (cores swapped every round), with extra arguments.
rounds=$1; out=$2; shift 2
run() {  # run CORE GROVE LABEL ROUND
  local d; d=$(mktemp -d)
  taskset -c $1 $2 bench paper --only 'htree s=16 T=5' --threads 1 "${@:5}" --out $d >/dev/null 2>&1
  echo "$3 round $4 core $1 $(grep '^| htree' $d/paper.md)" >> $out.$3
  rm -rf $d
}
for r in $(seq 1 $rounds); do
  if [ $((r % 2)) = 1 ]; then ca=0; cb=1; else ca=1; cb=0; fi
  run $ca $A/tools/grove A $r "$@" & run $cb $B/tools/grove B $r "$@" & wait
done
cat $out.A $out.B > $out; rm $out.A $out.B
