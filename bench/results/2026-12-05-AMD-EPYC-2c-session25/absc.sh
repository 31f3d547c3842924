#!/bin/bash
# absc.sh ROUNDS OUT A_DIR B_DIR: bench scaling (fixed grid, whole walk, 30,000 particles) of A and B
# once per round, order swapped every round; the threads rows of each, labelled.
rounds=$1; out=$2; : > $out
for r in $(seq 1 $rounds); do
  if [ $((r % 2)) = 1 ]; then order="A B"; else order="B A"; fi
  for l in $order; do
    if [ $l = A ]; then g=$3; else g=$4; fi
    d=$(mktemp -d)
    $g/tools/grove bench scaling --out $d --max-particles 30000 --grid fixed --steps 1418 >/dev/null 2>&1
    grep '^| threads' $d/scaling.md | sed "s/^/$l round $r /" >> $out
    rm -rf $d
  done
done
