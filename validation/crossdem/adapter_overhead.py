#!/usr/bin/env python3
"""The LIGGGHTS adapter's cost against LIGGGHTS's own step, at 20,000 particles, without a fluid.

    cargo build --release -p lbmdem-native
    PYTHONPATH=clients/python:clients/liggghts python3 validation/crossdem/adapter_overhead.py \\
        [--atoms-per-side 25 25 32] [--k 50] [--fluid-steps 10] [--rounds 3] [--modes ...]

A bed of 20,000 glass spheres (1 mm, Hertz, a floor, gravity) settles for 2000 LIGGGHTS steps;
then, in each round, one after another, the same fluid steps of k LIGGGHTS steps each are timed:

| Mode | Each fluid step |
|---|---|
| liggghts | `run k pre no post no`: LIGGGHTS's own steps |
| noop | the same with `fix external` and a compiled callback that writes zero forces (the fix's own cost) |
| native | the adapter's work with clients/native (the default where it is built), loads held as in a run with `--loads held`: gather x, v, omega, radius, ids into the fluid's particle states, hold the reply's force and torque, `fix external`'s compiled callback writing them every step |
| native-within | the same with the loads that follow the atoms (the sub-step drag and the squeeze films, the scene's defaults), evaluated in clients/native at each LIGGGHTS step |
| held | the held loads in Python (held_loads.py, where the library is not built) |
| within | the following loads in numpy (substep_loads.py; slow: one round is enough) |

The reply (force, torque) of each fluid step is made before the timing. The exchange with the
fluid (iceoryx2) is not in it: PROTOCOL.md section 10 measures it (20,000 particles, Python <->
Rust: ~0.55 ms per fluid step). Prints the time per LIGGGHTS step of each mode and round, and each
mode's share over LIGGGHTS's own: the median over the rounds of its time over LIGGGHTS's time in
the same round; writes them as JSON (--json).
"""

from __future__ import annotations

import argparse
import ctypes
import json
import sys
import time

import numpy as np

import lbmdem
import liggghts
import lbm_liggghts
import native
from check_native import bed_deck, within as following
from held_loads import HeldLoads

#: The ID of the adapter's fix external (lbm_liggghts.FIX_FLUID).
FIX = lbm_liggghts.FIX_FLUID


MODES = ("liggghts", "noop", "native", "native-within", "held")


def replies(lmp, count: int, steps: int, scale: float) -> list:
    """A reply per fluid step: random forces and torques, 40% of the weight upwards, all times
    ``scale`` (1e-12 by default: loads that move nothing, so that LIGGGHTS's own work, its
    neighbour-list rebuilds included, stays that of the run without them)."""
    rng = np.random.default_rng(1)
    atoms = lmp.atoms()
    mass = lmp.vector(b"rmass", atoms.count)
    out = []
    for _ in range(steps):
        r = np.zeros(count, lbmdem.REPLY_DTYPE)
        r["id"] = atoms.tag.astype(np.int64) - 1
        r["force"] = scale * (1e-6 * rng.standard_normal((count, 3))
                              + (mass * 9.81 * 0.4)[:, None] * [0, 0, 1])
        r["torque"] = scale * 1e-12 * rng.standard_normal((count, 3))
        out.append(r)
    return out


def time_mode(lmp, mode: str, k: int, loads, fluid: list) -> tuple:
    """Seconds per LIGGGHTS step over the fluid steps of ``fluid`` but the first: wall-clock and
    this process's CPU time (the share of a loaded machine's cores the others took left out)."""
    lo, hi, periodic = np.zeros(3), np.ones(3), np.zeros(3, bool)
    t0 = c0 = 0.0
    for i, reply in enumerate(fluid):
        if i == 1:  # the first, with LIGGGHTS's set-up of the new fix, is not timed
            t0, c0 = time.perf_counter(), time.process_time()
        if mode.startswith("native"):
            loads.states(lo, hi, periodic)
            loads.hold(reply, True)
        elif mode in ("held", "within"):
            atoms = lmp.atoms()
            states = lbm_liggghts.states_of(atoms, lo, hi, periodic)
            loads.hold(reply["id"], reply["force"], reply["torque"], atoms)
        lmp.command(f"run {k} pre no post no" if i else f"run {k} post no")
        if loads is not None:
            loads.check()
    steps = (len(fluid) - 1) * k
    return (time.perf_counter() - t0) / steps, (time.process_time() - c0) / steps


def make_loads(lmp, mode: str, within):
    """The loads of ``mode`` with their ``fix external`` added; the fixes' IDs."""
    if mode == "liggghts":
        return None, []
    if mode == "noop":
        lib = native.load_library()
        lmp.fix_external(FIX, (ctypes.cast(lib.lbmdem_zero_apply, ctypes.c_void_p).value, None))
        return None, [FIX]
    if mode.startswith("native"):
        loads = native.NativeLoads(native.load_library(), lmp)
        if mode == "native-within":
            loads.follow(within)
        return loads, loads.attach(FIX)
    loads = HeldLoads(lmp, within if mode == "within" else None)
    lmp.fix_external(FIX, loads.apply)
    return loads, [FIX]


def overhead(times: dict, modes: list) -> dict:
    """Each mode's median of its time over the mean of LIGGGHTS's own just before and after it
    (the machine's speed drifts), less 1."""
    own, per_round = times["liggghts"], len(modes) + 1
    out = {}
    for slot, m in enumerate(modes):
        ratios = []
        for r, t in enumerate(times[m]):
            before = own[r * per_round + slot]
            ratios.append(t / (0.5 * (before + own[r * per_round + slot + 1])))
        out[m] = round(float(np.median(ratios)) - 1.0, 4)
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--atoms-per-side", nargs=3, type=int, default=[25, 25, 32])
    ap.add_argument("--k", type=int, default=50, help="LIGGGHTS steps per fluid step")
    ap.add_argument("--fluid-steps", type=int, default=10)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--modes", nargs="+", default=list(MODES),
                    choices=list(MODES) + ["within"], help="the modes of each round, in order "
                    "(liggghts is always timed)")
    ap.add_argument("--load-scale", type=float, default=1e-12,
                    help="the replies' loads times this (1: 40%% of the weight and random forces "
                         "of about 1e-6 N, which make LIGGGHTS rebuild its neighbour lists more)")
    ap.add_argument("--json", help="write the times here")
    args = ap.parse_args(argv)
    lmp = liggghts.Liggghts(liggghts.load_library(), ["-log", "none", "-screen", "none"])
    for line in bed_deck(tuple(args.atoms_per_side), 2000):
        lmp.command(line)
    n = lmp.natoms()
    dt_fluid = args.k * lmp.timestep()
    within = following(dt_fluid)
    fluid = replies(lmp, n, args.fluid_steps + 1, args.load_scale)
    modes = [m for m in args.modes if m != "liggghts"]
    times, cpu = {m: [] for m in ["liggghts"] + modes}, {m: [] for m in ["liggghts"] + modes}
    for r in range(args.rounds):
        # LIGGGHTS alone before and after each mode: its neighbours' mean is the mode's baseline
        for mode in [x for m in modes for x in ("liggghts", m)] + ["liggghts"]:
            if mode == "within" and r:
                continue
            loads, fixes = make_loads(lmp, mode, within)
            t, c = time_mode(lmp, mode, args.k, loads, fluid)
            for fix in fixes:
                lmp.command(f"unfix {fix}")
            times[mode].append(t)
            cpu[mode].append(c)
            print(f"round {r + 1} {mode:13s} {1e3 * t:8.3f} ms per LIGGGHTS step, CPU {1e3 * c:8.3f} "
                  f"ms ({n} atoms, k = {args.k})", flush=True)
    result = {"atoms": n, "k": args.k, "fluid_steps": args.fluid_steps, "rounds": args.rounds,
              "load_scale": args.load_scale,
              "ms_per_liggghts_step": {m: [round(1e3 * t, 4) for t in ts] for m, ts in times.items()},
              "cpu_ms_per_liggghts_step": {m: [round(1e3 * t, 4) for t in ts]
                                           for m, ts in cpu.items()},
              "overhead_median": overhead(times, modes),
              "cpu_overhead_median": overhead(cpu, modes)}
    print(json.dumps({"wall": result["overhead_median"], "cpu": result["cpu_overhead_median"]}))
    if args.json:
        with open(args.json, "w") as f:
            json.dump(result, f, indent=1)
    lmp.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
