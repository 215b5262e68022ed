#!/usr/bin/env python3
"""Writes a scene's DEM as a LIGGGHTS deck (and its data file, DECK with .data for .in):

    PYTHONPATH=clients/python python3 clients/liggghts/scene_deck.py SCENE.toml DECK.in

``lbm-server run SCENE --dem liggghts`` writes OUT/dem.liggghts.in this way and runs it with
lbm_liggghts.py. The deck holds the scene's particles (atom ID i + 1 is particle i, from
lbmdem_scene.py, in the data file), one atom type per material, the contact law (Hertz:
``pair_style gran model hertz tangential history``; linear: ``hooke/stiffness ...
absolute_damping on``), the walls as ``wall/gran`` planes (the domain's faces unless periodic),
gravity, ``fix nve/sphere`` and the time step (scene_dem.py). LIGGGHTS's law is dem-client's
``preset = "liggghts"`` (docs/dem.md); another preset is written with a warning.
Exit status 2 where the scene cannot be written (a message says what to add by hand).
"""

from __future__ import annotations

import math
import os
import sys

import lbmdem_scene
import scene_dem

def deck_text(scene: lbmdem_scene.Scene, setup: scene_dem.DemSetup, data_file: str) -> str:
    names = [m.name for m in setup.materials]
    boundary = " ".join("p" if p else "f" for p in setup.periodic)
    radii = [p.radius for p in scene.particles] or [1.0]
    lines = [
        f"# The DEM of scene '{scene.name}' ({scene.path}) for LIGGGHTS, written by",
        "# clients/liggghts/scene_deck.py for `lbm-server run SCENE --dem liggghts`: edit it and run",
        "# it with clients/liggghts/lbm_liggghts.py --deck (README.md there). The fluid adds its force,",
        "# torque and buoyancy, the adapter the squeeze films (coupling.lubrication); this deck",
        "# applies gravity.",
        "# Atom types: " + ", ".join(f"{i + 1} = {name}" for i, name in enumerate(names)),
    ]
    if setup.preset != "liggghts":
        lines.append(f"# Note: the scene's contact preset is '{setup.preset}'; LIGGGHTS's law is "
                     "dem-client's 'liggghts' preset (docs/dem.md).")
    lines += [
        "units si", "atom_style granular", "atom_modify map array", f"boundary {boundary}",
        "newton off", "communicate single vel yes", f"read_data {data_file}",
        f"neighbor {setup.dem.get('skin', 0.5 * min(radii))!r} bin", "neigh_modify delay 0",
    ]
    lines += _materials(setup, names)
    model = _model(setup)
    lines += [f"pair_style gran {model}", "pair_coeff * *", f"timestep {setup.dt!r}"]
    for i, w in enumerate(setup.walls):
        lines.append(f"fix wall{i} all wall/gran {model} primitive type {names.index(w.material) + 1} "
                     f"{'xyz'[w.axis]}plane {w.at!r}")
    g = scene.gravity
    norm = math.sqrt(sum(c * c for c in g))
    if norm > 0.0:
        lines.append(f"fix gravi all gravity {norm!r} vector "
                     + " ".join(repr(c / norm) for c in g))
    lines.append("fix integr all nve/sphere")
    return "\n".join(lines) + "\n"


def _materials(setup: scene_dem.DemSetup, names: list) -> list:
    n = len(names)
    mats = setup.materials

    def matrix(fn):
        return " ".join(repr(fn(a, b)) for a in names for b in names)

    out = [
        "fix m1 all property/global youngsModulus peratomtype "
        + " ".join(repr(m.young_modulus) for m in mats),
        "fix m2 all property/global poissonsRatio peratomtype "
        + " ".join(repr(m.poisson_ratio) for m in mats),
        f"fix m3 all property/global coefficientRestitution peratomtypepair {n} "
        + matrix(lambda a, b: setup.pair(a, b)["restitution"]),
        f"fix m4 all property/global coefficientFriction peratomtypepair {n} "
        + matrix(lambda a, b: setup.pair(a, b)["friction"]),
    ]
    if setup.rolling == "constant_torque":
        out.append(f"fix m5 all property/global coefficientRollingFriction peratomtypepair {n} "
                   + matrix(lambda a, b: setup.pair(a, b)["rolling_friction"]))
    if setup.normal == "linear":
        for i, name in enumerate(("kn", "gamman_abs", "kt", "gammat_abs")):
            out.append(f"fix m{6 + i} all property/global {name} peratomtypepair {n} "
                       + matrix(lambda a, b, i=i: setup.linear(a, b)[i]))
    return out


def _model(setup: scene_dem.DemSetup) -> str:
    rolling = " rolling_friction cdt" if setup.rolling == "constant_torque" else ""
    if setup.normal == "linear":
        return f"model hooke/stiffness tangential history{rolling} absolute_damping on"
    return f"model hertz tangential history{rolling}"


def data_text(scene: lbmdem_scene.Scene, setup: scene_dem.DemSetup) -> str:
    """The data file: box, atoms (ID type diameter density x y z), velocities (ID v omega)."""
    names = [m.name for m in setup.materials]
    lines = [f"LIGGGHTS data file of scene '{scene.name}' (clients/liggghts/scene_deck.py)", "",
             f"{len(scene.particles)} atoms", f"{len(names)} atom types", ""]
    for a, axis in enumerate("xyz"):
        lines.append(f"{scene.domain_min[a]!r} {scene.domain_max[a]!r} {axis}lo {axis}hi")
    lines += ["", "Atoms", ""]
    for p in scene.particles:
        lines.append(f"{p.id + 1} {names.index(p.material) + 1} {2.0 * p.radius!r} {p.density!r} "
                     + " ".join(repr(float(c)) for c in p.position))
    lines += ["", "Velocities", ""]
    for p in scene.particles:
        lines.append(f"{p.id + 1} " + " ".join(repr(float(c)) for c in (*p.velocity,
                                                                         *p.angular_velocity)))
    return "\n".join(lines) + "\n"


def write(scene: lbmdem_scene.Scene, setup: scene_dem.DemSetup, deck: str) -> None:
    data = os.path.splitext(deck)[0] + ".data"
    with open(data, "w") as f:
        f.write(data_text(scene, setup))
    with open(deck, "w") as f:
        f.write(deck_text(scene, setup, data))


if __name__ == "__main__":
    sys.exit(scene_dem.writer_main(sys.argv, "scene_deck.py", "liggghts", write))
