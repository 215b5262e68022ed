"""DEM side of the LBM-DEM co-simulation protocol, version 2, for Python DEMs (YADE, scripts).

The contract is ``PROTOCOL.md`` at the repository root; this package implements its DEM side over
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

The package's modules: ``wire`` (the protocol's constants, flags, per-step types and handshake
messages), ``link`` (DemLink over iceoryx2, process_state), ``errors`` (LinkError and its kinds)
and ``checkpoint`` (checkpoint_dir, resume_dir, complete_checkpoint). Every public name is
re-exported here: ``import lbmdem`` and ``from lbmdem import X`` are all a DEM needs.
"""

from .checkpoint import CHECKPOINT_DIR_ENV, DEM_COMPLETE, RESUME_DIR_ENV, checkpoint_dir, complete_checkpoint, resume_dir
from .errors import (FLUID, BadCount, BadReply, Interrupted, LinkError, PeerDied, PeerStopped, PeerTimeout, Refused,
                     StepMismatch, TransportError, VersionMismatch)
from .link import POLL_S, STOPPED_GRACE_S, DemLink, process_state
from .wire import (KIND_HELLO, KIND_WELCOME, MAGIC, PREFIX_LEN, PROTOCOL_VERSION, REPLY_DTYPE, STATE_DTYPE, TEXT_LEN,
                   Capabilities, Hello, ParticleReply, ParticleState, Physics, Status, StepFlags, StepHeader, Units,
                   Welcome, decode_welcome)


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
