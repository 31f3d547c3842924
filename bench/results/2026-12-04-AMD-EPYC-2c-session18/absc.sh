#!/bin/bash
# absc.sh ROUNDS OUT: alternated `bench scaling --max-particles 30000`; A and B (environment) are
# two build directories (here A at 9ceb0d1, B at 52ddbbd)
rounds=$1; out=$2
for r in $(seq 1 $rounds); do
  for v in A B; do
    if [ $v = A ]; then g=$A/tools/grove; else g=$B/tools/grove; fi
    d=$(mktemp -d)
    $g bench scaling --max-particles 30000 --out $d >/dev/null 2>&1
    grep '^| threads' $d/scaling.md | sed "s/^/$v round $r /" >> $out
    rm -rf $d
  done
done
