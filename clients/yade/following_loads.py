"""The fluid's loads on YADE's spheres following them within a fluid step, as dem-client's do.

``lbmdem_yade.couple`` takes k ``O.step()``s per fluid step. Before each it sets the permanent
force and torque of every coupled sphere to what ``../python/substep_loads.py`` gives at that
time: the sub-step drag of PROTOCOL.md 3.2 (scene ``coupling.substep_drag``) and the squeeze films
of 4.5 (scene ``coupling.lubrication``: the module then declares ``LUBRICATION``). After each step
it adds that step's contact force (``O.forces.f`` less the permanent force: NewtonIntegrator
applies gravity apart) to the contact impulse that ``hold`` turns into the mean contact load.
"""

from __future__ import annotations

from typing import List, Optional

import numpy as np

import lbmdem
import lbmdem_scene
import scene_dem
from substep_loads import SqueezeFilms, SubstepLoads

import yade  # noqa: F401 - runs inside YADE
from yade.minieigenHP import Vector3

O = yade.Omega()


def within_step(scene: Optional[lbmdem_scene.Scene], welcome: lbmdem.Welcome):
    """The loads within a fluid step the scene asks for, or None (held constant)."""
    if scene is None or scene.lattice is None:
        return None
    drag = bool(scene.coupling.get("substep_drag", True))
    films = None
    if scene.lubrication:
        lo, hi = np.array(welcome.domain_min[:]), np.array(welcome.domain_max[:])
        periodic = tuple(welcome.periodic_axes())
        walls = [(w.axis, w.at, w.sense) for w in scene_dem.walls(scene, periodic)]
        films = SqueezeFilms(welcome.fluid_viscosity, scene.cell_size(), walls,
                             np.where(periodic, hi - lo, 0.0))
    if not drag and films is None:
        return None
    return SubstepLoads(welcome.fluid_density, welcome.dt, welcome.gravity[:], drag, films)


class FollowingLoads:
    """Sets the permanent loads of the coupled bodies before each YADE step."""

    def __init__(self, loads: SubstepLoads, scene_ids: List[int], body_ids: List[int]):
        self.loads = loads
        self.ids = np.asarray(scene_ids, np.int64)
        self.body_ids = body_ids
        bodies = [O.bodies[b] for b in body_ids]
        self.mass = np.array([b.state.mass for b in bodies])
        self.radius = np.array([b.shape.radius for b in bodies])

    def step_limit(self) -> float:
        return self.loads.step_limit(self.radius, self.mass)

    def _state(self):
        rows = np.array([(*b.state.pos, *b.state.vel, *b.state.angVel)
                         for b in (O.bodies[i] for i in self.body_ids)])
        return rows[:, 0:3], rows[:, 3:6], rows[:, 6:9]

    def hold(self, replies: np.ndarray) -> None:
        """The reply to the states just sent (same order as ``self.ids``)."""
        x, v, w = self._state()
        self.loads.hold(self.ids, replies["force"], replies["torque"], x, v, w, self.radius,
                        self.mass)

    def advance(self, k: int) -> None:
        """k YADE steps, the loads set before each from the state then."""
        set_f, set_t = O.forces.setPermF, O.forces.setPermT
        zero = np.zeros((len(self.ids), 3))
        for j in range(k):
            x, v, w = self._state()
            # the films of this step go into the impulse here, the contacts after the step
            force, torque = self.loads.loads(self.ids, j * O.dt, x, v, w, self.radius, zero,
                                             zero, O.dt)
            for body, f, t in zip(self.body_ids, force.tolist(), torque.tolist()):
                set_f(body, Vector3(*f))
                set_t(body, Vector3(*t))
            O.step()
            contact = np.array([(*(O.forces.f(b) - O.forces.permF(b)),
                                 *(O.forces.t(b) - O.forces.permT(b))) for b in self.body_ids])
            self.loads.impulse[self.ids] += O.dt * contact[:, 0:3]
            self.loads.angular_impulse[self.ids] += O.dt * contact[:, 3:6]
