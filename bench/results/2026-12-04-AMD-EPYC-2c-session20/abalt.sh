#!/bin/bash
# abalt.sh PAIRS THREADS OUT: A and B (environment: build directories) run the paper walk one
# after the other, alternating which goes first; one line per run (label, pair, the paper.md row).
pairs=$1; threads=$2; out=$3
run() {  # run GROVE LABEL PAIR
  local d; d=$(mktemp -d)
  $1 bench paper --only 'htree s=16 T=5' --threads $threads --out $d >/dev/null 2>&1
  echo "$2 round $3 threads $threads $(grep '^| htree' $d/paper.md)" >> $out
  rm -rf $d
}
: > $out
for r in $(seq 1 $pairs); do
  if [ $((r % 2)) = 1 ]; then run $A/tools/grove A $r; run $B/tools/grove B $r
  else run $B/tools/grove B $r; run $A/tools/grove A $r; fi
done
