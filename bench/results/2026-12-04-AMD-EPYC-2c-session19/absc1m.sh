#!/bin/bash
# absc1m.sh ROUNDS OUT: alternated `bench scaling --steps 100` sweeps up to 1,000,000 particles
rounds=$1; out=$2
for r in $(seq 1 $rounds); do
  for v in A B; do
    if [ $v = A ]; then g=$A/tools/grove; else g=$B/tools/grove; fi
    d=$(mktemp -d)
    $g bench scaling --steps 100 --out $d >/dev/null 2>&1
    grep '^| particles' $d/scaling.md | sed "s/^/$v round $r /" >> $out
    rm -rf $d
  done
done
