"""The DEM side of one run over iceoryx2 shared memory (DemLink): it opens the run's services,
handshakes, exchanges the steps in lockstep and watches the fluid server through the process table
(process_state) while it waits."""

from __future__ import annotations

import ctypes
import gc
import os
import re
import time as _time
from typing import Callable, Optional, Tuple

import numpy as np

try:
    import iceoryx2 as iox
except ImportError as e:  # pragma: no cover - depends on the environment
    raise ImportError(
        "lbmdem needs the iceoryx2 Python binding: pip install iceoryx2==0.10.0"
    ) from e

from .errors import (FLUID, BadCount, BadReply, Interrupted, LinkError, PeerDied, PeerStopped, PeerTimeout,
                     StepMismatch, TransportError)
from .wire import (KIND_HELLO, MAGIC, REPLY_DTYPE, STATE_DTYPE, Hello, ParticleReply, ParticleState, StepHeader,
                   Welcome, decode_welcome)


#: A waiting side wakes up this often to look at its peer [s].
POLL_S = 0.05
#: A peer stopped (SIGSTOP) for longer than this counts as hung [s].
STOPPED_GRACE_S = 0.4


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
