#!/usr/bin/env python3
"""Runs a LIGGGHTS input deck as the DEM of a coupled lbm-server run.

    lbm-server run SCENE.toml --dem external          # prints "DEM service: RUN"
    python3 clients/liggghts/lbm_liggghts.py --service RUN --scene SCENE.toml --deck DECK.in \\
                                             [--var NAME VALUE]... [--log FILE] [--echo]

LIGGGHTS (Debian's libliggghts3) is loaded at run time. The deck runs first and builds the DEM:
one atom per particle of the scene (atom ID i is the scene's particle i - 1), a granular atom
style, materials, contact law, walls, gravity and ``fix nve/sphere``. Then, each fluid step, the
adapter reads the atoms' x, v, omega and radius, sends them to the fluid (clients/python/lbmdem/,
PROTOCOL.md), and runs k LIGGGHTS steps (k = fluid dt / LIGGGHTS timestep) with the fluid's force
and torque on them (``fix external``), following the atoms within the fluid step as the scene's
``coupling.substep_drag`` and ``coupling.lubrication`` say (the adapter then integrates the
squeeze films). The per-step work runs in clients/native (native.py: the library the workspace
builds), else in Python (held_loads.py, substep_loads.py; much slower for large beds). LIGGGHTS applies gravity; the fluid adds buoyancy
(and lubrication where the scene turns the adapter's films off). Exit status 0 after the FINAL reply or a STOP, 1 when the link or
LIGGGHTS fails during the run, 2 for bad input (LIGGGHTS missing, a deck error, atoms that are not
the scene's particles).
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import time
from typing import Optional

import numpy as np

import lbmdem  # clients/python on PYTHONPATH (lbm-server sets it when it starts the adapter)
import lbmdem_scene
import liggghts
import scene_dem
from deck import BadInput, check_atoms, log_errors, open_deck, substeps, units_of, version
from exit_guard import ExitGuard
from held_loads import HeldLoads
import native
from substep_loads import SqueezeFilms, SubstepLoads

PROG = "lbm-liggghts"
EXIT_FAILURE, EXIT_BAD_INPUT = 1, 2
#: The ids of the fixes the adapter adds to the deck.
FIX_FLUID, FIX_GRAVITY = "lbm_fluid", "lbm_gravity"


def say(message: str) -> None:
    print(f"{PROG}: {message}", file=sys.stderr, flush=True)


def parse_args(argv=None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n\n")[0])
    ap.add_argument("--service", default=os.environ.get("LBMDEM_RUN"),
                    help="run name printed by lbm-server (DEM service: RUN; default $LBMDEM_RUN)")
    ap.add_argument("--scene", default=os.environ.get("LBMDEM_SCENE"),
                    help="the scene file of the run (checks the deck's atoms against its "
                         "particles; default $LBMDEM_SCENE)")
    ap.add_argument("--deck", help="the LIGGGHTS input deck")
    ap.add_argument("--var", nargs=2, action="append", metavar=("NAME", "VALUE"),
                    help="a deck variable, as liggghts -var NAME VALUE (repeatable)")
    ap.add_argument("--log", default="log.liggghts", help="LIGGGHTS's log file (default "
                                                          "log.liggghts)")
    ap.add_argument("--echo", action="store_true", help="show LIGGGHTS's screen output")
    ap.add_argument("--timeout", type=float, default=10.0,
                    help="longest wait for a live but silent fluid server [s] (default 10)")
    ap.add_argument("--loads", choices=("follow", "held"), default="follow",
                    help="follow: the fluid's loads follow the atoms within a fluid step as the "
                         "scene's coupling.substep_drag and coupling.lubrication say, the films "
                         "integrated here (default); held: held constant, the fluid adds its own "
                         "lubrication (cheaper for large beds)")
    ap.add_argument("--python-loads", action="store_true",
                    help="apply the loads in Python (held_loads.py) even where the native helper "
                         "(clients/native) is built")
    ap.add_argument("--probe", action="store_true",
                    help="only say whether LIGGGHTS can be loaded (exit 0) or not (exit 2)")
    args = ap.parse_args(argv)
    if not args.probe:
        for name in ("service", "scene", "deck"):
            if not getattr(args, name):
                ap.error(f"--{name} is required")
    return args


def states_of(atoms: liggghts.Atoms, lo: np.ndarray, hi: np.ndarray,
              periodic: np.ndarray) -> np.ndarray:
    """The atoms as the fluid's particles (ids atom ID - 1; centres wrapped along the periodic
    axes, where LIGGGHTS wraps only when it rebuilds its neighbour lists)."""
    states = np.zeros(atoms.count, lbmdem.STATE_DTYPE)
    states["id"] = atoms.tag.astype(np.int64) - 1
    states["position"] = atoms.x
    for axis in np.flatnonzero(periodic):
        states["position"][:, axis] = lo[axis] + np.mod(atoms.x[:, axis] - lo[axis],
                                                        hi[axis] - lo[axis])
    states["velocity"] = atoms.v
    states["angular_velocity"] = atoms.omega
    states["radius"] = atoms.radius
    return states


def within_step(scene: lbmdem_scene.Scene, welcome: lbmdem.Welcome,
                units: lbmdem.Units):
    """The loads within a fluid step as dem-client applies them (the scene's
    ``coupling.substep_drag`` and ``coupling.lubrication`` with a lattice), or None: held
    constant."""
    drag = bool(scene.coupling.get("substep_drag", True)) and scene.lattice is not None
    films = None
    if scene.lubrication:
        lo, hi = np.array(welcome.domain_min[:]), np.array(welcome.domain_max[:])
        periodic = welcome.periodic_axes()
        walls = [(w.axis, w.at / units.length_m, w.sense)
                 for w in scene_dem.walls(scene, tuple(periodic))]
        films = SqueezeFilms(welcome.fluid_viscosity, scene.cell_size() / units.length_m, walls,
                             np.where(periodic, hi - lo, 0.0))
    if not drag and films is None:
        return None
    return SubstepLoads(welcome.fluid_density, welcome.dt, welcome.gravity[:], drag, films)


class Adapter:
    """One coupled run of a deck: open, check, connect, step, leave."""

    def __init__(self, args: argparse.Namespace):
        self.args = args
        self.stop_requested = False
        self.lmp = None
        self.link = None
        self.guard = ExitGuard()
        self.last = None
        self.seconds = {"liggghts": 0.0, "fluid": 0.0}

    def run(self) -> int:
        try:
            lib = liggghts.load_library()
            self.scene = lbmdem_scene.Scene.load(self.args.scene)
            expected = len(self.scene.particles)
            self.guard.arm(self._deck_failed)
            self.lmp = open_deck(lib, self.args)
            check_atoms(self.lmp, self.args.deck, self.args.scene, expected)
            units = units_of(self.lmp)
            self.guard.arm(self._run_failed)
            welcome = self._connect(units)
            k = self._configure(welcome)
            self._loop(welcome, k)
        except (liggghts.NotInstalled, BadInput, lbmdem_scene.SceneError, liggghts.Unsupported) as e:
            return self._leave(f"error: {e}", EXIT_BAD_INPUT)
        except lbmdem.LinkError as e:
            return self._leave(f"error: {e}", EXIT_FAILURE)
        except Exception as e:  # noqa: BLE001 - report anything, exit non-zero
            return self._leave(f"error: {type(e).__name__}: {e} (last completed step "
                               f"{self.last if self.last is not None else 'none'})", EXIT_FAILURE)
        self._leave(None, 0)
        return self._report(welcome, k)

    def _leave(self, message, code: int) -> int:
        self.guard.disarm()
        if self.link is not None:
            self.link.close()
        if message:
            say(message)
        return code

    def _deck_failed(self) -> int:
        why = log_errors(self.args.log) or "LIGGGHTS ended the process"
        say(f"error: the deck {self.args.deck} failed: {why} (log: {self.args.log})")
        return EXIT_BAD_INPUT

    def _run_failed(self) -> int:
        if self.link is not None:
            self.link.close()
        last = self.last if self.last is not None else "none"
        why = log_errors(self.args.log) or "it ended the process"
        say(f"error: LIGGGHTS stopped during the coupled run: {why} (last completed step {last}; "
            f"log: {self.args.log})")
        return EXIT_FAILURE

    def _on_signal(self, signum, _frame) -> None:
        if self.stop_requested:  # second Ctrl-C: leave now
            if self.link is not None:
                self.link.close()
            say(f"interrupted twice, left after step {self.last}")
            os._exit(EXIT_FAILURE)
        self.stop_requested = True
        say(f"{signal.Signals(signum).name}: stopping (STOP goes with the next states)")

    def _connect(self, units: lbmdem.Units) -> lbmdem.Welcome:
        signal.signal(signal.SIGINT, self._on_signal)
        signal.signal(signal.SIGTERM, self._on_signal)
        if self.lmp.unit_style() is None:
            say("warning: cannot read this LIGGGHTS build's unit style: assuming units si")
        following = self.args.loads == "follow"
        films = lbmdem.Physics.LUBRICATION if following and self.scene.lubrication else 0
        self.units = units
        hello = lbmdem.Hello.new(units, lbmdem.Physics.GRAVITY | lbmdem.Physics.CONTACTS | films,
                                 initial_count=self.lmp.natoms(),
                                 software=f"{version(self.args.log)} (lbm_liggghts.py)")
        self.link = lbmdem.DemLink(self.args.service, timeout_s=self.args.timeout,
                                   interrupt=lambda: self.stop_requested)
        welcome = self.link.connect(hello)
        axes = [name for name, p in zip("xyz", welcome.periodic_axes()) if p]
        say(f"connected to {welcome.software_text()} (pid {welcome.pid}): {welcome.steps} steps "
            f"of {welcome.dt:g}, periodic along {axes}, {self.lmp.natoms()} atoms")
        return welcome

    def _configure(self, welcome: lbmdem.Welcome) -> int:
        """The LIGGGHTS steps per fluid step, gravity, and the fluid's loads on the atoms."""
        lmp = self.lmp
        k = substeps(welcome.dt, lmp.timestep())
        if not math.isclose(k * lmp.timestep(), welcome.dt, rel_tol=1e-9):
            say(f"the LIGGGHTS timestep {lmp.timestep():g} does not divide the fluid step "
                f"{welcome.dt:g}: LIGGGHTS steps at {welcome.dt / k:g} (fluid step / {k})")
            lmp.command(f"timestep {welcome.dt / k!r}")
        g = np.array(welcome.gravity[:])
        if lmp.has_fix_style("gravity"):
            say(f"gravity: the deck's fix gravity (the scene's is {g.tolist()})")
        elif np.any(g != 0.0):
            norm = float(np.linalg.norm(g))
            lmp.command(f"fix {FIX_GRAVITY} all gravity {norm!r} vector "
                        + " ".join(repr(float(c) / norm) for c in g))
            say(f"gravity: the deck has no fix gravity: added the scene's, {g.tolist()}")
        if not lmp.has_fix_style("nve"):
            say("warning: the deck has no fix nve/sphere: its atoms do not move")
        within = (within_step(self.scene, welcome, self.units) if self.args.loads == "follow"
                  else None)
        if within is not None:
            k = self._limit_step(welcome, k, within)
        self.loads = self._loads(within)
        if self.native:
            self.loads.attach(FIX_FLUID)
        else:
            lmp.fix_external(FIX_FLUID, self.loads.apply)
        return k

    def _loads(self, within: Optional[SubstepLoads]):
        """The loads in clients/native, or in Python where it is not built (or not wanted)."""
        self.native = False
        if not self.args.python_loads:
            try:
                loads = native.NativeLoads(native.load_library(), self.lmp)
            except native.NotBuilt as e:
                say(f"warning: {e}: the loads in Python (slower at each LIGGGHTS step)")
            else:
                if within is not None:
                    loads.follow(within)
                self.native = True
                say(f"the loads at each LIGGGHTS step: {loads.lib.path}")
                return loads
        return HeldLoads(self.lmp, within)

    def _states(self, lo: np.ndarray, hi: np.ndarray, periodic: np.ndarray):
        """The atoms' states, and the atoms' arrays (None with the native helper)."""
        if self.native:
            return self.loads.states(lo, hi, periodic), None
        atoms = self.lmp.atoms()
        return states_of(atoms, lo, hi, periodic), atoms

    def _hold(self, states: np.ndarray, forces: np.ndarray, atoms, ran: bool) -> None:
        """Holds the fluid's reply over the next run (``ran``: LIGGGHTS ran before)."""
        if self.native:
            self.loads.hold(forces, ran)
        else:
            self.loads.hold(states["id"], forces["force"], forces["torque"],
                            atoms if ran else None)

    def _limit_step(self, welcome: lbmdem.Welcome, k: int, within: SubstepLoads) -> int:
        """More LIGGGHTS steps per fluid step where the drag or the films need a shorter one."""
        atoms, lmp = self.lmp.atoms(), self.lmp
        limit = within.step_limit(atoms.radius, lmp.vector(b"rmass", atoms.count))
        if welcome.dt / k > limit:
            k = math.ceil(welcome.dt / limit)
            say(f"the fluid's loads within a step (PROTOCOL.md 3.2, 4.5) need LIGGGHTS steps of at "
                f"most {limit:g}: LIGGGHTS steps at {welcome.dt / k:g} (fluid step / {k})")
            lmp.command(f"timestep {welcome.dt / k!r}")
        return k

    def _loop(self, welcome: lbmdem.Welcome, k: int) -> None:
        lo, hi = np.array(welcome.domain_min[:]), np.array(welcome.domain_max[:])
        periodic = np.array(welcome.periodic_axes())
        ran, step, count = False, 0, self.lmp.natoms()
        while True:
            flags = lbmdem.StepFlags.STOP if self.stop_requested else 0
            states, atoms = self._states(lo, hi, periodic)
            if len(states) < count:
                say(f"warning: LIGGGHTS lost {count - len(states)} atoms in step {step - 1}")
            count = len(states)
            t0 = time.perf_counter()
            self.link.send_states(step, step * welcome.dt, states, flags)
            header, forces = self.link.receive_forces(step)
            t1 = time.perf_counter()
            self.last = step
            if header.flags & (lbmdem.StepFlags.FINAL | lbmdem.StepFlags.STOP) or flags:
                break
            if step + 1 >= welcome.steps:
                raise lbmdem.BadReply(f"the {lbmdem.FLUID} did not mark the reply to step "
                                      f"{step}, the last of {welcome.steps}, FINAL", step)
            self._hold(states, forces, atoms, ran)
            self.lmp.command(f"run {k} pre no post no" if ran else f"run {k}")
            self.loads.check()
            ran = True
            self.seconds["fluid"] += t1 - t0
            self.seconds["liggghts"] += time.perf_counter() - t1
            step += 1

    def _report(self, welcome: lbmdem.Welcome, k: int) -> int:
        say(f"time in LIGGGHTS {self.seconds['liggghts']:.2f} s, waiting for the fluid (the "
            f"exchange included) {self.seconds['fluid']:.2f} s ({k} LIGGGHTS steps per fluid "
            f"step)")
        if self.stop_requested:
            say(f"stopped on request after step {self.last}")
        elif self.last + 1 < welcome.steps:
            say(f"the fluid server stopped the run after step {self.last}")
        print(f"{PROG}: completed {self.last + 1} steps, {self.lmp.natoms()} atoms, last step "
              f"{self.last}", flush=True)
        return 0


def main(argv=None) -> int:
    args = parse_args(argv)
    if args.probe:
        try:
            liggghts.load_library()
        except liggghts.NotInstalled as e:
            say(str(e))
            return EXIT_BAD_INPUT
        print(f"{PROG}: LIGGGHTS found ({os.environ.get('LIGGGHTS_LIBRARY') or liggghts.LIBRARY})")
        return 0
    return Adapter(args).run()


if __name__ == "__main__":
    status = main()
    sys.stdout.flush()
    sys.stderr.flush()
    # Without the interpreter's shutdown: the exit guard's C handler must not run after it.
    os._exit(status)
