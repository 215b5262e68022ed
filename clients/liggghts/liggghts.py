"""LIGGGHTS as a library, loaded at run time with ctypes (Debian's libliggghts3, LIGGGHTS 3.8).

The C library interface of LAMMPS 2013 (``library.h``: ``lammps_open_no_mpi``, ``lammps_command``,
``lammps_extract_atom``, ``lammps_extract_global``) drives LIGGGHTS. Two things it lacks are reached
through symbols the library exports, each checked before use so that a build with another layout
is refused with a message instead of a crash:

- ``fix external``'s callback: ``FixExternal::set_callback`` is a C++ member function, called as a
  C function whose first argument is the fix. The fix comes from ``Modify::find_fix_id``; the
  ``Modify`` object is the member of the ``LAMMPS`` object whose virtual table is ``Modify``'s,
  and the fix found must have ``FixExternal``'s virtual table (``_ZTV...`` symbols).
- the unit style: ``Update::unit_style``, at its offset from ``Update::dt`` in ``update.h``, used
  only when the addresses ``lammps_extract_global`` gives for ``ntimestep``, ``atime`` and
  ``firststep`` sit at their offsets from ``dt`` in the same header, and read through
  ``/proc/self/mem`` (a bad address reads as nothing).

No compiler, headers or MPI development files are needed.
"""

from __future__ import annotations

import ctypes
import os
from typing import Callable, Optional

import numpy as np

#: The library's file name (Debian: package libliggghts3); LIGGGHTS_LIBRARY overrides it.
LIBRARY = "libliggghts.so.3"

INSTALL_HINT = ("install it: sudo apt-get install liggghts (Debian and Ubuntu; the library is the "
                "package libliggghts3), or set LIGGGHTS_LIBRARY to the path of a libliggghts.so")

_dp = ctypes.POINTER(ctypes.c_double)
_dpp = ctypes.POINTER(_dp)

#: ``FixExternal::FnPtr``: (caller, timestep, nlocal, tag, x, fexternal); bigint is int64_t and
#: tagint int in Debian's build (LAMMPS_SMALLBIG).
Callback = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_int64, ctypes.c_int,
                            ctypes.POINTER(ctypes.c_int), _dpp, _dpp)

# Itanium C++ ABI names of what the C interface lacks.
_SET_CALLBACK = "_ZN9LAMMPS_NS11FixExternal12set_callbackEPFvPvliPiPPdS4_ES1_"
_FIND_FIX_ID = "_ZN9LAMMPS_NS6Modify11find_fix_idEPKc"
_FIND_FIX_STYLE = "_ZN9LAMMPS_NS6Modify14find_fix_styleEPKci"
_VTABLE_MODIFY = "_ZTVN9LAMMPS_NS6ModifyE"
_VTABLE_FIX_EXTERNAL = "_ZTVN9LAMMPS_NS11FixExternalE"
#: A vtable pointer points past the offset-to-top and type-info words.
_VTABLE_SKIP = 16
#: The LAMMPS object starts with 14 pointers to its parts (lammps.h: memory ... timer).
_LAMMPS_PARTS = 14
#: Offsets from Update::dt in update.h (LIGGGHTS 3.8): checked ones and unit_style.
_UPDATE_CHECKS = {b"ntimestep": 24, b"atime": 48, b"firststep": 64}
_UNIT_STYLE = 152


class NotInstalled(Exception):
    """The LIGGGHTS library cannot be loaded."""


class Unsupported(Exception):
    """This LIGGGHTS build does not have what the adapter needs."""


def load_library() -> ctypes.CDLL:
    """The LIGGGHTS library, or NotInstalled saying how to install it."""
    name = os.environ.get("LIGGGHTS_LIBRARY") or LIBRARY
    try:
        # RTLD_GLOBAL: Open MPI's components, loaded later, look up libmpi's symbols.
        lib = ctypes.CDLL(name, mode=ctypes.RTLD_GLOBAL)
    except OSError as e:
        raise NotInstalled(f"LIGGGHTS is not installed ({name} cannot be loaded: {e}); "
                           f"{INSTALL_HINT}") from None
    for fn, args, res in (
        ("lammps_open_no_mpi", [ctypes.c_int, ctypes.POINTER(ctypes.c_char_p),
                                ctypes.POINTER(ctypes.c_void_p)], None),
        ("lammps_close", [ctypes.c_void_p], None),
        ("lammps_file", [ctypes.c_void_p, ctypes.c_char_p], None),
        ("lammps_command", [ctypes.c_void_p, ctypes.c_char_p], ctypes.c_char_p),
        ("lammps_extract_global", [ctypes.c_void_p, ctypes.c_char_p], ctypes.c_void_p),
        ("lammps_extract_atom", [ctypes.c_void_p, ctypes.c_char_p], ctypes.c_void_p),
    ):
        try:
            f = getattr(lib, fn)
        except AttributeError:
            raise NotInstalled(f"{name} is not a LIGGGHTS library with the LAMMPS C interface "
                               f"(no {fn}); {INSTALL_HINT}") from None
        f.argtypes, f.restype = args, res
    return lib


def peek(address: int, size: int) -> Optional[bytes]:
    """``size`` bytes of this process at ``address``, or None where nothing is mapped."""
    if not address:
        return None
    try:
        fd = os.open("/proc/self/mem", os.O_RDONLY)
    except OSError:
        return None
    try:
        raw = os.pread(fd, size, address)
        return raw if len(raw) == size else None
    except OSError:
        return None
    finally:
        os.close(fd)


def _word(address: int) -> Optional[int]:
    raw = peek(address, 8)
    return int.from_bytes(raw, "little") if raw is not None else None


class Atoms:
    """numpy views of the owned atoms' arrays (valid until LIGGGHTS runs again)."""

    def __init__(self, lmp: "Liggghts"):
        n = lmp.nlocal()
        self.count = n
        self.tag = lmp.int_vector(b"id", n)
        self.radius = lmp.vector(b"radius", n)
        self.x, self.v = lmp.array(b"x", n), lmp.array(b"v", n)
        self.omega = lmp.array(b"omega", n)
        self.f, self.torque = lmp.array(b"f", n), lmp.array(b"torque", n)


class Liggghts:
    """One LIGGGHTS instance in this process (no MPI: one rank owns every atom)."""

    def __init__(self, lib: ctypes.CDLL, args: list):
        self.lib = lib
        argv_list = [b"liggghts"] + [a.encode() for a in args]
        argv = (ctypes.c_char_p * len(argv_list))(*argv_list)
        handle = ctypes.c_void_p()
        lib.lammps_open_no_mpi(len(argv_list), argv, ctypes.byref(handle))
        if not handle.value:
            raise Unsupported("lammps_open_no_mpi returned no instance")
        self.handle = handle.value
        self._callback = None  # keeps the C callable alive while LIGGGHTS may call it
        self._views = {}

    def file(self, path: str) -> None:
        self.lib.lammps_file(self.handle, path.encode())

    def command(self, text: str) -> None:
        self.lib.lammps_command(self.handle, text.encode())

    def close(self) -> None:
        if self.handle:
            self.lib.lammps_close(self.handle)
            self.handle = 0

    # -- data --------------------------------------------------------------------------------

    def _global(self, name: bytes) -> int:
        return self.lib.lammps_extract_global(self.handle, name) or 0

    def nlocal(self) -> int:
        return ctypes.c_int.from_address(self._global(b"nlocal")).value

    def natoms(self) -> int:
        return ctypes.c_int64.from_address(self._global(b"natoms")).value

    def ntimestep(self) -> int:
        return ctypes.c_int64.from_address(self._global(b"ntimestep")).value

    def timestep(self) -> float:
        return ctypes.c_double.from_address(self._global(b"dt")).value

    def has_atom_array(self, name: str) -> bool:
        return bool(self.lib.lammps_extract_atom(self.handle, name.encode()))

    def _atom(self, name: bytes) -> int:
        address = self.lib.lammps_extract_atom(self.handle, name)
        if not address:
            raise Unsupported(f"the atom style has no per-atom '{name.decode()}'")
        return address

    def array(self, name: bytes, n: int) -> np.ndarray:
        """A per-atom double[n][3] (LAMMPS allocates its rows as one block)."""
        rows = ctypes.cast(self._atom(name), _dpp)
        return self._view(ctypes.cast(rows[0], ctypes.c_void_p).value, (n, 3))

    def vector(self, name: bytes, n: int) -> np.ndarray:
        return self._view(self._atom(name), (n,))

    def _view(self, address: Optional[int], shape: tuple) -> np.ndarray:
        """A numpy view of the doubles at ``address`` (kept while the address and shape are: a
        view costs tens of microseconds to make, and the callback asks for several each step)."""
        if not address or not shape[0]:
            return np.zeros(shape)
        key = (address, shape)
        view = self._views.get(key)
        if view is None:
            if len(self._views) > 64:
                self._views.clear()
            data = ctypes.cast(address, _dp)
            view = self._views[key] = np.ctypeslib.as_array(data, shape=shape)
        return view

    def int_vector(self, name: bytes, n: int) -> np.ndarray:
        data = ctypes.cast(self._atom(name), ctypes.POINTER(ctypes.c_int))
        return np.ctypeslib.as_array(data, shape=(n,)) if n else np.zeros(0, np.int32)

    def atoms(self) -> Atoms:
        return Atoms(self)

    # -- what the C interface lacks ----------------------------------------------------------

    def unit_style(self) -> Optional[str]:
        """The deck's ``units`` (si, cgs, ...), or None where this build's layout is not known."""
        dt = self._global(b"dt")
        if not dt or any(self._global(name) != dt + off for name, off in _UPDATE_CHECKS.items()):
            return None
        text = peek(_word(dt + _UNIT_STYLE) or 0, 16)
        if text is None or b"\0" not in text:
            return None
        return text.split(b"\0", 1)[0].decode("ascii", errors="replace")

    def _vtable(self, symbol: str) -> int:
        try:
            return ctypes.addressof(ctypes.c_char.in_dll(self.lib, symbol)) + _VTABLE_SKIP
        except ValueError:
            raise Unsupported(f"this LIGGGHTS library does not export {symbol}") from None

    def _member(self, symbol: str, args: list, res):
        try:
            f = getattr(self.lib, symbol)
        except AttributeError:
            raise Unsupported(f"this LIGGGHTS library does not export {symbol}") from None
        f.argtypes, f.restype = args, res
        return f

    def _modify(self) -> int:
        """The LAMMPS object's Modify (fixes and computes), found by its virtual table."""
        vtable = self._vtable(_VTABLE_MODIFY)
        for i in range(_LAMMPS_PARTS):
            part = _word(self.handle + 8 * i)
            if part and _word(part) == vtable:
                return part
        raise Unsupported("no Modify object found in the LAMMPS instance (another layout)")

    def has_fix_style(self, style: str) -> bool:
        find = self._member(_FIND_FIX_STYLE, [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int],
                            ctypes.c_void_p)
        return bool(find(self._modify(), style.encode(), 0))

    def fix_external(self, fix_id: str, callback, group: str = "all", napply: int = 1) -> None:
        """Adds ``fix ID GROUP external pf/callback 1 NAPPLY`` and points it at ``callback``,
        called in post_force every step to fill fexternal (added to the force of the group's
        atoms at the steps that are multiples of NAPPLY): a Python ``callback(timestep, nlocal,
        tag, x, fexternal)``, or a C one as (its address, its caller pointer) (native.py)."""
        self.command(f"fix {fix_id} {group} external pf/callback 1 {napply}")
        find = self._member(_FIND_FIX_ID, [ctypes.c_void_p, ctypes.c_char_p], ctypes.c_void_p)
        fix = find(self._modify(), fix_id.encode())
        if not fix or _word(fix) != self._vtable(_VTABLE_FIX_EXTERNAL):
            raise Unsupported(f"fix {fix_id} is not a FixExternal (another layout)")
        set_callback = self._member(_SET_CALLBACK, [ctypes.c_void_p, ctypes.c_void_p,
                                                    ctypes.c_void_p], None)
        if isinstance(callback, tuple):
            set_callback(fix, callback[0], callback[1])
            return
        self._callback = Callback(lambda _caller, step, n, tag, x, fext:
                                  callback(step, n, tag, x, fext))
        set_callback(fix, ctypes.cast(self._callback, ctypes.c_void_p), None)
