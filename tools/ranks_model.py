#!/usr/bin/python3
"""How one FootSLAM filter across MPI ranks (global resampling) would scale on a cluster.

A model, not a measurement: it takes from `grove bench ranks` runs (ranks.json) the measured
compute cost of a particle-step on one thread, the resampling rate, and the bytes of particles
each rank sends per resampling, and adds assumed network costs:
  - every step: 4 small collectives (status, maximum, block sums, squared-weight sums);
  - every resampling: 6 more MPI calls (block sums, the heaviest particle, the sizes, an
    allreduce, the all-to-all of particles, the status), and the rank's particles on the wire;
  - a small collective costs alpha * log2(K) (recursive doubling), alpha = 15 us on 10 Gbit/s
    Ethernet and 3 us on 100 Gbit/s (an assumption of this model, not measured here);
  - the particles cross the link at its full bandwidth (no contention), once per resampling;
  - writing and reading them costs what it cost per byte in a measured run (MIGRATE.json);
  - the ranks are balanced (the measured runs show waiting for the slowest rank besides this).
Usage: ranks_model.py ONE_RANK.json SHARE.json MIGRATE.json [--particles N]
  ONE_RANK.json: a 1-rank, 1-thread run (compute ns per particle-step);
  SHARE.json: a K-rank run whose per-rank share is the modelled one (its largest bytes a rank
  sent per resampling is taken as every rank's).
"""
import argparse
import json
import math


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("one_rank")
    ap.add_argument("share")
    ap.add_argument("migrate")
    ap.add_argument("--particles", type=int, default=1 << 20)
    args = ap.parse_args()
    one = json.load(open(args.one_rank))
    share = json.load(open(args.share))
    migrate = json.load(open(args.migrate))
    handled = 2 * sum(r["sent_particle_bytes"] for r in migrate["per_rank"])
    s_per_byte = sum(r["migrate_s"] for r in migrate["per_rank"]) / handled
    ns = one["ns_per_particle_step"]
    resample_rate = share["resamplings"] / share["steps"]
    per_rank_bytes = max(r["sent_particle_bytes"] for r in share["per_rank"]) / share["resamplings"]
    print(f"Measured: {ns:.0f} ns per particle-step on one thread ({one['particles']} particles); "
          f"resampling on {resample_rate:.0%} of steps; at most {per_rank_bytes / 1e3:.0f} kB "
          f"sent by a rank per resampling ({share['ranks']} ranks of "
          f"{share['particles'] // share['ranks']} particles); writing and reading them "
          f"{s_per_byte * 1e9:.1f} ns per byte ({migrate['ranks']} ranks).")
    print(f"\nModel: {args.particles} particles, one rank per core, one thread each.\n")
    print("| ranks | network | compute per step | communication and moving particles per step | "
          "efficiency |")
    print("| --- | --- | --- | --- | --- |")
    for k in (16, 64, 256):
        compute_s = args.particles / k * ns * 1e-9
        for name, alpha_s, bytes_per_s in (("10 Gbit/s", 15e-6, 10e9 / 8),
                                           ("100 Gbit/s", 3e-6, 100e9 / 8)):
            hop = alpha_s * math.log2(k)
            per_resampling = (6 * hop + per_rank_bytes / bytes_per_s +
                              2 * per_rank_bytes * s_per_byte)
            comm_s = 4 * hop + resample_rate * per_resampling
            eff = compute_s / (compute_s + comm_s)
            print(f"| {k} | {name} | {compute_s * 1e3:.2f} ms | {comm_s * 1e3:.3f} ms | "
                  f"{eff:.0%} |")


if __name__ == "__main__":
    main()
