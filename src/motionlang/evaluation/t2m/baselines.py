"""Reference rows of the text-to-motion table (:mod:`.compare`): what no model, a
retrieved real motion and the test motions themselves score, and how well a sentence ->
length model guesses the test lengths.

Each ``*_baseline`` returns ``generate(sentence, n_frames) -> (n_frames, 21, 3)`` positions
in metres, as ``models.t2m.TextToMotion.positions21`` does for a model.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from motionlang.evaluation.retrieval import SentenceIndex
from motionlang.evaluation.t2m.scoring import T2MItem
from motionlang.models.length import SentenceLength
from motionlang.models.t2m import stretch

GROUND_TRUTH = "ground truth (order check's ceiling)"
NEAREST = "nearest training sentence's motion (bag of words)"


def still_baseline(data):
    """``generate(sentence, T)`` of the no-motion baseline: the training set's mean first
    pose held for T frames, at the origin — what a model collapsed to the mean produces."""
    pose = data.features.decode(data.first_frames().mean(axis=0)[None])  # (1, 21, 3)
    return lambda sentence, n_frames: np.repeat(pose, n_frames, axis=0)


def retrieval_baseline(data, split: str = "train"):
    """``generate(sentence, T)`` of the nearest-neighbour baseline: the ``split`` motion
    whose description is closest to the sentence in bag of words
    (``evaluation.retrieval``), re-timed to T frames (``models.t2m.stretch``: all of its
    actions kept, as a model told the length would). A real motion of about what the
    sentence says (a bag of words misses counts and, but for ties, word order), so its APE
    shows how far apart two motions of one description lie."""
    index = SentenceIndex((rid, s) for rid in data.splits[split]
                          for s in data.records[rid].annotations)
    return lambda sentence, n_frames: stretch(
        data.features.decode(data.sequences[index.nearest(sentence)[0]]), n_frames)


def length_errors(data, items: Sequence[T2MItem], model=None) -> dict:
    """How well a sentence -> length model (``models.length.SentenceLength``;
    default: one fitted here on ``data``'s whole training motions, as ``train twostream``
    without ``--max-frames`` or ``--mirror`` fits it) predicts the test lengths:
    ``{"mae_frames", "constant_mae_frames" (always guessing the training mean), "n"}``."""
    model = model or SentenceLength.from_items(data.items["train"])
    mean = float(np.mean([len(it["motion"]) for it in data.items["train"]]))
    true = np.array([len(it.target) for it in items], dtype=float)
    pred = np.array([model.frames(it.sentence) for it in items], dtype=float)
    return {"mae_frames": float(np.abs(pred - true).mean()),
            "constant_mae_frames": float(np.abs(mean - true).mean()), "n": len(items)}
