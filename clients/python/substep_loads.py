"""The fluid's loads within a fluid step, as dem-client applies them in its DEM sub-steps.

An external DEM (clients/liggghts) takes k steps of its own per fluid step. Held constant over
them, the fluid's reply pumps energy into contacts (a rebound changes the velocity the reply
answered) and the fluid's own squeeze-film correction is evaluated once per fluid step. This
module gives, at each of the DEM's force evaluations, what ``dem-client`` applies there:

- the sub-step drag of PROTOCOL.md 3.2 (scene ``coupling.substep_drag``, default true):
  F(s) = F_n - c (v(s) - v_n - a_n s), T(s) = T_n - c_r (w(s) - w_n - alpha_n s), with
  c = rho_f V / dt, c_r = 0.4 c r^2, a_n = (F_n + J_{n-1} / dt) / m + g, alpha_n likewise with
  the angular impulse (``hold``);
- the squeeze films of PROTOCOL.md 4.5 (scene ``coupling.lubrication``, default true, with a
  ``[lattice]``): 6 pi mu R*^2 (1/h - 1/h_c) v_n along the line of centres for 0 < gap < h_c,
  h = max(gap, 0.01 R*), h_c one lattice cell, between spheres and against the scene's walls.
  A DEM that applies them declares ``LUBRICATION`` in its Hello (the fluid then adds none).

Plain numpy; per-particle tables are indexed by particle id. clients/yade uses it between
``O.step()``s; the LIGGGHTS adapter evaluates the same law compiled (clients/native, with the
protocol crate's ``substep_drag`` and ``squeeze_film``), and this module where that is not built.
"""

from __future__ import annotations

import itertools
import math
from typing import Optional

import numpy as np

#: Roughness floor of the gap as a fraction of R* (protocol/src/squeeze_film.rs).
MIN_GAP_FRACTION = 0.01
#: Largest c dt / m of a wall film at the roughness floor (dem-client/src/dem/lubrication.rs).
MAX_FILM_LAMBDA = 1.0 / 6.0
#: The DEM step stays below this fraction of the drag's relaxation time m / c (dem-client).
DRAG_STEP_FRACTION = 0.1


def film_damping(viscosity: float, r_eff, gap, cutoff: float):
    """6 pi mu R*^2 (1/h - 1/h_c) [N s/m] for 0 < gap < cutoff, else 0 (elementwise)."""
    r_eff, gap = np.asarray(r_eff, float), np.asarray(gap, float)
    h = np.maximum(gap, MIN_GAP_FRACTION * r_eff)
    inside = (gap > 0.0) & (gap < cutoff)
    return np.where(inside, 6.0 * math.pi * viscosity * r_eff ** 2 * (1.0 / h - 1.0 / cutoff), 0.0)


def near_pairs(x: np.ndarray, radius: np.ndarray, reach: float, periods: np.ndarray):
    """Pairs (i < j) whose surfaces are closer than ``reach`` (nearest image along the axes with a
    period > 0), found on a grid of cells one largest diameter plus ``reach`` wide."""
    n = len(x)
    if n < 2:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    size = 2.0 * float(radius.max()) + reach
    lo = x.min(axis=0)
    span = np.where(periods > 0, periods, x.max(axis=0) - lo + size)
    dims = np.maximum(np.floor(span / size).astype(np.int64), 1)
    cell = np.minimum(np.floor((x - lo) / (span / dims)).astype(np.int64), dims - 1)
    key = (cell[:, 0] * dims[1] + cell[:, 1]) * dims[2] + cell[:, 2]
    order = np.argsort(key, kind="stable")
    sorted_keys = key[order]
    found = []
    for offset in itertools.product((-1, 0, 1), repeat=3):
        other = cell + offset
        other = np.where(periods > 0, np.mod(other, dims), other)
        ok = np.all((other >= 0) & (other < dims), axis=1)
        other_key = (other[:, 0] * dims[1] + other[:, 1]) * dims[2] + other[:, 2]
        first = np.searchsorted(sorted_keys, other_key, "left")
        count = np.where(ok, np.searchsorted(sorted_keys, other_key, "right") - first, 0)
        i = np.repeat(np.arange(n), count)
        within = np.arange(count.sum()) - np.repeat(np.cumsum(count) - count, count)
        j = order[np.repeat(first, count) + within]
        i, j = i[i < j], j[i < j]
        d = separation(x[i] - x[j], periods)
        close = np.sqrt(np.einsum("ij,ij->i", d, d)) - radius[i] - radius[j] < reach
        found.append(i[close] * n + j[close])
    code = np.concatenate(found)
    if np.any((periods > 0) & (dims < 3)):  # a wrapped offset can meet the same cell twice
        code = np.unique(code)
    return code // n, code % n


def separation(d: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """x_i - x_j at the nearest image along the periodic axes."""
    if not np.any(periods > 0):
        return d
    return np.where(periods > 0, d - periods * np.round(d / np.where(periods > 0, periods, 1.0)), d)


class SqueezeFilms:
    """The squeeze films of PROTOCOL.md 4.5 between spheres and against axis-aligned walls."""

    def __init__(self, viscosity: float, cutoff: float, walls: list, periods):
        self.viscosity, self.cutoff = viscosity, cutoff
        #: The walls: axis, coordinate and inward normal sign of each plane.
        walls = list(walls)
        self.wall_axis = np.array([w[0] for w in walls], np.int64)
        self.wall_at = np.array([w[1] for w in walls], float)
        self.wall_sign = np.array([w[2] for w in walls], float)
        #: Sums each wall's force into its axis.
        self.wall_to_axis = np.eye(3)[self.wall_axis] if walls else np.zeros((0, 3))
        self.periods = np.asarray(periods, float)
        self.i = self.j = np.zeros(0, np.int64)
        self._rows = (None, None, None)

    def candidates(self, ids, x: np.ndarray, radius: np.ndarray, travel: float) -> None:
        """The pairs (by id) that can come within the cut-off while each sphere moves up to
        ``travel``."""
        i, j = near_pairs(x, radius, self.cutoff + 2.0 * travel, self.periods)
        self.i, self.j = ids[i], ids[j]
        self._rows = (None, None, None)

    def _pair_rows(self, ids: np.ndarray):
        """The candidate pairs as rows of ``ids`` (kept while the order of ids is)."""
        if self._rows[0] is None or not np.array_equal(self._rows[0], ids):
            row = np.full(int(max(ids.max(), self.i.max(), self.j.max())) + 1, -1)
            row[ids] = np.arange(len(ids))
            i, j = row[self.i], row[self.j]
            keep = (i >= 0) & (j >= 0)
            self._rows = (ids.copy(), i[keep], j[keep])
        return self._rows[1], self._rows[2]

    def forces(self, ids, x: np.ndarray, v: np.ndarray, radius: np.ndarray) -> np.ndarray:
        """The film force on each sphere (rows as ids, x) for the present gaps and velocities."""
        f = np.zeros_like(x)
        if self.i.size and len(ids):
            i, j = self._pair_rows(ids)
            d = separation(x[i] - x[j], self.periods)
            dist = np.sqrt(np.einsum("ij,ij->i", d, d))
            normal = d / np.where(dist > 0.0, dist, 1.0)[:, None]
            r_eff = radius[i] * radius[j] / (radius[i] + radius[j])
            approach = -np.einsum("ij,ij->i", v[i] - v[j], normal)
            pair = normal * (film_damping(self.viscosity, r_eff, dist - radius[i] - radius[j],
                                          self.cutoff) * approach)[:, None]
            slots = np.concatenate([3 * i[:, None], 3 * j[:, None]]) + np.arange(3)
            f += np.bincount(slots.ravel(), np.concatenate([pair, -pair]).ravel(),
                             3 * len(x)).reshape(-1, 3)
        if self.wall_axis.size:
            gap = self.wall_sign * (x[:, self.wall_axis] - self.wall_at) - radius[:, None]
            damping = film_damping(self.viscosity, radius[:, None], gap, self.cutoff)
            # sign * c * (approach speed -sign v) = -c v along the wall's axis
            f -= (damping * v[:, self.wall_axis]) @ self.wall_to_axis
        return f

    def step_limit(self, radius: np.ndarray, mass: np.ndarray) -> float:
        """Longest DEM step keeping c dt / m <= 1/6 for a wall film at the roughness floor."""
        stiffest = film_damping(self.viscosity, radius, MIN_GAP_FRACTION * radius, self.cutoff)
        return float(np.min(np.where(stiffest > 0, MAX_FILM_LAMBDA * mass / np.where(
            stiffest > 0, stiffest, 1.0), np.inf))) if len(radius) else math.inf


class SubstepLoads:
    """The force and torque on each particle at a force evaluation s into fluid step n."""

    def __init__(self, fluid_density: float, dt: float, gravity, drag: bool,
                 films: Optional[SqueezeFilms]):
        self.rate = fluid_density / dt if drag else 0.0
        self.dt, self.gravity, self.films = dt, np.asarray(gravity, float), films
        self.force = self.torque = self.v0 = self.w0 = np.zeros((0, 3))
        self.accel = self.spin_accel = self.impulse = self.angular_impulse = np.zeros((0, 3))

    def drag(self, radius: np.ndarray):
        """c = rho_f V / dt and c_r = 0.4 c r^2 of each sphere."""
        c = self.rate * 4.0 / 3.0 * math.pi * radius ** 3
        return c, 0.4 * c * radius ** 2

    def step_limit(self, radius: np.ndarray, mass: np.ndarray) -> float:
        """Longest DEM step for the drag (a tenth of m / c) and the films."""
        c, _ = self.drag(radius)
        limit = float(np.min(DRAG_STEP_FRACTION * mass / c)) if self.rate and len(c) else math.inf
        return min(limit, self.films.step_limit(radius, mass) if self.films else math.inf)

    def hold(self, ids, force, torque, x, v, w, radius, mass) -> None:
        """Takes the reply to the states (x, v, w) of ids: F_n, T_n, v_n, w_n, a_n, alpha_n; the
        impulses summed since the last ``hold`` make the previous step's mean contact load."""
        size = max(int(ids.max()) + 1 if len(ids) else 0, len(self.impulse))
        impulse, angular_impulse = self._table(size), self._table(size)
        impulse[:len(self.impulse)], angular_impulse[:len(self.impulse)] = (
            self.impulse, self.angular_impulse)
        inertia = 0.4 * mass * radius ** 2
        accel = (force + impulse[ids] / self.dt) / mass[:, None] + self.gravity
        spin_accel = (torque + angular_impulse[ids] / self.dt) / inertia[:, None]
        self.force, self.torque, self.v0, self.w0, self.accel, self.spin_accel = (
            self._table(size, ids, a) for a in (force, torque, v, w, accel, spin_accel))
        self.impulse, self.angular_impulse = self._table(size), self._table(size)
        if self.films:
            speed = float(np.max(np.linalg.norm(v, axis=1), initial=0.0))
            self.films.candidates(ids, x, radius, 2.0 * speed * self.dt + 1e-3 * self.films.cutoff)

    @staticmethod
    def _table(size: int, ids=None, rows=None) -> np.ndarray:
        """A per-id table of vectors: 0, with ``rows`` at ``ids``."""
        t = np.zeros((size, 3))
        if ids is not None:
            t[ids] = rows
        return t

    def loads(self, rows, s: float, x, v, w, radius, contact_force, contact_torque,
              substep: float):
        """The loads at time s into the step on the particles of ids ``rows`` (x, v, w, radius in
        that order, as ``hold`` saw them), their contact loads of this evaluation adding
        substep times themselves to the impulses."""
        c, c_r = self.drag(radius)
        force = self.force[rows] - c[:, None] * (v - self.v0[rows] - self.accel[rows] * s)
        torque = self.torque[rows] - c_r[:, None] * (w - self.w0[rows] - self.spin_accel[rows] * s)
        film = self.films.forces(rows, x, v, radius) if self.films else 0.0
        self.impulse[rows] += substep * (contact_force + film)
        self.angular_impulse[rows] += substep * contact_torque
        return force + film, torque
