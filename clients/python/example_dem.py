#!/usr/bin/env python3
"""A minimal external DEM for lbm-server: spheres in free flight under gravity and the fluid forces.

    lbm-server run SCENE.toml --dem external          # prints "DEM service: RUN"
    python3 clients/python/example_dem.py --service RUN [--particles N] [--density KG_M3]
                                          [--units LENGTH_M,TIME_S,MASS_KG]

Every step it sends the particle states, receives the hydrodynamic forces, and advances with
symplectic Euler (v += dt (F/m + g); x += dt v), reflecting elastically at the domain faces but
the periodic ones (Welcome.periodic), through which the spheres pass. It
applies gravity itself (Physics GRAVITY | BALLISTIC_STANDIN), so the fluid side must not.
Ctrl-C (or SIGTERM) sends STOP with the next states; the run then ends cleanly after that step.
"""

from __future__ import annotations

import argparse
import math
import os
import signal
import sys
import time

import numpy as np

import lbmdem

SOFTWARE = "lbmdem example_dem.py 1.0"


def grid_positions(n: int, lo: np.ndarray, hi: np.ndarray, radius: float) -> np.ndarray:
    """``n`` sphere centres on a regular grid filling the box [lo, hi], at least ``radius`` from
    every face (spheres may overlap when the box is too small; this DEM has no contacts)."""
    edge = hi - lo
    # Cells per axis proportional to the edges, enough cells for n spheres.
    scale = (n / float(np.prod(edge))) ** (1.0 / 3.0)
    cells = np.maximum(1, np.floor(edge * scale)).astype(int)
    axis = 0
    while int(np.prod(cells)) < n:
        axis = int(np.argmax(edge / cells))
        cells[axis] += 1
    i = np.arange(n)
    idx = np.stack([i % cells[0], (i // cells[0]) % cells[1], i // (cells[0] * cells[1])], axis=1)
    centre = lo + (idx + 0.5) * (edge / cells)
    return np.clip(centre, lo + radius, hi - radius)


def arguments() -> tuple[argparse.Namespace, tuple[float, float, float]] | None:
    """The command line and the units it names (length [m], time [s], mass [kg]); None, said,
    where a value is bad."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--service", default=os.environ.get("LBMDEM_RUN"),
                    help="run name printed by lbm-server (default: $LBMDEM_RUN, which "
                         "lbm-server run --dem-command sets)")
    ap.add_argument("--particles", type=int, default=64, help="number of spheres (default 64)")
    ap.add_argument("--density", type=float, default=2500.0,
                    help="particle density [kg/m^3] (default 2500)")
    ap.add_argument("--units", default="1,1,1",
                    help="the units this DEM speaks, each as its size in SI: length [m], time [s], "
                         "mass [kg] (default SI: 1,1,1; e.g. 1e-3,1e-3,1e-3 for mm, ms, g)")
    ap.add_argument("--timeout", type=float, default=10.0,
                    help="longest wait for a live but silent fluid server [s] (default 10)")
    args = ap.parse_args()
    if not args.service:
        ap.error("--service is required (or $LBMDEM_RUN)")
    if args.particles < 1:
        print("python-dem: error: --particles must be at least 1", file=sys.stderr)
        return None
    if not (args.density > 0.0 and math.isfinite(args.density)):
        print("python-dem: error: --density must be a positive number", file=sys.stderr)
        return None
    try:
        length_m, time_s, mass_kg = (float(u) for u in args.units.split(","))
    except ValueError:
        print(f"python-dem: error: --units {args.units!r}: must be three numbers LENGTH_M,TIME_S,MASS_KG",
              file=sys.stderr)
        return None
    return args, (length_m, time_s, mass_kg)


def stop_on_signals() -> dict:
    """Ctrl-C and SIGTERM set the returned ``{"flag": True}`` (STOP goes with the next states); a
    second one leaves at once (KeyboardInterrupt)."""
    stop_requested = {"flag": False}

    def on_signal(signum, _frame):
        if stop_requested["flag"]:  # second Ctrl-C: leave now
            raise KeyboardInterrupt
        stop_requested["flag"] = True
        print(f"python-dem: {signal.Signals(signum).name}: stopping (STOP goes with the next states)",
              file=sys.stderr, flush=True)

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    return stop_requested


class Spheres:
    """The spheres this DEM moves, from the Welcome: their states (sent as they are), mass, the
    box and its periodic axes, and gravity, all in this DEM's units."""

    def __init__(self, welcome, n: int, density_si: float, length_m: float, mass_kg: float):
        self.dt = welcome.dt
        self.lo = np.array(welcome.domain_min[:])
        self.hi = np.array(welcome.domain_max[:])
        self.g = np.array(welcome.gravity[:])
        self.periodic = np.array(welcome.periodic_axes())
        axes = [name for name, p in zip("xyz", self.periodic) if p]
        lo, hi = self.lo, self.hi
        print(f"python-dem: connected to {welcome.software_text()} (pid {welcome.pid}): "
              f"{welcome.steps} steps of {self.dt:g} s, domain {lo.tolist()} .. {hi.tolist()}, "
              f"periodic along {axes}, capacity {welcome.capacity}", file=sys.stderr, flush=True)

        radius = 0.02 * float(np.min(hi - lo))
        # Everything from the Welcome is in our units already; the density is given in SI.
        density = density_si * length_m ** 3 / mass_kg
        self.mass = density * 4.0 / 3.0 * math.pi * radius ** 3
        self.states = np.zeros(n, lbmdem.STATE_DTYPE)
        self.states["id"] = np.arange(n, dtype=np.uint64)
        self.states["position"] = grid_positions(n, lo, hi, radius)
        self.states["radius"] = radius
        self.low, self.high = lo + radius, hi - radius

    def advance(self, forces) -> None:
        """Symplectic Euler, then elastic reflection at the faces; along the periodic axes
        (Welcome.periodic) the spheres pass through and come back on the other side."""
        x = self.states["position"]  # views into the array that is sent
        v = self.states["velocity"]
        dt, lo, hi, low, high, periodic = self.dt, self.lo, self.hi, self.low, self.high, self.periodic
        v += dt * (forces["force"] / self.mass + self.g)
        x += dt * v
        x[:] = np.where(periodic, lo + np.mod(x - lo, hi - lo), x)
        below, above = (x < low) & ~periodic, (x > high) & ~periodic
        x[below] = 2.0 * np.broadcast_to(low, x.shape)[below] - x[below]
        x[above] = 2.0 * np.broadcast_to(high, x.shape)[above] - x[above]
        v[below | above] *= -1.0
        x[:] = np.where(periodic, x, np.clip(x, low, high))


def main() -> int:
    parsed = arguments()
    if parsed is None:
        return 1
    args, (length_m, time_s, mass_kg) = parsed
    units = lbmdem.Units(length_m, time_s, mass_kg)
    stop_requested = stop_on_signals()

    n = args.particles
    hello = lbmdem.Hello.new(
        units,
        lbmdem.Physics.GRAVITY | lbmdem.Physics.BALLISTIC_STANDIN,
        initial_count=n,
        software=SOFTWARE,
    )
    link = lbmdem.DemLink(args.service, timeout_s=args.timeout,
                          interrupt=lambda: stop_requested["flag"])
    last = None
    try:
        welcome = link.connect(hello)
        spheres = Spheres(welcome, n, args.density, length_m, mass_kg)
        round_trips = []
        step = 0
        while True:
            flags = lbmdem.StepFlags.STOP if stop_requested["flag"] else 0
            t0 = time.perf_counter()
            link.send_states(step, step * spheres.dt, spheres.states, flags)
            header, forces = link.receive_forces(step)  # checks step, count, ids
            round_trips.append(time.perf_counter() - t0)
            last = step
            ended = header.flags & (lbmdem.StepFlags.FINAL | lbmdem.StepFlags.STOP)
            if ended or flags:
                break
            if step + 1 >= welcome.steps:
                raise lbmdem.BadReply(f"the {lbmdem.FLUID} did not mark the reply to step {step}, "
                                      f"the last of {welcome.steps}, FINAL", last)
            spheres.advance(forces)
            step += 1
    except KeyboardInterrupt:
        link.close()
        print(f"python-dem: interrupted twice, left after step {last}", file=sys.stderr)
        return 1
    except lbmdem.LinkError as e:
        link.close()
        print(f"python-dem: error: {e}", file=sys.stderr)
        return 1
    except Exception as e:  # noqa: BLE001 - report anything, exit non-zero
        link.close()
        print(f"python-dem: error: {type(e).__name__}: {e} (last completed step "
              f"{last if last is not None else 'none'})", file=sys.stderr)
        return 1
    link.close()
    say_ended(round_trips, stop_requested["flag"], last, welcome.steps, n)
    return 0


def say_ended(round_trips: list, stopped: bool, last: int, steps: int, n: int) -> None:
    """The round trips' median and 99th percentile, how the run ended, and the steps completed."""
    rt = np.array(round_trips) * 1e6
    print(f"python-dem: round trip median {np.median(rt):.0f} us, p99 "
          f"{np.percentile(rt, 99):.0f} us over {rt.size} steps", file=sys.stderr)
    if stopped:
        print(f"python-dem: stopped on request after step {last}", file=sys.stderr)
    elif last + 1 < steps:
        print(f"python-dem: the fluid server stopped the run after step {last}", file=sys.stderr)
    print(f"python-dem: completed {last + 1} steps, {n} particles, last step {last}", flush=True)


if __name__ == "__main__":
    sys.exit(main())
