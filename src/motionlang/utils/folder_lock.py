"""One writer per output folder: a lock file, and the check that an output folder is new.

Two processes training into one run folder would interleave their checkpoints and both
report success. :func:`folder_lock` makes the second one refuse: the first holds
``FOLDER/.motionlang.lock``, a small JSON file naming its process id and host (the host as
:mod:`motionlang.utils.atomic` names it, PID namespace included). A lock whose process is
gone (same host, that PID no longer running: ``kill -9``, a power cut) is stale and taken
over; another host's lock is never guessed stale, the message says which file to remove.
The lock file is created complete (written under a temporary name, then hard-linked into
place, which fails if a lock exists), so a reader never sees a half-written one.
"""
from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterator
from pathlib import Path

from motionlang.errors import MotionlangError
from motionlang.utils.atomic import TAG, _alive, _host, make_temp, os_error_line

LOCK_NAME = ".motionlang.lock"


def _holder(lock: Path) -> dict | None:
    """The lock's ``{"pid", "host"}``; None when it vanished or is unreadable."""
    try:
        data = json.loads(lock.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _stale(holder: dict | None) -> bool:
    if holder is None:   # unreadable: not written by this code, or written by a crash
        return False
    pid = holder.get("pid")
    return holder.get("host") == _host() and isinstance(pid, int) and not _alive(pid)


def acquire(folder: Path) -> Path:
    """Create ``folder``'s lock for this process; returns its path.

    Raises:
        MotionlangError: another live process holds it (one line naming it and the file).
    """
    lock = folder / LOCK_NAME
    me = {"pid": os.getpid(), "host": _host()}
    tmp: Path | None = None
    try:
        tmp = make_temp(lock)
        tmp.write_text(json.dumps(me), encoding="utf-8")
    except OSError as exc:   # a full disk, a read-only folder: name the lock it is about
        if tmp is not None:
            with contextlib.suppress(OSError):
                tmp.unlink()
        raise MotionlangError(f"cannot take the lock {os_error_line(exc, lock)}") from None
    try:
        for _ in range(3):   # a stale lock removed, then one more try
            try:
                os.link(tmp, lock)
                return lock
            except FileExistsError:
                holder = _holder(lock)
                if not _stale(holder):
                    who = (f"process {holder.get('pid')} on {holder.get('host')}"
                           if holder else "another process")
                    raise MotionlangError(
                        f"{folder}: in use by {who} (its lock {lock}; remove it only if "
                        "that process is gone)") from None
                with contextlib.suppress(FileNotFoundError):
                    lock.unlink()
        raise MotionlangError(f"{folder}: could not take the lock {lock}")
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def release(lock: Path) -> None:
    """Remove ``lock`` if this process still holds it."""
    holder = _holder(lock)
    if holder is not None and holder.get("pid") == os.getpid() \
            and holder.get("host") == _host():
        with contextlib.suppress(FileNotFoundError):
            lock.unlink()


@contextlib.contextmanager
def folder_lock(folder: str | Path) -> Iterator[Path]:
    """Hold ``folder``'s lock (the folder made if missing) for the block; released when
    the block ends, by an error or by Ctrl-C / SIGTERM (``utils.signals``) too. A folder
    made here that holds nothing else afterwards is removed again."""
    folder = Path(folder)
    made = []   # the folders made here, innermost first
    p = folder
    while not os.path.lexists(p) and p != p.parent:
        made.append(p)
        p = p.parent
    folder.mkdir(parents=True, exist_ok=True)
    try:
        lock = acquire(folder)
    except BaseException:
        _remove_empty(made)
        raise
    try:
        yield lock
    finally:
        release(lock)
        _remove_empty(made)


def _remove_empty(folders: list[Path]) -> None:
    """Remove these folders, innermost first, while they are empty: a failed first run
    leaves no folder behind."""
    for p in folders:
        try:
            p.rmdir()
        except OSError:
            return


def entries(folder: str | Path) -> list[str]:
    """The names in ``folder`` that count as content: not its lock, not temporary files
    (``utils.atomic``); [] when the folder does not exist."""
    try:
        names = os.listdir(folder)
    except FileNotFoundError:
        return []
    except NotADirectoryError:
        return [str(folder)]
    return sorted(n for n in names if n != LOCK_NAME and TAG not in n)


#: what :func:`check_new_output` suggests by default
OVERWRITE_HINT = "give --overwrite to replace what is there, or another folder"


def check_new_output(folder: str | Path, option: str, hint: str = OVERWRITE_HINT) -> None:
    """Refuse an output folder that already holds something (a dataset, a run), naming a
    few of its entries; an absent or empty folder passes.

    Raises:
        MotionlangError: ``OPTION DIR: not empty (a, b, ...); HINT``.
    """
    names = entries(folder)
    if names:
        shown = ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")
        if Path(folder).exists() and not Path(folder).is_dir():
            raise MotionlangError(f"{option} {folder}: a file, not a folder")
        raise MotionlangError(f"{option} {folder}: not empty ({shown}); {hint}")


def check_no_clash(folder: str | Path, names: list[str] | set[str], option: str,
                   hint: str = "--overwrite") -> None:
    """Refuse to write ``names`` into ``folder`` where any of them exists already (an
    output that adds to a folder: split files beside a dataset, a corpus extended).

    Raises:
        MotionlangError: ``OPTION DIR: already holds a, b (...): give HINT ...``.
    """
    there = set(entries(folder))
    clash = sorted(there & set(names))
    if clash:
        shown = ", ".join(clash[:5]) + (f", ... ({len(clash)} in all)" if len(clash) > 5 else "")
        raise MotionlangError(f"{option} {folder}: already holds {shown}; give {hint} to "
                              "replace them, or another folder")
