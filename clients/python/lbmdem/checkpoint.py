"""Checkpoints on the DEM side (PROTOCOL.md 6.4): where lbm-server asks a DEM started by it to write
its part of a checkpoint, where a resumed run's state is, and the marker that the part is complete."""

from __future__ import annotations

import os
from typing import Optional


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
