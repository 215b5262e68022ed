#!/usr/bin/env python3
"""The LIGGGHTS adapter's cost against LIGGGHTS's own step, at 20,000 particles, without a fluid.

    PYTHONPATH=clients/python:clients/liggghts python3 validation/crossdem/adapter_overhead.py \\
        [--atoms-per-side 25 25 32] [--k 50] [--fluid-steps 10]

A bed of 20,000 glass spheres (1 mm, Hertz, a floor, gravity) settles for 2000 LIGGGHTS steps;
then, one after another, the same fluid steps of k LIGGGHTS steps each are timed:

| Mode | Each fluid step |
|---|---|
| liggghts | `run k pre no post no`: LIGGGHTS's own steps |
| held | the adapter's work as in a run with `coupling.substep_drag = false` and `lubrication = false`: read x, v, omega, radius, ids into the fluid's particle states, hold a load per atom (`held_loads.py`), run with `fix external`'s callback writing it every step |
| within | the same with the loads that follow the atoms (`substep_loads.py`: the sub-step drag and the squeeze films, the scene's defaults) |

The exchange with the fluid (iceoryx2) is not in it: PROTOCOL.md section 10 measures it (20,000
particles, Python <-> Rust: ~0.55 ms per fluid step). Prints the time per LIGGGHTS step of each
mode and the adapter's share over LIGGGHTS's own, and writes them as JSON (--json).
"""

from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np

import liggghts
import lbm_liggghts
from held_loads import HeldLoads
from substep_loads import SqueezeFilms, SubstepLoads

RADIUS, SPACING, DENSITY = 0.0005, 0.00105, 2500.0


def bed_deck(n: tuple) -> list:
    lx, ly, lz = (SPACING * c for c in n)
    return [
        "units si", "atom_style granular", "atom_modify map array", "boundary f f f",
        "newton off", "communicate single vel yes",
        f"region domain block 0 {lx!r} 0 {ly!r} 0 {2 * lz!r} units box", "create_box 1 domain",
        "neighbor 0.0002 bin", "neigh_modify delay 0",
        "fix m1 all property/global youngsModulus peratomtype 5.0e6",
        "fix m2 all property/global poissonsRatio peratomtype 0.3",
        "fix m3 all property/global coefficientRestitution peratomtypepair 1 0.9",
        "fix m4 all property/global coefficientFriction peratomtypepair 1 0.5",
        "pair_style gran model hertz tangential history", "pair_coeff * *",
        "timestep 2e-6", f"lattice sc {SPACING!r} origin 0.5 0.5 0.5",
        f"region bed block 0 {lx!r} 0 {ly!r} 0 {lz!r} units box",
        "create_atoms 1 region bed", f"set group all diameter {2 * RADIUS!r} density {DENSITY!r}",
        "fix floor all wall/gran model hertz tangential history primitive type 1 zplane 0.0",
        "fix gravity all gravity 9.81 vector 0.0 0.0 -1.0", "fix integr all nve/sphere",
        "run 2000",
    ]


def time_mode(lmp, mode: str, k: int, steps: int, loads) -> float:
    """Seconds per LIGGGHTS step over `steps` fluid steps of `mode`."""
    lo, hi, periodic = np.zeros(3), np.ones(3), np.zeros(3, bool)
    rng = np.random.default_rng(1)
    t0 = time.perf_counter()
    for i in range(steps + 1):
        if i == 1:  # the first, with LIGGGHTS's set-up of the new fix, is not timed
            t0 = time.perf_counter()
        if mode != "liggghts":
            atoms = lmp.atoms()
            states = lbm_liggghts.states_of(atoms, lo, hi, periodic)
            mass = lmp.vector(b"rmass", atoms.count)
            force = 1e-6 * rng.standard_normal((atoms.count, 3)) + (mass * 9.81 * 0.4)[:, None] * [0, 0, 1]
            loads.hold(states["id"], force, np.zeros_like(force), atoms)
        lmp.command(f"run {k} pre no post no" if i else f"run {k} post no")
        if mode != "liggghts":
            loads.check()
    return (time.perf_counter() - t0) / (steps * k)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--atoms-per-side", nargs=3, type=int, default=[25, 25, 32])
    ap.add_argument("--k", type=int, default=50, help="LIGGGHTS steps per fluid step")
    ap.add_argument("--fluid-steps", type=int, default=10)
    ap.add_argument("--json", help="write the times here")
    args = ap.parse_args(argv)
    lmp = liggghts.Liggghts(liggghts.load_library(), ["-log", "none", "-screen", "none"])
    for line in bed_deck(tuple(args.atoms_per_side)):
        lmp.command(line)
    n = lmp.natoms()
    dt_fluid = args.k * lmp.timestep()
    films = SqueezeFilms(0.07, 0.000625 / 4.0, [(2, 0.0, 1)], np.zeros(3))
    within = SubstepLoads(1210.0, dt_fluid, [0.0, 0.0, -9.81], True, films)
    held, follow = HeldLoads(lmp), HeldLoads(lmp, within)
    callback = {"held": held, "within": follow}
    current = {"loads": held}
    times = {}
    for mode in ("liggghts", "held", "within", "liggghts", "held"):
        if mode != "liggghts":
            current["loads"] = callback[mode]
            lmp.fix_external("lbm_fluid", lambda *a: current["loads"].apply(*a))
        t = time_mode(lmp, mode, args.k, args.fluid_steps, callback.get(mode))
        if mode != "liggghts":
            lmp.command("unfix lbm_fluid")
        times.setdefault(mode, []).append(t)
        print(f"{mode:9s} {1e3 * t:.3f} ms per LIGGGHTS step ({n} atoms, k = {args.k})",
              flush=True)
    own = min(times["liggghts"])
    result = {"atoms": n, "k": args.k, "fluid_steps": args.fluid_steps,
              "ms_per_liggghts_step": {m: [round(1e3 * t, 4) for t in ts] for m, ts in times.items()},
              "overhead": {m: round(min(times[m]) / own - 1.0, 4) for m in ("held", "within")}}
    print(json.dumps(result["overhead"]))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
    lmp.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
