"""YADE as the DEM of a coupled lbm-server run: one call from a YADE script.

A user's own YADE script builds its bodies, materials and engines, then calls :func:`couple`::

    import lbmdem_yade
    ...                                                   # O.bodies, O.engines, O.dt: plain YADE
    lbmdem_yade.couple("lbmdem_4242_1a2b3c", scene="validation/scenes/ten-cate-e1.toml")

and runs it with ``PYTHONPATH=IOX:clients/python:clients/yade yade -n -x script.py``. Each fluid step it sends
the coupled spheres' states (ids: the scene's particle ids, through an id map), receives the
fluid's force and torque, holds them on the spheres (``O.forces.setPermF`` / ``setPermT``: YADE's
ForceResetter wipes a force added from outside the loop, a permanent one it keeps) over ``k``
YADE steps of ``O.dt`` (``k`` = fluid dt / ``O.dt``, a whole number), and goes on until the
fluid's FINAL reply. YADE applies gravity (its NewtonIntegrator, set to the scene's), the fluid
buoyancy, the immersed boundary's force and the lubrication correction (PROTOCOL.md 4.5).
Non-spheres (walls, facets, boxes) and fixed spheres stay YADE's own walls: the fluid does not
see them. Ctrl-C (or SIGTERM) sends STOP with the next states and ends the run after that step.

Exit status (with ``exit_on_error``, the default): 0 after the FINAL reply or a STOP; 2 on bad
input (an id map the scene does not have, a sphere count that differs from the scene's, an
``O.dt`` that does not divide the fluid step, no NewtonIntegrator, ...), after ending the run
with STOP so that nothing is left running; 1 on a broken link (the message names the fluid
server and the last completed step). See README.md beside this file.
"""

from __future__ import annotations

import math
import os
import signal
import sys
from typing import Dict, Mapping, NamedTuple, Optional, Sequence, Union

import numpy as np

import lbmdem  # clients/python on PYTHONPATH (lbm-server sets it when it starts YADE)
import lbmdem_scene
import following_loads

import yade  # this module runs inside YADE: `yade -n -x script.py`
from yade.minieigenHP import Vector3

__all__ = ["couple", "Coupled", "BadInput", "id_map", "RUN_ENV", "SCENE_ENV"]

#: Environment variables a launcher may set instead of the arguments `run` and `scene`.
RUN_ENV = "LBMDEM_RUN"
SCENE_ENV = "LBMDEM_SCENE"
#: Exit status on bad input (as lbm-server's).
EXIT_BAD_INPUT = 2
#: `O.dt` divides the fluid step when k O.dt is within this fraction of it.
WHOLE_TOLERANCE = 1e-9
NAME = "yade-dem"
O = yade.Omega()


class BadInput(Exception):
    """The YADE script and the run do not fit together; ends the run with exit status 2.
    ``run_over``: the fluid server has already ended the run (it refused the Hello)."""

    def __init__(self, message: str, run_over: bool = False):
        super().__init__(message)
        self.run_over = run_over


class Coupled(NamedTuple):
    """How a coupled run ended: ``steps`` completed (the last one ``steps - 1``), ``ending`` one
    of "final" (the fluid's last step), "fluid-stop" (the fluid sent STOP), "interrupted"
    (Ctrl-C here), the coupled ``particles`` at the end, ``substeps`` YADE steps per fluid step."""

    steps: int
    ending: str
    particles: int
    substeps: int
    dt: float


# ---------------------------------------------------------------------------------------------
# The id map: scene particle id <-> YADE body id
# ---------------------------------------------------------------------------------------------

def _is_coupled_sphere(body) -> bool:
    return body is not None and isinstance(body.shape, yade.wrapper.Sphere) and body.dynamic


def id_map(ids: Union[None, Mapping[int, int], Sequence[int]] = None) -> Dict[int, int]:
    """{scene particle id: YADE body id}. ``ids`` None: YADE's dynamic spheres in body-id order
    take the scene ids 0, 1, 2, ... (clumps, walls, facets, boxes and fixed spheres are left
    out); a sequence: its i-th body takes scene id i; a mapping: as given. Raises BadInput for a
    body that is missing, not a sphere, or mapped twice."""
    if ids is None:
        spheres = [b.id for b in O.bodies if _is_coupled_sphere(b)]
        return {i: body for i, body in enumerate(spheres)}
    pairs = ids.items() if isinstance(ids, Mapping) else enumerate(ids)
    out: Dict[int, int] = {}
    seen: Dict[int, int] = {}
    for scene_id, body_id in pairs:
        scene_id, body_id = int(scene_id), int(body_id)
        if scene_id < 0:
            raise BadInput(f"scene particle id {scene_id} is negative (ids are 0, 1, 2, ...)")
        if body_id in seen:
            raise BadInput(f"YADE body {body_id} is mapped to scene particles {seen[body_id]} "
                           f"and {scene_id}: one body per particle")
        body = O.bodies[body_id] if 0 <= body_id < len(O.bodies) else None
        if body is None:
            raise BadInput(f"scene particle {scene_id} is mapped to YADE body {body_id}, which "
                           f"does not exist ({len(O.bodies)} bodies)")
        if not isinstance(body.shape, yade.wrapper.Sphere):
            raise BadInput(f"scene particle {scene_id} is mapped to YADE body {body_id}, a "
                           f"{type(body.shape).__name__}: only spheres are coupled")
        seen[body_id] = scene_id
        out[scene_id] = body_id
    return out


def _check_against_scene(ids: Dict[int, int], scene: lbmdem_scene.Scene) -> None:
    """The scene's particles are the run's: the same count, no id it does not have. A scene
    without particles leaves them to the DEM (up to `coupling.capacity`)."""
    n = len(scene.particles)
    if n == 0:
        if len(ids) > scene.capacity:
            raise BadInput(f"YADE couples {len(ids)} spheres, more than the capacity "
                           f"{scene.capacity} of the scene {scene.path} (coupling.capacity)")
        return
    unknown = sorted(i for i in ids if i >= n)
    if len(ids) != n:
        missing = sorted(set(range(n)) - set(ids))
        raise BadInput(f"YADE couples {len(ids)} spheres, the scene {scene.path} has {n} "
                       f"particles (ids 0 .. {n - 1}; missing: {_few(missing) or 'none'}, "
                       f"beyond: {_few(unknown) or 'none'}): build one YADE sphere per scene "
                       f"particle (lbmdem_scene.Scene.load(PATH).particles) or map them with "
                       f"ids={{scene_id: body_id}}")
    if unknown:
        body = ids[unknown[0]]
        raise BadInput(f"YADE body {body} is mapped to scene particle {unknown[0]}, which the "
                       f"scene {scene.path} does not have (its particles are 0 .. {n - 1}); "
                       f"{len(unknown)} such id(s)")


def _warn_if_unlike_scene(ids: Dict[int, int], scene: lbmdem_scene.Scene) -> None:
    """A warning (not an error: the script may mean it) where a sphere's radius or position is
    not its scene particle's."""
    unlike = []
    for p in scene.particles:
        body = O.bodies[ids[p.id]]
        dr = abs(body.shape.radius - p.radius)
        dx = max(abs(body.state.pos[a] - p.position[a]) for a in range(3))
        if dr > 1e-9 * p.radius or dx > 1e-9 * p.radius:
            unlike.append((p, body))
    if unlike:
        p, body = unlike[0]
        _say(f"warning: {len(unlike)} of {len(ids)} YADE spheres are not where or as large as "
             f"their scene particles, e.g. particle {p.id} (body {body.id}): radius "
             f"{body.shape.radius:g} m at {tuple(body.state.pos)} in YADE, {p.radius:g} m at "
             f"{p.position} in the scene")


def _few(items: list) -> str:
    return ", ".join(str(i) for i in items[:8]) + (", ..." if len(items) > 8 else "")


# ---------------------------------------------------------------------------------------------
# YADE's side of the physics: engines, gravity, sub-steps
# ---------------------------------------------------------------------------------------------

def _newton():
    found = [e for e in O.engines if isinstance(e, yade.wrapper.NewtonIntegrator)]
    if len(found) != 1:
        raise BadInput(f"O.engines has {len(found)} NewtonIntegrator(s): the coupling needs "
                       f"exactly one (it applies gravity and moves the spheres)")
    return found[0]


def _check_engines() -> None:
    newton = _newton()
    steppers = [type(e).__name__ for e in O.engines
                if isinstance(e, yade.wrapper.TimeStepper) and e.active]
    if steppers:
        raise BadInput(f"a time stepper ({', '.join(steppers)}; YADE's default O.engines has "
                       f"one) would change O.dt within a fluid step: leave it out of O.engines "
                       f"or set its active = False, and set O.dt (or pass max_dt=...)")
    if newton.damping != 0.0:
        _say(f"warning: NewtonIntegrator.damping = {newton.damping:g}: YADE's numerical damping "
             f"also damps the motion the fluid drives (set damping=0)")


def _set_gravity(welcome: lbmdem.Welcome) -> None:
    """Gravity is YADE's (Hello declares GRAVITY), at the scene's value: the fluid's buoyancy
    balances the scene's gravity. A NewtonIntegrator without gravity gets the scene's."""
    newton = _newton()
    scene_g = Vector3(*welcome.gravity)
    yade_g = newton.gravity
    if yade_g.norm() == 0.0:
        newton.gravity = scene_g
        if scene_g.norm() != 0.0:
            _say(f"NewtonIntegrator.gravity set to the scene's {tuple(scene_g)} m/s^2")
        return
    if (yade_g - scene_g).norm() > 1e-9 * scene_g.norm():
        raise BadInput(f"YADE's gravity {tuple(yade_g)} m/s^2 is not the scene's "
                       f"{tuple(scene_g)}: the fluid's buoyancy balances the scene's gravity; "
                       f"set NewtonIntegrator.gravity to the scene's (or leave it zero)")


def _substeps(fluid_dt: float, max_dt: Optional[float]) -> int:
    """k YADE steps per fluid step. Without ``max_dt``, O.dt must divide the fluid step (and is
    then set to fluid dt / k exactly, so the two clocks agree); with it, O.dt becomes the
    largest fluid dt / k not above ``max_dt``."""
    if max_dt is not None:
        if not (max_dt > 0.0 and math.isfinite(max_dt)):
            raise BadInput(f"max_dt = {max_dt!r}: must be a positive number of seconds")
        k = max(1, math.ceil(fluid_dt / max_dt * (1.0 - WHOLE_TOLERANCE)))
    else:
        ratio = fluid_dt / O.dt
        k = round(ratio)
        if k < 1 or abs(k * O.dt - fluid_dt) > WHOLE_TOLERANCE * fluid_dt:
            fit = max(1, math.ceil(ratio))
            raise BadInput(f"the fluid step {fluid_dt:.10g} s is not a whole number of YADE "
                           f"steps O.dt = {O.dt:.10g} s (ratio {ratio:.6g}): set O.dt to the "
                           f"fluid step divided by a whole number, e.g. {fluid_dt / fit:.10g} s "
                           f"({fit} steps), or pass max_dt=O.dt and the coupling picks it")
    O.dt = fluid_dt / k
    return k


def _periodic_wrap(welcome: lbmdem.Welcome):
    """(axes, lo, length) to wrap centres into the domain along the Welcome's periodic axes; YADE
    must then be periodic with the domain's length along them (PROTOCOL.md 6.2)."""
    axes = np.array(welcome.periodic_axes())
    lo, hi = np.array(welcome.domain_min[:]), np.array(welcome.domain_max[:])
    if not axes.any():
        return None
    names = "".join(n for n, p in zip("xyz", axes) if p)
    if not O.periodic:
        raise BadInput(f"the scene is periodic along {names}: make YADE periodic too "
                       f"(O.periodic = True, O.cell.setBox(...)) with the domain's lengths")
    size = np.array([O.cell.hSize[a, a] for a in range(3)])
    if np.any(np.abs(size - (hi - lo))[axes] > 1e-9 * (hi - lo)[axes]):
        raise BadInput(f"YADE's periodic cell {size.tolist()} m is not the domain "
                       f"{(hi - lo).tolist()} m along {names}")
    return axes, lo, hi - lo


# ---------------------------------------------------------------------------------------------
# The exchange: YADE's spheres -> states, the fluid's loads -> permanent forces
# ---------------------------------------------------------------------------------------------

class _Spheres:
    """The coupled spheres: their states out, the fluid's loads in (held as permanent forces)."""

    def __init__(self, ids: Dict[int, int], wrap=None):
        self.scene_ids = list(ids)
        self.body_ids = [ids[i] for i in self.scene_ids]
        self.wrap = wrap
        #: The run's scene (None: not given).
        self.scene = None

    def __len__(self) -> int:
        return len(self.body_ids)

    def states(self) -> np.ndarray:
        """States of the coupled spheres; a body the script erased leaves the run (the protocol
        lets the count change)."""
        bodies = [O.bodies[b] for b in self.body_ids]
        if any(b is None for b in bodies):
            keep = [i for i, b in enumerate(bodies) if b is not None]
            self.scene_ids = [self.scene_ids[i] for i in keep]
            self.body_ids = [self.body_ids[i] for i in keep]
            bodies = [bodies[i] for i in keep]
        rows = np.empty((len(bodies), 10))
        for i, body in enumerate(bodies):
            s = body.state
            p, v, w = s.pos, s.vel, s.angVel
            rows[i] = (p[0], p[1], p[2], v[0], v[1], v[2], w[0], w[1], w[2], body.shape.radius)
        out = np.zeros(len(bodies), lbmdem.STATE_DTYPE)
        out["id"] = self.scene_ids
        out["position"] = rows[:, 0:3]
        if self.wrap is not None:
            axes, lo, length = self.wrap
            out["position"] = np.where(axes, lo + np.mod(rows[:, 0:3] - lo, length), rows[:, 0:3])
        out["velocity"] = rows[:, 3:6]
        out["angular_velocity"] = rows[:, 6:9]
        out["radius"] = rows[:, 9]
        return out

    def hold(self, loads: np.ndarray) -> None:
        """The fluid's force and torque, held over the fluid step's YADE steps (ForceResetter
        keeps permanent forces; an O.forces.addF from here would be wiped)."""
        set_f, set_t = O.forces.setPermF, O.forces.setPermT
        for body, f, t in zip(self.body_ids, loads["force"].tolist(), loads["torque"].tolist()):
            set_f(body, Vector3(*f))
            set_t(body, Vector3(*t))

    def release(self) -> None:
        """Removes the fluid's loads, so that the script's YADE steps after the run have none."""
        zero = Vector3(0.0, 0.0, 0.0)
        for body in self.body_ids:
            if O.bodies[body] is not None:
                O.forces.setPermF(body, zero)
                O.forces.setPermT(body, zero)


# ---------------------------------------------------------------------------------------------
# Ctrl-C, messages, exit status
# ---------------------------------------------------------------------------------------------

class _StopRequest:
    """Ctrl-C or SIGTERM: STOP goes with the next states; a second one leaves at once."""

    def __init__(self):
        self.requested = False
        self._previous = {}

    def __call__(self) -> bool:
        return self.requested

    def _on_signal(self, signum, _frame):
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True
        _say(f"{signal.Signals(signum).name}: stopping (STOP goes with the next states)")

    def install(self) -> None:
        for sig in (signal.SIGINT, signal.SIGTERM):
            self._previous[sig] = signal.signal(sig, self._on_signal)

    def restore(self) -> None:
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


def _say(message: str) -> None:
    print(f"{NAME}: {message}", file=sys.stderr, flush=True)


def _software() -> str:
    return f"YADE {getattr(yade.config, 'version', '?')} lbmdem_yade 1.0"


# ---------------------------------------------------------------------------------------------
# The run
# ---------------------------------------------------------------------------------------------

def couple(run: Optional[str] = None, scene: Optional[str] = None,
           ids: Union[None, Mapping[int, int], Sequence[int]] = None,
           max_dt: Optional[float] = None, timeout_s: float = 10.0,
           exit_on_error: bool = True, loads: str = "follow") -> Coupled:
    """Runs YADE as the DEM of the lbm-server run ``run`` until its last step.

    run: the name lbm-server printed (``DEM service: RUN``; default: $LBMDEM_RUN).
    scene: the run's scene file (default: $LBMDEM_SCENE): the coupled spheres must then be its
        particles, one per particle id (a scene without particles leaves them to YADE).
    ids: the id map (:func:`id_map`): None (YADE's dynamic spheres in body order are scene ids
        0, 1, ...), a sequence of body ids (the i-th is scene id i) or {scene id: body id}.
    max_dt: None: O.dt must divide the fluid step; a number: O.dt becomes the largest fluid
        step / k not above it (e.g. ``0.5 * PWaveTimeStep()``).
    timeout_s: longest wait for a live fluid server that does not answer.
    exit_on_error: exit the process (2 bad input, 1 broken link) instead of raising.
    loads: "follow": the fluid's loads follow the spheres within a fluid step as the scene's
        coupling.substep_drag and coupling.lubrication say (following_loads.py; the films are
        integrated here); "held": held constant, the fluid adds its own lubrication.
    """
    stop = _StopRequest()
    stop.install()
    link = None
    spheres = None
    try:
        run = _run_name(run)
        if loads not in ("follow", "held"):
            raise BadInput(f"loads = {loads!r}: 'follow' or 'held'")
        spheres, hello = _prepare(scene or os.environ.get(SCENE_ENV), ids, loads == "follow")
        link = lbmdem.DemLink(run, timeout_s=timeout_s, interrupt=stop)
        return _exchange(link, hello, spheres, max_dt, stop)
    except BadInput as e:
        _say(f"error: {e}")
        if e.run_over:
            _close(link)
        else:
            _end_run(link, run, timeout_s)
        return _fail(e, EXIT_BAD_INPUT, exit_on_error)
    except lbmdem.LinkError as e:
        _close(link)
        _say(f"error: {e}")
        return _fail(e, 1, exit_on_error)
    except KeyboardInterrupt as e:
        _close(link)
        _say("interrupted twice: left at once")
        return _fail(e, 1, exit_on_error)
    except Exception as e:  # noqa: BLE001 - YADE or the script failed mid-run: report, leave
        _close(link)
        last = None if link is None else link.last_completed
        _say(f"error: {type(e).__name__}: {e} (last completed step "
             f"{'none' if last is None else last})")
        return _fail(e, 1, exit_on_error)
    finally:
        stop.restore()
        if spheres is not None:
            spheres.release()


def _run_name(run: Optional[str]) -> str:
    run = run or os.environ.get(RUN_ENV)
    if not run:
        raise BadInput(f"no run name: pass the name lbm-server printed (DEM service: RUN) "
                       f"or set {RUN_ENV}")
    return run


def _prepare(scene_path: Optional[str], ids, follow: bool = True):
    """Checks the YADE script against the scene before joining; returns the spheres and Hello."""
    coupled = id_map(ids)
    scene = None
    if scene_path:
        try:
            scene = lbmdem_scene.Scene.load(scene_path)
        except (OSError, ValueError, KeyError, TypeError) as e:
            raise BadInput(f"cannot read the scene {scene_path}: {e}") from None
        _check_against_scene(coupled, scene)
        if scene.particles:
            _warn_if_unlike_scene(coupled, scene)
    if not coupled:
        _say("warning: no dynamic sphere to couple: the fluid sees no particle")
    _check_engines()
    scene = scene if follow else None  # the loads within the step follow the scene's coupling
    films = lbmdem.Physics.LUBRICATION if scene is not None and scene.lubrication else 0
    hello = lbmdem.Hello.new(lbmdem.Units.si(),
                             lbmdem.Physics.GRAVITY | lbmdem.Physics.CONTACTS | films,
                             initial_count=len(coupled), software=_software())
    spheres = _Spheres(coupled)
    spheres.scene = scene
    return spheres, hello


def _exchange(link: lbmdem.DemLink, hello: lbmdem.Hello, spheres: _Spheres,
              max_dt: Optional[float], stop: _StopRequest) -> Coupled:
    """Joins the run, then steps: states out, loads in, k YADE steps with the loads held."""
    try:
        welcome = link.connect(hello)
    except lbmdem.BadCount as e:
        raise BadInput(e.message) from None
    except lbmdem.Refused as e:
        if "CAPACITY_EXCEEDED" in e.message:  # the fluid refused, and ends the run itself
            raise BadInput(e.message, run_over=True) from None
        raise
    dt = welcome.dt
    k = _substeps(dt, max_dt)
    _set_gravity(welcome)
    spheres.wrap = _periodic_wrap(welcome)
    following = _following(spheres, welcome)
    if following is not None and O.dt > following.step_limit():
        k = math.ceil(dt / following.step_limit())
        O.dt = dt / k
        _say(f"the fluid's loads within a step (PROTOCOL.md 3.2, 4.5) need YADE steps of at most "
             f"{following.step_limit():g} s: O.dt = {O.dt:g} s (fluid step / {k})")
    _say(f"connected to {welcome.software_text()} (pid {welcome.pid}): {welcome.steps} steps "
         f"of {dt:g} s, {len(spheres)} spheres, {k} YADE steps of {O.dt:g} s each, capacity "
         f"{welcome.capacity}, fluid physics {lbmdem.Physics.names(welcome.physics)}")
    step = 0
    while True:
        flags = lbmdem.StepFlags.STOP if stop.requested else 0
        link.send_states(step, step * dt, spheres.states(), flags)
        header, loads = link.receive_forces(step)
        if flags or header.flags & (lbmdem.StepFlags.FINAL | lbmdem.StepFlags.STOP):
            break
        if step + 1 >= welcome.steps:
            raise lbmdem.BadReply(f"the {lbmdem.FLUID} did not mark the reply to step {step}, "
                                  f"the last of {welcome.steps}, FINAL", step)
        if following is not None:
            following.hold(loads)
            following.advance(k)
        else:
            spheres.hold(loads)
            for _ in range(k):
                O.step()
        step += 1
    link.close()
    ending = ("interrupted" if flags else
              "final" if header.flags & lbmdem.StepFlags.FINAL else "fluid-stop")
    said = {"final": "completed", "interrupted": "stopped on request after",
            "fluid-stop": "the fluid server stopped the run after"}[ending]
    _say(f"{said} {step + 1} steps")
    print(f"{NAME}: completed {step + 1} steps, {len(spheres)} particles, last step {step}",
          flush=True)
    return Coupled(step + 1, ending, len(spheres), k, dt)


def _following(spheres: _Spheres, welcome: lbmdem.Welcome):
    """The loads that follow the spheres within a fluid step (following_loads.py), as the
    scene's coupling.substep_drag and coupling.lubrication say; None: held constant."""
    loads = following_loads.within_step(spheres.scene, welcome)
    if loads is None:
        return None
    return following_loads.FollowingLoads(loads, spheres.scene_ids, spheres.body_ids)


def _end_run(link: Optional[lbmdem.DemLink], run: Optional[str], timeout_s: float) -> None:
    """Bad input: ends the run with STOP on the next step (no particles), so that the fluid
    server does not wait for a DEM that will not come; then removes this side's ports."""
    try:
        if link is None or link.welcome is None:
            _close(link)
            if not run:
                return
            link = lbmdem.DemLink(run, timeout_s=timeout_s)
            link.connect(lbmdem.Hello.new(lbmdem.Units.si(), lbmdem.Physics.GRAVITY,
                                          initial_count=0, software=_software()))
        step = 0 if link.last_completed is None else link.last_completed + 1
        link.send_states(step, step * link.welcome.dt, np.zeros(0, lbmdem.STATE_DTYPE),
                         lbmdem.StepFlags.STOP)
        link.receive_forces(step)
        _say(f"ended the run {run} with STOP at step {step}")
    except lbmdem.LinkError as e:
        _say(f"could not end the run {run}: {e}")
    finally:
        _close(link)


def _close(link: Optional[lbmdem.DemLink]) -> None:
    if link is not None:
        link.close()


def _fail(error: BaseException, status: int, exit_on_error: bool):
    if exit_on_error:
        sys.stdout.flush()
        sys.exit(status)
    raise error
