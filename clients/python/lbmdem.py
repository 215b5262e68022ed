"""DEM side of the LBM-DEM co-simulation protocol, version 2, for Python DEMs (YADE, scripts).

The contract is ``PROTOCOL.md`` at the repository root; this module implements its DEM side over
iceoryx2 shared memory (PyPI ``iceoryx2==0.10.0``) and numpy::

    import lbmdem
    hello = lbmdem.Hello.new(lbmdem.Units.si(), lbmdem.Physics.GRAVITY, initial_count=len(states))
    with lbmdem.DemLink(run_name) as link:
        welcome = link.connect(hello)
        for n in range(welcome.steps):
            link.send_states(n, n * welcome.dt, states)          # numpy array of STATE_DTYPE
            header, forces = link.receive_forces(n)             # numpy array of REPLY_DTYPE
            ...                                                 # advance the particles
            if header.flags & (lbmdem.StepFlags.FINAL | lbmdem.StepFlags.STOP):
                break

Every failure raises a :class:`LinkError` whose message names the peer and the last completed step.

Checkpoints (PROTOCOL.md 6.4): a DEM that can save and restore its whole state builds its Hello with
``capabilities=Capabilities.CHECKPOINT``; a reply whose flags carry ``StepFlags.CHECKPOINT`` then
asks it to write its state for the next step into :func:`checkpoint_dir`, and last the empty file
``dem.complete`` (:func:`complete_checkpoint`), before it sends the next states (or, after FINAL or
STOP, before it ends). A resumed run's Welcome has ``first_step`` > 0: the DEM restores that step's
state from :func:`resume_dir` and starts its loop there.
"""

from __future__ import annotations

import ctypes
import enum
import gc
import os
import re
import time as _time
from typing import Callable, Optional, Sequence, Tuple, Union

import numpy as np

try:
    import iceoryx2 as iox
except ImportError as e:  # pragma: no cover - depends on the environment
    raise ImportError(
        "lbmdem needs the iceoryx2 Python binding: pip install iceoryx2==0.10.0"
    ) from e

__all__ = [
    "PROTOCOL_VERSION", "MAGIC", "PREFIX_LEN", "KIND_HELLO", "KIND_WELCOME", "TEXT_LEN",
    "Physics", "Status", "StepFlags", "Capabilities", "Units", "Hello", "Welcome",
    "CHECKPOINT_DIR_ENV", "RESUME_DIR_ENV", "DEM_COMPLETE", "checkpoint_dir", "resume_dir",
    "complete_checkpoint",
    "ParticleState", "ParticleReply", "StepHeader", "STATE_DTYPE", "REPLY_DTYPE",
    "LinkError", "PeerDied", "PeerStopped", "PeerTimeout", "StepMismatch", "BadCount",
    "BadReply", "Refused", "VersionMismatch", "Interrupted", "TransportError",
    "DemLink", "process_state", "decode_welcome",
]

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

#: A waiting side wakes up this often to look at its peer [s].
POLL_S = 0.05
#: A peer stopped (SIGSTOP) for longer than this counts as hung [s].
STOPPED_GRACE_S = 0.4


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


#: The environment variables of a DEM started by lbm-server: the staging folder of the checkpoint
#: being written, and the folder of the checkpoint a resumed run goes on from.
CHECKPOINT_DIR_ENV = "LBMDEM_CHECKPOINT_DIR"
RESUME_DIR_ENV = "LBMDEM_RESUME_DIR"
#: The marker a DEM writes last into the checkpoint folder: its part is complete.
DEM_COMPLETE = "dem.complete"


def checkpoint_dir() -> Optional[str]:
    """The folder to write this DEM's part of a checkpoint into ($LBMDEM_CHECKPOINT_DIR)."""
    return os.environ.get(CHECKPOINT_DIR_ENV) or None


def resume_dir() -> Optional[str]:
    """The folder of the checkpoint a resumed run goes on from ($LBMDEM_RESUME_DIR)."""
    return os.environ.get(RESUME_DIR_ENV) or None


def complete_checkpoint(folder: str) -> None:
    """Writes the marker that this DEM's part of the checkpoint in ``folder`` is complete."""
    with open(os.path.join(folder, DEM_COMPLETE), "wb") as f:
        f.flush()
        os.fsync(f.fileno())


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


class Hello(ctypes.Structure):
    """DEM -> fluid, once, before step 0 (144 bytes)."""

    _fields_ = [
        ("magic", _u32),
        ("version", _u32),
        ("size", _u32),
        ("kind", _u32),
        ("pid", _u64),
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

    _fields_ = [
        ("magic", _u32),
        ("version", _u32),
        ("size", _u32),
        ("kind", _u32),
        ("pid", _u64),
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

# ---------------------------------------------------------------------------------------------
# Errors
# ---------------------------------------------------------------------------------------------

FLUID = "fluid server (lbm-server)"


def _last(step: Optional[int]) -> str:
    return "no step completed" if step is None else f"last completed step {step}"


class LinkError(Exception):
    """Anything that ends a link. ``last_step`` is the last completed step (None: none)."""

    def __init__(self, message: str, last_step: Optional[int] = None):
        self.message = message
        self.last_step = last_step
        super().__init__(f"{message} ({_last(last_step)})")


class PeerDied(LinkError):
    pass


class PeerStopped(LinkError):
    pass


class PeerTimeout(LinkError):
    pass


class StepMismatch(LinkError):
    pass


class BadCount(LinkError):
    pass


class BadReply(LinkError):
    pass


class Refused(LinkError):
    pass


class VersionMismatch(Refused):
    def __init__(self, ours: int, theirs: int, peer: str, last_step: Optional[int] = None):
        self.ours, self.theirs = ours, theirs
        me = "this side" if "DEM" in peer else "this DEM"
        super().__init__(
            f"protocol version mismatch: {me} speaks version {ours}, the {peer} speaks "
            f"version {theirs}", last_step)


class Interrupted(LinkError):
    pass


class TransportError(LinkError):
    pass


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


# ---------------------------------------------------------------------------------------------
# Peer liveness through the process table
# ---------------------------------------------------------------------------------------------

def process_state(pid: int) -> str:
    """'running', 'stopped' (T/t) or 'dead' (missing, Z, X) from /proc/PID/stat."""
    try:
        with open(f"/proc/{int(pid)}/stat", "rb") as f:
            stat = f.read()
    except OSError:
        return "dead"
    close = stat.rfind(b")")
    rest = stat[close + 1:].split() if close >= 0 else []
    if not rest:
        return "dead"
    letter = rest[0][:1]
    if letter in (b"T", b"t"):
        return "stopped"
    if letter in (b"Z", b"X", b"x"):
        return "dead"
    return "running"


# ---------------------------------------------------------------------------------------------
# The link
# ---------------------------------------------------------------------------------------------

iox.set_log_level(iox.LogLevel.Error)

_RUN_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")


def _states_array(states) -> np.ndarray:
    """Any accepted states container -> C-contiguous numpy array of STATE_DTYPE."""
    if isinstance(states, np.ndarray):
        if states.dtype == STATE_DTYPE:
            return np.ascontiguousarray(states)
        if states.dtype.names:  # other structured dtype: copy the fields by name, zeros else
            missing = {"id", "position", "radius"} - set(states.dtype.names)
            if missing:
                raise TypeError(f"states array lacks the fields {sorted(missing)}")
            out = np.zeros(states.shape[0] if states.ndim else 1, STATE_DTYPE)
            for name in STATE_DTYPE.names:
                if name in states.dtype.names:
                    out[name] = states[name]
            return out
        raise TypeError(f"states array has dtype {states.dtype}, expected lbmdem.STATE_DTYPE")
    if isinstance(states, ctypes.Array) and states._type_ is ParticleState:
        return np.frombuffer(bytes(states), STATE_DTYPE)
    seq = list(states)
    if seq and isinstance(seq[0], ParticleState):
        return np.frombuffer(b"".join(bytes(s) for s in seq), STATE_DTYPE)
    # tuples (id, position, velocity, angular_velocity, radius)
    return np.array([tuple(s) for s in seq], dtype=STATE_DTYPE)


class DemLink:
    """The DEM side of one run: opens the run's services, handshakes, exchanges the steps.

    ``run`` is the name printed by ``lbm-server`` (``DEM service: RUN``); ``timeout_s`` the longest
    wait for a live fluid server that does not answer; ``interrupt`` an optional callable that,
    when it returns True, aborts the waits of :meth:`connect` (Ctrl-C before the run starts).
    """

    def __init__(self, run: str, timeout_s: float = 10.0,
                 interrupt: Optional[Callable[[], bool]] = None):
        if not _RUN_NAME.match(run or ""):
            raise ValueError(f"invalid run name {run!r} (letters, digits, '_', '-', '.')")
        self.run = run
        self.timeout_s = float(timeout_s)
        self.interrupt = interrupt
        self.welcome: Optional[Welcome] = None
        self.peer_pid: Optional[int] = None
        self.capacity = 0
        #: The last step whose reply was received (None before step 0 completes).
        self.last_completed: Optional[int] = None
        self._next_step = 0
        self._sent_ids: Optional[np.ndarray] = None
        self._config = None
        self._node = None
        self._services: list = []
        self._ports: list = []
        self._closed = False

    # -- context manager ------------------------------------------------------------------

    def __enter__(self) -> "DemLink":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __del__(self) -> None:  # best effort; call close() explicitly
        try:
            self.close()
        except Exception:
            pass

    # -- plumbing -------------------------------------------------------------------------

    def _fail(self, cls, message: str):
        return cls(message, self.last_completed)

    def _name(self, what: str):
        return iox.ServiceName.new(f"{self.run}/{what}")

    def _pubsub(self, what: str, payload, header=None):
        builder = self._node.service_builder(self._name(what)).publish_subscribe(iox.Slice[payload])
        if header is not None:
            builder = builder.user_header(header)
        service = builder.open()  # the fluid side created it with the QoS of PROTOCOL.md
        self._services.append(service)
        return service

    def _event(self, what: str):
        service = self._node.service_builder(self._name(what)).event().open()
        self._services.append(service)
        return service

    def _port(self, port):
        self._ports.append(port)
        return port

    def _outbox(self, what, payload, header, max_len):
        service = self._pubsub(what, payload, header)
        publisher = self._port(
            service.publisher_builder()
            .initial_max_slice_len(max(int(max_len), 1))
            .allocation_strategy(iox.AllocationStrategy.PowerOfTwo)
            .create())
        notifier = self._port(self._event(what).notifier_builder().create())
        return service, publisher, notifier

    def _inbox(self, what, payload, header):
        service = self._pubsub(what, payload, header)
        subscriber = self._port(service.subscriber_builder().create())
        listener = self._port(self._event(what).listener_builder().create())
        return service, subscriber, listener

    @staticmethod
    def _send(publisher, notifier, header: Optional[ctypes.Structure], data: np.ndarray | bytes,
              count: int) -> None:
        sample = publisher.loan_slice_uninit(count)
        if header is not None:
            ctypes.memmove(sample.user_header_ptr, ctypes.addressof(header),
                           ctypes.sizeof(header))
        if isinstance(data, np.ndarray):
            if data.nbytes:
                ctypes.memmove(sample.payload_ptr, data.ctypes.data, data.nbytes)
        elif data:
            ctypes.memmove(sample.payload_ptr, data, len(data))
        sample.assume_init().send()
        notifier.notify()

    def _wait(self, subscriber, listener, what: str, pid: Optional[int], timeout_s: float,
              take: Callable, interruptible: bool, left: Callable[[], bool]):
        """Blocks until ``take(sample)`` yields, the fluid dies, hangs or leaves, or the timeout
        passes. ``left()`` is True once the fluid has removed the port it should answer on."""
        start = _time.monotonic()
        stopped_since = None
        while True:
            sample = subscriber.receive()
            if sample is not None:
                return take(sample)
            try:
                listener.timed_wait(iox.Duration.from_secs_f64(POLL_S))
            except iox.ListenerWaitError as e:
                if "Interrupt" not in str(e):  # EINTR from a signal: just look again
                    raise self._fail(TransportError, f"waiting for {what} failed: {e!r}")
            sample = subscriber.receive()
            if sample is not None:
                return take(sample)
            if left():
                # A message whose sender is gone can be lost: iceoryx2 maps a growable
                # (PowerOfTwo) data segment on first use, and the sender unlinks it on exit.
                raise self._fail(PeerDied, f"the {FLUID} closed the run without sending {what} "
                                           f"(see its output for the reason)")
            if pid is not None:
                state = process_state(pid)
                if state == "dead":
                    raise self._fail(PeerDied, f"the {FLUID} (pid {pid}) died while this DEM "
                                               f"waited for {what}")
                if state == "stopped":
                    stopped_since = stopped_since or _time.monotonic()
                    if _time.monotonic() - stopped_since >= STOPPED_GRACE_S:
                        raise self._fail(PeerStopped, f"the {FLUID} (pid {pid}) is suspended "
                                                      f"(stopped) and hangs the run")
                else:
                    stopped_since = None
            if interruptible and self.interrupt is not None and self.interrupt():
                raise self._fail(Interrupted, f"interrupted while waiting for {what}")
            waited = _time.monotonic() - start
            if waited >= timeout_s:
                raise self._fail(PeerTimeout, f"the {FLUID} did not send {what} within "
                                              f"{waited:.1f} s (hung?)")

    def _fluid_left_hello(self) -> bool:
        return self._hello_service.dynamic_config.number_of_subscribers == 0

    def _fluid_left_forces(self) -> bool:
        return self._forces_service.dynamic_config.number_of_publishers == 0

    @staticmethod
    def _take_bytes(sample) -> bytes:
        # payload().len() is in bytes in iceoryx2 0.10's Python binding; use the header's count.
        n = sample.header.number_of_elements
        raw = ctypes.string_at(sample.payload_ptr, n) if n else b""
        sample.delete()
        return raw

    # -- API ------------------------------------------------------------------------------

    def connect(self, hello: Hello) -> Welcome:
        """Opens the run's services, sends ``hello``, returns the fluid's accepting Welcome.

        Raises Refused (VersionMismatch for another protocol version) when the fluid refuses,
        PeerTimeout when no fluid server answers within the timeout.
        """
        if self._node is not None:
            raise RuntimeError("connect() called twice")
        if hello.magic != MAGIC or hello.kind != KIND_HELLO:
            raise ValueError("build the Hello with Hello.new(...)")
        try:
            self._config = iox.config.global_config()  # a copy
            self._config.global_cfg.prefix = iox.FileName.new(f"{self.run}_")
            self._node = (iox.NodeBuilder.new()
                          .config(self._config)
                          .signal_handling_mode(iox.SignalHandlingMode.Disabled)
                          .create(iox.ServiceType.Ipc))
        except Exception as e:
            raise self._fail(TransportError, f"cannot create the iceoryx2 node: {e!r}")

        # 1. The fluid side creates the services: wait until the hello service exists and the
        #    fluid's subscriber is on it (start-up barrier: history 0 loses earlier messages).
        #    Failures come back as exceptions without traceback and are raised after close():
        #    a traceback would keep iceoryx2 objects (and so the node) alive.
        failure = self._open_and_greet(hello)
        welcome = self._await_welcome() if failure is None else failure
        if isinstance(welcome, Exception):
            self.close()
            raise welcome
        self.welcome = welcome
        self.peer_pid = int(welcome.pid)
        self.capacity = int(welcome.capacity)
        if hello.initial_count > self.capacity:
            self.close()
            raise BadCount(f"{hello.initial_count} particles exceed the capacity "
                           f"{self.capacity} of the {FLUID}")
        return welcome

    def _open_and_greet(self, hello: Hello):
        start = _time.monotonic()
        hello_service = None
        last_error = ""
        while True:
            try:
                if hello_service is None:
                    hello_service = self._pubsub("hello", ctypes.c_uint8)
                if hello_service.dynamic_config.number_of_subscribers > 0:
                    break
            except Exception as e:  # DoesNotExist while the server is starting
                last_error = repr(e)
            if self.interrupt is not None and self.interrupt():
                return Interrupted("interrupted while waiting for the fluid server")
            if _time.monotonic() - start >= self.timeout_s:
                if hello_service is None:
                    return PeerTimeout(f"no run named '{self.run}' found ({last_error}); is "
                                       f"lbm-server running?")
                return PeerTimeout(f"the {FLUID} of run '{self.run}' has no hello subscriber "
                                   f"after {self.timeout_s:.1f} s")
            _time.sleep(POLL_S)
        try:
            # 2. All DEM ports exist before Hello is sent.
            self._services.remove(hello_service)  # _outbox opens it again and keeps it
            del hello_service
            self._hello_service, self._hello_pub, self._hello_notifier = self._outbox(
                "hello", ctypes.c_uint8, None, ctypes.sizeof(Hello))
            _, self._welcome_sub, self._welcome_listener = self._inbox(
                "welcome", ctypes.c_uint8, None)
            self._forces_service, self._forces_sub, self._forces_listener = self._inbox(
                "forces", ParticleReply, StepHeader)
            _, self._states_pub, self._states_notifier = self._outbox(
                "states", ParticleState, StepHeader, hello.initial_count)
            # 3. Hello.
            raw = hello.to_bytes()
            self._send(self._hello_pub, self._hello_notifier, None, raw, len(raw))
        except Exception as e:
            return TransportError(f"cannot open the services of run '{self.run}': {e!r}")
        return None

    def _await_welcome(self):
        # No fluid pid before the Welcome: only the timeout applies.
        try:
            reply = self._wait(self._welcome_sub, self._welcome_listener, "the Welcome", None,
                               self.timeout_s, self._take_bytes, interruptible=True,
                               left=self._fluid_left_hello)
            return decode_welcome(reply)
        except LinkError as e:
            return e.with_traceback(None)
        except Exception as e:
            return TransportError(f"waiting for the Welcome failed: {e!r}")

    def send_states(self, step: int, time: float, states, flags: int = 0) -> None:
        """Publishes the states of ``step`` (numpy array of STATE_DTYPE, ctypes array or list of
        ParticleState, or list of (id, position, velocity, angular_velocity, radius) tuples).

        ``time`` is this DEM's clock at the start of the step (normally t0 + step * dt; the fluid
        echoes it and writes it into its particle outputs, PROTOCOL.md 3.3); positions and
        velocities are of that instant (3.1). Raises BadCount, without sending, for more
        particles than the capacity."""
        self._require_connected()
        if step != self._next_step:
            raise self._fail(StepMismatch, f"this DEM tried to send step {step} where step "
                                           f"{self._next_step} is due")
        if self._sent_ids is not None:
            raise self._fail(StepMismatch, f"this DEM tried to send step {step} before receiving "
                                           f"the reply to step {step - 1}")
        arr = _states_array(states)
        count = int(arr.shape[0])
        if count > self.capacity:
            raise self._fail(BadCount, f"this DEM has {count} particles in step {step}, more "
                                       f"than the capacity {self.capacity} of the {FLUID}")
        header = StepHeader(int(step), float(time), count, int(flags))
        try:
            self._send(self._states_pub, self._states_notifier, header, arr, count)
        except Exception as e:
            raise self._fail(TransportError, f"sending the states of step {step} failed: {e!r}")
        self._sent_ids = arr["id"].copy()

    def receive_forces(self, step: int) -> Tuple[StepHeader, np.ndarray]:
        """Waits for the fluid's reply to ``step``: (StepHeader, array of REPLY_DTYPE, a copy).

        A fluid that finds the states broken (wrong step or count) leaves without a reply: this
        raises PeerDied, and the reason is in the fluid's stderr and summary.json
        (PROTOCOL.md 7)."""
        self._require_connected()
        if self._sent_ids is None or step != self._next_step:
            raise self._fail(StepMismatch, f"this DEM waits for the reply to step {step} but "
                                           f"sent no states for it")

        def take(sample):
            try:
                header = StepHeader.from_buffer_copy(
                    ctypes.string_at(sample.user_header_ptr, ctypes.sizeof(StepHeader)))
                # payload().len() is in bytes (binding bug): the element count is in the header.
                n = int(sample.header.number_of_elements)
                if header.step != step:
                    raise self._fail(StepMismatch, f"the {FLUID} sent step {header.step} where "
                                                   f"step {step} was due (lockstep broken)")
                if header.count != n or n > self.capacity:
                    raise self._fail(BadCount, f"the {FLUID} sent a step header counting "
                                               f"{header.count} particles with {n} in the slice "
                                               f"(capacity {self.capacity})")
                forces = np.empty(n, REPLY_DTYPE)
                if n:
                    ctypes.memmove(forces.ctypes.data, sample.payload_ptr, n * REPLY_DTYPE.itemsize)
                return header, forces
            finally:
                sample.delete()

        header, forces = self._wait(self._forces_sub, self._forces_listener,
                                    f"the forces of step {step}", self.peer_pid, self.timeout_s,
                                    take, interruptible=False, left=self._fluid_left_forces)
        sent = self._sent_ids
        if forces.shape[0] != sent.shape[0]:
            raise self._fail(BadCount, f"the {FLUID} answered step {step} with {forces.shape[0]} "
                                       f"particles, {sent.shape[0]} were sent")
        if not np.array_equal(forces["id"], sent):
            i = int(np.argmax(forces["id"] != sent))
            raise self._fail(BadReply, f"the {FLUID} answered step {step} with id "
                                       f"{int(forces['id'][i])} at index {i} where id "
                                       f"{int(sent[i])} was sent")
        self._sent_ids = None
        self.last_completed = step
        self._next_step = step + 1
        return header, forces

    def close(self) -> None:
        """Deletes every port, the services and the node, so no shared-memory files remain."""
        if self._closed:
            return
        self._closed = True
        for port in reversed(self._ports):
            try:
                port.delete()
            except Exception:
                pass
        self._ports.clear()
        self._services.clear()
        for name in ("_hello_pub", "_hello_notifier", "_welcome_sub", "_welcome_listener",
                     "_forces_sub", "_forces_listener", "_states_pub", "_states_notifier",
                     "_hello_service", "_forces_service"):
            self.__dict__.pop(name, None)
        had_node = self._node is not None
        self._node = None
        gc.collect()
        if had_node:
            self._remove_global_mgmt()

    def _remove_global_mgmt(self) -> None:
        """Removes what a dead fluid server left behind (kill -9), and iceoryx2's one 16-byte
        ``/dev/shm/PREFIX<hash>_node.<ver>.global_mgmt`` file that remains per prefix after a
        clean exit, when this process is the last one of the run."""
        try:
            for state in iox.Node.list(iox.ServiceType.Ipc, self._config):
                if isinstance(state, iox.NodeState.Dead):
                    state[0].try_remove_stale_resources()
            if list(iox.Node.list(iox.ServiceType.Ipc, self._config)):
                return  # the fluid server still runs: it is the last one out
        except Exception:
            return
        pattern = re.compile(re.escape(f"{self.run}_") + r"[0-9a-f]+_node\.[0-9_]+\.global_mgmt$")
        try:
            names = os.listdir("/dev/shm")
        except OSError:
            return
        for name in names:
            if pattern.match(name):
                try:
                    os.unlink(os.path.join("/dev/shm", name))
                except OSError:
                    pass

    def _require_connected(self) -> None:
        if self._closed or self.welcome is None:
            raise RuntimeError("DemLink is not connected (call connect() first)")
