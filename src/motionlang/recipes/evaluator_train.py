"""Training the text-motion evaluator (``models.evaluator``) with the shared trainer, on the
items of ``datasets.evaluator_items``."""
from __future__ import annotations

from collections.abc import Sequence

from motionlang.datasets.evaluator_items import fit_normalizer
from motionlang.errors import DatasetError
from motionlang.training.trainer import TrainConfig, Trainer


def train_evaluator(model, train_items: Sequence[dict], config: TrainConfig, *,
                    val_items: Sequence[dict] | None = None, body: str | None = "kit",
                    fit_stats: bool = True, resume: bool = False, select=None):
    """Train a ``TextMotionEvaluator`` with the shared trainer (``config.out_dir`` gets
    ``last.pt``/``best.pt``, the model's own checkpoints). ``fit_stats``: first set its
    mean/std from the training items (:func:`fit_normalizer` with ``body``). ``select``:
    model -> validation score picking ``best.pt`` (lower is better; default the validation
    loss), e.g. ``evaluation.t2m.yardstick.r_precision_miss``.

    Returns:
        (model in eval mode, history)
    """
    if not train_items:
        raise DatasetError("no training items for the evaluator")
    if fit_stats:
        model.set_normalizer(*fit_normalizer(train_items, body))
    trainer = Trainer(model, list(train_items), model.collate, config,
                      val_set=list(val_items) if val_items else None, select=select)
    history = trainer.fit(resume=resume)
    return model.eval(), history
