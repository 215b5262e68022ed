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

With :class:`substep_loads.SubstepLoads` (the scene's ``coupling.substep_drag`` or
``coupling.lubrication``) the loads are not held constant but follow the atoms within the fluid
step as ``dem-client``'s do (PROTOCOL.md 3.2 and 4.5): the callback evaluates them at every
LIGGGHTS step from the atoms' x, v, omega and the contact force LIGGGHTS summed for that step
(the atoms' force less gravity: the deck's ``fix gravity`` and the walls come before
``fix external``).
"""

from __future__ import annotations

import ctypes
from typing import TYPE_CHECKING, Optional

import numpy as np

from liggghts import Atoms, Liggghts

if TYPE_CHECKING:  # clients/python, on PYTHONPATH where the loads follow the atoms
    from substep_loads import SubstepLoads


class HeldLoads:
    """Force and torque by particle id (atom ID - 1), applied by ``fix external``."""

    def __init__(self, lmp: Liggghts, within: Optional[SubstepLoads] = None):
        self.lmp = lmp
        self.force = np.zeros((0, 3))
        self.torque = np.zeros((0, 3))
        #: The loads within the fluid step (None: held constant), the LIGGGHTS step at its start.
        self.within, self.first_step = within, 0
        #: The atoms' tags, the held force and torque in their order, whether any torque is not
        #: 0 (None: not yet known); the address of the fexternal written with them.
        self._order, self._written = None, None
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
        if self.within is not None:
            self._hold_within(new_force, new_torque, atoms)
        if atoms is not None and atoms.count:
            rows = atoms.tag.astype(np.int64) - 1
            atoms.f += new_force[rows] - self.force[rows]
            atoms.torque += new_torque[rows] - self.torque[rows]
        self.force, self.torque = new_force, new_torque
        self._order = None

    def _hold_within(self, new_force: np.ndarray, new_torque: np.ndarray,
                     atoms: Optional[Atoms]) -> None:
        """Starts the fluid step of ``self.within`` from the atoms' state; ``new_force`` takes the
        loads at its start (the drag is 0 there: F_n and the films)."""
        now = atoms if atoms is not None else self.lmp.atoms()
        rows = now.tag.astype(np.int64) - 1
        order = np.argsort(rows)
        mass = self.lmp.vector(b"rmass", now.count)[order]
        self.within.hold(rows[order], new_force[rows[order]], new_torque[rows[order]],
                         now.x[order], now.v[order], now.omega[order], now.radius[order], mass)
        self.first_step = self.lmp.ntimestep()
        new_force[rows] = self.within.loads(rows, 0.0, now.x, now.v, now.omega, now.radius,
                                            0.0, 0.0, 0.0)[0]

    def apply(self, step: int, n: int, tag, _x, fexternal) -> None:
        """``fix external``'s callback: fexternal = the held force, torque += the held torque."""
        if n <= 0 or self.error is not None:
            return
        try:
            tags = np.ctypeslib.as_array(tag, shape=(n,))
            if self.within is None and self._order is not None and np.array_equal(
                    tags, self._order[0]):
                # fexternal is the fix's own array: it keeps what was written while LIGGGHTS
                # keeps its atoms in that order and the array where it was.
                address = ctypes.addressof(fexternal[0].contents)
                if address != self._written:
                    np.ctypeslib.as_array(fexternal[0], shape=(n, 3))[:] = self._order[1]
                    self._written = address
                if self._order[3]:
                    self.lmp.array(b"torque", n)[:] += self._order[2]
                return
            rows = tags.astype(np.int64) - 1
            self._fit(rows)
            if self.within is not None:
                self._follow(step, n, rows, fexternal)
                return
            force, torque = self._in_atom_order(tags)
            np.ctypeslib.as_array(fexternal[0], shape=(n, 3))[:] = force
            self._written = ctypes.addressof(fexternal[0].contents)
            self.lmp.array(b"torque", n)[:] += torque
        except BaseException as e:  # noqa: BLE001 - raised after the run by check()
            self.error = e

    def _in_atom_order(self, tags: np.ndarray):
        """The held loads in the order of the atoms (``tags``), kept for the next calls while
        LIGGGHTS keeps its atoms in that order (it sorts them now and then)."""
        rows = tags.astype(np.int64) - 1
        torque = self.torque[rows]
        self._order = (tags.copy(), self.force[rows], torque, bool(np.any(torque)))
        self._written = None
        return self._order[1], self._order[2]

    def _follow(self, step: int, n: int, rows: np.ndarray, fexternal) -> None:
        """The loads of ``self.within`` at this LIGGGHTS step; what the callback wrote is kept
        in ``self.force``, ``self.torque`` (the next ``hold`` corrects the first half kick by it)."""
        lmp, dt = self.lmp, self.lmp.timestep()
        f, torque = lmp.array(b"f", n), lmp.array(b"torque", n)
        mass = lmp.vector(b"rmass", n)
        contact = f - mass[:, None] * self.within.gravity
        force, spin = self.within.loads(rows, (step - self.first_step) * dt, lmp.array(b"x", n),
                                        lmp.array(b"v", n), lmp.array(b"omega", n),
                                        lmp.vector(b"radius", n), contact, torque.copy(), dt)
        np.ctypeslib.as_array(fexternal[0], shape=(n, 3))[:] = force
        torque += spin
        self.force[rows], self.torque[rows] = force, spin

    def check(self) -> None:
        """Raises what went wrong in the callback during the last run."""
        if self.error is not None:
            raise RuntimeError(f"fix external callback failed: {self.error!r}")
