"""Python API over the trained seq2seq models: describe motion features, generate frames.

Both work at the level of per-frame features (``motionlang.features``); the model's own
normaliser (stored in its checkpoint) is applied on the way in and inverted on the way out,
so callers pass and receive raw features.
"""
from __future__ import annotations

from typing import Any, Sequence

import numpy as np
import torch

from motionlang.decoding.beam import beam_search, greedy_search
from motionlang.decoding.motion_beam import mean_decode, sampled_beam
from motionlang.errors import MotionlangError
from motionlang.models.l2m import LanguageToMotion
from motionlang.models.m2l import MotionToLanguage

UNK_ID = 3


def _normalize(norm: Any, x: np.ndarray) -> np.ndarray:
    if norm is None:
        return x
    if hasattr(norm, "transform"):
        return norm.transform(x)
    return (x - np.asarray(norm["mean"])) / np.asarray(norm["std"])


def _denormalize(norm: Any, x: np.ndarray) -> np.ndarray:
    if norm is None:
        return x
    if hasattr(norm, "inverse"):
        return norm.inverse(x)
    return x * np.asarray(norm["std"]) + np.asarray(norm["mean"])


def _words(vocab: Any, ids: Sequence[int]) -> str:
    if vocab is None:
        return " ".join(map(str, ids))
    if hasattr(vocab, "decode"):
        return vocab.decode(ids)
    return " ".join(vocab[i] for i in ids if i >= 4)  # list vocab: drop PAD/SOS/EOS/UNK


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


@torch.no_grad()
def describe_features(model: MotionToLanguage, features: np.ndarray, *, width: int = 5,
                      max_len: int | None = None) -> list[tuple[str, float]]:
    """features (T, F) raw -> W sentences with their total log probability, best first.

    width=1 uses greedy decoding.
    """
    if features.ndim != 2 or features.shape[1] != model.config.n_features:
        raise MotionlangError(f"expected features of shape (T, {model.config.n_features}), "
                              f"got {features.shape}")
    model.eval()
    c = model.config
    x = torch.as_tensor(_normalize(model.normalizer, features), dtype=torch.float32)[None]
    state = model.encode(x, torch.tensor([len(features)]))
    kw = dict(batch_size=1, sos=c.sos_id, eos=c.eos_id, max_len=max_len or c.max_len,
              banned=(c.pad_id, c.sos_id))
    if width == 1:
        hyps = greedy_search(model.step, state, **kw)
    else:
        hyps = beam_search(model.step, state, width=width, **kw)[0]
    return [(_words(model.vocab, h.tokens), h.score) for h in hyps]


@torch.no_grad()
def generate_features(model: LanguageToMotion, sentence: str | Sequence[int], *,
                      width: int = 5, max_frames: int | None = None, method: str = "beam",
                      samples: int = 5, seed: int = 0) -> list[tuple[np.ndarray, float]]:
    """Sentence -> W motions as raw features (T, F) with their log likelihood, best first.

    method: "beam" (the sampled beam, ``samples`` candidates per hypothesis and step) or
    "mean" (one deterministic motion from the heaviest component's means).
    """
    if method not in ("beam", "mean"):
        raise MotionlangError(f"method must be 'beam' or 'mean', not {method!r}")
    model.eval()
    ids = encode_sentence(model.vocab, sentence)
    state = model.encode(torch.tensor([ids]), torch.tensor([len(ids)]))
    cap = max_frames or model.config.max_frames
    F = model.config.n_features
    if method == "mean":
        hyps = mean_decode(model.step, state, batch_size=1, max_frames=cap, dim=F)
    else:
        hyps = sampled_beam(model.step, state, batch_size=1, width=width, max_frames=cap,
                            samples=samples, dim=F,
                            generator=torch.Generator().manual_seed(seed))[0]
    return [(_denormalize(model.normalizer, h.frames).astype(np.float32), h.score)
            for h in hyps]
