"""The learning-rate schedule of the shared trainer: constant, then an optional half-cosine
decay over the run's last epochs (a warm-up-stable-decay schedule without the warm-up)."""
from __future__ import annotations

import math

from motionlang.errors import MotionlangError


def learning_rate(lr: float, position: float, total: float, decay: float,
                  decay_to: float) -> float:
    """The learning rate of one optimiser step: ``lr`` until the last ``decay`` steps, then
    a half cosine from ``lr`` down to ``lr * decay_to``, reached at the last step (every one
    of the ``decay`` steps is lowered).

    Args:
        position: the step's index in the whole run, counted from 0 (``epoch * B + batch``
            for B batches per epoch), so a resumed run gets the same rates.
        total: the run's number of steps; decay: the length of the decay in steps (0: none).

    The decay lets a run trained at a constant rate be resumed with a decay added at its end
    (a warm-up-stable-decay schedule without the warm-up).
    """
    start = total - decay
    if decay <= 0 or position < start:
        return lr
    frac = min((position - start + 1) / decay, 1.0)
    return lr * (decay_to + (1.0 - decay_to) * 0.5 * (1.0 + math.cos(math.pi * frac)))


def check_schedule(decay_epochs: float, decay_to: float, epochs: int) -> None:
    """MotionlangError unless 0 <= decay_epochs <= epochs and 0 <= decay_to <= 1."""
    if not 0.0 <= decay_epochs <= epochs:
        raise MotionlangError(f"decay_epochs must be in [0, epochs={epochs}], got {decay_epochs}")
    if not 0.0 <= decay_to <= 1.0:
        raise MotionlangError(f"decay_to must be in [0, 1], got {decay_to}")
