#!/usr/bin/env python3
"""Writes a scene's DEM as a YADE script:

    PYTHONPATH=clients/python python3 clients/yade/scene_script.py SCENE.toml SCRIPT.py

``lbm-server run SCENE --dem yade`` writes OUT/dem.yade.py this way and runs it
(``yade -n -x OUT/dem.yade.py``, the run in $LBMDEM_RUN). The script builds the scene's particles
with lbmdem_scene.py when it runs (body i is particle i), one YADE material per scene material,
the walls (the domain's faces unless periodic), the contact law (Hertz: FrictMat with
Ip2_FrictMat_FrictMat_MindlinPhys(en, es) and Law2_ScGeom_MindlinPhys_Mindlin; linear: ViscElMat
with twice the pair's k_n, gamma_n, k_t, gamma_t, two equal materials in series, and
Law2_ScGeom_ViscElPhys_Basic), gravity, and couples with lbmdem_yade.couple at YADE steps of at
most the scene's DEM step (scene_dem.py). YADE's law is dem-client's ``preset = "yade"``
(docs/dem.md); another preset is written with a warning. Exit status 2 where the scene cannot be
written.
"""

from __future__ import annotations

import math
import os
import sys

import lbmdem_scene
import scene_dem

def script_text(scene: lbmdem_scene.Scene, setup: scene_dem.DemSetup) -> str:
    path = os.path.abspath(scene.path)
    lines = [
        f"# The DEM of scene '{scene.name}' ({path}) for YADE, written by",
        "# clients/yade/scene_script.py for `lbm-server run SCENE --dem yade`, which runs it as",
        "# LBMDEM_RUN=RUN PYTHONPATH=IOX:clients/python:clients/yade yade -n -x dem.yade.py",
        "# Edit it and run it so (README.md in clients/yade). The fluid adds its force, torque,",
        "# buoyancy and lubrication; YADE applies gravity.",
    ]
    if setup.preset != "yade":
        lines.append(f"# Note: the scene's contact preset is '{setup.preset}'; YADE's law is "
                     "dem-client's 'yade' preset (docs/dem.md).")
    lines += [
        "import math", "import os", "", "import lbmdem_scene", "import lbmdem_yade", "",
        f"SCENE = os.environ.get(lbmdem_yade.SCENE_ENV) or {path!r}",
        "scene = lbmdem_scene.Scene.load(SCENE)", "", "materials = {}",
    ]
    lines += _materials(setup)
    lines += [
        "# The scene's particles: body i is scene particle i.",
        "for p in scene.particles:",
        "    b = O.bodies.append(sphere(p.position, p.radius, material=materials[p.material]))",
        "    O.bodies[b].state.vel = Vector3(*p.velocity)",
        "    O.bodies[b].state.angVel = Vector3(*p.angular_velocity)",
        "# Walls, after the spheres.",
    ]
    for w in setup.walls:
        lines.append(f"O.bodies.append(wall({w.at!r}, axis={w.axis}, sense={w.sense}, "
                     f"material=materials[{w.material!r}]))")
    if any(setup.periodic):
        lengths = [hi - lo for lo, hi in zip(scene.domain_min, scene.domain_max)]
        lines += ["O.periodic = True", f"O.cell.setBox({', '.join(repr(v) for v in lengths)})"]
    ip2, law = _law(setup)
    # A wall spans a periodic cell: YADE's collider refuses bodies as long as the period unless
    # told (its floor-in-a-periodic-cell case); the walls never move.
    bigger = ", allowBiggerThanPeriod=True" if any(setup.periodic) and setup.walls else ""
    lines += [
        "O.engines = [",
        "    ForceResetter(),",
        f"    InsertionSortCollider([Bo1_Sphere_Aabb(), Bo1_Wall_Aabb()]{bigger}),",
        "    InteractionLoop([Ig2_Sphere_Sphere_ScGeom(), Ig2_Wall_Sphere_ScGeom()],",
        f"                    [{ip2}],",
        f"                    [{law}]),",
        f"    NewtonIntegrator(damping=0.0, gravity=Vector3{tuple(scene.gravity)!r}),",
        "]",
        "# YADE steps of at most the scene's DEM step, a whole number per fluid step.",
        f"lbmdem_yade.couple(scene=SCENE, max_dt={setup.dt!r})",
    ]
    return "\n".join(lines) + "\n"


def _materials(setup: scene_dem.DemSetup) -> list:
    out = []
    for m in setup.materials:
        density = m.density if math.isfinite(m.density) else 1000.0
        common = f"frictionAngle=math.atan({setup.pair(m.name, m.name)['friction']!r}), density={density!r}"
        if setup.normal == "linear":
            k_n, gamma_n, k_t, gamma_t = setup.linear(m.name, m.name)
            mat = (f"ViscElMat(kn={2 * k_n!r}, cn={2 * gamma_n!r}, ks={2 * k_t!r}, cs={2 * gamma_t!r}, "
                   f"{common}, label={m.name!r})")
        else:
            mat = (f"FrictMat(young={m.young_modulus!r}, poisson={m.poisson_ratio!r}, {common}, "
                   f"label={m.name!r})")
        out.append(f"materials[{m.name!r}] = O.materials.append({mat})")
    return out


def _law(setup: scene_dem.DemSetup) -> tuple:
    if setup.normal == "linear":
        return "Ip2_ViscElMat_ViscElMat_ViscElPhys()", "Law2_ScGeom_ViscElPhys_Basic()"
    names = [m.name for m in setup.materials]
    if len(names) == 1:
        e = repr(setup.pair(names[0], names[0])["restitution"])
    else:
        pairs = ", ".join(f"({i}, {j}, {setup.pair(a, b)['restitution']!r})"
                          for i, a in enumerate(names) for j, b in enumerate(names) if i <= j)
        e = f"MatchMaker(matches=({pairs},))"
    return f"Ip2_FrictMat_FrictMat_MindlinPhys(en={e}, es={e})", "Law2_ScGeom_MindlinPhys_Mindlin()"


def write(scene: lbmdem_scene.Scene, setup: scene_dem.DemSetup, script: str) -> None:
    with open(script, "w") as f:
        f.write(script_text(scene, setup))


if __name__ == "__main__":
    sys.exit(scene_dem.writer_main(sys.argv, "scene_script.py", "yade", write))
