"""What every model checkpoint shares and that needs no torch (so that the numpy-only CRBM
family can use it): the format version, the config-field check and the wording of a file
that cannot be read.

A checkpoint records the layout it was written in (``"format"`` in torch checkpoints,
``"version"`` / ``format`` in the CRBM family's ``.npz``); files without one are format 0 and
read as before. A newer format is refused by name: its fields may mean something else.
"""
from __future__ import annotations

import zipfile
from dataclasses import fields
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


def check_config_fields(config_cls: type, config: Any, path: str | Path, kind: str) -> None:
    """One clear line when a checkpoint's ``config`` (a dict) sets fields ``config_cls`` (a
    dataclass) does not have: a file written by a newer motionlang, whose options this one
    cannot honour (without this the constructor's TypeError reads as a damaged file). A
    ``config`` that is not a dict is left to the loader (a damaged file)."""
    if not isinstance(config, dict):
        return
    unknown = sorted(set(config) - {f.name for f in fields(config_cls)})
    if unknown:
        raise MotionlangError(f"{path}: this {kind} checkpoint sets {', '.join(unknown)}, which "
                              f"this version of motionlang does not know: it was written by a "
                              f"newer one (upgrade motionlang to read it)")


#: what reading a checkpoint that opened raises when its content is not what it should be
DAMAGE = (KeyError, TypeError, ValueError, AttributeError, IndexError, RuntimeError, EOFError,
          zipfile.BadZipFile)


#: a file that opens but is no checkpoint of this motionlang's kinds at all
NOT_A_CHECKPOINT = "not a readable motionlang checkpoint (truncated, or another kind of file)"


def unreadable(exc: BaseException) -> str:
    """Why a checkpoint file could not be opened or parsed at all, in one line (without the
    path: callers put it first)."""
    if isinstance(exc, FileNotFoundError):
        return "no such checkpoint file"
    if isinstance(exc, OSError):
        return f"cannot read checkpoint: {exc.strerror or type(exc).__name__}"
    return NOT_A_CHECKPOINT


def damaged(kind: str, exc: BaseException) -> str:
    """Why a checkpoint of ``kind`` that opened could not be rebuilt, in one line (without
    the path)."""
    first = (str(exc).splitlines() or [""])[0]
    what = type(exc).__name__
    return f"a damaged {kind} checkpoint ({what}: {first})" if first else \
        f"a damaged {kind} checkpoint ({what})"


def check_archive(path: str | Path) -> None:
    """Refuse a zip-based model file (torch ``.pt``, numpy ``.npz``) with a damaged member:
    every member is read through :mod:`zipfile`, which checks its CRC-32. ``torch.load``
    does not check them, so a flipped byte in the weights would otherwise load and run.
    A file that is not a zip archive (a legacy pickle) is left to its loader.

    Raises:
        MotionlangError: ``PATH: a damaged checkpoint (...)`` naming the first bad member,
            or the file cannot be read.
    """
    where = ""
    try:
        if not zipfile.is_zipfile(path):
            return
        with zipfile.ZipFile(path) as zf:
            for info in zf.infolist():
                where = f"member {info.filename}: "
                with zf.open(info) as member:
                    while member.read(1 << 20):   # zipfile checks the CRC at the end
                        pass
    except OSError as exc:
        raise MotionlangError(f"{path}: {unreadable(exc)}") from exc
    except (zipfile.BadZipFile, EOFError, ValueError, NotImplementedError) as exc:
        raise MotionlangError(f"{path}: a damaged checkpoint ({where}{exc})") from exc


def load_problem(kind: str, exc: BaseException) -> str:
    """:func:`unreadable` for an OSError, else :func:`damaged`: the one line of a loader that
    opens and parses in one step (the CRBM family's ``.npz``)."""
    return unreadable(exc) if isinstance(exc, OSError) else damaged(kind, exc)
