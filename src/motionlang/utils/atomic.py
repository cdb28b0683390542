"""Atomic writes: write to a temporary file in the target folder, then rename.

A reader never sees a half-written file, and a failure (exception, Ctrl-C) leaves the
previous version of the target, or nothing, in place.

Temporary files left by a killed process. No code runs when a process gets SIGKILL (the
OOM killer, ``kill -9``, a job scheduler), nor by default on SIGTERM or a power cut, so no
scheme that relies on cleaning up can stop a kill from leaving a temporary file. Linux's
``O_TMPFILE`` (an unnamed file, linked in when complete) would avoid that for writes done
through our own file object, but not for the writers that need a *path* (matplotlib picks
the format from its extension; imageio hands it to an ffmpeg child process), it still needs
a named link before the final rename, and not every file system has it. So instead the
temporary files are named recognisably::

    .<target name>.motionlang-tmp.<host>.<pid>.<random><target suffix>

and the first atomic write of a process into a folder removes the leftovers there whose
writer is gone: same host (and PID namespace) and that process id no longer running, or
another host and older than :data:`FOREIGN_STALE_S`. A live writer's file is never
touched (its process exists), so concurrent writers of the same target are safe. A kill
therefore leaves at most one stray file per target until the next run writes into that
folder. The same names and sweep serve
the temporary folders of archive extraction (``datasets.download``).
"""
from __future__ import annotations

import contextlib
import functools
import os
import re
import shutil
import socket
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path
from typing import IO

TAG = ".motionlang-tmp."
FOREIGN_STALE_S = 24 * 3600  # another host's temporary file older than this is stale
_OWNER = re.compile(re.escape(TAG) + r"([A-Za-z0-9-]+)\.(\d+)\.")
_swept: set[str] = set()  # folders this process has already swept


@functools.lru_cache(maxsize=1)
def _host() -> str:
    """This machine's name, plus the PID namespace where there is one (two containers
    may share a host name and a folder, but not process ids)."""
    host = re.sub(r"[^A-Za-z0-9-]", "-", socket.gethostname())[:40] or "host"
    with contextlib.suppress(OSError):
        host += "-" + format(os.stat("/proc/self/ns/pid").st_ino, "x")
    return host


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    if os.name == "nt":  # os.kill(pid, 0) would terminate it there; keep to the age rule
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # PermissionError: it exists, under another user
        return True
    return True


def is_stale(path: Path, now: float | None = None) -> bool:
    """Whether ``path`` is a motionlang temporary file or folder whose writer is gone."""
    m = _OWNER.search(path.name)
    if not path.name.startswith(".") or m is None:
        return False
    host, pid = m.group(1), int(m.group(2))
    if host == _host() and os.name != "nt":
        return not _alive(pid)
    try:
        age = (now or time.time()) - path.lstat().st_mtime
    except OSError:
        return False
    return age > FOREIGN_STALE_S


def sweep_stale(folder: str | Path, *, force: bool = False) -> list[Path]:
    """Remove the stale temporary files and folders in ``folder`` (once per process and
    folder unless ``force``); returns what was removed. Errors are ignored: another
    process may be sweeping too."""
    folder = Path(folder)
    key = os.path.abspath(folder)
    if key in _swept and not force:
        return []
    _swept.add(key)
    removed = []
    try:
        entries = [Path(e.path) for e in os.scandir(folder) if TAG in e.name]
    except OSError:
        return []
    for p in entries:
        if is_stale(p):
            with contextlib.suppress(OSError):
                if p.is_dir() and not p.is_symlink():
                    shutil.rmtree(p)
                else:
                    p.unlink()
                removed.append(p)
    return removed


def temp_prefix(target: Path) -> str:
    """Start of the names of ``target``'s temporary files (the name cut to stay short)."""
    return f".{target.name[:96]}{TAG}{_host()}.{os.getpid()}."


def make_temp(target: str | Path, suffix: str = "", *, directory: bool = False) -> Path:
    """Create an empty temporary file (or folder) next to ``target``, named as in the
    module docstring, after sweeping the folder's stale ones."""
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    sweep_stale(target.parent)
    if directory:
        return Path(tempfile.mkdtemp(prefix=temp_prefix(target), suffix=suffix,
                                     dir=target.parent))
    fd, tmp = tempfile.mkstemp(prefix=temp_prefix(target), suffix=suffix, dir=target.parent)
    os.close(fd)
    return Path(tmp)


@contextlib.contextmanager
def atomic_path(target: str | Path, suffix: str | None = None) -> Iterator[Path]:
    """Yield a temporary path next to ``target``; rename it onto ``target`` on success.

    Use this for libraries that insist on writing to a path themselves (matplotlib,
    imageio, torch.save). The temporary file keeps the target's suffix so that writers
    which pick a format from the extension still work.
    """
    target = Path(target)
    tmp_path = make_temp(target, target.suffix if suffix is None else suffix)
    # mkstemp creates 0600 files; give the result the permissions a plain open() would.
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp_path, 0o666 & ~umask)
    try:
        yield tmp_path
        os.replace(tmp_path, target)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


@contextlib.contextmanager
def atomic_write(target: str | Path, mode: str = "w", encoding: str | None = "utf-8",
                 fsync: bool = True) -> Iterator[IO]:
    """Open a temporary file for writing; it replaces ``target`` only if the block succeeds.

    ``fsync=False`` skips forcing the data to disk before the rename: still never a
    half-written file for readers, but a power cut may lose it. Bulk writers of thousands of
    small files (the procedural corpus) use it, since the sync dominates their run time.
    """
    binary = "b" in mode
    with atomic_path(target) as tmp:
        with open(tmp, mode, encoding=None if binary else encoding) as fh:
            yield fh
            fh.flush()
            if fsync:
                os.fsync(fh.fileno())


def write_texts(files: dict) -> None:
    """Write each ``{path: text}`` atomically (UTF-8; missing folders are made)."""
    for target, text in files.items():
        with atomic_write(target) as fh:
            fh.write(text)
