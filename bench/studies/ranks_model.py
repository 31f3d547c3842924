#!/usr/bin/python3
"""How one FootSLAM filter across MPI ranks (global resampling) would scale on a cluster.

A model, not a measurement: it takes from `grove_ranks_benchmark` runs (ranks.json) the measured
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
Island mode (--islands ISLANDS.json, a K-rank island-mode run with the modelled share, one
island per rank): the same 4 small collectives every step, 2 more per resampling (the status and
the heaviest particle), and every exchange_steps steps one more call and the largest message a
rank sent at an exchange, on the wire and written and read as above.
Usage: ranks_model.py ONE_RANK.json SHARE.json MIGRATE.json [--particles N] [--islands FILE]
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
    ap.add_argument("--islands")
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
    islands = None
    if args.islands:
        isl = json.load(open(args.islands))
        exchanges = isl["steps"] // isl["exchange_steps"]
        islands = {
            "resample_rate": isl["resamplings"] / isl["steps"],
            "bytes": max(r["sent_particle_bytes"] for r in isl["per_rank"]) / exchanges,
            "every": isl["exchange_steps"],
        }
        print(f"Island mode: resampling on {islands['resample_rate']:.0%} of steps; at most "
              f"{islands['bytes'] / 1e3:.0f} kB sent by a rank per exchange, every "
              f"{islands['every']} steps ({isl['ranks']} ranks of "
              f"{isl['particles'] // isl['ranks']} particles, {isl['islands']} islands, "
              f"{isl['exchange_fraction']:.0%} sent).")
    print(f"\nModel: {args.particles} particles, one rank per core, one thread each; "
          "communication and moving particles per step.\n")
    head = "| ranks | network | compute per step | global mode | efficiency |"
    rule = "| --- | --- | --- | --- | --- |"
    if islands:
        head += " island mode | efficiency |"
        rule += " --- | --- |"
    print(head)
    print(rule)
    for k in (16, 64, 256):
        compute_s = args.particles / k * ns * 1e-9
        for name, alpha_s, bytes_per_s in (("10 Gbit/s", 15e-6, 10e9 / 8),
                                           ("100 Gbit/s", 3e-6, 100e9 / 8)):
            hop = alpha_s * math.log2(k)

            def moved(b):  # on the wire once, written once and read once
                return b / bytes_per_s + 2 * b * s_per_byte

            comm_s = 4 * hop + resample_rate * (6 * hop + moved(per_rank_bytes))
            row = (f"| {k} | {name} | {compute_s * 1e3:.2f} ms | {comm_s * 1e3:.3f} ms | "
                   f"{compute_s / (compute_s + comm_s):.0%} |")
            if islands:
                isl_s = (4 * hop + islands["resample_rate"] * 2 * hop +
                         (hop + moved(islands["bytes"])) / islands["every"])
                row += f" {isl_s * 1e3:.3f} ms | {compute_s / (compute_s + isl_s):.0%} |"
            print(row)

if __name__ == "__main__":
    main()
