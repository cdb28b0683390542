"""A small on-disk cache of computed arrays (features of a dataset, say).

``cached(key_parts, compute)`` returns ``compute()``'s dict of arrays, stored as one
``.npz`` under ``$MOTIONLANG_CACHE`` (default ``~/.cache/motionlang``). The key is the
sha256 of ``key_parts`` (JSON, sorted keys); put the identity of every source in it with
``file_identity(path)`` (resolved path, size, mtime) so that an edited file invalidates the
entry. A corrupt or unreadable cache file is recomputed, never an error; a cache folder
that cannot be written (read-only, a file, a full disk) is a warning, once.
"""
from __future__ import annotations

import hashlib
import json
import logging
import os
import zipfile
from collections.abc import Callable, Iterable
from pathlib import Path

import numpy as np

from motionlang.errors import DatasetError
from motionlang.utils.atomic import WriteError, atomic_write

CACHE_ENV = "MOTIONLANG_CACHE"
log = logging.getLogger(__name__)


def cache_dir() -> Path:
    """``$MOTIONLANG_CACHE`` or ``~/.cache/motionlang``."""
    env = os.environ.get(CACHE_ENV)
    return Path(env).expanduser() if env else Path.home() / ".cache" / "motionlang"


def file_identity(path: str | Path) -> dict:
    """``{"path", "size", "mtime_ns"}`` of a file, for cache keys."""
    p = Path(path).resolve()
    try:
        st = p.stat()
    except OSError as exc:
        raise DatasetError(f"{path}: cannot stat ({exc.strerror})") from None
    return {"path": str(p), "size": st.st_size, "mtime_ns": st.st_mtime_ns}


def files_identity(paths: Iterable[str | Path]) -> list[dict]:
    return [file_identity(p) for p in paths]


def cache_key(key_parts: dict) -> str:
    """Hex sha256 of ``key_parts`` as canonical JSON (non-JSON values via ``str``)."""
    blob = json.dumps(key_parts, sort_keys=True, default=str, separators=(",", ":"))
    return hashlib.sha256(blob.encode("utf-8")).hexdigest()


def _load(path: Path) -> dict[str, np.ndarray] | None:
    try:
        with np.load(path, allow_pickle=False) as z:
            return {k: z[k] for k in z.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, KeyError):
        return None  # corrupt or half-written by a crashed foreign process: recompute


def cached(key_parts: dict, compute: Callable[[], dict[str, np.ndarray]], *,
           name: str = "cache", directory: str | Path | None = None,
           refresh: bool = False) -> dict[str, np.ndarray]:
    """Load the arrays stored under ``key_parts`` or compute and store them.

    Args:
        key_parts: everything the result depends on (sources via ``file_identity``, options,
            a version string of the computation).
        compute: returns ``{name: array}`` (no object arrays).
        name: readable prefix of the cache file name.
        directory: cache folder (default ``cache_dir()``).
        refresh: ignore an existing entry.

    Returns:
        ``{name: np.ndarray}``, identical whether loaded or computed.
    """
    folder = Path(directory) if directory is not None else cache_dir()
    safe = "".join(c if c.isalnum() or c in "-_" else "_" for c in name)[:40]
    path = folder / f"{safe}-{cache_key(key_parts)[:32]}.npz"
    if not refresh and path.exists():
        hit = _load(path)
        if hit is not None:
            return hit
    arrays = compute()
    if not isinstance(arrays, dict):
        raise TypeError("cached(): compute() must return a dict of arrays")
    arrays = {k: np.asarray(v) for k, v in arrays.items()}
    try:
        with atomic_write(path, "wb") as fh:
            np.savez(fh, **arrays)
    except (OSError, WriteError) as exc:   # the cache is optional: go on without it
        _warn_once(folder, exc)
    return arrays


_warned: set[str] = set()


def _warn_once(folder: Path, exc: Exception) -> None:
    """One warning per cache folder that cannot be written (read-only, a file, full)."""
    if str(folder) in _warned:
        return
    _warned.add(str(folder))
    log.warning("cache %s not used (%s); set %s to a writable folder to keep results",
                folder, exc, CACHE_ENV)
