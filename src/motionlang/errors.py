"""Errors raised by motionlang.

Every problem with user input is reported as a :class:`MotionlangError` (or a subclass)
whose message names the file and, where known, the line or frame. The CLI turns these
into a one-line message and a non-zero exit code instead of a traceback.
"""
from __future__ import annotations

from pathlib import Path


class MotionlangError(Exception):
    """Base class of every error motionlang raises on purpose."""


class MotionFormatError(MotionlangError):
    """A motion or skeleton file could not be read.

    Args:
        path: the file that was being read (``None`` for in-memory data).
        message: what is wrong.
        line: 1-based line number, if known.
        frame: 0-based frame index, if known.
    """

    def __init__(self, path: str | Path | None, message: str, *, line: int | None = None,
                 frame: int | None = None):
        self.path = None if path is None else str(path)
        self.line = line
        self.frame = frame
        where = self.path or "<data>"
        if line is not None:
            where += f":{line}"
        if frame is not None:
            where += f" (frame {frame})"
        super().__init__(f"{where}: {message}")
        self.reason = message


class DatasetError(MotionlangError):
    """A dataset could not be found, downloaded, verified or parsed."""


class SkeletonError(MotionlangError):
    """A skeleton is inconsistent (unknown joint name, broken tree, asymmetric mirror...)."""
