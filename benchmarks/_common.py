"""Shared bits of the benchmark scripts: where the real data is, and a median timer."""
from __future__ import annotations

import os
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DATA = Path(os.environ.get("MOTIONLANG_DATA", ROOT.parent / "shared" / "data"))


def need_data(rel: str) -> Path:
    path = DATA / rel
    if not path.exists():
        sys.exit(f"benchmark needs {path} (set MOTIONLANG_DATA)")
    return path


def median_time(fn, repeat: int = 7, number: int = 1) -> float:
    """Median over ``repeat`` runs of the mean seconds per call of ``fn`` (``number`` calls)."""
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        for _ in range(number):
            fn()
        times.append((time.perf_counter() - t0) / number)
    return statistics.median(times)
