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


#: the stop signals this process received under :func:`sigterm_unwinds`, in order
_RECEIVED: list[int] = []


def received() -> int | None:
    """The last stop signal (SIGTERM or SIGINT) received under :func:`sigterm_unwinds`: a
    library's C code can turn the interrupt it raises into an error of its own (matplotlib's
    "Invalid affine transformation matrix"), and the command still stopped because of it."""
    return _RECEIVED[-1] if _RECEIVED else None


@contextlib.contextmanager
def sigterm_unwinds() -> Iterator[None]:
    """Within the block, SIGTERM raises :class:`Terminated` in this process (nothing is
    changed outside the main thread, or where someone else already handles SIGTERM)."""
    if threading.current_thread() is not threading.main_thread() \
            or signal.getsignal(signal.SIGTERM) not in (signal.SIG_DFL, None):
        yield
        return
    owner = os.getpid()
    _RECEIVED.clear()

    def handler(signum, frame):
        if os.getpid() != owner:   # a forked child: die as it would have without us
            signal.signal(signal.SIGTERM, signal.SIG_DFL)
            os.kill(os.getpid(), signal.SIGTERM)
            return
        _RECEIVED.append(signal.SIGTERM)
        raise Terminated()

    def interrupt(signum, frame):
        _RECEIVED.append(signal.SIGINT)
        signal.default_int_handler(signum, frame)

    signal.signal(signal.SIGTERM, handler)
    own_int = signal.getsignal(signal.SIGINT) is signal.default_int_handler
    if own_int:
        signal.signal(signal.SIGINT, interrupt)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        if own_int:
            signal.signal(signal.SIGINT, signal.default_int_handler)


def stopped(exc: BaseException, after: str = "") -> int:
    """Say why a command stopped (on stderr; ``after``: what the user can do now, added to
    the line) and return its exit status as a shell reports a signal: 128 + its number
    (``exc``: the interrupt, or the error a library made of it, see :func:`received`)."""
    term = isinstance(exc, Terminated) or (not isinstance(exc, KeyboardInterrupt)
                                           and received() == signal.SIGTERM)
    print(("terminated" if term else "interrupted") + (f": {after}" if after else ""),
          file=sys.stderr)
    return 128 + (signal.SIGTERM if term else signal.SIGINT)
