"""argparse ``type=`` helpers shared by every subcommand: numbers in range, seeds, output paths.

A value argparse rejects becomes one line naming the option (``argument --lr: must be a
finite number > 0, got nan``) and exit code 2, like every other bad input (``cli/main.py``),
before any data is read or anything is written.
"""
from __future__ import annotations

import argparse
import math
import os
from collections.abc import Callable
from pathlib import Path

from motionlang.utils.checks import MAX_WIDTH, SEED_MAX, real_ok

# caps well past any sensible value, far below what would exhaust memory
MAX_FRAMES = 100_000
MAX_THREADS = 256


def parse_number(text: str, kind: type):
    """``int(text)`` or ``float(text)``, a failure as argparse's one-line error."""
    try:
        return kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"must be {'an integer' if kind is int else 'a number'}, got {text!r}") from None


def int_range(lo: int, hi: int | None = None) -> Callable[[str], int]:
    """An integer in [lo, hi] (no upper bound with ``hi=None``)."""
    def parse(text: str) -> int:
        v = parse_number(text, int)
        if v < lo or (hi is not None and v > hi):
            bound = f">= {lo}" if hi is None else f"in {lo}..{hi}"
            raise argparse.ArgumentTypeError(f"must be an integer {bound}, got {text}")
        return v
    parse.__name__ = "integer"
    return parse


def float_range(lo: float = -math.inf, hi: float = math.inf, *,
                open_lo: bool = False) -> Callable[[str], float]:
    """A number in [lo, hi] (``(lo, hi]`` with ``open_lo``), finite and within the bounds
    of every toolkit number (``utils.checks.real_ok``: no 1e308 or 1e-300)."""
    def parse(text: str) -> float:
        v = parse_number(text, float)
        ok = real_ok(v) and (v > lo if open_lo else v >= lo) and v <= hi
        if not ok:
            bounds = []
            if lo > -math.inf:
                bounds.append(f"{'>' if open_lo else '>='} {lo:g}")
            if hi < math.inf:
                bounds.append(f"<= {hi:g}")
            odd = "" if not math.isfinite(v) or real_ok(v) else " (0 or 1e-12..1e12 in size)"
            raise argparse.ArgumentTypeError(
                f"must be a finite number {' and '.join(bounds)}".rstrip() + f"{odd}, got {text}")
        return v
    parse.__name__ = "number"
    return parse


positive_int = int_range(1)             # counts without a memory cost (epochs, batch size)
count_int = int_range(1, 100_000)       # repeats of a slow step (Gibbs updates, fill-ins)
nonneg_int = int_range(0)
frames_int = int_range(1, MAX_FRAMES)
width_int = int_range(1, MAX_WIDTH)
seed_int = int_range(0, SEED_MAX)
threads_int = int_range(1, MAX_THREADS)
nonneg_float = float_range(0.0)
positive_float = float_range(0.0, open_lo=True)
rate_float, seconds_float = float_range(0.01, 10_000.0), float_range(0.0, 1e7)   # Hz; s


def _check_writable(path: Path, what: str) -> None:
    """``path`` can be created (or replaced): not an existing folder when a file is wanted,
    no file on the way to it, its nearest existing folder writable."""
    parent = path.parent
    while not parent.exists():   # folders the writer will create
        if parent.is_symlink() or parent == parent.parent:
            break
        parent = parent.parent
    if not parent.is_dir():
        raise argparse.ArgumentTypeError(f"{path}: {parent} is not a folder")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise argparse.ArgumentTypeError(f"{path}: cannot write in {parent}")
    # access() trusts mode bits; virtual file systems refuse new files whatever they say
    top = parent.resolve().parts[1:2]
    if top in (("sys",), ("proc",)):
        raise argparse.ArgumentTypeError(f"{path}: cannot write {what} under /{top[0]}")


def output_file(text: str) -> str:
    """A file to write: not empty, not an existing folder, its folder writable."""
    if not text.strip():
        raise argparse.ArgumentTypeError("empty path")
    path = Path(text)
    if path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a folder; give a file name")
    if path.exists() and not os.access(path, os.W_OK):
        raise argparse.ArgumentTypeError(f"{text}: not writable")
    _check_writable(path, "a file")
    return text


def output_dir(text: str) -> str:
    """A folder to write into (made if missing): not empty, not an existing file."""
    if not text.strip():
        raise argparse.ArgumentTypeError("empty path (use . for the current folder)")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text} is a file, not a folder")
    if path.is_dir():
        if not os.access(path, os.W_OK | os.X_OK):
            raise argparse.ArgumentTypeError(f"{text}: cannot write in it")
        _check_writable(path / "x", "files")
    else:
        _check_writable(path, "a folder")
    return text
