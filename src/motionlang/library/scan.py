"""The motion files of a folder, what identifies each one, and the takes each one holds.

A file is known by its SHA-256 digest, so an index re-embeds a file only when its bytes
change, whatever its modification time says, and a file moved or renamed inside the folder
keeps its embeddings. An ``.amc`` file's motion also depends on the ``.asf`` skeleton beside
it: its digest covers both.
"""
from __future__ import annotations

import hashlib
import os
import re
from dataclasses import dataclass
from pathlib import Path

from motionlang.datasets.download import sha256_file
from motionlang.errors import MotionlangError
from motionlang.formats import find_asf, is_motion_file, read_motion
from motionlang.kinematics.motion import Motion


def motion_files(root: str | Path) -> list[Path]:
    """Every file under ``root`` (recursively) with an extension a reader knows (``.txt``:
    a DeepMimic clip, known by its content), sorted by relative path. Hidden files and
    folders (a name starting with ".": version control, the temporary files of atomic
    writes) are left out.

    Raises:
        MotionlangError: ``root`` is not a folder.
    """
    root = Path(root)
    if not root.is_dir():
        raise MotionlangError(f"{root}: not a folder")
    found = []
    for folder, dirs, names in os.walk(root):
        dirs[:] = [d for d in dirs if not d.startswith(".")]
        found += [Path(folder) / n for n in names
                  if not n.startswith(".") and is_motion_file(Path(folder) / n)]
    return sorted(found, key=lambda p: p.relative_to(root).as_posix())


@dataclass(frozen=True)
class FileFacts:
    """What identifies a file: ``path`` relative to the indexed folder (POSIX), size in
    bytes, modification time (seconds since the epoch) and SHA-256 digest (hex)."""

    path: str
    size: int
    mtime: float
    sha256: str


def file_facts(root: Path, path: Path) -> FileFacts:
    """The facts of ``path`` (under ``root``); an ``.amc`` file's digest covers its ASF.

    Raises:
        MotionlangError: the file (or an AMC's skeleton) cannot be read.
    """
    try:
        st = path.stat()
        digest = sha256_file(path)
        if path.suffix.lower() == ".amc":
            both = digest + sha256_file(find_asf(path))
            digest = hashlib.sha256(both.encode("ascii")).hexdigest()
    except OSError as exc:
        raise MotionlangError(f"{path}: cannot read: {exc.strerror or exc}") from None
    return FileFacts(path.relative_to(root).as_posix(), int(st.st_size), float(st.st_mtime),
                     digest)


def read_takes(path: Path) -> list[Motion]:
    """The takes of a motion file: one, or each sequence of a MIT ``.mat`` file.

    Raises:
        MotionlangError: the reader's one-line reason.
    """
    if path.suffix.lower() == ".mat":
        from motionlang.formats.mit import read_mit
        return read_mit(path)
    return [read_motion(path)]


def rig_of(motion: Motion) -> dict:
    """``{"joints": n, "map": name}``: the rig's joint count and the built-in map that
    puts it on the 21-joint body.

    Raises:
        MotionlangError: no map fits the rig (the reason names its unmatched joints).
    """
    from motionlang.features.joint_map import match_rig
    match = match_rig(motion.skeleton, joint_map=motion.meta.get("joint_map"))
    return {"joints": len(motion.skeleton), "map": match.name}


def take_name(path: str, sequence: int, sequences: int) -> str:
    """How a take is named in hits: the file's relative path, with ``#N`` after the path
    of a file holding several sequences (N counts from 1)."""
    return path if sequences == 1 else f"{path}#{sequence}"


def reason(exc: BaseException, path: Path, rel: str) -> str:
    """One line saying why ``path`` was skipped, without the file's name in front (the
    listing names it) and with any other mention of it relative to the indexed folder."""
    text = str(exc) if isinstance(exc, MotionlangError) else \
        f"unexpected {type(exc).__name__}: {exc}"
    text = " ".join(text.replace(str(path), rel).split())
    m = re.match(rf"{re.escape(rel)}(?::(\d+))?: ", text)
    if m is None:
        return text
    return (f"line {m.group(1)}: " if m.group(1) else "") + text[m.end():]
