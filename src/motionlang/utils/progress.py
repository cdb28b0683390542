"""Progress of long phases: a tqdm bar on a terminal, plain log lines elsewhere.

When stderr is not a terminal (a log file, a pipe, a batch job) a bar would be either
silent or a stream of carriage returns; :class:`LogProgress` prints one line to stderr at
most every :data:`LOG_EVERY` seconds instead (``describe: 120/600 motions, 45 s elapsed,
~3 min left``), and a last line when a phase that printed any ends. A phase shorter than
that prints nothing.
"""
from __future__ import annotations

import sys
import time
from collections.abc import Callable, Iterable, Iterator
from typing import TypeVar

from tqdm.auto import tqdm

T = TypeVar("T")
#: seconds between two log lines of one phase when stderr is not a terminal
LOG_EVERY = 30.0


def progress(iterable: Iterable[T] | None = None, *, desc: str = "", total: int | None = None,
             unit: str = "it", disable: bool | None = None, **kwargs):
    """A progress display on stderr with tqdm's interface (iterate, ``update``,
    ``set_postfix``, ``close``). ``disable=None``: a bar on a terminal, else log lines
    (:class:`LogProgress`); ``True``: nothing; ``False``: a bar even off a terminal."""
    if disable is None and not sys.stderr.isatty():
        return LogProgress(iterable, desc=desc, total=total, unit=unit,
                           initial=kwargs.get("initial", 0))
    return tqdm(iterable, desc=desc, total=total, unit=unit, disable=bool(disable),
                file=sys.stderr, dynamic_ncols=True, **kwargs)


def _duration(seconds: float) -> str:
    if seconds < 90:
        return f"{seconds:.0f} s"
    if seconds < 5400:
        return f"{seconds / 60:.0f} min"
    return f"{seconds / 3600:.1f} h"


class LogProgress:
    """tqdm's interface, shown as a line on stderr every ``interval`` seconds.

    Args:
        iterable: iterated over (each item counts one), or None to count with ``update``.
        total: the count at the end (default ``len(iterable)`` when it has one), for the
            estimate of the time left.
        clock: seconds, monotonic (tests pass a fake one).
    """

    def __init__(self, iterable: Iterable[T] | None = None, *, desc: str = "",
                 total: int | None = None, unit: str = "it", initial: int = 0,
                 interval: float = LOG_EVERY, clock: Callable[[], float] = time.monotonic):
        if total is None and iterable is not None and hasattr(iterable, "__len__"):
            total = len(iterable)
        self.iterable, self.desc, self.total, self.unit = iterable, desc, total, unit
        self.n = self._start = initial
        self.interval, self.clock = interval, clock
        self.postfix = ""
        self.lines = 0
        self._closed_at: int | None = None
        self._t0 = self._last = clock()

    def __iter__(self) -> Iterator[T]:
        try:
            for item in self.iterable:
                yield item
                self.update(1)
        finally:
            self.close()

    def __len__(self) -> int:
        return len(self.iterable) if self.iterable is not None else (self.total or 0)

    def __enter__(self) -> LogProgress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def update(self, n: int = 1) -> None:
        self.n += n
        now = self.clock()
        if now - self._last >= self.interval:
            self._emit(now)

    def set_postfix(self, ordered_dict=None, refresh: bool = True, **kwargs) -> None:
        items = {**(ordered_dict or {}), **kwargs}
        self.postfix = ", ".join(f"{k} {v}" for k, v in items.items())

    def set_description(self, desc: str = "", refresh: bool = True) -> None:
        self.desc = desc

    def refresh(self) -> None:
        pass

    def close(self) -> None:
        """A last line, if the phase printed any (a short one stays silent)."""
        if self.lines and self.n != self._closed_at:
            self._emit(self.clock(), done=True)
        self._closed_at = self.n

    def line(self, now: float, done: bool = False) -> str:
        elapsed = now - self._t0
        count = f"{self.n}/{self.total}" if self.total else f"{self.n}"
        parts = [f"{count} {self.unit}", f"{_duration(elapsed)} elapsed"]
        done_here = self.n - self._start
        if done:
            parts[-1] = f"done in {_duration(elapsed)}"
        elif self.total and done_here > 0 and self.n < self.total:
            left = elapsed / done_here * (self.total - self.n)
            parts.append(f"~{_duration(left)} left")
        if self.postfix:
            parts.append(self.postfix)
        return f"{self.desc}: " * bool(self.desc) + ", ".join(parts)

    def _emit(self, now: float, done: bool = False) -> None:
        print(self.line(now, done), file=sys.stderr, flush=True)
        self._last = now
        self.lines += 1
