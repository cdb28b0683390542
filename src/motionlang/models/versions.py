"""Checkpoint format versions, shared by every model kind (torch-free, so that the numpy-only
CRBM family can use them).

A checkpoint records the layout it was written in (``"format"`` in torch checkpoints,
``"version"`` / ``format`` in the CRBM family's ``.npz``); files without one are format 0 and
read as before. A newer format is refused by name: its fields may mean something else.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

from motionlang.errors import MotionlangError

#: the checkpoint layout this version writes and the newest it reads
FORMAT_VERSION = 1


def check_format(path: str | Path, version: Any) -> None:
    """Refuse a checkpoint written in a newer layout than this motionlang reads."""
    if isinstance(version, bool) or not isinstance(version, int) or version < 0:
        raise MotionlangError(f"{path}: checkpoint format {version!r} is not a version number")
    if version > FORMAT_VERSION:
        raise MotionlangError(f"{path}: checkpoint format {version} is newer than this "
                              f"motionlang reads ({FORMAT_VERSION}); upgrade motionlang")
