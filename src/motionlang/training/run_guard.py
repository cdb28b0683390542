"""What keeps a run folder from being clobbered (torch-free: checked before any data is
read).

* A new run refuses a folder that already holds something: ``--resume`` continues it,
  ``--overwrite`` starts afresh (the previous run's files are removed first, so no old
  checkpoint is ever mixed with new ones).
* ``run.json`` records what decides a run's vocabulary, features and split: the data
  sources, the seed and the data options. A resume that would change any of them is
  refused before anything is written (a rebuilt split would put training motions in the
  test set; a rebuilt vocabulary would give token ids other words).
* A resume also keeps ``splits/`` as written at the start (:func:`keep_splits`): splits
  rebuilt from data that changed on disk are refused, naming the ids.
"""
from __future__ import annotations

import contextlib
import json
import shutil
from pathlib import Path
from typing import Any

from motionlang.datasets.splits import load_splits, save_splits
from motionlang.errors import MotionlangError
from motionlang.utils.atomic import atomic_write
from motionlang.utils.folder_lock import entries

RUN_FILE = "run.json"
#: what a run of the shared trainer writes besides its model file (``--overwrite`` removes
#: these and the family's model file, nothing else)
RUN_FILES = ("last.pt", "best.pt", "history.json", "loss_curve.png", "commands.jsonl",
             "splits", RUN_FILE)


def check_run_folder(out: Path, *, resume: bool, overwrite: bool) -> None:
    """A new run needs an absent or empty ``out`` (or ``overwrite``).

    Raises:
        MotionlangError: both ``resume`` and ``overwrite``; a non-empty folder without
            either (naming what is in it).
    """
    if resume and overwrite:
        raise MotionlangError("--resume continues the run in --out, --overwrite replaces it: "
                              "give one of them")
    if out.exists() and not out.is_dir():
        raise MotionlangError(f"--out {out}: a file, not a folder")
    names = entries(out)
    if names and not resume and not overwrite:
        shown = ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")
        if stopped_before_checkpoint(out):
            raise MotionlangError(f"--out {out}: a run that stopped before its first "
                                  f"checkpoint ({shown}; no last.pt): --overwrite to start "
                                  "it again, or another --out")
        raise MotionlangError(f"--out {out}: not empty ({shown}): --resume to continue the "
                              f"run there, --overwrite to replace it, or another --out")


def checkpoints(out: Path) -> list[Path]:
    """The checkpoints a run in ``out`` can resume from: ``last.pt``, then each stage's
    ``*/last.pt``."""
    return [p for p in (out / "last.pt", *sorted(out.glob("*/last.pt"))) if p.is_file()]


def stopped_before_checkpoint(out: Path) -> bool:
    """Whether ``out`` holds a run (its ``run.json``) that has no checkpoint to resume."""
    return (out / RUN_FILE).is_file() and not checkpoints(out)


def clear_run(out: Path, model_file: str, extra: tuple[str, ...] = ()) -> list[str]:
    """Remove a previous run's files from ``out`` (:data:`RUN_FILES`, ``model_file`` and
    ``extra``); anything else in the folder stays. Returns the names removed."""
    removed = []
    for name in (*RUN_FILES, model_file, *extra):
        p = out / name
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p)
        elif p.exists() or p.is_symlink():
            p.unlink()
        else:
            continue
        removed.append(name)
    return removed


def run_identity(kind: str, sources: list, seed: int | None, data_options: dict[str, Any]
                 ) -> dict[str, Any]:
    """What a resume must keep: ``{"kind", "data", "seed", "data_options"}`` as plain JSON."""
    return json.loads(json.dumps({"kind": kind, "data": [str(s) for s in sources],
                                  "seed": seed, "data_options": data_options},
                                 sort_keys=True, default=str))


def write_identity(out: Path, identity: dict[str, Any]) -> None:
    with atomic_write(out / RUN_FILE) as fh:
        json.dump(identity, fh, indent=1, sort_keys=True)


def check_identity(out: Path, identity: dict[str, Any], may_change: tuple[str, ...] = ()
                   ) -> None:
    """Refuse a resume whose data, seed or data options differ from the run's ``run.json``
    (options named in ``may_change`` may differ). A run folder from before ``run.json``
    has none: nothing to compare.

    Raises:
        MotionlangError: one line naming every changed option, the run's value and the new.
    """
    path = out / RUN_FILE
    if not path.is_file():
        return
    try:
        old = json.loads(path.read_text(encoding="utf-8"))
        assert isinstance(old, dict)
    except (OSError, ValueError, AssertionError):
        raise MotionlangError(f"{path}: unreadable, so a resume cannot be checked against "
                              "the run's data and options") from None
    changed = []
    if old.get("kind") != identity["kind"]:
        changed.append(f"model {old.get('kind')} -> {identity['kind']}")
    if old.get("data") != identity["data"]:
        changed.append(f"--data {' '.join(old.get('data') or [])} -> "
                       f"{' '.join(identity['data'])}")
    if old.get("seed") != identity["seed"]:
        changed.append(f"--seed {old.get('seed')} -> {identity['seed']}")
    before, now = old.get("data_options") or {}, identity["data_options"]
    for key in sorted(set(before) | set(now)):
        if key not in may_change and before.get(key) != now.get(key):
            changed.append(f"--{key.replace('_', '-')} {before.get(key)} -> {now.get(key)}")
    if changed:
        raise MotionlangError(f"--resume: {out} was started with other data or options "
                              f"({'; '.join(changed)}); a resume keeps the run's vocabulary, "
                              "features and split: give the run's values, or train afresh "
                              "in another --out")


def keep_splits(splits: dict[str, list[str]], folder: Path, resume: bool) -> None:
    """Write ``splits`` into ``folder`` for a new run; on a resume leave the folder as it
    is and check that the split rebuilt from the data is the one the run trained on.

    Raises:
        MotionlangError: the rebuilt split differs (the data changed on disk), naming ids.
    """
    if not (resume and folder.is_dir()):
        save_splits(splits, folder)
        return
    saved = {}
    with contextlib.suppress(MotionlangError):
        saved = load_splits(folder)
    for name in sorted(set(saved) | set(splits)):
        old, new = set(saved.get(name, [])), set(splits.get(name, []))
        if old != new:
            gone, added = sorted(old - new), sorted(new - old)
            parts = [f"{verb} {', '.join(ids[:5])}{' ...' if len(ids) > 5 else ''}"
                     for verb, ids in (("lacks", gone), ("adds", added)) if ids]
            what = "; ".join(parts)
            raise MotionlangError(f"--resume: the data changed since the run began: its "
                                  f"{name} split ({folder / (name + '.txt')}) {what}; train "
                                  "afresh in another --out")
