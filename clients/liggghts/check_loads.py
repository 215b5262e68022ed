#!/usr/bin/env python3
"""Measures that the held force and torque act on LIGGGHTS's atoms as the adapter applies them.

    python3 clients/liggghts/check_loads.py [--steps-per-load K] [--native]

One sphere (r 5 mm, 1000 kg/m^3, no gravity, no walls) takes three "fluid steps" of K LIGGGHTS
steps each, with a different force and torque held over each (held_loads.py, fix external; with
--native clients/native, native.py), as the coupled loop does; the first span starts at step 0. Velocity Verlet with a constant force over each span is exact, so the sphere
must end with v = sum(F) K dt / m and omega = sum(T) K dt / I, I = 2/5 m r^2. Prints both and
exits 0 when they agree to 1e-9, 1 when not, 2 when LIGGGHTS (or the native helper) is missing.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import tempfile

import numpy as np

import liggghts
from held_loads import HeldLoads

try:  # with clients/python (lbmdem) on PYTHONPATH: --native
    import native
except ImportError:
    native = None

RADIUS, DENSITY, DT = 0.005, 1000.0, 1.0e-5
#: (force [N], torque [N m]) held over each span.
LOADS = [
    ([1.0e-3, 2.0e-3, -3.0e-3], [1.0e-6, 0.0, -2.0e-6]),
    ([-4.0e-3, 0.5e-3, 1.0e-3], [0.0, 3.0e-6, 1.0e-6]),
    ([2.0e-3, -1.0e-3, 0.0], [-1.0e-6, 1.0e-6, 0.0]),
]

DECK = f"""units si
atom_style granular
atom_modify map array
boundary f f f
newton off
communicate single vel yes
region domain block -1 1 -1 1 -1 1 units box
create_box 1 domain
neighbor 0.001 bin
fix m1 all property/global youngsModulus peratomtype 5.0e6
fix m2 all property/global poissonsRatio peratomtype 0.3
fix m3 all property/global coefficientRestitution peratomtypepair 1 0.9
fix m4 all property/global coefficientFriction peratomtypepair 1 0.5
pair_style gran model hertz tangential history
pair_coeff * *
timestep {DT!r}
create_atoms 1 single 0.0 0.0 0.0 units box
set atom 1 diameter {2 * RADIUS!r} density {DENSITY!r}
fix integr all nve/sphere
"""


def measure(k: int, compiled: bool) -> tuple:
    """(v, omega) of the sphere after the spans of LOADS, K LIGGGHTS steps each."""
    folder = tempfile.mkdtemp(prefix="lbm-liggghts-check-")
    deck = os.path.join(folder, "check.in")
    with open(deck, "w") as f:
        f.write(DECK)
    lmp = liggghts.Liggghts(liggghts.load_library(),
                            ["-log", os.path.join(folder, "log.liggghts"), "-screen", "none"])
    lmp.file(deck)
    if compiled:
        loads = native.NativeLoads(native.load_library(), lmp)
        loads.attach("lbm_fluid")
    else:
        loads = HeldLoads(lmp)
        lmp.fix_external("lbm_fluid", loads.apply)
    for i, (force, torque) in enumerate(LOADS):
        if compiled:
            loads.hold(np.array([(0, force, torque)], native.lbmdem.REPLY_DTYPE), i > 0)
        else:
            loads.hold(np.array([0]), np.array([force]), np.array([torque]),
                       lmp.atoms() if i else None)
        lmp.command(f"run {k} pre no post no" if i else f"run {k}")
        loads.check()
    atoms = lmp.atoms()
    return atoms.v[0].copy(), atoms.omega[0].copy()


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps-per-load", type=int, default=7, help="LIGGGHTS steps per span")
    ap.add_argument("--native", action="store_true",
                    help="the loads of clients/native (clients/python on PYTHONPATH)")
    args = ap.parse_args()
    k = args.steps_per_load
    try:
        v, omega = measure(k, args.native)
    except (liggghts.NotInstalled, *((native.NotBuilt,) if native else ())) as e:
        print(f"check_loads: {e}", file=sys.stderr)
        return 2
    mass = DENSITY * 4.0 / 3.0 * math.pi * RADIUS ** 3
    inertia = 0.4 * mass * RADIUS ** 2
    force, torque = (np.sum([np.array(load[j]) for load in LOADS], axis=0) for j in (0, 1))
    expect_v, expect_w = force * k * DT / mass, torque * k * DT / inertia
    err_v = np.max(np.abs(v - expect_v)) / np.max(np.abs(expect_v))
    err_w = np.max(np.abs(omega - expect_w)) / np.max(np.abs(expect_w))
    print(f"check_loads: v {v.tolist()} expected {expect_v.tolist()} (relative error {err_v:.1e})")
    print(f"check_loads: omega {omega.tolist()} expected {expect_w.tolist()} "
          f"(relative error {err_w:.1e})")
    ok = err_v <= 1e-9 and err_w <= 1e-9
    print(f"check_loads: {'force and torque act as held' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    os._exit(status)
