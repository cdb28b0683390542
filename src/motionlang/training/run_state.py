"""A run folder's resumable state, apart from the run folder: what a long training run
needs to go on later, on a fresh checkout, where the run folder is gone.

``save_state(run, state)`` copies into ``state`` only what ``--resume`` reads (the trainer's
``last.pt``: model, optimiser moments, RNG states, position and history; ``run.json``: the
run's data and options; ``splits/``: its split) and its record (``history.json``,
``commands.jsonl``), leaving out what a run rebuilds or never reads again (``best.pt``, the
loss plot, the model file). ``restore_state(state, run)`` puts them back into an empty run
folder, and ``train ... --resume`` then continues exactly where the saved run stopped: the
data and features are rebuilt from the same data (checked against the saved split and
features), and the step, RNG streams and schedules come from ``last.pt``. A recipe that
trains in stages (the two-stream "no-joint-training" ablation) keeps each stage's files in
a sub-folder: ``stages`` names them.
"""
from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from pathlib import Path

from motionlang.errors import MotionlangError
from motionlang.training.run_files import read_training_checkpoint
from motionlang.utils.atomic import WriteError, make_temp
from motionlang.utils.folder_lock import entries

#: what ``--resume`` reads, and the run's record; ``last.pt`` must be there
STATE_FILES = ("last.pt", "run.json", "splits", "history.json", "commands.jsonl")
#: written by :func:`save_state` beside them: the saved position, for people and scripts
STATE_INFO = "state.json"


def _copy(src: Path, dst: Path) -> None:
    if src.is_dir():
        shutil.copytree(src, dst)
    else:
        shutil.copy2(src, dst)


def _names(folder: Path, stages: Sequence[str]) -> list[str]:
    names = [n for n in STATE_FILES if (folder / n).exists()]
    names += [f"{s}/{n}" for s in stages for n in STATE_FILES if (folder / s / n).exists()]
    return names


def save_state(run_dir: str | Path, state_dir: str | Path, stages: Sequence[str] = (),
               **info) -> dict:
    """Replace ``state_dir`` with the resumable state of the run folder ``run_dir``.

    ``info`` (JSON values) is stored in ``state.json`` with the checkpoint's epoch and
    step. The new state is written beside the old one and swapped in by renames: an
    interrupted save leaves the previous state whole.

    Returns:
        the ``state.json`` contents.

    Raises:
        MotionlangError: ``run_dir`` has no readable ``last.pt`` (in it or in a stage).
    """
    run, state = Path(run_dir), Path(state_dir)
    names = _names(run, stages)
    lasts = [n for n in names if n.endswith("last.pt")]
    if not lasts:
        raise MotionlangError(f"{run}: no last.pt to save (nothing has been trained there)")
    ck = read_training_checkpoint(run / lasts[-1])   # the latest stage's
    about = {**info, "epoch": int(ck["epoch"]), "batch": int(ck["batch"]),
             "step": int(ck["step"]), "files": names}
    try:
        tmp = make_temp(state, directory=True)
        for name in names:
            (tmp / name).parent.mkdir(parents=True, exist_ok=True)
            _copy(run / name, tmp / name)
        (tmp / STATE_INFO).write_text(json.dumps(about, indent=1) + "\n", encoding="utf-8")
        old = None
        if state.exists():
            old = make_temp(state, ".old", directory=True)
            state.replace(old)
        tmp.replace(state)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except OSError as exc:
        raise WriteError(state, exc) from None
    return about


def read_state(state_dir: str | Path) -> dict:
    """The ``state.json`` of a saved state (one-line error if there is none)."""
    path = Path(state_dir) / STATE_INFO
    try:
        about = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        raise MotionlangError(f"{state_dir}: no saved run state ({STATE_INFO} missing or "
                              f"unreadable)") from None
    if not isinstance(about, dict) or not isinstance(about.get("files"), list):
        raise MotionlangError(f"{path}: not a saved run state")
    return about


def restore_state(state_dir: str | Path, run_dir: str | Path) -> dict:
    """Copy a saved state into the run folder ``run_dir`` (absent or empty), ready for
    ``--resume``. Returns its ``state.json``.

    Raises:
        MotionlangError: no saved state; ``run_dir`` not empty; a file the state lists is
            missing.
    """
    state, run = Path(state_dir), Path(run_dir)
    about = read_state(state)
    if entries(run):
        raise MotionlangError(f"{run}: not empty; the saved state goes into an empty run "
                              f"folder")
    missing = [n for n in about["files"] if not (state / n).exists()]
    if missing:
        raise MotionlangError(f"{state}: lacks {', '.join(missing)} that its {STATE_INFO} "
                              f"lists")
    try:
        run.mkdir(parents=True, exist_ok=True)
        for name in about["files"]:
            (run / name).parent.mkdir(parents=True, exist_ok=True)
            _copy(state / name, run / name)
    except OSError as exc:
        raise WriteError(run, exc) from None
    return about
