"""Training the two-stream model with the shared trainer: annealed teacher forcing, the
rest pose from the training set, the two-stage "w/o joint training" ablation, and a refit
of a trained model's sentence encoder alone.

Annealed teacher forcing: the decoder is unrolled from the initial pose; trained on its own
outputs from the first step it collapses to the mean pose (``docs/results/twostream.md``,
Annealed teacher forcing). So the probability of feeding the
true previous frame goes linearly from ``forcing_start`` (1) to ``forcing_end`` (0) over
``forcing_steps`` optimiser steps, then stays at ``forcing_end``. The schedule is a function
of the global step only, so ``fit(resume=True)`` continues it exactly.
"""
from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from motionlang.errors import MotionlangError
from motionlang.models.twostream.config import ABLATIONS as ABLATIONS  # importable here
from motionlang.models.twostream.config import TwoStreamConfig
from motionlang.models.twostream.model import TwoStreamModel
from motionlang.training.run_files import ranked_by, read_training_checkpoint
from motionlang.training.trainer import TrainConfig, Trainer

if TYPE_CHECKING:
    from motionlang.models.twostream.model import TwoStreamModel


@dataclass
class ForcingSchedule:
    """Teacher-forcing probability ``start -> end`` linearly over ``steps`` optimiser steps."""

    start: float = 1.0
    end: float = 0.0
    steps: int = 200

    def __call__(self, step: int) -> float:
        if self.steps <= 0:
            return self.end
        a = min(max(step, 0) / self.steps, 1.0)
        return self.start + a * (self.end - self.start)


class TwoStreamTrainer(Trainer):
    """:class:`Trainer` that sets ``model.teacher_forcing = schedule(step)`` before every
    optimiser step (``step`` = steps already taken in this stage)."""

    model: TwoStreamModel

    def __init__(self, *args, schedule: ForcingSchedule | None = None, **kw):
        super().__init__(*args, **kw)
        self.schedule = schedule or ForcingSchedule()
        self.steps_done = 0

    def _load(self, path: Path) -> dict:
        ck = super()._load(path)
        self.steps_done = int(ck["step"])
        return ck

    def _train_step(self, idx: list[int]) -> dict[str, float]:
        self.model.teacher_forcing = self.schedule(self.steps_done)
        terms = super()._train_step(idx)
        self.steps_done += 1
        return {**terms, "forcing": self.model.teacher_forcing} if terms else terms


def make_config(ablation: str = "full", **fields):
    """A ``TwoStreamConfig`` with ``fields`` and the ablation's flags."""
    if ablation not in ABLATIONS:
        raise MotionlangError(f"unknown ablation {ablation!r}; choose from {sorted(ABLATIONS)}")
    return TwoStreamConfig(**{**fields, **ABLATIONS[ablation]})


def train_twostream(model, train_items: Sequence[dict], config: TrainConfig, *,
                    val_items: Sequence[dict] | None = None, first_frames=None,
                    schedule: ForcingSchedule | None = None, resume: bool = False,
                    select=None):
    """Train ``model`` (a ``TwoStreamModel``) and return it with ``history``.

    Joint training: one run in ``config.out_dir``. Without joint training
    (``model.config.joint_training`` False): stage "pose" (pose autoencoder +
    discriminator) in ``OUT/pose``, then stage "text" (sentence encoder onto the frozen
    pose embedding) in ``OUT/text``, each for ``config.epochs`` epochs with a fresh
    optimiser and its own forcing schedule. The returned model holds the final weights, in
    eval mode (not ``best.pt``: the trainer ranks epochs by the total loss, which includes
    the discriminator's own term, and early epochs are still teacher-forced), unless
    ``select`` (``evaluation.t2m.selection.guo_selector``) scores the epochs of the stage
    that makes motions from sentences (the last) on ``val_items``: then it holds that
    stage's ``best.pt``, the epoch of the best score.

    Returns:
        (model, history) — history is a list of per-epoch dicts with a ``stage`` key; the
        selected epoch's also has ``"selected": True``.
    """

    if first_frames is not None:
        model.set_rest_pose(first_frames)
    out = Path(config.out_dir)
    stages = ["joint"] if model.config.joint_training else ["pose", "text"]
    history: list[dict] = []
    for stage in stages:
        model.set_stage(stage)
        cfg = config if len(stages) == 1 else replace(config, out_dir=str(out / stage))
        scored = select if stage == stages[-1] else None   # the pose stage makes none
        trainer = TwoStreamTrainer(model, list(train_items), TwoStreamModel.collate, cfg,
                                   val_set=list(val_items) if val_items else None,
                                   schedule=schedule, select=scored)
        # a later stage resumes only if it had begun (the first must have a checkpoint)
        begun = stage == stages[0] or (Path(cfg.out_dir) / "last.pt").is_file()
        history += [{**h, "stage": stage} for h in trainer.fit(resume=resume and begun)]
    if select is not None and val_items:
        epoch = _load_selected(model, Path(cfg.out_dir) / "best.pt",
                               str(getattr(select, "key", "select")))
        for h in history:   # the record of the epoch the model now holds
            if h["stage"] == stages[-1] and h["epoch"] == epoch:
                h["selected"] = True
    model.teacher_forcing = 0.0
    return model.eval(), history


def _load_selected(model, best: Path, key: str) -> int | None:
    """``best``'s weights into ``model`` if ``key``'s scores ranked it, and its epoch; else
    (no epoch was scored since the selection began, e.g. a finished run resumed with it) a
    warning, the final weights stay, and None."""
    import logging

    ck = read_training_checkpoint(best) if best.is_file() else None
    if ck is None or ranked_by(ck) != key:
        logging.getLogger(__name__).warning(
            "%s: no epoch was scored by the selection (no epoch trained since it was "
            "given?): the model keeps the final weights", best.parent)
        return None
    model.load_state_dict(ck["model"]["state_dict"])
    return int(ck["epoch"])


def refit_sentence_encoder(model, train_items: Sequence[dict], config: TrainConfig, *,
                           val_items: Sequence[dict] | None = None, resume: bool = False):
    """Train the sentence encoder of a trained ``model`` alone (stage "text": the pose
    encoder, decoder and discriminator frozen, no teacher forcing) for ``config.epochs``
    epochs in ``config.out_dir``, with a fresh optimiser; the model keeps its stage.

    The loss is the text stage's: pose (and energy, with a weight) of the motion decoded
    from the sentence embedding, plus the embedding term. With ``lambdas["pose"]`` and
    ``["energy"]`` at 0 it is the embedding term alone, and no motion is decoded.

    Returns:
        (model in eval mode, history)
    """

    stage = model.stage
    model.set_stage("text")
    try:
        trainer = TwoStreamTrainer(model, list(train_items), TwoStreamModel.collate, config,
                                   val_set=list(val_items) if val_items else None,
                                   schedule=ForcingSchedule(0.0, 0.0, 0))
        history = [{**h, "stage": "text"} for h in trainer.fit(resume=resume)]
    finally:
        model.set_stage(stage)
    model.teacher_forcing = 0.0
    return model.eval(), history
