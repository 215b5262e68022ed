"""A user's LIGGGHTS input deck, run and checked before it joins a coupled run.

The deck builds the DEM: box, atoms (a granular atom style: radius and omega per atom), materials,
contact law, walls, gravity and the integrator (``fix nve/sphere``); it may run steps of its own
(e.g. a settling phase). After it, the atoms must be the scene's particles: as many, and atom ID
i is the scene's particle i - 1.
"""

from __future__ import annotations

import math
import os

import numpy as np

import lbmdem
from liggghts import Liggghts


class BadInput(Exception):
    """The deck, the scene or the installation does not allow the run (exit status 2)."""


#: What a granular atom style provides and the coupling reads or writes.
PER_ATOM = ("radius", "omega", "torque", "rmass")

#: Unit styles a granular deck may use, as the size in SI of their length, time and mass units.
UNITS = {"si": lbmdem.Units(1.0, 1.0, 1.0), "cgs": lbmdem.Units(0.01, 1.0, 0.001)}


def log_errors(log: str) -> str:
    """The ``ERROR`` lines LIGGGHTS wrote to its log (empty where there are none)."""
    try:
        with open(log, encoding="utf-8", errors="replace") as f:
            lines = [l.strip() for l in f if l.startswith("ERROR")]
    except OSError:
        return ""
    return " ".join(dict.fromkeys(lines))


def version(log: str) -> str:
    """LIGGGHTS's version from the first line of its log (``LIGGGHTS (Version X, ...``)."""
    try:
        with open(log, encoding="utf-8", errors="replace") as f:
            first = f.readline()
    except OSError:
        return "LIGGGHTS"
    if "Version " in first:
        return first.split("Version ", 1)[1].split(",", 1)[0].strip()
    return "LIGGGHTS"


def units_of(lmp: Liggghts) -> lbmdem.Units:
    """The deck's units; refuses styles a granular deck cannot use."""
    style = lmp.unit_style()
    if style is None:
        return UNITS["si"]  # an unknown layout: LIGGGHTS's usual units (stated by the caller)
    if style not in UNITS:
        raise BadInput(f"the deck uses 'units {style}': a granular deck uses units si or cgs")
    return UNITS[style]


def _count(n: int, noun: str) -> str:
    return f"{n} {noun}" + ("" if n == 1 else "s")


def check_atoms(lmp: Liggghts, deck: str, scene: str, expected: int) -> None:
    """Refuses a deck whose atoms are not the scene's particles (PER_ATOM arrays, count, IDs)."""
    missing = [name for name in PER_ATOM if not lmp.has_atom_array(name)]
    if missing:
        raise BadInput(f"the atom style of {deck} has no per-atom {', '.join(missing)}: use "
                       f"'atom_style granular' (or sphere), whose atoms have a radius and a spin")
    natoms = lmp.natoms()
    if natoms != expected:
        raise BadInput(f"{deck} creates {_count(natoms, 'atom')}, the scene {scene} has "
                       f"{_count(expected, 'particle')}: the deck must create one atom per particle of the scene "
                       f"(atom ID i is the scene's particle i - 1)")
    tags = lmp.atoms().tag.astype(np.int64)
    if tags.size and tags.min() <= 0:
        raise BadInput(f"the atoms of {deck} have no IDs: remove 'atom_modify id no'")
    outside = tags[tags > expected]
    if outside.size:
        raise BadInput(f"atom ID {int(outside.min())} of {deck} has no particle in the scene "
                       f"{scene}, whose {_count(expected, 'particle')} are atom IDs 1 .. "
                       f"{expected} (ID i is the scene's particle i - 1)")
    if np.unique(tags).size != tags.size:
        raise BadInput(f"{deck} has atoms with the same ID")


def substeps(fluid_dt: float, dt: float) -> int:
    """LIGGGHTS steps per fluid step: fluid_dt / dt where that is whole, else the next whole
    number above (the caller then shortens the LIGGGHTS step to fluid_dt / k)."""
    ratio = fluid_dt / dt
    k = max(round(ratio), 1)
    if abs(ratio - k) <= 1e-9 * ratio:
        return k
    return max(math.ceil(ratio), 1)


def open_deck(lib, args) -> Liggghts:
    """Starts LIGGGHTS with the command-line options of ``args`` and runs the deck."""
    if not os.path.isfile(args.deck):
        raise BadInput(f"the deck {args.deck} does not exist")
    options = ["-log", args.log]
    if not args.echo:
        options += ["-screen", "none"]
    for name, value in args.var or []:
        options += ["-var", name, value]
    lmp = Liggghts(lib, options)
    lmp.file(args.deck)
    if args.log != "none":
        lmp.command(f"log {args.log} append")  # reopens it: what the deck wrote is on disk
    return lmp
