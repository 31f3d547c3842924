#!/usr/bin/env python3
"""Writes the maps of the seed's Simulations II and III (Ankışhan et al., 2016), whose own maps (the seed's
Figs. 5 and 7) are not published: a loop of waypoints and landmarks scattered near the route, in
Bailey's text map format (tools/sim/fastslam_simulator.h). Deterministic (fixed seeds)."""
import math
import random


def write(path, header, lms, wps):
    with open(path, "w") as f:
        f.write(header)
        f.write("#type columns rows\n")
        f.write(f"lm 2 {len(lms)}\n")
        for x, y in lms:
            f.write(f"{x:.4f} {y:.4f}\n")
        f.write(f"\nwp 2 {len(wps)}\n")
        for x, y in wps:
            f.write(f"{x:.4f} {y:.4f}\n")


def seg_dist(p, a, b):
    ax, ay = a
    bx, by = b
    px, py = p
    dx, dy = bx - ax, by - ay
    length2 = dx * dx + dy * dy
    t = max(0, min(1, ((px - ax) * dx + (py - ay) * dy) / length2)) if length2 > 0 else 0
    return math.hypot(px - (ax + t * dx), py - (ay + t * dy))


def landmarks(rng, n, wps, clear, spread, mind):
    """n landmarks at least `clear` from the route and each other's `mind`, within `spread` of a
    point of the route."""
    out = []
    route = list(zip(wps, wps[1:] + wps[:1]))
    while len(out) < n:
        a, b = route[rng.randrange(len(route))]
        t = rng.random()
        px, py = a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])
        ang = rng.uniform(0, 2 * math.pi)
        r = rng.uniform(clear, spread)
        q = (px + r * math.cos(ang), py + r * math.sin(ang))
        if min(seg_dist(q, a, b) for a, b in route) < clear:
            continue
        if any(math.hypot(q[0] - o[0], q[1] - o[1]) < mind for o in out):
            continue
        out.append(q)
    return out


# Simulation II: a second outdoor scenario at the webmap's scale: a 240 m x 140 m loop with a
# dog-leg, 60 landmarks within 25 m of the route.
rng = random.Random(2)
wps = [(0, -60), (60, -65), (110, -40), (120, 10), (90, 45), (40, 40), (10, 65), (-40, 70),
       (-95, 50), (-115, 0), (-90, -45), (-45, -55)]
write("sim2_map.txt",
      "# grove: Simulation II map. Written by tools/data/scenarios/make_maps.py; the seed's\n"
      "# Fig. 5 map is not published. Bailey's text map format (tools/sim/fastslam_simulator.h).\n",
      landmarks(rng, 60, wps, 4.0, 25.0, 6.0), wps)

# Simulation III: a small robot (wheelbase 0.26 m, 0.8 m/s, 5 m range): a 16 m x 10 m loop with
# 30 landmarks within 3 m of the route.
rng = random.Random(3)
wps = [(0, -4), (5, -4.5), (8, -2), (8, 2), (5, 4.5), (0, 4), (-4, 5), (-8, 2.5), (-8, -2),
       (-4, -4.5)]
write("sim3_map.txt",
      "# grove: Simulation III map. Written by tools/data/scenarios/make_maps.py; the seed's\n"
      "# Fig. 7 map is not published. Bailey's text map format (tools/sim/fastslam_simulator.h).\n",
      landmarks(rng, 30, wps, 0.6, 3.0, 1.0), wps)
