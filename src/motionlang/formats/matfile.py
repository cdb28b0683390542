"""A strict reader of MATLAB 5 MAT-files, written so that no file can crash the process.

scipy's reader (compiled code) trusts the tags it reads: a 264-byte file whose double-array
tag says type 8 instead of 9 kills the process with SIGSEGV, and it has no bound on what a
compressed variable expands to. This reader is numpy and the standard library only. Every
tag is checked against the bytes that contain it before it is used, every element count
against the bytes left, decompressed bytes and arrays against ``MOTIONLANG_MAX_MEMORY``
(:mod:`motionlang.utils.limits`), nesting to :data:`MAX_DEPTH` levels. A bad file is a
:class:`MotionFormatError` naming the file, the byte and what is wrong. The price is some
speed against scipy's ``loadmat`` in the same process, far less than scipy isolated in a
child process, the other way to survive such files (``benchmarks/bench_mit_read.py``;
figures in ``docs/results/real-rigs.md``).

It reads what MATLAB's ``save`` writes for numeric, logical, char, cell and struct arrays:
level 5 files (``-v6`` and ``-v7``: compressed or not), either byte order. Sparse arrays,
objects, function handles and v7.3 (HDF5) files are refused with a message.

Values: numeric and logical arrays as numpy arrays of the MATLAB class's dtype (a double
array that MATLAB stored as uint8, as it does for small integers, comes back as float64),
shaped as in MATLAB; char arrays as ``str`` (rows joined by newlines); cell arrays as
object arrays; struct arrays as object arrays of ``dict`` (field name -> value).
"""
from __future__ import annotations

import math
import zlib
from pathlib import Path

import numpy as np

from motionlang.errors import MotionFormatError
from motionlang.utils import limits

MAX_DEPTH = 32   # cells and structs nested deeper than this are refused
MAX_DIMS = 32
MI_INT8, MI_UINT8, MI_INT32, MI_UINT32 = 1, 2, 5, 6
MI_MATRIX, MI_COMPRESSED, MI_UTF8, MI_UTF16, MI_UTF32 = 14, 15, 16, 17, 18
MI_NUMERIC = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 9: "f8",
              12: "i8", 13: "u8"}
CELL, STRUCT, CHAR = 1, 2, 4
CLASS_DTYPE = {6: "f8", 7: "f4", 8: "i1", 9: "u1", 10: "i2", 11: "u2", 12: "i4", 13: "u4",
               14: "i8", 15: "u8"}
UNSUPPORTED = {3: "object", 5: "sparse", 16: "function handle", 17: "object (opaque)"}
LOGICAL, COMPLEX = 0x02, 0x08


class _Bad(Exception):
    """Internal: what is wrong, turned into a MotionFormatError naming the file."""


class _Reader:
    """Parses elements of one byte buffer (the file, or a decompressed variable)."""

    def __init__(self, order: str, budget: int):
        self.order = order      # "<" or ">"
        self.budget = budget    # bytes that decompression and arrays may still take

    def spend(self, nbytes: int, what: str) -> None:
        if nbytes > self.budget:
            lim = limits.current().max_memory_bytes
            raise _Bad(f"{what} needs more memory than the limit of {lim / 2**30:.3g} GiB "
                       f"allows (raise it with {limits.ENV['max_memory_bytes']}=...)")
        self.budget -= nbytes

    def uint32(self, buf: bytes, pos: int) -> int:
        return int.from_bytes(buf[pos:pos + 4], "little" if self.order == "<" else "big")

    def tag(self, buf: bytes, pos: int, end: int, padded: bool = True):
        """``(type, data start, data bytes, next element)`` of the element at ``pos``."""
        if pos + 8 > end:
            raise _Bad(f"truncated element at byte {pos}")
        word = self.uint32(buf, pos)
        if word >> 16:  # small data element: type and size in one word, data in the next
            mtype, n = word & 0xFFFF, word >> 16
            if n > 4:
                raise _Bad(f"small element at byte {pos} claims {n} bytes (at most 4)")
            return mtype, pos + 4, n, pos + 8
        n = self.uint32(buf, pos + 4)
        start = pos + 8
        if n > end - start:
            raise _Bad(f"element at byte {pos} claims {n} bytes, {end - start} are left")
        return word, start, n, min(end, start + ((n + 7) // 8 * 8 if padded else n))

    # -------------------------------------------------------------------- variables
    def variables(self, buf: bytes, pos: int, out: dict, top: bool) -> None:
        while pos < len(buf):
            if len(buf) - pos < 8 and not any(buf[pos:]):
                return  # trailing padding
            mtype, start, n, pos = self.tag(buf, pos, len(buf), padded=not top)
            if mtype == MI_COMPRESSED and top:
                self.variables(self.inflate(buf[start:start + n], start), 0, out, False)
            elif mtype == MI_MATRIX:
                name, value = self.matrix(buf, start, start + n, 0)
                out[name] = value
            else:
                raise _Bad(f"unexpected element type {mtype} at byte {start - 8} "
                           "(a variable must be an array)")

    def inflate(self, data: bytes, at: int) -> bytes:
        d = zlib.decompressobj()
        try:
            out = d.decompress(data, self.budget + 1)
        except zlib.error as exc:
            raise _Bad(f"corrupt compressed variable at byte {at - 8} ({exc})") from None
        self.spend(len(out), f"the compressed variable at byte {at - 8}")
        if not d.eof:
            raise _Bad(f"truncated compressed variable at byte {at - 8}")
        return out

    # -------------------------------------------------------------------- arrays
    def matrix(self, buf: bytes, pos: int, end: int, depth: int):
        """``(name, value)`` of the array whose content is ``buf[pos:end]``."""
        if pos == end:
            return "", np.zeros((0, 0))  # MATLAB writes an empty cell element this way
        if depth > MAX_DEPTH:
            raise _Bad(f"arrays nested deeper than {MAX_DEPTH} levels at byte {pos}")
        at = pos
        mtype, s, n, pos = self.tag(buf, pos, end)
        if mtype != MI_UINT32 or n != 8:
            raise _Bad(f"array at byte {at - 8}: malformed array flags")
        word = self.uint32(buf, s)
        cls, flags = word & 0xFF, (word >> 8) & 0xFF
        mtype, s, n, pos = self.tag(buf, pos, end)
        if mtype != MI_INT32 or n % 4 or not 8 <= n <= 4 * MAX_DIMS:
            raise _Bad(f"array at byte {at - 8}: malformed dimensions")
        dims = tuple(int(d) for d in np.frombuffer(buf, self.order + "i4", n // 4, s))
        if min(dims) < 0:
            raise _Bad(f"array at byte {at - 8}: negative dimension {dims}")
        mtype, s, n, pos = self.tag(buf, pos, end)
        if mtype not in (MI_INT8, MI_UINT8):
            raise _Bad(f"array at byte {at - 8}: malformed name")
        name = bytes(buf[s:s + n]).decode("latin-1")
        count = math.prod(dims)
        where = f"array {name!r} at byte {at - 8}" if name else f"array at byte {at - 8}"
        try:
            if cls in CLASS_DTYPE:
                value = self.numeric(buf, pos, end, cls, flags, count).reshape(dims, order="F")
            elif cls == CHAR:
                value = self.chars(buf, pos, end, dims, count)
            elif cls == CELL:
                value = self.cell(buf, pos, end, dims, count, depth)
            elif cls == STRUCT:
                value = self.struct(buf, pos, end, dims, count, depth)
            else:
                kind = UNSUPPORTED.get(cls, f"class {cls}")
                raise _Bad(f"MATLAB {kind} arrays are not supported")
        except _Bad as exc:
            msg = str(exc)
            raise _Bad(msg if msg.startswith(("array", "arrays")) else f"{where}: {msg}") \
                from None
        return name, value

    def numeric(self, buf, pos, end, cls, flags, count) -> np.ndarray:
        parts = []
        for _ in range(2 if flags & COMPLEX else 1):
            mtype, s, n, pos = self.tag(buf, pos, end)
            if mtype not in MI_NUMERIC:
                raise _Bad(f"number data of element type {mtype}")
            dt = np.dtype(self.order + MI_NUMERIC[mtype])
            if n != count * dt.itemsize:
                raise _Bad(f"{n} bytes of data for {count} values of {dt.itemsize} bytes")
            parts.append(np.frombuffer(buf, dt, count, s))
        out = np.dtype("c16") if flags & COMPLEX else \
            np.dtype(bool) if flags & LOGICAL else np.dtype(CLASS_DTYPE[cls])
        self.spend(count * out.itemsize, f"{count:,} values")
        with np.errstate(all="ignore"):  # e.g. NaN stored for an integer class
            if flags & COMPLEX:
                return parts[0] + 1j * parts[1].astype(float)
            return parts[0] != 0 if flags & LOGICAL else parts[0].astype(out)

    def chars(self, buf, pos, end, dims, count) -> str:
        mtype, s, n, pos = self.tag(buf, pos, end)
        enc = {MI_INT8: "utf-8", MI_UINT8: "utf-8", MI_UTF8: "utf-8", 3: "utf-16", 4: "utf-16",
               MI_UTF16: "utf-16", MI_INT32: "utf-32", MI_UINT32: "utf-32",
               MI_UTF32: "utf-32"}.get(mtype)
        if enc is None:
            raise _Bad(f"text data of element type {mtype}")
        if enc != "utf-8":
            enc += "-le" if self.order == "<" else "-be"
        text = bytes(buf[s:s + n]).decode(enc, errors="replace")
        rows = dims[0] if len(dims) == 2 else 1
        if rows > 1 and len(text) == count:  # stored column by column
            return "\n".join(text[r::rows] for r in range(rows))
        return text

    def _elements(self, buf, pos, end, count, what):
        """``count`` nested arrays (cell elements, struct fields) starting at ``pos``."""
        if count * 8 > end - pos:
            raise _Bad(f"{count:,} {what} cannot fit in the {end - pos} bytes left")
        self.spend(count * 8, f"{count:,} {what}")
        for _ in range(count):
            mtype, s, n, pos = self.tag(buf, pos, end)
            if mtype != MI_MATRIX:
                raise _Bad(f"{what[:-1]} at byte {s - 8} is not an array (type {mtype})")
            yield s, s + n

    def cell(self, buf, pos, end, dims, count, depth) -> np.ndarray:
        out = np.empty(count, dtype=object)
        for i, (s, e) in enumerate(self._elements(buf, pos, end, count, "cell elements")):
            out[i] = self.matrix(buf, s, e, depth + 1)[1]
        return out.reshape(dims, order="F")

    def struct(self, buf, pos, end, dims, count, depth) -> np.ndarray:
        mtype, s, n, pos = self.tag(buf, pos, end)
        if mtype != MI_INT32 or n != 4:
            raise _Bad("malformed field name length")
        width = self.uint32(buf, s)
        mtype, s, n, pos = self.tag(buf, pos, end)
        if mtype not in (MI_INT8, MI_UINT8) or not 0 < width <= 4096 or n % width:
            raise _Bad("malformed field names")
        names = [bytes(buf[a:a + width]).split(b"\0", 1)[0].decode("latin-1")
                 for a in range(s, s + n, width)]
        if len(set(names)) != len(names) or "" in names:
            raise _Bad(f"empty or repeated field names {names[:8]}")
        out = np.empty(count, dtype=object)
        fields = self._elements(buf, pos, end, count * len(names), "struct fields")
        for i in range(count):
            out[i] = {f: self.matrix(buf, s, e, depth + 1)[1] for f, (s, e) in zip(names, fields)}
        return out.reshape(dims, order="F")


def read_mat(path: str | Path) -> dict:
    """All variables of a level-5 MAT-file, ``{name: value}`` (values as in the module
    docstring).

    Raises:
        MotionFormatError: missing, too big (``MOTIONLANG_MAX_FILE_BYTES``), not a level-5
            MAT-file, or malformed (the byte named), or expanding beyond
            ``MOTIONLANG_MAX_MEMORY``.
    """
    path = Path(path)
    limits.check_file(path)  # its size counts against the memory limit too
    try:
        buf = path.read_bytes()
    except OSError as exc:
        raise MotionFormatError(path, f"cannot read file: {exc.strerror or exc}") from None
    if len(buf) < 128 or not buf.startswith(b"MATLAB") or buf[126:128] not in (b"IM", b"MI"):
        raise MotionFormatError(path, "not a MATLAB 5 MAT-file (no 'MATLAB ... MAT-file' "
                                      "header)")
    order = "<" if buf[126:128] == b"IM" else ">"
    version = int.from_bytes(buf[124:126], "little" if order == "<" else "big")
    if version == 0x0200:
        raise MotionFormatError(path, "MATLAB v7.3 (HDF5) files are not supported; save it "
                                      "with save(..., '-v7')")
    if version != 0x0100:
        raise MotionFormatError(path, f"unknown MAT-file version {version:#06x}")
    out: dict = {}
    reader = _Reader(order, limits.current().max_memory_bytes - len(buf))
    try:
        reader.variables(buf, 128, out, True)
    except _Bad as exc:
        raise MotionFormatError(path, f"malformed MAT-file: {exc}") from None
    except RecursionError:  # not reachable with MAX_DEPTH; kept as a last line of defence
        raise MotionFormatError(path, "malformed MAT-file: nested too deeply") from None
    return out


__all__ = ["read_mat"]
