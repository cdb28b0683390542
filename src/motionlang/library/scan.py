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
import stat
import warnings
from dataclasses import dataclass
from pathlib import Path

from motionlang.analysis.rate import at_its_rate, read_at
from motionlang.datasets.download import sha256_file
from motionlang.errors import MotionlangError
from motionlang.features.joint_map import match_rig
from motionlang.formats import READ_EXTENSIONS, find_asf, is_motion_file, read_motion
from motionlang.formats.mit import read_mit
from motionlang.kinematics.motion import Motion
from motionlang.library.rates import SharedRate


def motion_files(root: str | Path, unlisted: list[tuple[str, str]] | None = None
                 ) -> list[Path]:
    """Every file under ``root`` (recursively, however deep) with an extension a reader
    knows (``.txt``: a DeepMimic clip, known by its content, read only from a regular
    file), sorted by relative path. Hidden files and folders (a name starting with ".":
    version control, the temporary files of atomic writes) are left out; so are folder
    links, which could lead round in a circle. A file that is not a regular one (a FIFO, a
    link to a device) is listed, for its reader to refuse in one line, never read.

    unlisted: where given, gets ``(folder relative to root, reason)`` of each folder that
    could not be listed.

    Raises:
        MotionlangError: ``root`` is not a folder.
    """
    root = Path(root)
    if not root.is_dir():
        raise MotionlangError(f"{root}: not a folder")
    found = []
    stack = [root]
    while stack:   # not os.walk: its recursion ends a folder nested ~1,000 deep
        folder = stack.pop()
        try:
            with os.scandir(folder) as it:
                entries = list(it)
        except OSError as exc:
            if unlisted is not None:
                unlisted.append(((folder.relative_to(root).as_posix() or ".") + "/",
                                 f"cannot list this folder: {exc.strerror or exc}"))
            continue
        for e in entries:
            if e.name.startswith("."):
                continue
            path = Path(e.path)
            try:
                if e.is_dir(follow_symlinks=False):
                    stack.append(path)
                    continue
                regular = e.is_file()
            except OSError:
                regular = False
            if path.suffix.lower() in READ_EXTENSIONS or (regular and is_motion_file(path)):
                found.append(path)
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
        if not stat.S_ISREG(st.st_mode):
            raise MotionlangError(f"{path}: not a regular file (a FIFO, device or socket): "
                                  "left out")
        digest = sha256_file(path)
        if path.suffix.lower() == ".amc":
            both = digest + sha256_file(find_asf(path))
            digest = hashlib.sha256(both.encode("ascii")).hexdigest()
    except OSError as exc:
        raise MotionlangError(f"{path}: cannot read: {exc.strerror or exc}") from None
    return FileFacts(path.relative_to(root).as_posix(), int(st.st_size), float(st.st_mtime),
                     digest)


def read_takes(path: Path, export: SharedRate | None = None, *,
               fps: float | None = None) -> list[Motion]:
    """The takes of a motion file: one, or each sequence of a MIT ``.mat`` file; read at
    ``fps`` Hz where given (the rate an index read them at), else at the rate of the
    file's ``export`` (``library.rates.shared_rates``) where given, else at its header's
    rate unless its body contradicts it (``analysis.rate``).

    Raises:
        MotionlangError: the reader's one-line reason.
    """
    with warnings.catch_warnings():   # one line a file is too many for a library
        warnings.simplefilter("ignore")
        if path.suffix.lower() == ".mat":
            motions = read_mit(path)
        else:
            motion = read_motion(path)
            motions = [motion if fps is not None
                       else read_at(motion, export.rate, export.line(str(path)))
                       if export is not None else at_its_rate(motion, str(path))]
    if fps is None:
        return motions
    return [m if m.fps == fps else m.replace(
        fps=fps, meta={**m.meta, "declared_fps": m.meta.get("declared_fps", m.fps)})
        for m in motions]


def rig_of(motion: Motion) -> dict:
    """``{"joints": n, "map": name}``: the rig's joint count and the built-in map that
    puts it on the 21-joint body.

    Raises:
        MotionlangError: no map fits the rig (the reason names its unmatched joints).
    """
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
