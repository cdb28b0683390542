"""What passes between raw data and a seq2seq model: features in and out of the model's
normaliser, and a sentence as the model's token ids.

Shared by the describe/generate API (:mod:`.seq2seq`), the reranker (:mod:`.rerank`) and the
context-vector maps; it imports neither, so both can import it.
"""
from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from motionlang.errors import MotionlangError

#: token id of a word the vocabulary lacks (after PAD 0, SOS 1, EOS 2)
UNK_ID = 3


def normalize(norm: Any, x: np.ndarray) -> np.ndarray:
    """Raw features -> the model's units: ``norm`` is a fitted ``Normalizer``, a
    ``{"mean", "std"}`` dict, or None (no normalisation)."""
    if norm is None:
        return x
    if hasattr(norm, "transform"):
        return norm.transform(x)
    return (x - np.asarray(norm["mean"])) / np.asarray(norm["std"])


def denormalize(norm: Any, x: np.ndarray) -> np.ndarray:
    """Inverse of :func:`normalize`."""
    if norm is None:
        return x
    if hasattr(norm, "inverse"):
        return norm.inverse(x)
    return x * np.asarray(norm["std"]) + np.asarray(norm["mean"])


def encode_sentence(vocab: Any, sentence: str | Sequence[int]) -> list[int]:
    """Token ids SOS .. EOS of a sentence (ids pass through unchanged)."""
    if not isinstance(sentence, str):
        return [int(i) for i in sentence]
    if vocab is None:
        raise MotionlangError("this model has no vocabulary; pass token ids")
    if hasattr(vocab, "encode"):
        return list(vocab.encode(sentence))
    index = {w: i for i, w in enumerate(vocab)}
    return [1] + [index.get(w, UNK_ID) for w in sentence.lower().split()] + [2]
