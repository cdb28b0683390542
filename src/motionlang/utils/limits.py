"""Limits on what motionlang will read: file size, joints, frames, memory, archive expansion.

A crafted or broken file can declare a million frames of ten thousand joints in two
megabytes, or a zip can expand a thousandfold. Every reader checks what a file asks for
*before* asking the system for it, and refuses a file beyond these limits with one line that
names the file, the quantity and the environment variable that raises the limit:

=====================  ==========  ================================  ==========================
limit                  default     environment variable              what it bounds
=====================  ==========  ================================  ==========================
``max_file_bytes``     2 GiB       ``MOTIONLANG_MAX_FILE_BYTES``     size of one motion file
``max_joints``         2,000       ``MOTIONLANG_MAX_JOINTS``         nodes of one skeleton
``max_frames``         10,000,000  ``MOTIONLANG_MAX_FRAMES``         frames of one motion (23 h
                                                                     at 120 Hz)
``max_memory_bytes``   4 GiB       ``MOTIONLANG_MAX_MEMORY``         memory one motion needs:
                                                                     its arrays and forward
                                                                     kinematics
``max_archive_ratio``  100         ``MOTIONLANG_MAX_ARCHIVE_RATIO``  extracted bytes per archive
                                                                     byte (beyond 64 MiB)
``max_archive_bytes``  64 GiB      ``MOTIONLANG_MAX_ARCHIVE_BYTES``  bytes extracted from one
                                                                     archive
``max_json_bytes``     64 MiB      ``MOTIONLANG_MAX_JSON_BYTES``     size of one JSON sidecar
                                                                     (joint map, metadata)
``max_caption_chars``  10,000      ``MOTIONLANG_MAX_CAPTION_CHARS``  characters of one caption
``max_vocabulary``     200,000     ``MOTIONLANG_MAX_VOCABULARY``     distinct words a
                                                                     vocabulary keeps
=====================  ==========  ================================  ==========================

Byte values take an optional binary suffix: ``MOTIONLANG_MAX_MEMORY=16G``, ``500M``, ``2T``.
The environment is read at every check, so ``export`` in the shell or ``os.environ[...] =``
in Python takes effect at once. The defaults leave room for real data (a 10-minute 120 Hz
take of a 100-joint rig needs about 0.8 GiB of forward kinematics; KIT-ML and Bandai
archives expand 5-7 fold) and refuse what only an attack or a corrupt file asks for.
"""
from __future__ import annotations

import dataclasses
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

from motionlang.errors import MotionFormatError, MotionlangError

GiB = 1 << 30
#: below this many extracted bytes an archive's expansion ratio is not checked
RATIO_FLOOR_BYTES = 64 << 20
#: bytes a motion needs per frame and joint (forward kinematics: a 3x3 rotation and a
#: position, plus the canonical-frame copy of the positions) ...
BYTES_PER_JOINT_FRAME = 8 * (9 + 3 + 3)
#: ... and per frame and file channel (the parsed values, the angle copy, a spare)
BYTES_PER_CHANNEL_FRAME = 8 * 3


@dataclass(frozen=True)
class Limits:
    """The limits in force (see the module docstring); :func:`current` reads them."""
    max_file_bytes: int = 2 * GiB
    max_joints: int = 2_000
    max_frames: int = 10_000_000
    max_memory_bytes: int = 4 * GiB
    max_archive_ratio: float = 100.0
    max_archive_bytes: int = 64 * GiB
    max_json_bytes: int = 64 << 20
    max_caption_chars: int = 10_000
    max_vocabulary: int = 200_000


ENV = {"max_file_bytes": "MOTIONLANG_MAX_FILE_BYTES", "max_joints": "MOTIONLANG_MAX_JOINTS",
       "max_frames": "MOTIONLANG_MAX_FRAMES", "max_memory_bytes": "MOTIONLANG_MAX_MEMORY",
       "max_archive_ratio": "MOTIONLANG_MAX_ARCHIVE_RATIO",
       "max_archive_bytes": "MOTIONLANG_MAX_ARCHIVE_BYTES",
       "max_json_bytes": "MOTIONLANG_MAX_JSON_BYTES",
       "max_caption_chars": "MOTIONLANG_MAX_CAPTION_CHARS",
       "max_vocabulary": "MOTIONLANG_MAX_VOCABULARY"}
_SUFFIX = {"": 1, "k": 1 << 10, "m": 1 << 20, "g": 1 << 30, "t": 1 << 40}
_VALUE = re.compile(r"^\s*(\d+(?:\.\d*)?(?:e\d+)?)\s*([kmgt]?)(?:i?b)?\s*$", re.IGNORECASE)


def _parse(var: str, text: str, kind: type):
    m = _VALUE.match(text)
    value = float(m.group(1)) * _SUFFIX[m.group(2).lower()] if m else 0.0
    if not value > 0 or value > 1e18:
        raise MotionlangError(f"{var}={text!r}: expected a positive number such as 5000000 "
                              "or 8G")
    return kind(value)


def current() -> Limits:
    """The limits in force: the defaults, overridden by the ``MOTIONLANG_MAX_*`` variables.

    Raises:
        MotionlangError: a variable that is not a positive number.
    """
    changes = {}
    for f in dataclasses.fields(Limits):
        text = os.environ.get(ENV[f.name])
        if text is not None and text.strip():
            changes[f.name] = _parse(ENV[f.name], text, float if f.type == "float" else int)
    return dataclasses.replace(Limits(), **changes) if changes else Limits()


def human(name: str, value: float) -> str:
    """``value`` of limit ``name`` for a message: ``4 GiB``, ``2,000``."""
    if name.endswith("bytes"):
        for unit, size in (("TiB", 1 << 40), ("GiB", 1 << 30), ("MiB", 1 << 20),
                           ("KiB", 1 << 10)):
            if value >= size:
                return f"{value / size:.3g} {unit}"
        return f"{int(value)} bytes"
    return f"{value:,.0f}" if float(value).is_integer() else f"{value:.3g}"


def message(name: str, value: float, what: str, limits: Limits | None = None) -> str | None:
    """The refusal for ``value`` of limit ``name`` (a :class:`Limits` field), None if within."""
    limit = getattr(limits or current(), name)
    if value <= limit:
        return None
    return (f"{what} {human(name, value)} exceeds the limit of {human(name, limit)} "
            f"(raise it with {ENV[name]}=...)")


def check(path: str | Path | None, name: str, value: float, what: str,
          limits: Limits | None = None, line: int | None = None) -> None:
    """Raise :class:`MotionFormatError` for ``path`` (and ``line``) if ``value`` exceeds
    limit ``name``."""
    msg = message(name, value, what, limits)
    if msg:
        raise MotionFormatError(path, msg, line=line)


def not_regular(mode: int) -> str | None:
    """What a file of ``st_mode`` is when it is not a regular file ("a FIFO", "a folder"),
    None for a regular one. Reading a FIFO or a terminal blocks for ever and a device may
    never end, so readers refuse them before opening."""
    if stat.S_ISREG(mode):
        return None
    for test, what in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO (named pipe)"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return what
    return "not a regular file"


def check_file(path: str | Path, parse_factor: float = 1.0) -> int:
    """Size in bytes of a file about to be read; MotionFormatError if it is missing, not a
    regular file (a FIFO, device or folder), too big, or would take more than the memory
    limit to parse (``parse_factor`` x its size: a reader that holds the file's lines or XML
    tree as Python objects needs 5-10x).
    """
    try:
        st = os.stat(path)
    except OSError as exc:
        raise MotionFormatError(path, f"cannot read file: {exc.strerror or exc}") from None
    what = not_regular(st.st_mode)
    if what:
        raise MotionFormatError(path, f"{what}, not a file: only regular files are read")
    size = st.st_size
    lim = current()
    check(path, "max_file_bytes", size, "file size", lim)
    check(path, "max_memory_bytes", int(size * parse_factor), "memory needed to parse it", lim)
    return size


def motion_bytes(frames: int, joints: int, channels: int = 0) -> int:
    """Bytes a motion of ``frames`` x ``joints`` (and ``channels`` file values per frame)
    needs to be read and put through forward kinematics."""
    return frames * (joints * BYTES_PER_JOINT_FRAME + channels * BYTES_PER_CHANNEL_FRAME)


def check_motion(path: str | Path | None, frames: int, joints: int, channels: int = 0) -> None:
    """Refuse a motion beyond the frame, joint or memory limits, before building it."""
    lim = current()
    check(path, "max_frames", frames, "frame count", lim)
    check(path, "max_joints", joints, "joint count", lim)
    check(path, "max_memory_bytes", motion_bytes(frames, joints, channels),
          f"memory needed for {frames:,} frames of {joints:,} joints", lim)


__all__ = ["Limits", "ENV", "current", "human", "message", "check", "check_file",
           "check_motion", "motion_bytes", "not_regular"]
