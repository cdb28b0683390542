"""SIGTERM handled like Ctrl-C, so that a stopped command cleans up after itself.

Python turns SIGINT into :class:`KeyboardInterrupt`, which unwinds the stack: every
``finally`` and every atomic write (``utils.atomic``) removes its temporary file. SIGTERM,
what job schedulers, ``timeout`` and ``docker stop`` send, kills the process by default
without running any of that. :func:`sigterm_unwinds` makes SIGTERM raise
:class:`Terminated` (a ``KeyboardInterrupt``) in the main thread instead, so both signals
take the same road out. Child processes forked while it is in force (worker pools) keep
the default: they die at once, as their parent expects when it terminates them.
"""
from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading
from collections.abc import Iterator


class Terminated(KeyboardInterrupt):
    """Raised in the main thread when the process receives SIGTERM."""


@contextlib.contextmanager
def sigterm_unwinds() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` in this process (nothing is
    changed outside the main thread, or where someone else already handles SIGTERM)."""
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGTERM) not in (signal.SIG_DFL, None):
        yield
        return
    owner = os.getpid()

    def handler(signum, frame):
        if os.getpid() != owner:   # a forked child: die as it would have without us
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)
            return
        raise Terminated()

    signal.signal(signal.SIGTERM, handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)


def stopped(exc: KeyboardInterrupt) -> int:
    """Say why a command stopped (on stderr) and return its exit status as a shell
    reports a signal: 128 + its number."""
    term = isinstance(exc, Terminated)
    print("terminated" if term else "interrupted", file=sys.stderr)
    return 128 + (signal.SIGTERM if term else signal.SIGINT)
