"""The adapter's per-step work in compiled code: clients/native (``liblbmdem_native.so``).

The workspace builds the library with lbm-server (``cargo build``); the adapter loads it at run
time with ctypes, and hands LIGGGHTS's ``fix external`` its C callback, so that no Python runs at
LIGGGHTS's steps. Once per fluid step :meth:`NativeLoads.states` gathers the atoms into the
fluid's particle states and :meth:`NativeLoads.hold` holds the fluid's reply; the callback writes
the held force and adds the held torque at each LIGGGHTS step, or, after :meth:`NativeLoads.follow`,
evaluates the loads that follow the atoms (the sub-step drag and the squeeze films, as
clients/python/substep_loads.py and dem-client do). :class:`held_loads.HeldLoads` does the same in
Python where the library is not built.

The library is found at ``$LBMDEM_NATIVE``, else as the newest of ``target/release``,
``target/debug`` and their ``deps`` (where ``cargo test`` leaves it) of the checkout these clients
belong to (``$CARGO_TARGET_DIR`` first).
"""

from __future__ import annotations

import ctypes
import os
from pathlib import Path
from typing import Optional

import numpy as np

import lbmdem

#: The library's file name, and the version of its functions' signatures this module speaks.
LIBRARY = "liblbmdem_native.so"
ABI_VERSION = 3

_dp = ctypes.POINTER(ctypes.c_double)


class NotBuilt(Exception):
    """The native helper is not built (or not this version)."""


def candidates() -> list:
    """Where the library may be, the explicit path first."""
    if os.environ.get("LBMDEM_NATIVE"):
        return [Path(os.environ["LBMDEM_NATIVE"])]
    roots = [Path(os.environ["CARGO_TARGET_DIR"])] if os.environ.get("CARGO_TARGET_DIR") else []
    roots.append(Path(__file__).resolve().parents[2] / "target")
    found = [r / p / LIBRARY for r in roots for p in ("release", "debug", "release/deps",
                                                      "debug/deps")]
    return sorted((p for p in found if p.exists()), key=lambda p: -p.stat().st_mtime)


def load_library() -> ctypes.CDLL:
    """The native helper (the first candidate of this version), or NotBuilt saying how to build
    it."""
    paths, why = candidates(), []
    for path in paths:
        try:
            lib = ctypes.CDLL(str(path))
        except OSError as e:
            why.append(f"{path} cannot be loaded: {e}")
            continue
        lib.lbmdem_native_abi.restype = ctypes.c_uint32
        if lib.lbmdem_native_abi() == ABI_VERSION:
            return _declare(lib, path)
        why.append(f"{path} is another version")
    raise NotBuilt(f"{LIBRARY} {'; '.join(why) if why else 'not found'} (build it: cargo build "
                   f"--release -p lbmdem-native, or set LBMDEM_NATIVE to its path)")


def _declare(lib: ctypes.CDLL, path: Path) -> ctypes.CDLL:
    """``lib`` with its functions' signatures."""
    lib.lbmdem_held_napply.restype = ctypes.c_int64
    vp, sz = ctypes.c_void_p, ctypes.c_size_t
    for fn, args, res in (
        ("lbmdem_loads_new", [vp, vp, vp], vp),
        ("lbmdem_loads_free", [vp], None),
        ("lbmdem_loads_follow", [vp, ctypes.c_double, ctypes.c_double, _dp, ctypes.c_int,
                                 ctypes.c_double, ctypes.c_double, sz,
                                 ctypes.POINTER(ctypes.c_int64), _dp, _dp, _dp], None),
        ("lbmdem_loads_hold", [vp, vp, sz, ctypes.c_int], ctypes.c_int),
        ("lbmdem_states", [vp, vp, sz, _dp, _dp, ctypes.POINTER(ctypes.c_uint8)], ctypes.c_ssize_t),
        ("lbmdem_loads_error", [vp, ctypes.c_char_p, sz], sz),
    ):
        f = getattr(lib, fn)
        f.argtypes, f.restype = args, res
    lib.path = path
    return lib


def _doubles(values) -> ctypes.Array:
    values = [float(v) for v in values]
    return (ctypes.c_double * max(len(values), 1))(*values)


class NativeLoads:
    """The held (or following) loads and the states, in clients/native; the same interface as
    :class:`held_loads.HeldLoads` for the adapter's loop."""

    def __init__(self, lib: ctypes.CDLL, lmp):
        self.lib, self.lmp = lib, lmp
        address = lambda fn: ctypes.cast(getattr(lmp.lib, fn), ctypes.c_void_p).value  # noqa: E731
        self.ctx = lib.lbmdem_loads_new(lmp.handle, address("lammps_extract_atom"),
                                        address("lammps_extract_global"))
        self.within = None

    def follow(self, within) -> None:
        """The loads follow the atoms as ``within`` (a :class:`substep_loads.SubstepLoads`)
        describes: the same drag and films, evaluated here."""
        films = within.films
        walls = [] if films is None else list(zip(films.wall_axis, films.wall_at, films.wall_sign))
        axis = (ctypes.c_int64 * max(len(walls), 1))(*[int(w[0]) for w in walls])
        periods = films.periods if films is not None else np.zeros(3)
        self.lib.lbmdem_loads_follow(
            self.ctx, within.rate * within.dt, within.dt, _doubles(within.gravity),
            int(within.rate != 0.0), films.viscosity if films else 0.0,
            films.cutoff if films else 0.0, len(walls), axis, _doubles(w[1] for w in walls),
            _doubles(w[2] for w in walls), _doubles(periods))
        self.within = within

    def attach(self, fix_id: str) -> list:
        """Adds the ``fix external`` that applies the loads. Held, its per-atom array keeps the
        force in the atoms' order (LIGGGHTS moves it with them), and a second one, of no atoms,
        keeps the torque; the second's callback adds both to the atoms' force and torque in one
        pass, the fixes' own loop skipped (``napply`` a step never reached). Returns the fixes'
        IDs."""
        address = lambda fn: ctypes.cast(getattr(self.lib, fn), ctypes.c_void_p).value  # noqa: E731
        if self.within is not None:
            self.lmp.fix_external(fix_id, (address("lbmdem_loads_apply"), self.ctx))
            return [fix_id]
        never = self.lib.lbmdem_held_napply()
        self.lmp.fix_external(fix_id, (address("lbmdem_loads_apply"), self.ctx), napply=never)
        group = f"{fix_id}_none"
        self.lmp.command(f"group {group} id 0")  # no atom has ID 0
        self.lmp.fix_external(f"{fix_id}_torque", (address("lbmdem_torque_apply"), self.ctx),
                              group, napply=never)
        return [fix_id, f"{fix_id}_torque"]

    def states(self, lo, hi, periodic) -> np.ndarray:
        """The atoms as the fluid's particle states (ids atom ID - 1, centres wrapped along the
        periodic axes)."""
        out = np.zeros(self.lmp.nlocal(), lbmdem.STATE_DTYPE)
        flags = (ctypes.c_uint8 * 3)(*[int(bool(p)) for p in periodic])
        n = self.lib.lbmdem_states(self.ctx, out.ctypes.data, len(out), _doubles(lo), _doubles(hi),
                                   flags)
        if n < 0:
            self.check()
        return out[:n]

    def hold(self, replies: np.ndarray, ran: bool) -> None:
        """Holds the fluid's reply (an array of lbmdem.REPLY_DTYPE); ``ran``: LIGGGHTS ran
        before (its summed forces take the change of the loads)."""
        replies = np.ascontiguousarray(replies, lbmdem.REPLY_DTYPE)
        if self.lib.lbmdem_loads_hold(self.ctx, replies.ctypes.data, len(replies), int(ran)):
            self.check()

    def error(self) -> Optional[str]:
        buf = ctypes.create_string_buffer(512)
        n = self.lib.lbmdem_loads_error(self.ctx, buf, len(buf))
        return buf.value.decode(errors="replace") if n else None

    def check(self) -> None:
        """Raises what went wrong in the helper (the callback included) during the last run."""
        message = self.error()
        if message is not None:
            raise RuntimeError(f"fix external callback failed: {message}")

    def close(self) -> None:
        if self.ctx:
            self.lib.lbmdem_loads_free(self.ctx)
            self.ctx = None
