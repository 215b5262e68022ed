"""The errors of a link: every failure raises a LinkError subclass whose message names the peer
and the last completed step."""

from __future__ import annotations

from typing import Optional


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
