#!/bin/bash
# abrot.sh ROUNDS THREADS OUT LABEL=BUILD_DIR... -- ARGS...: runs `bench paper` of each build once
# per round, in an order rotated every round, so the builds see the same host drift; one line
# per run (label, round, the paper table's row).
rounds=$1; threads=$2; out=$3; shift 3
labels=(); dirs=()
while [ $# -gt 0 ] && [ "$1" != "--" ]; do labels+=("${1%%=*}"); dirs+=("${1#*=}"); shift; done
[ "${1:-}" = "--" ] && shift
n=${#labels[@]}
: > $out
for r in $(seq 1 $rounds); do
  for k in $(seq 0 $((n - 1))); do
    i=$(( (k + r) % n ))
    d=$(mktemp -d)
    ${dirs[$i]}/tools/grove bench paper --only 'htree s=16 T=5' --threads $threads "$@" --out $d >/dev/null 2>&1
    echo "${labels[$i]} round $r threads $threads $(grep '^| htree' $d/paper.md)" >> $out
    rm -rf $d
  done
done
