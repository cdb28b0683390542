"""Reading the small files that travel beside motions and models: joint maps, caption
files, vocabularies, JSON metadata inside ``.npz`` model files.

Each is a file a user (or someone else) wrote, so nothing in it is trusted:

* only regular files are opened (:func:`open_regular`): a FIFO or a terminal would block
  the read for ever, a device may never end, a folder is a mistake;
* sizes are bounded before reading (``max_json_bytes``, ``max_file_bytes`` of
  :mod:`motionlang.utils.limits`);
* text is UTF-8, with or without a byte-order mark;
* JSON (:func:`parse_json`) is read with bounds on nesting (:data:`MAX_JSON_DEPTH`) and on
  the digits of a number (:data:`MAX_DIGITS`; Python refuses to convert an int of more
  than 4,300 digits, and ``1e999`` is infinite), and without ``NaN``/``Infinity``;
* names and captions carry no NUL or control characters (:func:`check_text`): they are
  written back out into other files, terminals and reports.

Every refusal is one :class:`~motionlang.errors.MotionlangError` line naming the file.
"""
from __future__ import annotations

import json
import math
import os
import re
from pathlib import Path
from typing import IO, Any

from motionlang.errors import MotionlangError
from motionlang.utils import limits

#: deepest nesting of arrays and objects a JSON sidecar may have (real ones have 3-4)
MAX_JSON_DEPTH = 64
#: most digits of one number in a JSON or text sidecar
MAX_DIGITS = 40
#: control characters never accepted in a caption (tab is; line breaks are not: a caption
#: is one line of its file)
_CAPTION_CONTROL = re.compile(r"[\x00-\x08\x0a-\x1f\x7f]")
#: control characters never accepted in a name (joints, files, words)
_NAME_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def open_regular(path: str | Path, what: str = "file") -> IO[bytes]:
    """``path`` opened for binary reading, refused unless it is a regular file.

    The file is opened without blocking and checked on the open descriptor, so a FIFO
    named in place of a file is refused at once (and a file swapped for one between a check
    and the open cannot slip through).

    Raises:
        MotionlangError: ``PATH: cannot read WHAT: ...`` or ``PATH: WHAT is a FIFO ...``.
    """
    flags = os.O_RDONLY | getattr(os, "O_NONBLOCK", 0) | getattr(os, "O_BINARY", 0)
    try:
        fd = os.open(path, flags)
    except OSError as exc:
        raise MotionlangError(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    try:
        kind = limits.not_regular(os.fstat(fd).st_mode)
        if kind:
            raise MotionlangError(f"{path}: the {what} is {kind}, not a file: only regular "
                                  f"files are read")
        if hasattr(os, "set_blocking"):
            os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bytes(path: str | Path, what: str = "file", limit: str = "max_file_bytes") -> bytes:
    """The bytes of a regular file no larger than the :mod:`~motionlang.utils.limits` limit
    named ``limit`` (``"max_file_bytes"`` or ``"max_json_bytes"``)."""
    cap = int(getattr(limits.current(), limit))
    with open_regular(path, what) as fh:
        try:
            size = os.fstat(fh.fileno()).st_size
            if size <= cap:
                # read(n) allocates n bytes at once: ask for the size, then follow a file
                # that grew while being read a megabyte at a time, up to the cap
                data = fh.read(size + 1)
                while size < len(data) <= cap and (more := fh.read(1 << 20)):
                    data += more
        except OSError as exc:
            raise MotionlangError(f"{path}: cannot read {what}: {exc.strerror or exc}"
                                  ) from None
    if size > cap or len(data) > cap:
        msg = limits.message(limit, size if size > cap else len(data), f"the {what}'s size")
        raise MotionlangError(f"{path}: {msg}")
    return data


def read_text(path: str | Path, what: str = "file", limit: str = "max_file_bytes") -> str:
    """A regular UTF-8 text file (a byte-order mark is dropped), size bounded as
    :func:`read_bytes`."""
    data = read_bytes(path, what, limit)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        line = data[:exc.start].count(b"\n") + 1
        raise MotionlangError(f"{path}:{line}: the {what} is not UTF-8 text (byte "
                              f"{exc.start})") from None


def _number(text: str, where: str) -> float | int:
    digits = sum(c.isdigit() for c in text)
    if digits > MAX_DIGITS:
        raise MotionlangError(f"{where}: a number of {digits} digits (at most {MAX_DIGITS})")
    if re.fullmatch(r"-?\d+", text):
        return int(text)
    value = float(text)
    if not math.isfinite(value):
        raise MotionlangError(f"{where}: the number {text[:20]} is not finite")
    return value


def _constant(text: str, where: str) -> Any:
    raise MotionlangError(f"{where}: {text} is not a number JSON allows")


def depth(obj: Any) -> int:
    """Nesting depth of lists and dicts in ``obj`` (0 for a scalar), without recursion."""
    deepest, stack = 0, [(obj, 1)]
    while stack:
        node, d = stack.pop()
        if isinstance(node, dict):
            node = list(node.values())
        elif not isinstance(node, (list, tuple)):
            continue
        deepest = max(deepest, d)
        if d <= MAX_JSON_DEPTH:
            stack.extend((v, d + 1) for v in node)
    return deepest


def parse_json(text: str | bytes, where: str) -> Any:
    """``text`` parsed as JSON with the bounds of the module docstring.

    Raises:
        MotionlangError: ``WHERE: ...`` for invalid JSON (with its line), nesting deeper
            than :data:`MAX_JSON_DEPTH`, a number of more than :data:`MAX_DIGITS` digits
            or one that is not finite.
    """
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8-sig")
        except UnicodeDecodeError:
            raise MotionlangError(f"{where}: not UTF-8 text") from None
    text = text.removeprefix("\ufeff")
    try:
        obj = json.loads(text, parse_int=lambda t: _number(t, where),
                         parse_float=lambda t: _number(t, where),
                         parse_constant=lambda t: _constant(t, where))
    except RecursionError:
        raise MotionlangError(f"{where}: JSON nested deeper than {MAX_JSON_DEPTH} "
                              f"levels") from None
    except json.JSONDecodeError as exc:
        raise MotionlangError(f"{where}: invalid JSON ({exc.msg} at line {exc.lineno}, "
                              f"column {exc.colno})") from None
    if depth(obj) > MAX_JSON_DEPTH:
        raise MotionlangError(f"{where}: JSON nested deeper than {MAX_JSON_DEPTH} levels")
    return obj


def load_json(path: str | Path, what: str = "JSON file") -> Any:
    """A regular JSON file of at most ``max_json_bytes``, parsed by :func:`parse_json`."""
    text = read_text(path, what, "max_json_bytes")
    return parse_json(text, str(path))


def check_text(text: str, where: str, what: str = "caption") -> str:
    """``text`` unchanged if it is an acceptable caption: no NUL or control characters
    except tab, at most ``max_caption_chars`` characters.

    Raises:
        MotionlangError: ``WHERE: the caption ...`` naming the problem.
    """
    limit = limits.current().max_caption_chars
    if len(text) > limit:
        raise MotionlangError(f"{where}: the {what} has {len(text):,} characters, over the "
                              f"limit of {limit:,} (raise it with "
                              f"{limits.ENV['max_caption_chars']}=...)")
    m = _CAPTION_CONTROL.search(text)
    if m:
        raise MotionlangError(f"{where}: the {what} holds the control character "
                              f"{m.group()!r} at {m.start()}")
    return text


def check_name(name: str, where: str, what: str = "name") -> str:
    """``name`` unchanged if it holds no NUL or other control character.

    Raises:
        MotionlangError: ``WHERE: the NAME ... holds the control character ...``.
    """
    m = _NAME_CONTROL.search(name)
    if m:
        raise MotionlangError(f"{where}: the {what} {name[:40]!r} holds the control "
                              f"character {m.group()!r}")
    return name


__all__ = ["MAX_JSON_DEPTH", "MAX_DIGITS", "open_regular", "read_bytes", "read_text",
           "parse_json", "load_json", "check_text", "check_name", "depth"]
