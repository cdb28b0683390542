"""The run-folder steps every recipe takes, in one order, once each.

After its data is read and checked (so that a run refused for its data writes nothing),
a recipe calls :func:`begin_run`: the split (``splits/``, kept on a resume), the licence
note where a source restricts use, and the command's line in ``commands.jsonl``. After
training, :func:`finish_run` writes the model file and prints its summary and the
licence's first line. Under torchrun only the lead process writes or prints.
"""
from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

from motionlang.training.run_guard import keep_splits
from motionlang.training.run_log import lead_process, log_command, write_licence


def begin_run(out: Path, *, sources: Sequence, what: str, logged: Mapping[str, Any],
              resume: bool, splits: Mapping[str, Sequence[str]] | None = None,
              options: Mapping[str, Any] | None = None) -> str | None:
    """``splits`` (``{"train": ids, "val": ids, "test": ids}``; None: a recipe whose data
    has no split of its own) into ``out/splits`` (``run_guard.keep_splits``: a resume
    checks the rebuilt one against the run's), the licence of ``sources`` for ``what``
    (``run_log.write_licence``), then one line of ``commands.jsonl``: ``options`` as given
    (the command line's), else ``logged`` (the configs). Returns the licence note (None:
    no restriction)."""
    out.mkdir(parents=True, exist_ok=True)
    if splits is not None and lead_process():
        keep_splits({k: list(v) for k, v in splits.items()}, out / "splits", resume)
    note = write_licence(out, sources, what)
    log_command(out / "commands.jsonl", dict(options) if options is not None else dict(logged))
    return note


def finish_run(path: Path, model: Any, summary: Callable[[], str] | None = None,
               note: str | None = None) -> Path:
    """``model.save(path)`` (the run's model file), then its one-line ``summary`` (made
    only by the lead process: it may score the test split) and the licence note's first
    line. Returns ``path``."""
    if lead_process():
        model.save(path)
        print(summary() if summary is not None else str(path))
        if note:
            print(note.splitlines()[0])
    return path
