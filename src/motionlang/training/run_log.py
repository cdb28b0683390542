"""The options of every training invocation and the licence note, kept beside the run's
checkpoints (torch-free: the command line reads it at start-up)."""
from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
from pathlib import Path

from motionlang.datasets.sources import LICENCE_FILE, licence_text
from motionlang.utils.atomic import atomic_write


def lead_process() -> bool:
    """True outside torchrun and on its rank 0: the one process that writes run files."""
    return os.environ.get("RANK", "0") == "0"


def log_command(path: Path, args: argparse.Namespace | dict) -> None:
    """Append this invocation's options to ``path`` (one JSON line per invocation, resumes
    included): data options (offsets, --balance, --max-frames, ...) are not in the
    checkpoint, and a resumed run may differ from its start. Under torchrun only rank 0
    writes."""
    if not lead_process():
        return
    items = args.items() if isinstance(args, dict) else vars(args).items()
    opts = {k: v for k, v in items if not callable(v)}
    old = path.read_text() if path.exists() else ""
    with atomic_write(path) as fh:
        fh.write(old + json.dumps(opts, sort_keys=True, default=str) + "\n")


def write_licence(run: Path, sources, what: str) -> str | None:
    """The licence note (``datasets.sources.LICENCE_FILE``) in ``run`` when a source
    restricts the use of ``what`` (e.g. "M2L") and the figures made with it; nothing
    otherwise. Only the lead process writes. Returns the note (None: no restriction)."""
    note = licence_text(sources, what)
    if note is not None and lead_process():
        run.mkdir(parents=True, exist_ok=True)
        with atomic_write(run / LICENCE_FILE) as fh:
            fh.write(note)
    return note


@contextlib.contextmanager
def lead_output():
    """Under torchrun, ranks other than 0 print nothing to stdout and log only warnings and
    errors (each line would otherwise come once per process); rank 0 and single processes
    are untouched."""
    if lead_process():
        yield
        return
    package = logging.getLogger("motionlang")   # the level basicConfig leaves alone
    level = package.level
    package.setLevel(logging.WARNING)
    try:
        with open(os.devnull, "w") as devnull, contextlib.redirect_stdout(devnull):
            yield
    finally:
        package.setLevel(level)
