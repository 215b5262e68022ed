"""The fluid's force and torque on each atom, held over the LIGGGHTS steps of one fluid step.

LIGGGHTS integrates with velocity Verlet (``fix nve/sphere``): each step kicks the velocities with
half the force of the step before, drifts, computes the forces, and kicks with the other half.
``fix external``'s callback, called where the forces are summed (``post_force``), writes the held
force into ``fexternal`` (which the fix then adds to the atoms' force) and adds the held torque
to the atoms' torque. The coupled loop runs ``run k pre no post no``, so the first half kick of a
fluid step uses the forces LIGGGHTS summed at the end of the previous one, with the previous
loads: :meth:`HeldLoads.hold` adds the change of the loads to them, so that every LIGGGHTS step of
fluid step n sees the loads of step n (a constant force F over k steps changes the momentum by
exactly k dt F).
"""

from __future__ import annotations

from typing import Optional

import numpy as np

from liggghts import Atoms, Liggghts


class HeldLoads:
    """Force and torque by particle id (atom ID - 1), applied by ``fix external``."""

    def __init__(self, lmp: Liggghts):
        self.lmp = lmp
        self.force = np.zeros((0, 3))
        self.torque = np.zeros((0, 3))
        #: An exception raised in the callback (LIGGGHTS cannot be stopped from there).
        self.error: Optional[BaseException] = None

    def _fit(self, ids: np.ndarray) -> None:
        """Grows the tables (with zero loads) to hold ``ids``."""
        need = int(ids.max()) + 1 if ids.size else 0
        if need > self.force.shape[0]:
            pad = need - self.force.shape[0]
            self.force = np.vstack([self.force, np.zeros((pad, 3))])
            self.torque = np.vstack([self.torque, np.zeros((pad, 3))])

    def hold(self, ids: np.ndarray, force: np.ndarray, torque: np.ndarray,
             atoms: Optional[Atoms]) -> None:
        """Holds the reply's loads (``ids`` those of the states sent). With ``atoms`` (the
        arrays as the last run left them) their force and torque take the change of the loads,
        for the first half kick of the next run."""
        ids = ids.astype(np.int64)
        self._fit(ids)
        new_force, new_torque = np.zeros_like(self.force), np.zeros_like(self.torque)
        new_force[ids], new_torque[ids] = force, torque
        if atoms is not None and atoms.count:
            rows = atoms.tag.astype(np.int64) - 1
            atoms.f += new_force[rows] - self.force[rows]
            atoms.torque += new_torque[rows] - self.torque[rows]
        self.force, self.torque = new_force, new_torque

    def apply(self, _step: int, n: int, tag, _x, fexternal) -> None:
        """``fix external``'s callback: fexternal = the held force, torque += the held torque."""
        if n <= 0 or self.error is not None:
            return
        try:
            rows = np.ctypeslib.as_array(tag, shape=(n,)).astype(np.int64) - 1
            self._fit(rows)
            np.ctypeslib.as_array(fexternal[0], shape=(n, 3))[:] = self.force[rows]
            self.lmp.array(b"torque", n)[:] += self.torque[rows]
        except BaseException as e:  # noqa: BLE001 - raised after the run by check()
            self.error = e

    def check(self) -> None:
        """Raises what went wrong in the callback during the last run."""
        if self.error is not None:
            raise RuntimeError(f"fix external callback failed: {self.error!r}")
