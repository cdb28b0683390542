"""Resumable HTTP downloads with checksum checks, and safe zip extraction.

Standard library only (``urllib``): a dataset download must work in a bare environment.
"""
from __future__ import annotations

import contextlib
import hashlib
import http.client
import os
import shutil
import stat
import tempfile
import urllib.error
import urllib.request
import zipfile
from pathlib import Path, PurePosixPath
from typing import Callable

from motionlang.errors import DatasetError
from motionlang.utils.progress import progress

CHUNK = 1 << 20  # bytes per read


def sha256_file(path: str | Path, chunk: int = CHUNK) -> str:
    """Hex sha256 of a file, read in chunks."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(chunk), b""):
            h.update(block)
    return h.hexdigest()


def _open(url: str, offset: int, timeout: float):
    req = urllib.request.Request(url, headers={"User-Agent": "motionlang"})
    if offset:
        req.add_header("Range", f"bytes={offset}-")
    return urllib.request.urlopen(req, timeout=timeout)  # noqa: S310 (http/https only, checked)


def download_file(url: str, target: str | Path, *, sha256: str | None = None,
                  timeout: float = 60.0, desc: str | None = None) -> Path:
    """Download ``url`` to ``target``, resuming an earlier partial download.

    The bytes go to ``target + ".part"``, which is kept when the transfer breaks off so that
    the next call continues it with an HTTP ``Range`` request (a server that ignores
    ``Range`` and answers 200 makes the download start again from byte 0). Only a complete,
    verified file is renamed onto ``target`` (atomic ``os.replace``), so ``target`` is never
    partial. The ``.part`` file is not written through ``utils.atomic`` on purpose: keeping
    the partial bytes across failures is the point of it.

    Args:
        url: http(s) URL.
        target: final file path; an existing file is reused (after the checksum, if given).
        sha256: expected hex digest; mismatch -> ``DatasetError`` and the ``.part`` is
            deleted (resuming corrupt bytes would never succeed).
        timeout: seconds without data before giving up.

    Raises:
        DatasetError: offline / connection refused, HTTP error, short read, bad checksum;
            the message names the URL.
    """
    if not url.lower().startswith(("http://", "https://")):
        raise DatasetError(f"{url}: only http(s) URLs can be downloaded")
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    expected = sha256.lower().strip() if sha256 else None
    if target.exists():
        if expected is None or sha256_file(target) == expected:
            return target
        target.unlink()  # stale or corrupt: fetch again
    part = target.with_name(target.name + ".part")
    offset = part.stat().st_size if part.exists() else 0
    try:
        try:
            resp = _open(url, offset, timeout)
        except urllib.error.HTTPError as exc:
            if exc.code == 416 and offset:  # our .part is no prefix of the file: start over
                part.unlink()
                offset = 0
                resp = _open(url, 0, timeout)
            else:
                raise
        with resp:
            status = getattr(resp, "status", 200)
            content_range = resp.headers.get("Content-Range", "")
            if offset and not (status == 206 and content_range.startswith(f"bytes {offset}-")):
                offset = 0  # Range ignored: the body is the whole file
            length = resp.headers.get("Content-Length")
            total = offset + int(length) if length and length.isdigit() else None
            with open(part, "ab" if offset else "wb") as fh, \
                    progress(desc=desc or target.name, total=total, unit="B", unit_scale=True,
                             unit_divisor=1024, initial=offset) as bar:
                for block in iter(lambda: resp.read(CHUNK), b""):
                    fh.write(block)
                    bar.update(len(block))
    except urllib.error.HTTPError as exc:
        raise DatasetError(f"{url}: HTTP error {exc.code} {exc.reason}") from None
    except urllib.error.URLError as exc:
        raise DatasetError(f"{url}: cannot connect ({exc.reason}); are you offline?") from None
    except (http.client.HTTPException, OSError) as exc:
        kept = part.stat().st_size if part.exists() else 0
        raise DatasetError(f"{url}: transfer interrupted ({exc!r}); {kept} bytes kept in "
                           f"{part}, run again to resume") from None
    size = part.stat().st_size
    if total is not None and size != total:
        raise DatasetError(f"{url}: incomplete download ({size} of {total} bytes); "
                           "run again to resume")
    if expected is not None:
        got = sha256_file(part)
        if got != expected:
            part.unlink()
            raise DatasetError(f"{url}: sha256 mismatch: expected {expected}, got {got}")
    os.replace(part, target)
    return target


def _member_path(name: str, archive: Path) -> PurePosixPath:
    """The relative path of a zip member, refusing anything that could leave the folder."""
    p = PurePosixPath(name.replace("\\", "/"))
    if p.is_absolute() or ".." in p.parts or (p.parts and ":" in p.parts[0]):
        raise DatasetError(f"{archive}: unsafe path in archive: {name!r}")
    return p


def safe_extract(archive: str | Path, dest: str | Path, *,
                 keep: Callable[[str], bool] | None = None) -> Path:
    """Extract a zip into ``dest`` without path traversal, atomically.

    Members are written to a temporary folder next to ``dest`` that is renamed onto
    ``dest`` at the end, so ``dest`` either does not exist or is complete. Absolute paths,
    ``..`` components and symbolic links are refused with ``DatasetError``.

    Args:
        keep: predicate on member names; members it rejects are skipped.
    """
    archive, dest = Path(archive), Path(dest)
    if dest.exists():
        raise DatasetError(f"{dest}: already exists; remove it to extract {archive} again")
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", dir=dest.parent))
    try:
        with zipfile.ZipFile(archive) as zf:
            for info in zf.infolist():
                rel = _member_path(info.filename, archive)
                if stat.S_ISLNK(info.external_attr >> 16):
                    raise DatasetError(f"{archive}: symbolic link in archive: {info.filename!r}")
                if info.is_dir() or not rel.parts or (keep and not keep(info.filename)):
                    continue
                out = tmp.joinpath(*rel.parts)
                out.parent.mkdir(parents=True, exist_ok=True)
                with zf.open(info) as src, open(out, "wb") as dst:
                    shutil.copyfileobj(src, dst, CHUNK)
        os.replace(tmp, dest)
    except zipfile.BadZipFile as exc:
        raise DatasetError(f"{archive}: not a valid zip archive ({exc})") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            shutil.rmtree(tmp)
    return dest


def safe_extract_tar(archive: str | Path, dest: str | Path, *,
                     keep: Callable[[str], bool] | None = None) -> Path:
    """:func:`safe_extract` for tar archives (``.tar``, ``.tar.gz``, ``.tar.xz``...):
    regular files only (links, devices and FIFOs refused), no absolute or ``..`` paths,
    extracted to a temporary folder renamed onto ``dest`` when complete."""
    import lzma
    import tarfile
    import zlib

    archive, dest = Path(archive), Path(dest)
    if dest.exists():
        raise DatasetError(f"{dest}: already exists; remove it to extract {archive} again")
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{dest.name}.", dir=dest.parent))
    try:
        with tarfile.open(archive) as tf:
            for info in tf:
                rel = _member_path(info.name, archive)
                if info.isdir() or not rel.parts or (keep and not keep(info.name)):
                    continue
                if not info.isfile():
                    raise DatasetError(f"{archive}: not a regular file in archive: {info.name!r}")
                out = tmp.joinpath(*rel.parts)
                out.parent.mkdir(parents=True, exist_ok=True)
                src = tf.extractfile(info)
                with src, open(out, "wb") as dst:
                    shutil.copyfileobj(src, dst, CHUNK)
        os.replace(tmp, dest)
    except (tarfile.TarError, EOFError, lzma.LZMAError, zlib.error) as exc:
        raise DatasetError(f"{archive}: not a valid tar archive ({exc})") from None
    except OSError as exc:
        raise DatasetError(f"{archive}: cannot extract: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            shutil.rmtree(tmp)
    return dest
