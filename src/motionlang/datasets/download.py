"""Resumable HTTP downloads with checksum checks, and safe zip and tar extraction.

Standard library only (``urllib``): a dataset download must work in a bare environment.
Downloads named as archives are checked to be archives before they are kept; extraction
refuses path tricks, links, name clashes, encrypted members, unknown compression and
archives that expand beyond the limits of :mod:`motionlang.utils.limits`
(``MOTIONLANG_MAX_ARCHIVE_RATIO``, ``MOTIONLANG_MAX_ARCHIVE_BYTES``), each with one
``DatasetError`` line, leaving nothing behind.
"""
from __future__ import annotations

import contextlib
import errno
import hashlib
import http.client
import lzma
import os
import shutil
import stat
import tarfile
import urllib.error
import urllib.request
import zipfile
import zlib
from collections.abc import Callable
from pathlib import Path, PurePosixPath

from motionlang.errors import DatasetError
from motionlang.utils import limits
from motionlang.utils.atomic import make_temp
from motionlang.utils.progress import progress

CHUNK = 1 << 20  # bytes per read
ZIP_METHODS = {zipfile.ZIP_STORED, zipfile.ZIP_DEFLATED, zipfile.ZIP_BZIP2, zipfile.ZIP_LZMA}
TAR_SUFFIXES = (".tar", ".tar.gz", ".tgz", ".tar.bz2", ".tbz2", ".tar.xz", ".txz")


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

    A ``target`` named as an archive (``.zip``, ``.tar``, ``.tar.gz``, ``.tar.xz``...) must
    hold one: without a checksum, what the server sent is checked to be such an archive
    before it becomes ``target`` (a login or error page served with status 200 is refused
    and not kept), and an existing ``target`` that is not one (left by an older version) is
    downloaded again rather than reused.

    Args:
        url: http(s) URL.
        target: final file path; an existing file is reused (after the checksum, if given).
        sha256: expected hex digest; mismatch -> ``DatasetError`` and the ``.part`` is
            deleted (resuming corrupt bytes would never succeed).
        timeout: seconds without data before giving up.

    Raises:
        DatasetError: offline / connection refused, HTTP error, short read, bad checksum,
            not the archive the name promises; the message names the URL.
    """
    if not url.lower().startswith(("http://", "https://")):
        raise DatasetError(f"{url}: only http(s) URLs can be downloaded")
    target = Path(target)
    target.parent.mkdir(parents=True, exist_ok=True)
    expected = sha256.lower().strip() if sha256 else None
    if target.exists():
        if _still_good(target, expected):
            return target
        target.unlink()  # stale, corrupt, or a web page saved as the archive: fetch again
    part = target.with_name(target.name + ".part")
    total = _fetch(url, part, timeout, desc or target.name)
    _check_part(url, part, target.name, total, expected)
    os.replace(part, target)
    return target


def _still_good(target: Path, expected: str | None) -> bool:
    """Whether an existing ``target`` can be reused: its checksum matches, or (without
    one) it is the archive its name promises."""
    return sha256_file(target) == expected if expected else \
        _archive_problem(target, target.name) is None


def _fetch(url: str, part: Path, timeout: float, desc: str) -> int | None:
    """Append the rest of ``url`` to ``part`` (or write it afresh when the server cannot
    resume); the file's full size when the server told it, else None."""
    offset = _part_size(part)
    try:
        resp, offset = _open_resuming(url, part, offset, timeout)
        with resp:
            status = getattr(resp, "status", 200)
            content_range = resp.headers.get("Content-Range", "")
            if offset and not (status == 206 and content_range.startswith(f"bytes {offset}-")):
                offset = 0  # Range ignored: the body is the whole file
            length = resp.headers.get("Content-Length")
            total = offset + int(length) if length and length.isdigit() else None
            with _open_part(part, append=bool(offset)) as fh, \
                    progress(desc=desc, total=total, unit="B", unit_scale=True,
                             unit_divisor=1024, initial=offset) as bar:
                for block in iter(lambda: resp.read(CHUNK), b""):
                    fh.write(block)
                    bar.update(len(block))
    except urllib.error.HTTPError as exc:
        raise DatasetError(f"{url}: HTTP error {exc.code} {exc.reason}") from None
    except urllib.error.URLError as exc:
        raise DatasetError(f"{url}: cannot connect ({exc.reason}); are you offline?") from None
    except (http.client.HTTPException, OSError) as exc:
        kept = _part_size(part)
        raise DatasetError(f"{url}: transfer interrupted ({exc!r}); {kept} bytes kept in "
                           f"{part}, run again to resume") from None
    return total


def _part_size(part: Path) -> int:
    """Bytes already in ``part`` (0 when absent), read without following a link.

    Raises:
        DatasetError: ``part`` is a symbolic link or not a regular file: writing through
            it would change another file (a planted link), or hang (a FIFO).
    """
    try:
        st = os.lstat(part)
    except FileNotFoundError:
        return 0
    if not stat.S_ISREG(st.st_mode):
        what = "a symbolic link" if stat.S_ISLNK(st.st_mode) else "not a regular file"
        raise DatasetError(f"{part}: {what}, not a partial download; it is left as it is: "
                           "remove it to download afresh")
    return st.st_size


def _open_part(part: Path, append: bool):
    """``part`` opened for writing without following links: appended to, truncated, or
    created new (``O_EXCL``, so a link or file put there meanwhile fails instead)."""
    flags = os.O_WRONLY | getattr(os, "O_NOFOLLOW", 0) | getattr(os, "O_BINARY", 0)
    if append:
        flags |= os.O_APPEND
    elif os.path.lexists(part):
        flags |= os.O_TRUNC
    else:
        flags |= os.O_CREAT | os.O_EXCL
    try:
        fd = os.open(part, flags, 0o644)
    except OSError as exc:
        if exc.errno in (errno.ELOOP, errno.EEXIST):
            raise DatasetError(f"{part}: replaced by a link or another file during the "
                               "download; it is left as it is") from None
        raise
    if not stat.S_ISREG(os.fstat(fd).st_mode):
        os.close(fd)
        raise DatasetError(f"{part}: not a regular file, not a partial download")
    return os.fdopen(fd, "ab" if append else "wb")


def _open_resuming(url: str, part: Path, offset: int, timeout: float):
    """(response, offset) of a request for ``url`` from byte ``offset``; from 0 when the
    server says the range cannot be satisfied (the ``.part`` is deleted)."""
    try:
        return _open(url, offset, timeout), offset
    except urllib.error.HTTPError as exc:
        if exc.code == 416 and offset:  # our .part is no prefix of the file: start over
            part.unlink()
            return _open(url, 0, timeout), 0
        raise


def _check_part(url: str, part: Path, name: str, total: int | None,
                expected: str | None) -> None:
    """Refuse a ``.part`` that is short, fails the checksum, or (without one) is not the
    archive ``name`` promises; the last two are deleted."""
    size = part.stat().st_size
    if total is not None and size != total:
        raise DatasetError(f"{url}: incomplete download ({size} of {total} bytes); "
                           "run again to resume")
    if expected is not None:
        got = sha256_file(part)
        if got != expected:
            part.unlink()
            raise DatasetError(f"{url}: sha256 mismatch: expected {expected}, got {got}")
    elif (problem := _archive_problem(part, name)) is not None:
        part.unlink()
        raise DatasetError(f"{url}: {problem}; nothing was kept: check the URL, or run again "
                           "later")


def _archive_problem(path: Path, name: str) -> str | None:
    """Why the file ``path`` is not the archive that ``name`` promises; None if it is one,
    or if ``name`` promises none."""
    name = name.lower()
    if name.endswith(".zip"):
        kind, ok = "zip", zipfile.is_zipfile(path)
    elif name.endswith(TAR_SUFFIXES):
        kind = "tar"
        try:
            with tarfile.open(path) as tf:
                ok = tf.next() is not None
        except (tarfile.TarError, EOFError, lzma.LZMAError, zlib.error, OSError):
            ok = False
    else:
        return None
    if ok:
        return None
    with open(path, "rb") as fh:
        head = fh.read(2048).lstrip().lower()
    if head.startswith((b"<!doctype html", b"<html", b"<?xml")) or b"<html" in head:
        return f"the server sent a web page (HTML), not the {kind} archive"
    return f"what the server sent is not a {kind} archive"


def _member_path(name: str, archive: Path) -> PurePosixPath:
    """The relative path of an archive member, refusing anything that could leave the folder."""
    p = PurePosixPath(name.replace("\\", "/"))
    if p.is_absolute() or ".." in p.parts or (p.parts and ":" in p.parts[0]) or "\0" in name:
        raise DatasetError(f"{archive}: unsafe path in archive: {name!r}")
    return p


class _Budget:
    """What an extraction may still write: the limits of ``utils.limits`` (total bytes,
    expansion ratio over the archive's size beyond a floor) and the free disk space; and
    the names written so far, to refuse name clashes."""

    def __init__(self, archive: Path, dest: Path):
        lim = limits.current()
        self.archive, self.left, self.name = archive, lim.max_archive_bytes, "max_archive_bytes"
        by_ratio = max(limits.RATIO_FLOOR_BYTES, lim.max_archive_ratio * archive.stat().st_size)
        if by_ratio < self.left:
            self.left, self.name = int(by_ratio), "max_archive_ratio"
        self.limit, self.ratio = self.left, lim.max_archive_ratio
        self.free = shutil.disk_usage(dest).free
        self.files: set[PurePosixPath] = set()
        self.folders: set[PurePosixPath] = set()

    def check(self, nbytes: int, what: str) -> None:
        """Refuse if ``nbytes`` more would not fit."""
        if nbytes > self.left:
            why = "" if self.name == "max_archive_bytes" else \
                f" ({self.ratio:g} times the archive's size, " \
                f"{limits.human('max_archive_bytes', limits.RATIO_FLOOR_BYTES)} at least)"
            raise DatasetError(
                f"{self.archive}: refused: {what} would expand it to more than "
                f"{limits.human('max_archive_bytes', self.limit)}{why}; raise it with "
                f"{limits.ENV[self.name]}=... if the archive is genuine")
        if nbytes > self.free:
            raise DatasetError(f"{self.archive}: not enough free disk space to extract it "
                               f"({what})")

    def take(self, nbytes: int, what: str) -> None:
        """Account for ``nbytes`` more, written for member ``what``."""
        self.check(nbytes, f"member {what!r}")
        self.left -= nbytes
        self.free -= nbytes

    def add_name(self, rel: PurePosixPath, folder: bool, name: str) -> None:
        """Refuse a member whose path another member already has, as a file or a folder."""
        parents = set(rel.parents) - {PurePosixPath(".")}
        if (not folder and (rel in self.files or rel in self.folders)) or \
                (folder and rel in self.files) or parents & self.files:
            raise DatasetError(f"{self.archive}: name clash in archive: {name!r} (two members "
                               "with the same path, or a file where a folder is needed)")
        (self.folders if folder else self.files).add(rel)
        self.folders |= parents


def _copy(src, out: Path, budget: _Budget, name: str) -> None:
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "wb") as dst:
        for block in iter(lambda: src.read(CHUNK), b""):
            budget.take(len(block), name)
            dst.write(block)


def _zip_members(zf: zipfile.ZipFile, archive: Path, budget: _Budget, keep):
    """The members to extract, checked before anything is written: safe paths, no links,
    no clash, not encrypted, a compression zipfile reads, declared sizes within budget."""
    out = []
    for info in zf.infolist():
        rel = _member_path(info.filename, archive)
        if stat.S_ISLNK(info.external_attr >> 16):
            raise DatasetError(f"{archive}: symbolic link in archive: {info.filename!r}")
        if not rel.parts or (keep and not info.is_dir() and not keep(info.filename)):
            continue
        budget.add_name(rel, info.is_dir(), info.filename)
        if info.is_dir():
            continue
        if info.flag_bits & 0x1:
            raise DatasetError(f"{archive}: encrypted member {info.filename!r} "
                               "(password-protected archives are not supported)")
        if info.compress_type not in ZIP_METHODS:
            raise DatasetError(f"{archive}: member {info.filename!r} uses compression method "
                               f"{info.compress_type}, which cannot be read (stored, deflate, "
                               "bzip2 and lzma can)")
        out.append((info, rel))
    budget.check(sum(info.file_size for info, _ in out), "the sizes its members declare")
    return out


def safe_extract(archive: str | Path, dest: str | Path, *,
                 keep: Callable[[str], bool] | None = None) -> Path:
    """Extract a zip into ``dest`` safely and atomically.

    Members are written to a temporary folder next to ``dest`` (named and swept as in
    :mod:`motionlang.utils.atomic`) that is renamed onto ``dest`` at the end, so ``dest``
    either does not exist or is complete. Refused with a ``DatasetError``, before anything is
    written: absolute paths, ``..`` components, symbolic links, two members with one path,
    encrypted members, unknown compression methods, and archives that expand beyond
    ``MOTIONLANG_MAX_ARCHIVE_BYTES``, beyond ``MOTIONLANG_MAX_ARCHIVE_RATIO`` times their
    own size, or beyond the free disk space (:mod:`motionlang.utils.limits`); the sizes are
    also counted as the bytes come, whatever the archive declares.

    Args:
        keep: predicate on member names; members it rejects are skipped.
    """
    archive, dest = Path(archive), Path(dest)
    bad = (zipfile.BadZipFile, zlib.error, EOFError, lzma.LZMAError, NotImplementedError,
           ValueError)
    with _staged(archive, dest, "zip", bad) as (tmp, budget):
        with zipfile.ZipFile(archive) as zf:
            for info, rel in _zip_members(zf, archive, budget, keep):
                with zf.open(info) as src:
                    _copy(src, tmp.joinpath(*rel.parts), budget, info.filename)
    return dest


@contextlib.contextmanager
def _staged(archive: Path, dest: Path, kind: str, bad: tuple):
    """Extraction into a temporary folder beside ``dest``, renamed onto it when the body
    ends without error and removed in every case; yields (folder, size budget). ``bad``:
    the exceptions that mean a broken ``kind`` archive."""
    if dest.exists():
        raise DatasetError(f"{dest}: already exists; remove it to extract {archive} again")
    tmp = make_temp(dest, ".extract", directory=True)
    try:
        yield tmp, _Budget(archive, dest.parent)
        os.replace(tmp, dest)
    except bad as exc:
        raise DatasetError(f"{archive}: not a valid {kind} archive ({exc}); if it was "
                           "downloaded, delete it and download it again") from None
    except OSError as exc:
        raise DatasetError(f"{archive}: cannot extract: {exc.strerror or exc}") from None
    finally:
        with contextlib.suppress(FileNotFoundError):
            shutil.rmtree(tmp)


def safe_extract_tar(archive: str | Path, dest: str | Path, *,
                     keep: Callable[[str], bool] | None = None) -> Path:
    """:func:`safe_extract` for tar archives (``.tar``, ``.tar.gz``, ``.tar.xz``...):
    regular files only (links, devices and FIFOs refused), no absolute or ``..`` paths, no
    name clash, the same size limits (checked member by member as the stream is read, a
    compressed tar having no index), extracted to a temporary folder renamed onto ``dest``
    when complete."""
    archive, dest = Path(archive), Path(dest)
    bad = (tarfile.TarError, EOFError, lzma.LZMAError, zlib.error)
    with _staged(archive, dest, "tar", bad) as (tmp, budget):
        with tarfile.open(archive) as tf:
            for info in tf:
                rel = _member_path(info.name, archive)
                if not rel.parts or (keep and not info.isdir() and not keep(info.name)):
                    continue
                if not (info.isdir() or info.isfile()):
                    raise DatasetError(f"{archive}: not a regular file in archive: {info.name!r}")
                budget.add_name(rel, info.isdir(), info.name)
                if info.isfile():
                    budget.check(info.size, f"member {info.name!r}")
                    _copy(tf.extractfile(info), tmp.joinpath(*rel.parts), budget, info.name)
    return dest
