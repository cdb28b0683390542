"""A run folder's resumable state, apart from the run folder: what a long training run
needs to go on later, on a fresh checkout, where the run folder is gone.

``save_state(run, state)`` copies into ``state`` only what ``--resume`` reads (the trainer's
``last.pt``: model, optimiser moments, RNG states, position and history; ``run.json``: the
run's data and options; ``splits/``: its split) and its record (``history.json``,
``commands.jsonl``), leaving out what a run rebuilds or never reads again (the loss plot,
the model file, and ``best.pt`` unless told to keep it: where a ``select`` score ranks the
epochs, the best so far may be an earlier part's, and the recipe's model is that one). ``restore_state(state, run)`` puts them back into an empty run
folder, and ``train ... --resume`` then continues exactly where the saved run stopped: the
data and features are rebuilt from the same data (checked against the saved split and
features), and the step, RNG streams and schedules come from ``last.pt``. A recipe that
trains in stages (the two-stream "no-joint-training" ablation) keeps each stage's files in
a sub-folder: ``stages`` names them.

A compact state (``save_state(..., compact=True)``) stores the large tensors of ``last.pt``
narrower: weight matrices in float16, the optimiser's moments of them in bfloat16 (its
range: squared gradients underflow float16), a third of the bytes; ``restore_state`` widens
them back to float32, and the file is xz-compressed (``last.pt.xz``), about 40 % of the
bytes in all. The resumed run is then the saved run up to that rounding (about 1e-3
relative, once per part), no longer bit for bit: for states that must stay small enough to
commit.
"""
from __future__ import annotations

import json
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from motionlang.errors import MotionlangError
from motionlang.models.checkpoint import write_checkpoint
from motionlang.training.run_files import read_training_checkpoint
from motionlang.utils.atomic import WriteError, make_temp
from motionlang.utils.folder_lock import entries

#: what ``--resume`` reads, and the run's record; ``last.pt`` must be there
STATE_FILES = ("last.pt", "run.json", "splits", "history.json", "commands.jsonl")
#: written by :func:`save_state` beside them: the saved position, for people and scripts
STATE_INFO = "state.json"
#: kept too where ``save_state(..., keep_best=True)``: the epoch a ``select`` score chose
#: (``training.trainer.Trainer``), which a later part may not beat; its model only
BEST = "best.pt"


#: a compact state narrows tensors of at least this many elements (weight matrices and their
#: moments); smaller ones (biases, norms, step counts, buffers) stay as they are
COMPACT_MIN = 4096


def _recast(ck: dict, model: Any, moments: Any) -> dict:
    """A training checkpoint with the floating tensors of at least :data:`COMPACT_MIN`
    elements in its model weights cast to ``model`` and in its optimiser state to
    ``moments`` (torch dtypes), in place."""
    import torch

    def cast(t: Any, dtype: Any) -> Any:
        big = isinstance(t, torch.Tensor) and t.is_floating_point() and t.numel() >= COMPACT_MIN
        return t.to(dtype) if big else t

    weights = ck["model"]["state_dict"]
    for k, t in weights.items():
        weights[k] = cast(t, model)
    for per_param in ck["optimizer"].get("state", {}).values():
        for k, t in per_param.items():
            per_param[k] = cast(t, moments)
    return ck


def _stored(name: str, compact: bool) -> str:
    """The name under which a state holds the run folder's file ``name``."""
    return name + ".xz" if compact and name.endswith((STATE_FILES[0], BEST)) else name


def _read(path: Path) -> dict:
    """A training checkpoint; a ``best.pt`` without the optimiser's moments, which nothing
    reads back from it (a resume reads ``last.pt``), so that a state holds its weights only."""
    ck = read_training_checkpoint(path)
    if path.name == BEST:
        ck["optimizer"] = {**ck["optimizer"], "state": {}}
    return ck


def _write_compact(last: Path, dst: Path) -> None:
    """``last.pt`` (or ``best.pt``) narrowed and xz-compressed into ``dst``."""
    import io
    import lzma

    import torch
    buf = io.BytesIO()
    torch.save(_recast(_read(last), torch.float16, torch.bfloat16), buf)
    dst.write_bytes(lzma.compress(buf.getvalue()))


def _read_compact(src: Path, last: Path) -> None:
    """A compact ``last.pt.xz`` widened back into the training checkpoint ``last``."""
    import lzma

    import torch

    from motionlang.models.checkpoint import load_checkpoint
    tmp = make_temp(last)
    try:
        tmp.write_bytes(lzma.decompress(src.read_bytes()))
        ck = load_checkpoint(tmp)
    except lzma.LZMAError:
        raise MotionlangError(f"{src}: damaged (not xz)") from None
    finally:
        tmp.unlink(missing_ok=True)
    write_checkpoint(_recast(ck, torch.float32, torch.float32), last)


def _copy(src: Path, dst: Path) -> None:
    if src.is_dir():
        shutil.copytree(src, dst)
    else:
        shutil.copy2(src, dst)


def _names(folder: Path, stages: Sequence[str], keep_best: bool = False) -> list[str]:
    files = (*STATE_FILES, BEST) if keep_best else STATE_FILES
    names = [n for n in files if (folder / n).exists()]
    names += [f"{s}/{n}" for s in stages for n in files if (folder / s / n).exists()]
    return names


def save_state(run_dir: str | Path, state_dir: str | Path, stages: Sequence[str] = (),
               *, compact: bool = False, keep_best: bool = False, **info) -> dict:
    """Replace ``state_dir`` with the resumable state of the run folder ``run_dir``
    (``compact``: its ``last.pt`` files narrowed, see the module docstring; ``keep_best``:
    its ``best.pt`` too, weights only, for a run whose epochs a ``select`` score ranks).

    ``info`` (JSON values) is stored in ``state.json`` with the checkpoint's epoch and
    step. The new state is written beside the old one and swapped in by renames: an
    interrupted save leaves the previous state whole.

    Returns:
        the ``state.json`` contents.

    Raises:
        MotionlangError: ``run_dir`` has no readable ``last.pt`` (in it or in a stage).
    """
    run, state = Path(run_dir), Path(state_dir)
    names = _names(run, stages, keep_best)
    lasts = [n for n in names if n.endswith(STATE_FILES[0])]
    if not lasts:
        raise MotionlangError(f"{run}: no last.pt to save (nothing has been trained there)")
    ck = read_training_checkpoint(run / lasts[-1])   # the latest stage's
    about = {**info, "epoch": int(ck["epoch"]), "batch": int(ck["batch"]),
             "step": int(ck["step"]), "files": names, "compact": bool(compact)}
    try:
        tmp = make_temp(state, directory=True)
        for name in names:
            (tmp / name).parent.mkdir(parents=True, exist_ok=True)
            if _stored(name, compact) != name:
                _write_compact(run / name, tmp / _stored(name, compact))
            elif name.endswith(BEST):
                write_checkpoint(_read(run / name), tmp / name)
            else:
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
    compact = bool(about.get("compact"))
    missing = [n for n in about["files"] if not (state / _stored(n, compact)).exists()]
    if missing:
        raise MotionlangError(f"{state}: lacks {', '.join(missing)} that its {STATE_INFO} "
                              f"lists")
    try:
        run.mkdir(parents=True, exist_ok=True)
        for name in about["files"]:
            (run / name).parent.mkdir(parents=True, exist_ok=True)
            if _stored(name, compact) != name:
                _read_compact(state / _stored(name, compact), run / name)
            else:
                _copy(state / name, run / name)
    except OSError as exc:
        raise WriteError(run, exc) from None
    return about
