#!/bin/bash
# abalt_args.sh PAIRS THREADS OUT ARGS...: abalt.sh with extra `bench paper` arguments.
pairs=$1; threads=$2; out=$3; shift 3
run() {  # run GROVE LABEL PAIR
  local d; d=$(mktemp -d)
  $1 bench paper --only 'htree s=16 T=5' --threads $threads "${@:4}" --out $d >/dev/null 2>&1
  echo "$2 round $3 threads $threads $(grep '^| htree' $d/paper.md)" >> $out
  rm -rf $d
}
: > $out
for r in $(seq 1 $pairs); do
  if [ $((r % 2)) = 1 ]; then run $A/tools/grove A $r "$@"; run $B/tools/grove B $r "$@"
  else run $B/tools/grove B $r "$@"; run $A/tools/grove A $r "$@"; fi
done
