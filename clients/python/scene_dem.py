"""A scene's DEM as another DEM code sets it up (plain Python 3.11): walls, contact law per
material pair, time step, the way ``dem-client`` derives them (scene/src/dem.rs, docs/dem.md).

``lbm-server run SCENE --dem yade|liggghts`` writes a YADE script / LIGGGHTS deck of the scene
(clients/yade/scene_script.py, clients/liggghts/scene_deck.py) from this and
``lbmdem_scene.Scene`` (the particles):

- walls: the domain's six faces unless the scene has planes or boxes (``dem.domain_walls``), none
  on a periodic axis (``lattice.faces``), the axis-aligned ``[[dem.plane]]``s and the faces of
  each ``[[dem.box]]`` container; another wall is ``Unsupported`` (write it into the file by hand);
- the contact law: ``normal`` (hertz, linear), ``tangential`` (history, none: friction 0),
  ``rolling`` (none, constant_torque); pair restitution, friction and rolling friction the smaller
  of the two materials'; the linear law's k_n, gamma_n, k_t, gamma_t from ``normal_stiffness``,
  ``normal_damping``, ``contact_time`` and the restitution as dem-client derives them, at the m*
  of the smallest spheres of the two materials (dem-client derives them per contact);
- the time step: ``dem.dt``, else the shortest contact time / ``dem.dt_divisor`` (the smallest
  sphere of each material against each material and each wall, Hertz at the impact velocity).
"""

from __future__ import annotations

import math
import os
import sys
from typing import Callable, NamedTuple

import lbmdem_scene

__all__ = ["DemSetup", "Wall", "Unsupported", "writer_main"]

#: (2/5) B(2/5, 1/2), of the undamped Hertz contact time (dem-client/src/dem/timestep.rs).
HERTZ_INTEGRAL = 1.471637592
FACES = ("x_min", "x_max", "y_min", "y_max", "z_min", "z_max")


class Unsupported(ValueError):
    """A part of the scene's DEM the writer cannot express."""


class Wall(NamedTuple):
    """A plane normal to ``axis`` at ``at``; the particles on the side of ``sense`` (+1, -1)."""

    axis: int
    at: float
    sense: int
    material: str


class DemSetup:
    """The scene's `[dem]` beyond the particles."""

    def __init__(self, scene: lbmdem_scene.Scene):
        self.scene = scene
        dem = scene.data.get("dem", {})
        self.dem = dem
        c = dem.get("contact", {})
        self.contact = c
        self.preset = c.get("preset", "liggghts")
        self.normal = c.get("normal", "hertz")
        self.tangential = c.get("tangential", "history")
        self.rolling = c.get("rolling", "none")
        self.wall_radius_factor = float(c.get("wall_radius_factor",
                                              0.5 if self.preset == "yade" else 1.0))
        self.periodic = periodic_axes(scene)
        self.walls = walls(scene, self.periodic)
        self.dt = float(dem["dt"]) if "dt" in dem else (
            self.shortest_contact_time() / float(dem.get("dt_divisor", 50.0)))

    @property
    def materials(self) -> list:
        """The scene's materials, in file order."""
        return list(self.scene.materials.values())

    def pair(self, a: str, b: str) -> dict:
        """Restitution, friction and rolling friction of a pair: the smaller of the two."""
        ma, mb = self.scene.materials[a], self.scene.materials[b]
        friction = 0.0 if self.tangential == "none" else min(ma.friction, mb.friction)
        return dict(restitution=min(ma.restitution, mb.restitution), friction=friction,
                    rolling_friction=min(ma.rolling_friction, mb.rolling_friction))

    def linear(self, a: str, b: str) -> tuple:
        """The linear law's (k_n, gamma_n, k_t, gamma_t) of materials a and b, at the m* of
        their smallest spheres (dem-client/src/dem/contact.rs `linear_spring_dashpot`)."""
        e = self.pair(a, b)["restitution"]
        m_eff = self._pair_mass(a, b)
        c, log_e = self.contact, math.log(e)
        if "contact_time" in c:
            t_c = float(c["contact_time"])
            k_n, gamma_n = m_eff * (math.pi ** 2 + log_e ** 2) / t_c ** 2, -2.0 * m_eff * log_e / t_c
        else:
            k_n = float(c["normal_stiffness"])
            gamma_n = float(c.get("normal_damping", math.sqrt(
                4.0 * m_eff * k_n * log_e ** 2 / (log_e ** 2 + math.pi ** 2))))
        return (k_n, gamma_n, float(c.get("tangential_stiffness", k_n)),
                float(c.get("tangential_damping", gamma_n)))

    def shortest_contact_time(self) -> float:
        """dem-client/src/dem/mod.rs `shortest_contact_time`."""
        smallest = self._smallest()
        v = self._impact_velocity()
        times = []
        for ma, (ra, mass_a) in smallest.items():
            for mb, (rb, mass_b) in smallest.items():
                times.append(self._contact_time(ma, mb, ra * rb / (ra + rb),
                                                mass_a * mass_b / (mass_a + mass_b), v))
            for w in self.walls:
                times.append(self._contact_time(ma, w.material, self.wall_radius_factor * ra,
                                                mass_a, v))
        return min(times) if times else math.inf

    def _contact_time(self, a: str, b: str, r_eff: float, m_eff: float, v: float) -> float:
        if self.normal == "linear":
            k_n, gamma_n, _, _ = self.linear(a, b)
            w2 = k_n / m_eff - (gamma_n / (2.0 * m_eff)) ** 2
            return math.pi / math.sqrt(w2) if w2 > 0.0 else math.pi * math.sqrt(m_eff / k_n)
        ma, mb = self.scene.materials[a], self.scene.materials[b]
        y_star = 1.0 / ((1.0 - ma.poisson_ratio ** 2) / ma.young_modulus
                        + (1.0 - mb.poisson_ratio ** 2) / mb.young_modulus)
        overlap = (15.0 * m_eff * v * v / (16.0 * y_star * math.sqrt(r_eff))) ** 0.4
        return 2.0 * HERTZ_INTEGRAL * overlap / v

    def _smallest(self) -> dict:
        """material -> (radius, mass) of its smallest sphere."""
        out = {}
        for p in self.scene.particles:
            if p.material not in out or p.radius < out[p.material][0]:
                out[p.material] = (p.radius, 4.0 / 3.0 * math.pi * p.radius ** 3 * p.density)
        return out

    def _pair_mass(self, a: str, b: str) -> float:
        """m* of the smallest spheres of a and b; a material without spheres is a wall's (m* = m)."""
        smallest = self._smallest()
        masses = [smallest[m][1] for m in (a, b) if m in smallest]
        if len(masses) == 2:
            return masses[0] * masses[1] / (masses[0] + masses[1])
        return masses[0] if masses else 1.0

    def _impact_velocity(self) -> float:
        """dem-client/src/dem/mod.rs `impact_velocity`."""
        if "impact_velocity" in self.contact:
            return float(self.contact["impact_velocity"])
        g = self.scene.gravity
        norm = math.sqrt(sum(c * c for c in g))
        extent = [hi - lo for lo, hi in zip(self.scene.domain_min, self.scene.domain_max)]
        height = sum(e * abs(c) for e, c in zip(extent, g)) / norm if norm > 0.0 else 0.0
        fastest = max((math.sqrt(sum(c * c for c in p.velocity)) for p in self.scene.particles),
                      default=0.0)
        return max(math.sqrt(2.0 * norm * height) + fastest, 0.1)


def periodic_axes(scene: lbmdem_scene.Scene) -> tuple:
    """The axes whose lattice faces are periodic."""
    faces = (scene.lattice or {}).get("faces", {})
    return tuple(faces.get(FACES[2 * a]) == "periodic" for a in range(3))


def walls(scene: lbmdem_scene.Scene, periodic: tuple) -> list:
    """The scene's walls as axis planes (docs/dem.md, Walls)."""
    dem = scene.data.get("dem", {})
    own = scene.particle_material
    planes, boxes = dem.get("plane", []), dem.get("box", [])
    out = []
    if dem.get("domain_walls", not planes and not boxes):
        material = dem.get("domain_wall_material") or own
        for a in range(3):
            if not periodic[a]:
                out += [Wall(a, scene.domain_min[a], 1, material),
                        Wall(a, scene.domain_max[a], -1, material)]
    for i, p in enumerate(planes):
        axes = [a for a in range(3) if p["normal"][a] != 0.0]
        if len(axes) != 1:
            raise Unsupported(f"dem.plane[{i}]: normal {p['normal']} is not along an axis: "
                              f"only axis-aligned planes are written (add it by hand)")
        a = axes[0]
        out.append(Wall(a, p["point"][a], 1 if p["normal"][a] > 0 else -1, p.get("material") or own))
    for i, b in enumerate(boxes):
        if not b.get("inside", True):
            raise Unsupported(f"dem.box[{i}]: a solid obstacle (inside = false) is not written "
                              f"(add it by hand)")
        for a in range(3):
            out += [Wall(a, b["min"][a], 1, b.get("material") or own),
                    Wall(a, b["max"][a], -1, b.get("material") or own)]
    return out


def writer_main(argv: list, prog: str, code: str, write: Callable) -> int:
    """The command line of a writer, ``prog SCENE.toml FILE``: ``write(scene, setup, FILE)``
    (FILE absolute); exit status 2 where the scene cannot be read or written, a warning where the
    scene's contact preset is not the one ``code`` reproduces."""
    if len(argv) != 3:
        print(f"usage: {prog} SCENE.toml FILE", file=sys.stderr)
        return 2
    try:
        scene = lbmdem_scene.Scene.load(argv[1])
        setup = DemSetup(scene)
    except (lbmdem_scene.SceneError, Unsupported) as e:
        print(f"{prog}: error: {e}", file=sys.stderr)
        return 2
    write(scene, setup, os.path.abspath(argv[2]))
    if setup.preset != code:
        print(f"{prog}: warning: the scene's contact preset is '{setup.preset}'; {code.upper()} "
              f"runs dem-client's '{code}' preset (docs/dem.md)", file=sys.stderr)
    return 0
