#!/bin/sh
# Landmark FastSLAM as one filter across 2 MPI ranks against one process on 2 threads, on this
# machine's 2 cores: the first 120 s of the simulated webmap drive (seed 1), FastSLAM 2.0 under
# unknown association, 32,768 particles; ROUNDS alternated rounds (default 2). Prints one line
# per run from its summary.json (rank 0's figures across ranks) and checks the outputs are the
# same bytes. Usage: fastslam_ranks.sh GROVE_BINARY OUT_DIR
set -eu
grove=$1
out=$2
rounds=${ROUNDS:-2}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
mkdir -p "$out"
"$grove" fastslam simulate --out "$out/sim" >/dev/null 2>&1
awk -F, 'NR == 1 || $1 < 120' "$out/sim/controls.csv" >"$out/controls.csv"
awk -F, 'NR == 1 || $1 < 120' "$out/sim/observations.csv" >"$out/observations.csv"
args="--controls $out/controls.csv --observations $out/observations.csv --no-progress
  --particles 32768 --filter fastslam2 --association ml"
show() {
  /usr/bin/python3 - "$1" "$2" <<'PY'
import json, sys
s = json.load(open(sys.argv[2] + "/summary.json"))
p = s["phases_s"]
print(f"{sys.argv[1]}: {s['filter_time_s']:.2f} s, {s['ns_per_particle_step']:.0f} ns per "
      f"particle-step; advance {p['advance']:.2f}, normalise {p['normalize']:.2f}, resample "
      f"{p['resample']:.2f}, release {p['release']:.2f}, bookkeeping {p['bookkeeping']:.2f} s; "
      f"{s['resamplings']} resamplings; sent {s['sent_particles']} particles, "
      f"{s['sent_bytes'] / 1e6:.1f} MB, migrate {s['migrate_s']:.2f} s; peak RSS "
      f"{s.get('peak_rss_bytes', 0) / 2**20:.0f} MiB")
PY
}
for r in $(seq 1 "$rounds"); do
  "$grove" fastslam run $args --threads 2 --out "$out/one$r" 2>/dev/null
  show "round $r, one process, 2 threads" "$out/one$r"
  mpirun --bind-to core -np 2 "$grove" fastslam run $args --threads 1 --out "$out/np2_$r" 2>/dev/null
  show "round $r, mpirun -np 2, 1 thread each" "$out/np2_$r"
  for f in trajectory.csv heaviest_trajectory.csv landmarks.csv; do
    cmp -s "$out/one$r/$f" "$out/np2_$r/$f" || echo "round $r: $f differs"
  done
done
