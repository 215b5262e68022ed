"""What happens when LIGGGHTS ends the process.

An error in a LIGGGHTS command (a typo in the deck, atoms lost during a run) makes LIGGGHTS print
``ERROR: ...`` to its log and screen and call ``exit(1)``: the Python code that called it never
resumes. The guard registers a C ``on_exit`` handler (glibc) that, while armed, runs a Python
function (print the error, close the coupling link so that no shared-memory files stay) and
leaves with that function's exit status. Disarmed (the normal end), it does nothing.
"""

from __future__ import annotations

import ctypes
import os
import sys
from typing import Callable, Optional

_OnExit = ctypes.CFUNCTYPE(None, ctypes.c_int, ctypes.c_void_p)


class ExitGuard:
    """``arm(handler)``: on a C-level exit, ``handler()`` returns the exit status to leave with."""

    def __init__(self):
        self._handler: Optional[Callable[[], int]] = None
        self._c_handler = _OnExit(self._on_exit)  # kept alive for the process's lifetime
        ctypes.CDLL(None).on_exit(self._c_handler, None)

    def arm(self, handler: Callable[[], int]) -> None:
        self._handler = handler

    def disarm(self) -> None:
        self._handler = None

    def _on_exit(self, _status: int, _arg) -> None:
        handler, self._handler = self._handler, None
        if handler is None:
            return
        try:
            code = handler()
        except BaseException as e:  # noqa: BLE001 - the process ends here whatever happens
            print(f"lbm-liggghts: error while leaving: {e!r}", file=sys.stderr)
            code = 1
        sys.stderr.flush()
        sys.stdout.flush()
        os._exit(code)
