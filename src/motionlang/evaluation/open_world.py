"""The open-world check as a measure: how often a motion shows the actions its sentence asks
for, by the grounded analysis (``analysis.check``) rather than a classifier of a fixed set of
actions, so that generated motion can be judged on any action the analysis reads.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlang.analysis import analyse_positions
from motionlang.analysis.check import check_sentence
from motionlang.errors import MotionlangError


def shown(text: str, p21: np.ndarray, fps: float) -> bool | None:
    """Whether the motion (T, 21, 3) does every action of ``text`` that the analysis can
    tell, as the sentence says it (its side, direction, order; not where it says not:
    ``ActionCheck.met``); None where the sentence names none it can tell (or the motion
    cannot be read)."""
    try:
        checks = [c for c in check_sentence(text, analyse_positions(p21, fps))
                  if c.met is not None]
    except MotionlangError:
        return None
    return all(c.met for c in checks) if checks else None


def check_share(texts: Sequence[str], motions: Sequence[np.ndarray], fps: float) -> float:
    """Share (0..1) of the motions that show every checkable action of their sentence, over
    the pairs that have one; NaN where none has."""
    if len(texts) != len(motions):
        raise MotionlangError(f"check_share: {len(texts)} sentences for {len(motions)} "
                              "motions")
    got = [s for s in (shown(t, m, fps) for t, m in zip(texts, motions)) if s is not None]
    return float(np.mean(got)) if got else float("nan")
