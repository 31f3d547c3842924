#!/bin/bash
# ab.sh THREADS ROUNDS OUT: alternated paper walks; A and B (environment) are two build
# directories (here A at 9ceb0d1, B at 52ddbbd)
t=$1; rounds=$2; out=$3
for r in $(seq 1 $rounds); do
  for v in A B; do
    if [ $v = A ]; then g=$A/tools/grove; else g=$B/tools/grove; fi
    d=$(mktemp -d)
    $g bench paper --only 'htree s=16 T=5' --threads $t --out $d >/dev/null 2>&1
    echo "$v round $r $(grep '^| htree' $d/paper.md)" >> $out
    rm -rf $d
  done
done
