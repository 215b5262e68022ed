"""The wire of PROTOCOL.md: what crosses between the DEM and the fluid, byte for byte.

The protocol's constants and flags (Physics, Status, StepFlags, Capabilities), the per-step types
(ParticleState, ParticleReply, StepHeader) with their numpy mirrors (STATE_DTYPE, REPLY_DTYPE), the
handshake messages (Units, Hello, Welcome) with their layouts checked on import, and the check and
decoding of a handshake message (decode_welcome).
"""

from __future__ import annotations

import ctypes
import enum
import os
from typing import Optional

import numpy as np

from .errors import FLUID, Refused, VersionMismatch


# ---------------------------------------------------------------------------------------------
# Constants
# ---------------------------------------------------------------------------------------------

#: Version of the protocol this module speaks.
PROTOCOL_VERSION = 2
#: First four bytes of every handshake message: ASCII "LBDM" as a little-endian u32.
MAGIC = 0x4D44424C
assert MAGIC == int.from_bytes(b"LBDM", "little")
#: Length of the version-independent prefix (magic, version, size, kind).
PREFIX_LEN = 16
KIND_HELLO = 1
KIND_WELCOME = 2
#: Length of the NUL padded UTF-8 text fields.
TEXT_LEN = 64


class Physics(enum.IntFlag):
    """What physics a side applies (``Hello.physics``, ``Welcome.physics``)."""

    GRAVITY = 1 << 0
    BUOYANCY = 1 << 1
    STOKES_DRAG_STANDIN = 1 << 2  # retired (the Stokes-drag stand-in fluid): reserved, never sent
    LATTICE_BOLTZMANN = 1 << 3
    IMMERSED_BOUNDARY = 1 << 4
    CONTACTS = 1 << 5
    LUBRICATION = 1 << 6
    BALLISTIC_STANDIN = 1 << 7

    @staticmethod
    def exclusive() -> int:
        """Effects that exactly one side may apply."""
        return int(Physics.GRAVITY | Physics.BUOYANCY | Physics.LUBRICATION)

    @staticmethod
    def names(bits: int) -> list:
        return [p.name.lower().replace("_", "-") for p in Physics if int(bits) & int(p)]


class Status(enum.IntEnum):
    """Outcome of the handshake (``Welcome.status``)."""

    ACCEPTED = 0
    VERSION_MISMATCH = 1
    LAYOUT_MISMATCH = 2
    CAPACITY_EXCEEDED = 3
    BAD_UNITS = 4
    PHYSICS_CONFLICT = 5
    #: The run resumes from a checkpoint and the DEM does not declare Capabilities.CHECKPOINT.
    CANNOT_RESUME = 6


class StepFlags(enum.IntFlag):
    """Bits of ``StepHeader.flags``."""

    #: The sender wants the run to end after this step.
    STOP = 1
    #: Fluid -> DEM: the reply to the last step of the run.
    FINAL = 2
    #: Fluid -> DEM (to a DEM with Capabilities.CHECKPOINT): write your state for the next step
    #: into checkpoint_dir(), then dem.complete, before sending its states (PROTOCOL.md 6.4).
    CHECKPOINT = 4


class Capabilities(enum.IntFlag):
    """Bits of ``Hello.capabilities``."""

    #: The DEM writes its state when asked (StepFlags.CHECKPOINT) and resumes at first_step.
    CHECKPOINT = 1


# ---------------------------------------------------------------------------------------------
# Wire types (C layout, little-endian, 8-byte aligned, no padding)
# ---------------------------------------------------------------------------------------------

_u32, _u64, _f64 = ctypes.c_uint32, ctypes.c_uint64, ctypes.c_double
_vec3 = ctypes.c_double * 3


class ParticleState(ctypes.Structure):
    """DEM -> fluid, one per particle (88 bytes)."""

    _fields_ = [
        ("id", _u64),
        ("position", _vec3),
        ("velocity", _vec3),
        ("angular_velocity", _vec3),
        ("radius", _f64),
    ]

    @staticmethod
    def type_name() -> str:
        return "ParticleState"


class ParticleReply(ctypes.Structure):
    """Fluid -> DEM, one per particle, in the order of the states (56 bytes)."""

    _fields_ = [("id", _u64), ("force", _vec3), ("torque", _vec3)]

    @staticmethod
    def type_name() -> str:
        return "ParticleReply"


class StepHeader(ctypes.Structure):
    """User header of the per-step messages (32 bytes)."""

    _fields_ = [("step", _u64), ("time", _f64), ("count", _u64), ("flags", _u64)]

    @staticmethod
    def type_name() -> str:
        return "StepHeader"

    def has(self, flag: int) -> bool:
        return bool(self.flags & int(flag))

    def __repr__(self) -> str:
        return (f"StepHeader(step={self.step}, time={self.time!r}, count={self.count}, "
                f"flags={self.flags:#x})")


#: numpy mirror of ParticleState (use it for the arrays given to DemLink.send_states).
STATE_DTYPE = np.dtype({
    "names": ["id", "position", "velocity", "angular_velocity", "radius"],
    "formats": ["<u8", ("<f8", (3,)), ("<f8", (3,)), ("<f8", (3,)), "<f8"],
    "offsets": [0, 8, 32, 56, 80],
    "itemsize": 88,
})
#: numpy mirror of ParticleReply (the arrays DemLink.receive_forces returns).
REPLY_DTYPE = np.dtype({
    "names": ["id", "force", "torque"],
    "formats": ["<u8", ("<f8", (3,)), ("<f8", (3,))],
    "offsets": [0, 8, 32],
    "itemsize": 56,
})


class Units(ctypes.Structure):
    """The size in SI of one unit of length, time and mass. The wire speaks the DEM's units."""

    _fields_ = [("length_m", _f64), ("time_s", _f64), ("mass_kg", _f64)]

    @staticmethod
    def si() -> "Units":
        return Units(1.0, 1.0, 1.0)


def _text(value: str, n: int = TEXT_LEN) -> bytes:
    """Truncates ``value`` to ``n`` bytes of UTF-8 on a character boundary."""
    raw = value.encode("utf-8")[:n]
    return raw.decode("utf-8", errors="ignore").encode("utf-8")


def _field_text(raw: bytes) -> str:
    return raw.split(b"\0", 1)[0].decode("utf-8", errors="replace")


# The fields every handshake message opens with: the prefix (PROTOCOL.md 4.1, which
# `_check_prefix` reads: magic, protocol version, size in bytes, kind), then the sender's pid.
_PREFIX = [
    ("magic", _u32),
    ("version", _u32),
    ("size", _u32),
    ("kind", _u32),
    ("pid", _u64),
]


class Hello(ctypes.Structure):
    """DEM -> fluid, once, before step 0 (144 bytes)."""

    _fields_ = _PREFIX + [
        ("state_size", _u32),
        ("reply_size", _u32),
        ("header_size", _u32),
        ("capabilities", _u32),  # Capabilities bits (version 1: reserved, 0)
        ("units", Units),
        ("physics", _u64),
        ("initial_count", _u64),
        ("software", ctypes.c_char * TEXT_LEN),
    ]

    @staticmethod
    def type_name() -> str:
        return "Hello"

    @classmethod
    def new(cls, units: Optional[Units] = None, physics: int = 0, initial_count: int = 0,
            software: str = "lbmdem.py", capabilities: int = 0) -> "Hello":
        units = units if units is not None else Units.si()
        return cls(
            magic=MAGIC, version=PROTOCOL_VERSION, size=ctypes.sizeof(cls), kind=KIND_HELLO,
            pid=os.getpid(), state_size=ctypes.sizeof(ParticleState),
            reply_size=ctypes.sizeof(ParticleReply), header_size=ctypes.sizeof(StepHeader),
            capabilities=int(capabilities), units=Units(units.length_m, units.time_s, units.mass_kg),
            physics=int(physics), initial_count=int(initial_count), software=_text(software),
        )

    def to_bytes(self) -> bytes:
        return bytes(self)

    @classmethod
    def from_bytes(cls, raw: bytes) -> "Hello":
        _check_prefix(raw, KIND_HELLO, ctypes.sizeof(cls), "DEM client")
        return cls.from_buffer_copy(raw[: ctypes.sizeof(cls)])

    def software_text(self) -> str:
        return _field_text(self.software)


class Welcome(ctypes.Structure):
    """Fluid -> DEM, once, in answer to Hello (360 bytes). Quantities in the DEM's units."""

    _fields_ = _PREFIX + [
        ("status", _u32),
        ("periodic", _u32),  # periodic axes: bit 0 x, 1 y, 2 z; 0 none (PROTOCOL.md 4.4)
        ("capacity", _u64),
        ("steps", _u64),
        ("dt", _f64),
        ("domain_min", _vec3),
        ("domain_max", _vec3),
        ("gravity", _vec3),
        ("fluid_density", _f64),
        ("fluid_viscosity", _f64),
        ("physics", _u64),
        ("software", ctypes.c_char * TEXT_LEN),
        ("reason", ctypes.c_char * (2 * TEXT_LEN)),
        ("first_step", _u64),  # the run's first step: > 0 in a resumed run (PROTOCOL.md 6.4)
        ("cell_size", _f64),  # the lattice's cell size, the lubrication cut-off; 0 without one
    ]

    @staticmethod
    def type_name() -> str:
        return "Welcome"

    def to_bytes(self) -> bytes:
        return bytes(self)

    @classmethod
    def from_bytes(cls, raw: bytes) -> "Welcome":
        """Decodes a Welcome; raises VersionMismatch / Refused for anything unreadable."""
        _check_prefix(raw, KIND_WELCOME, ctypes.sizeof(cls), FLUID)
        return cls.from_buffer_copy(raw[: ctypes.sizeof(cls)])

    def software_text(self) -> str:
        return _field_text(self.software)

    def reason_text(self) -> str:
        return _field_text(self.reason)

    def periodic_axes(self) -> tuple:
        """(x, y, z): whether the domain is periodic along each axis (PROTOCOL.md 6.2)."""
        return tuple(bool(self.periodic & (1 << a)) for a in range(3))


def _check_layouts() -> None:
    """The layouts of PROTOCOL.md; a mismatch here is a bug in this file."""
    expect = {
        ParticleState: (88, {"position": 8, "velocity": 32, "angular_velocity": 56, "radius": 80}),
        ParticleReply: (56, {"force": 8, "torque": 32}),
        StepHeader: (32, {"time": 8, "count": 16, "flags": 24}),
        Units: (24, {"time_s": 8, "mass_kg": 16}),
        Hello: (144, {"pid": 16, "state_size": 24, "reply_size": 28, "header_size": 32,
                      "capabilities": 36, "units": 40, "physics": 64, "initial_count": 72, "software": 80}),
        Welcome: (360, {"pid": 16, "status": 24, "periodic": 28, "capacity": 32, "steps": 40, "dt": 48,
                        "domain_min": 56, "domain_max": 80, "gravity": 104,
                        "fluid_density": 128, "fluid_viscosity": 136, "physics": 144,
                        "software": 152, "reason": 216, "first_step": 344, "cell_size": 352}),
    }
    for t, (size, offsets) in expect.items():
        assert ctypes.sizeof(t) == size, (t.__name__, ctypes.sizeof(t))
        for name, off in offsets.items():
            assert getattr(t, name).offset == off, (t.__name__, name)
    for t, dt in ((ParticleState, STATE_DTYPE), (ParticleReply, REPLY_DTYPE)):
        assert dt.itemsize == ctypes.sizeof(t)
        for name, _ in t._fields_:
            assert dt.fields[name][1] == getattr(t, name).offset


_check_layouts()


def _check_prefix(raw: bytes, kind: int, size: int, peer: str) -> None:
    """Checks the version-independent prefix of a handshake message (PROTOCOL.md)."""
    if len(raw) < PREFIX_LEN:
        raise Refused(f"handshake message of {len(raw)} bytes from the {peer} is too short")
    magic, version, msg_size, msg_kind = np.frombuffer(raw[:PREFIX_LEN], "<u4").tolist()
    if magic != MAGIC:
        raise Refused(f"handshake magic {magic:#010x} from the {peer} is not \"LBDM\"")
    if version != PROTOCOL_VERSION:
        raise VersionMismatch(PROTOCOL_VERSION, version, peer)
    if msg_kind != kind:
        raise Refused(f"unexpected handshake message kind {msg_kind} from the {peer}")
    if msg_size != size or len(raw) < size:
        raise Refused(f"handshake layout mismatch: {size} bytes here, {msg_size} bytes "
                      f"announced ({len(raw)} received) from the {peer}")


def decode_welcome(raw: bytes) -> Welcome:
    """Decodes the fluid's answer; raises Refused (or VersionMismatch) unless it accepts."""
    welcome = Welcome.from_bytes(raw)
    if welcome.status != Status.ACCEPTED:
        try:
            status = Status(welcome.status).name
        except ValueError:
            status = f"status {welcome.status}"
        raise Refused(f"handshake refused by the {FLUID} ({status}): {welcome.reason_text()}")
    return welcome
