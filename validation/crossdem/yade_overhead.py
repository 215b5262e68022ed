# The YADE adapter's cost against YADE's own step, at 20,000 particles, without a fluid.
#
#   PYTHONPATH=clients/python:clients/yade yade -n -x validation/crossdem/yade_overhead.py \
#       [--per-side 25 25 32] [--k 50] [--fluid-steps 4] [--rounds 3] [--json FILE]
#
# A bed of 20,000 glass spheres (1 mm, Hertz-Mindlin, a floor, gravity) on a simple cubic lattice,
# each touching its six neighbours (spacing 0.99999 d), steps 200 YADE steps first; then, in each
# round, one after another, the same fluid steps of k YADE steps each are timed:
#
# | Mode | Each fluid step |
# |---|---|
# | yade | k `O.step()`s: YADE's own steps |
# | held | the adapter's work with the loads held (`lbmdem_yade.couple(..., loads="held")`): the
# |      | spheres' states gathered into the fluid's particle states, the reply's force and torque
# |      | held as YADE's permanent forces, then the k steps |
#
# The reply (force, torque, ~1e-18 N: the bed stays YADE's alone) is made before the timing. The
# exchange with the fluid (iceoryx2) is not in it: PROTOCOL.md section 10 measures it. Prints the
# CPU time per YADE step of each mode and round, and the adapter's share over YADE's own: the
# median over the rounds of (held - yade) / yade in the same round; writes them as JSON (--json).
# YADE runs on one thread unless given -jN.
import argparse
import json
import math
import statistics
import sys
import time

import numpy as np

import lbmdem
import lbmdem_yade

ap = argparse.ArgumentParser(prog="yade_overhead.py")
ap.add_argument("--per-side", type=int, nargs=3, default=[25, 25, 32])
ap.add_argument("--k", type=int, default=50, help="YADE steps per fluid step")
ap.add_argument("--fluid-steps", type=int, default=4, help="timed fluid steps per mode and round")
ap.add_argument("--rounds", type=int, default=3)
ap.add_argument("--json", help="write the figures here")
args = ap.parse_args(sys.argv[1:])

D = 1e-3
glass = O.materials.append(FrictMat(young=6.0e10, poisson=0.23, frictionAngle=math.atan(0.3),
                                    density=2500.0))
nx, ny, nz = args.per_side
spacing = 0.99999 * D
ids = {}
for z in range(nz):
    for y in range(ny):
        for x in range(nx):
            centre = ((x + 0.5) * spacing, (y + 0.5) * spacing, (z + 0.5) * spacing)
            ids[len(ids)] = O.bodies.append(sphere(centre, D / 2, material=glass))
O.bodies.append(wall(0.0, axis=2, sense=1, material=glass))
O.engines = [
    ForceResetter(),
    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]),
    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],
                    [Ip2_FrictMat_FrictMat_MindlinPhys(en=0.9, es=0.9)],
                    [Law2_ScGeom_MindlinPhys_Mindlin()]),
    NewtonIntegrator(damping=0.0, gravity=Vector3(0, 0, -9.81)),
]
O.dt = 0.5 * PWaveTimeStep()
O.run(200, True)

spheres = lbmdem_yade._Spheres(ids)
rng = np.random.default_rng(1)
loads = np.zeros(len(ids), lbmdem.REPLY_DTYPE)
loads["force"] = 1e-18 * rng.standard_normal((len(ids), 3))
loads["torque"] = 1e-21 * rng.standard_normal((len(ids), 3))


def steps_only():
    for _ in range(args.k):
        O.step()


def held():
    spheres.states()
    spheres.hold(loads)
    steps_only()


def per_step(run) -> float:
    """CPU seconds per YADE step of `run`, over the timed fluid steps."""
    started = time.process_time()
    for _ in range(args.fluid_steps):
        run()
    return (time.process_time() - started) / (args.fluid_steps * args.k)


def parts() -> dict:
    """CPU seconds of the adapter's two parts, once: the states gathered, the loads held."""
    t0 = time.process_time()
    spheres.states()
    t1 = time.process_time()
    spheres.hold(loads)
    t2 = time.process_time()
    return {"states_s": t1 - t0, "hold_s": t2 - t1}


rounds = []
for r in range(args.rounds):
    yade_s = per_step(steps_only)
    held_s = per_step(held)
    rounds.append({"yade_s": yade_s, "held_s": held_s, **parts()})
    print(f"round {r}: YADE {yade_s * 1e3:.3f} ms per step, held {held_s * 1e3:.3f} ms "
          f"({(held_s / yade_s - 1) * 100:+.1f}%); states {rounds[-1]['states_s'] * 1e3:.1f} ms, "
          f"hold {rounds[-1]['hold_s'] * 1e3:.1f} ms per fluid step", flush=True)
shares = [r["held_s"] / r["yade_s"] - 1 for r in rounds]
print(f"held over YADE's own: median {statistics.median(shares) * 100:+.1f}% "
      f"({min(shares) * 100:+.1f} .. {max(shares) * 100:+.1f}%), {len(ids)} spheres, k = {args.k}, "
      f"{O.interactions.countReal()} contacts", flush=True)
if args.json:
    with open(args.json, "w") as f:
        json.dump({"spheres": len(ids), "k": args.k, "rounds": rounds,
                   "median_share": statistics.median(shares)}, f, indent=1)
