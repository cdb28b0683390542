"""The files of a training run folder besides the model: resumable checkpoints
(``last.pt`` / ``best.pt``), their RNG states, and the loss curve.

A run folder (``motionlang train ... --out DIR``) holds ``last.pt`` and ``best.pt`` (training
checkpoints: model, optimiser, RNG states, position), ``history.json``, ``loss_curve.png``,
``commands.jsonl`` (every invocation's options), ``splits/`` and the final model
``model.pt`` that the other commands read when given the folder.
"""
from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.models.checkpoint import load_checkpoint
from motionlang.utils.atomic import atomic_path


def check_resume(out_dir: str | Path, *, read: bool = True) -> Path:
    """``out_dir/last.pt``, which a resumed run continues from; an error if there is none
    (a resume that silently started afresh would overwrite the run) or, with ``read``, if
    it is not a readable training checkpoint. Commands call it before anything is written."""
    last = Path(out_dir) / "last.pt"
    if not last.is_file():
        raise MotionlangError(f"--resume: no checkpoint {last} to continue from")
    if read:
        read_training_checkpoint(last)
    return last


def read_training_checkpoint(path: Path) -> dict:
    """A ``last.pt`` / ``best.pt`` written by the trainer (one-line error otherwise)."""
    ck = load_checkpoint(path)
    if not (isinstance(ck, dict) and {"model", "optimizer", "rng", "step"} <= set(ck)):
        raise MotionlangError(f"{path}: not a training checkpoint (last.pt) to resume")
    return ck


def ranked_by(ck: dict) -> str:
    """What ranked a training checkpoint's ``best.pt`` (``Trainer._best_by``); one from
    before that was recorded: "select" if its history has select scores, else "loss"."""
    if "best_by" in ck:
        return str(ck["best_by"])
    scored = any("select" in (h.get("val") or {}) for h in ck.get("history") or [])
    return "select" if scored else "loss"


#: checkpoint entries made from the data (``Checkpointed.checkpoint_state``) that a resumed
#: run must find unchanged: its token ids and its fitted features (layout, normaliser)
DATA_ENTRIES = ("vocab", "features")


def check_same_data(path: Path, old: dict, new: dict) -> None:
    """Refuse to resume from ``path`` (model dict ``old``) a model built with another
    vocabulary or other fitted features (``new``): its weights would load (same sizes) and
    read other words or other numbers. Entries either side lacks are not compared.

    Raises:
        MotionlangError: naming the entry (for a vocabulary, the first words that differ).
    """
    for key in DATA_ENTRIES:
        a, b = old.get(key), new.get(key)
        if a is None or b is None or a == b:
            continue
        detail = ""
        if key == "vocab":
            wa, wb = _words(a), _words(b)
            moved = sum(x != y for x, y in zip(wa, wb)) + abs(len(wa) - len(wb))
            detail = f" ({len(wa)} -> {len(wb)} words, {moved} ids mean other words)"
        raise MotionlangError(f"{path}: the run was trained with another {key}{detail} than "
                              "these data and options give; resume with the run's data and "
                              "options, or train afresh in another --out")


def check_resume_data(out_dir: str | Path, model: Any) -> None:
    """:func:`check_same_data` of ``out_dir/last.pt`` against a model about to resume it
    (a ``Checkpointed``), for a recipe that builds its model before writing anything."""
    last = check_resume(out_dir, read=False)
    check_same_data(last, read_training_checkpoint(last)["model"], model.to_checkpoint())


def _words(packed: dict) -> list:
    data = packed.get("data") if isinstance(packed, dict) else None
    if isinstance(data, dict):
        data = data.get("itos")   # a Vocabulary's to_dict
    return list(data) if isinstance(data, (list, tuple)) else []


def rng_state() -> dict:
    """torch, numpy and Python RNG states as plain lists (``weights_only`` loadable)."""
    np_state = np.random.get_state()
    assert isinstance(np_state, tuple)   # the global RandomState's MT19937, legacy form
    py_state = random.getstate()
    return {"torch": torch.get_rng_state(),
            "numpy": [np_state[0], np_state[1].tolist(), *map(float, np_state[2:])],
            "python": [py_state[0], list(py_state[1]), py_state[2]]}


def set_rng_state(s: dict) -> None:
    """Restore what :func:`rng_state` returned."""
    torch.set_rng_state(s["torch"])
    n = s["numpy"]
    np.random.set_state((n[0], np.array(n[1], dtype=np.uint32), int(n[2]), int(n[3]), n[4]))
    random.setstate((s["python"][0], tuple(s["python"][1]), s["python"][2]))


def plot_loss_curve(history: list[dict], path: str | Path) -> None:
    """Train and validation loss per epoch as a PNG (atomic write)."""
    # A bare Figure with the Agg canvas: no pyplot, so no global backend switch.
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    epochs = [h["epoch"] for h in history]
    fig = Figure(figsize=(5, 3.2), dpi=100)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    ax.plot(epochs, [h["train"].get("loss", np.nan) for h in history], "o-", label="train")
    if any(h["val"] for h in history):
        ax.plot(epochs, [h["val"].get("loss", np.nan) for h in history], "s-", label="validation")
    ax.set_xlabel("epoch")
    ax.set_ylabel("loss")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp)
