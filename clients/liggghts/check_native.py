#!/usr/bin/env python3
"""Measures that clients/native applies the same loads as the Python adapter.

    cargo build -p lbmdem-native
    PYTHONPATH=clients/python:clients/liggghts python3 clients/liggghts/check_native.py

Each run in a process of its own: a bed of 6 x 6 x 4 spheres (1 mm, Hertz, a floor, gravity)
settles, then takes four fluid steps of 20 LIGGGHTS steps with random replies (LIGGGHTS reordering
its atoms in the third), twice for each mode: the loads held (held_loads.py against native.py) and
following the atoms (the sub-step drag and the squeeze films, substep_loads.py against the same law
in clients/native). Prints the largest difference of the
atoms' x, v and omega between the Python and the native run of each mode, relative to each
column's largest value, and exits 0 when the held runs agree to the bit and the following
runs within 1e-9, 1 when not, 2 when LIGGGHTS or the native helper is missing.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile

import numpy as np

import lbmdem
import liggghts
import native
from held_loads import HeldLoads
from substep_loads import SqueezeFilms, SubstepLoads

K, FLUID_STEPS, N = 20, 4, (6, 6, 4)
RADIUS, SPACING, DENSITY = 0.0005, 0.00105, 2500.0


def bed_deck(n: tuple, settle: int) -> list:
    """A bed of n[0] x n[1] x n[2] glass spheres of 1 mm on a floor, under gravity, that settles
    for ``settle`` steps (also validation/crossdem/adapter_overhead.py's)."""
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
        f"run {settle}",
    ]


def within(dt_fluid: float) -> SubstepLoads:
    """The loads following the atoms: water-like liquid (1210 kg/m^3, 0.07 Pa s), the films' cut-off
    a cell of 0.156 mm, the floor's film."""
    films = SqueezeFilms(0.07, 0.000625 / 4.0, [(2, 0.0, 1)], np.zeros(3))
    return SubstepLoads(1210.0, dt_fluid, [0.0, 0.0, -9.81], True, films)


def run(lib, how: str, following: bool) -> np.ndarray:
    """x, v, omega (by atom ID) after the fluid steps, the loads applied by ``how``."""
    lmp = liggghts.Liggghts(lib, ["-log", "none", "-screen", "none"])
    for line in bed_deck(N, 300):
        lmp.command(line)
    law = within(K * lmp.timestep()) if following else None
    if how == "native":
        loads = native.NativeLoads(native.load_library(), lmp)
        if law is not None:
            loads.follow(law)
        loads.attach("lbm_fluid")
    else:
        loads = HeldLoads(lmp, law)
        lmp.fix_external("lbm_fluid", loads.apply)
    rng = np.random.default_rng(3)
    for step in range(FLUID_STEPS):
        if step == 2:  # LIGGGHTS reorders its atoms (by bins of another size) within this step
            lmp.command("atom_modify sort 7 0.0016")
        atoms = lmp.atoms()
        reply = np.zeros(atoms.count, lbmdem.REPLY_DTYPE)
        reply["id"] = atoms.tag.astype(np.int64) - 1
        reply["force"] = 2e-6 * rng.standard_normal((atoms.count, 3))
        reply["torque"] = 1e-12 * rng.standard_normal((atoms.count, 3))
        if how == "native":
            loads.hold(reply, step > 0)
        else:
            loads.hold(reply["id"], reply["force"], reply["torque"], atoms if step else None)
        lmp.command(f"run {K} pre no post no" if step else f"run {K}")
        loads.check()
    atoms = lmp.atoms()
    order = np.argsort(atoms.tag)
    state = np.hstack([atoms.x[order], atoms.v[order], atoms.omega[order]])
    lmp.close()
    return state


def in_child(how: str, following: bool, folder: str) -> np.ndarray:
    """``run`` in a process of its own (a second LIGGGHTS instance in one process warns of each
    style it registers again)."""
    path = os.path.join(folder, f"{how}-{int(following)}.npy")
    subprocess.run([sys.executable, __file__, "--one", how, str(int(following)), path], check=True)
    return np.load(path)


def main() -> int:
    if sys.argv[1:2] == ["--one"]:
        how, following, path = sys.argv[2], sys.argv[3] == "1", sys.argv[4]
        np.save(path, run(liggghts.load_library(), how, following))
        return 0
    try:
        liggghts.load_library()
        native.load_library()
    except (liggghts.NotInstalled, native.NotBuilt) as e:
        print(f"check_native: {e}", file=sys.stderr)
        return 2
    ok, folder = True, tempfile.mkdtemp(prefix="lbm-liggghts-native-")
    for following, tolerance in ((False, 0.0), (True, 1e-9)):
        py, nat = (in_child(how, following, folder) for how in ("python", "native"))
        scale = np.max(np.abs(py), axis=0)
        diff = float(np.max(np.abs(py - nat) / np.where(scale > 0, scale, 1.0)))
        mode = "following" if following else "held"
        print(f"check_native: loads {mode}: largest difference {diff:.1e} (of each column's "
              f"largest value; allowed {tolerance:g})")
        ok &= diff <= tolerance
    print(f"check_native: {'the native loads are the adapter' + chr(39) + 's' if ok else 'FAILED'}")
    return 0 if ok else 1


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    os._exit(status)
