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
import errno
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

from motionlang.errors import MotionlangError

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
def atomic_path(target: str | Path, suffix: str | None = None, *,
                min_bytes: int = 1, sync: bool = True) -> Iterator[Path]:
    """Yield a temporary path next to ``target``; rename it onto ``target`` on success.

    Use this for libraries that insist on writing to a path themselves (matplotlib,
    imageio, torch.save). The temporary file keeps the target's suffix so that writers
    which pick a format from the extension still work. Before the rename the file is
    checked (it exists, with at least ``min_bytes`` bytes: a writer whose child process
    died may leave it empty) and, unless ``sync=False``, forced to disk, and the folder
    synced after the rename.

    Raises:
        WriteError: the write failed for a reason of the file system (disk full,
            read-only, permission, a folder in the way), raised by the writer itself or
            found in its exception chain (imageio reports ffmpeg's broken pipe as another
            error); the target is untouched and the temporary file gone.
    """
    target = Path(target)
    try:
        tmp_path = make_temp(target, target.suffix if suffix is None else suffix)
        # mkstemp creates 0600 files; give the result the permissions a plain open() would.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp_path, 0o666 & ~umask)
    except OSError as exc:
        if isinstance(exc, FileExistsError):   # mkdir of a folder that is a file
            exc = NotADirectoryError(errno.ENOTDIR, os.strerror(errno.ENOTDIR))
        raise WriteError(target, exc) from None
    try:
        yield tmp_path
        _settle(tmp_path, target, min_bytes, sync)
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp_path.unlink()
        cause = _os_cause(exc, target.parent)
        if cause is not None and not isinstance(exc, WriteError):
            raise WriteError(target, cause) from None
        raise


def _settle(tmp: Path, target: Path, min_bytes: int, sync: bool) -> None:
    """Check ``tmp``, fsync it, rename it onto ``target`` and fsync the folder."""
    size = os.stat(tmp).st_size
    if size < min_bytes:
        raise WriteError(target, f"the writer produced {size} bytes")
    if not sync:
        os.replace(tmp, target)
        return
    fd = os.open(tmp, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)
    os.replace(tmp, target)
    with contextlib.suppress(OSError):   # not every file system syncs a folder
        dfd = os.open(target.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)


def _os_cause(exc: BaseException, folder: Path) -> OSError | None:
    """The file-system error behind a failed write: ``exc`` itself or one in its chain, or,
    for a writer that hides it (torch reports a full disk as a RuntimeError), ENOSPC when
    the folder's file system has no space left. None for other failures (a bug, Ctrl-C)."""
    if not isinstance(exc, Exception):
        return None
    found, seen = None, exc
    for _ in range(8):
        if isinstance(seen, OSError) and seen.errno in CAUSES:
            found = seen
            break
        nxt = seen.__cause__ or seen.__context__
        if nxt is None:
            break
        seen = nxt
    if found is not None and found.errno != errno.EPIPE:
        return found
    with contextlib.suppress(OSError):   # a writer's child that died of a full disk
        st = os.statvfs(folder)
        if st.f_bavail == 0 or (st.f_files and st.f_favail == 0):
            return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    return found


#: file-system causes of a failed write, as a user would name them
CAUSES = {errno.ENOSPC: "disk full", errno.EDQUOT: "disk quota exceeded",
          errno.EROFS: "read-only file system", errno.EACCES: "permission denied",
          errno.EPERM: "operation not permitted", errno.EISDIR: "is a folder",
          errno.ENOTDIR: "a file stands where a folder is needed",
          errno.EEXIST: "already exists", errno.ENOENT: "no such file or folder",
          errno.ENAMETOOLONG: "name too long", errno.EFBIG: "file too large",
          errno.EIO: "input/output error", errno.ELOOP: "too many symbolic links",
          errno.EMFILE: "too many open files", errno.ENXIO: "no such device",
          errno.EPIPE: "the writing process stopped"}


def os_error_line(exc: OSError, path: str | Path | None = None) -> str:
    """One line naming the path and the cause of ``exc``: ``out/model.pt: cannot write:
    disk full (No space left on device)``."""
    where = path if path is not None else exc.filename
    cause = CAUSES.get(exc.errno or 0)
    text = exc.strerror or str(exc) or type(exc).__name__
    reason = f"{cause} ({text})" if cause and cause.lower() != text.lower() else text
    return f"{where}: {reason}" if where else reason


def error_line(exc: BaseException) -> str:
    """The one line of an error for the user: :func:`os_error_line` for an ``OSError``."""
    return os_error_line(exc) if isinstance(exc, OSError) else str(exc)


class WriteError(MotionlangError):
    """A file could not be written; the message names the path and the cause."""

    def __init__(self, path: str | Path, cause: OSError | str):
        self.path = str(path)
        self.errno = cause.errno if isinstance(cause, OSError) else None
        reason = os_error_line(cause, "") if isinstance(cause, OSError) else cause
        super().__init__(f"{path}: cannot write: {reason}")


@contextlib.contextmanager
def atomic_write(target: str | Path, mode: str = "w", encoding: str | None = "utf-8",
                 fsync: bool = True) -> Iterator[IO]:
    """Open a temporary file for writing; it replaces ``target`` only if the block succeeds.

    ``fsync=False`` skips forcing the data to disk before the rename: still never a
    half-written file for readers, but a power cut may lose it. Bulk writers of thousands of
    small files (the procedural corpus) use it, since the sync dominates their run time.
    """
    binary = "b" in mode
    with atomic_path(target, min_bytes=0, sync=fsync) as tmp:
        with open(tmp, mode, encoding=None if binary else encoding) as fh:
            yield fh
            fh.flush()


@contextlib.contextmanager
def new_folder(path: str | Path, *, remove_files: bool = False) -> Iterator[Path]:
    """Make the output folder ``path`` (and its missing parents) for a block of writes.

    If the block fails (an error, Ctrl-C, SIGTERM under ``utils.signals``) and this call
    made the folder, it is removed again when it holds no file, so a failed first write
    leaves no half-made folder behind; with ``remove_files`` it is removed with whatever
    the block wrote (for outputs that are useless unless complete, a generated corpus). A
    folder that existed before is never removed, and files in it are left as they are (a
    run folder with checkpoints stays resumable).

    Raises:
        WriteError: the folder cannot be made (permission, read-only, a file in the way).
    """
    path = Path(path)
    top = None
    p = path
    while not os.path.lexists(p) and p != p.parent:
        top, p = p, p.parent
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise WriteError(path, exc) from None
    try:
        yield path
    except BaseException:
        if top is not None and (remove_files or not any(f for _, _, f in os.walk(top))):
            shutil.rmtree(top, ignore_errors=True)
        raise


def write_texts(files: dict) -> None:
    """Write each ``{path: text}`` atomically (UTF-8; missing folders are made)."""
    for target, text in files.items():
        with atomic_write(target) as fh:
            fh.write(text)
