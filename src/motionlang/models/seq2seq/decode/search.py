"""Python API over the trained seq2seq models: describe motions, generate motions.

:func:`describe` / :func:`generate` work on :class:`Motion` objects through the feature set
stored in the model's checkpoint; :func:`describe_features` / :func:`generate_features`
work on per-frame features, applying the model's own normaliser (if any) on the way in and
inverting it on the way out, so callers pass and receive raw features.

Model frames are the feature set's normalised dimensions only: a trailing binary "active"
flag (AnglesFeatures) is dropped, since L2M predicts its own end-of-motion flag.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np
import torch

from motionlang.errors import MotionlangError
from motionlang.features.frames import frames_to_features, motion_frames
from motionlang.models.seq2seq.decode.beam import beam_search, greedy_search
from motionlang.models.seq2seq.decode.codec import denormalize as _denormalize
from motionlang.models.seq2seq.decode.codec import encode_sentence
from motionlang.models.seq2seq.decode.codec import normalize as _normalize
from motionlang.models.seq2seq.decode.mbr import mbr_rank
from motionlang.models.seq2seq.decode.motion_beam import mean_decode, sample_decode, sampled_beam
from motionlang.models.seq2seq.decode.rerank import check_same_features, rerank
from motionlang.models.seq2seq.l2m import LanguageToMotion
from motionlang.models.seq2seq.m2l import MotionToLanguage

#: motion decoding methods of :func:`generate_features`
METHODS = ("beam", "mean", "sample")
#: how :func:`describe_features` orders a beam: total log P (the paper's), or minimum Bayes risk
RANKS = ("logp", "mbr")

def _words(vocab: Any, ids: Sequence[int]) -> str:
    if vocab is None:
        return " ".join(map(str, ids))
    if hasattr(vocab, "decode"):
        return vocab.decode(ids)
    return " ".join(vocab[i] for i in ids if i >= 4)  # list vocab: drop PAD/SOS/EOS/UNK


def _ids(vocab: Any, words: Sequence[str]) -> tuple[int, ...]:
    stoi = getattr(vocab, "stoi", None)
    if stoi is None:
        return ()
    return tuple(stoi[w] for w in words if w in stoi)


@torch.no_grad()
def describe_features(model: MotionToLanguage, features: np.ndarray, *, width: int = 5,
                      max_len: int | None = None, length_penalty: float = 0.0,
                      rank: str = "logp", banned_words: Sequence[str] = (),
                      prefix: Sequence[str] = ()) -> list[tuple[str, float]]:
    """features (T, F) raw -> W sentences with their total log probability, best first:
    ``rank`` "logp" (the paper's) by the total, or by total / length ** ``length_penalty``
    (see ``beam_search``); "mbr" by expected agreement with the beam (``models.seq2seq.decode.mbr``).

    width=1 uses greedy decoding. banned_words: words never generated; prefix: words every
    sentence starts with (beam search only); words the vocabulary lacks are ignored in both.
    """
    if rank not in RANKS:
        raise MotionlangError(f"rank must be one of {', '.join(RANKS)}, got {rank!r}")
    if features.ndim != 2 or features.shape[1] != model.config.n_features:
        raise MotionlangError(f"expected features of shape (T, {model.config.n_features}), "
                              f"got {features.shape}")
    model.eval()
    c = model.config
    x = torch.as_tensor(_normalize(model.normalizer, features), dtype=torch.float32)[None]
    if not (len(features) and torch.isfinite(x).all()):   # no sentence means anything then
        bad = "no frames" if not len(features) else \
            f"{int((~torch.isfinite(x)).sum()):,} values that are not finite numbers"
        raise MotionlangError(f"the motion's features hold {bad} (after normalising); "
                              "nothing to describe")
    state = model.encode(x, torch.tensor([len(features)]))
    ids = _ids(model.vocab, banned_words)
    kw = dict(batch_size=1, sos=c.sos_id, eos=c.eos_id, max_len=max_len or c.max_len,
              banned=(c.pad_id, c.sos_id, *ids), min_len=1)
    if width == 1 and not prefix:
        hyps = greedy_search(model.step, state, **kw)
    else:
        hyps = beam_search(model.step, state, width=width, length_penalty=length_penalty,
                           prefix=_ids(model.vocab, prefix), **kw)[0]
    out = [(_words(model.vocab, h.tokens), h.score) for h in hyps]
    if not out or not all(math.isfinite(score) for _, score in out):
        raise MotionlangError("decoding gave no sentence with a finite score")
    return mbr_rank(out) if rank == "mbr" else out


def _planned_length(model: LanguageToMotion, sentence, n_frames: int | None,
                    max_frames: int | None) -> int:
    """n_frames if given, else the length model's guess for ``sentence`` capped at
    ``max_frames`` (or ``max_frames`` alone)."""
    if n_frames:
        return n_frames
    guess = model.frames_for(sentence) if isinstance(sentence, str) else None
    options = [x for x in (guess, max_frames) if x]
    if not options:
        raise MotionlangError("this L2M model needs the motion's length: give n_frames or "
                              "max_frames (its checkpoint has no length model, or the "
                              "sentence is token ids)")
    return min(options)


@torch.no_grad()
def generate_features(model: LanguageToMotion, sentence: str | Sequence[int], *,
                      width: int = 5, max_frames: int | None = None, method: str = "beam",
                      samples: int = 5, seed: int = 0, min_frames: int = 1,
                      length_norm: bool = False, temperature: float = 1.0,
                      n_frames: int | None = None, first_frame: np.ndarray | None = None
                      ) -> list[tuple[np.ndarray, float]]:
    """Sentence -> W motions as raw features (T, F) with their log likelihood, best first.

    method: "beam" (the sampled beam, ``samples`` candidates per hypothesis and step),
    "mean" (one deterministic motion from the heaviest component's means, or the expected
    frames for a model trained on those: ``rollout_input="mean"``) or "sample"
    (W independent ancestral samples, ranked by log likelihood). The library default stays
    the paper's sampled beam; the CLI's is "sample" (the beam favours standing still).
    length_norm: rank by log likelihood per frame ("beam" and "sample").
    temperature: tau of the frames drawn by "beam" and "sample" (``models.seq2seq.mdn.sample``: 1 =
    the model's distribution, -> 0 = its heaviest component's means).
    n_frames: the motion's length for a model told it (``progress_input``; it ends there at
    the latest), a cap like ``max_frames`` for the others. Without it such a model plans the
    length from the sentence (its length model), at most ``max_frames``.
    first_frame: (F,) raw model features ("mean" and "sample"): every motion starts with this
    frame and continues from it (a given first pose, e.g. the start of a test motion).
    """
    if method not in METHODS:
        raise MotionlangError(f"method must be one of {METHODS}, not {method!r}")
    first: torch.Tensor | None = None   # normalised
    if first_frame is not None:
        if method == "beam":
            raise MotionlangError("a given first frame works with method 'mean' or 'sample', "
                                  "not the sampled beam")
        raw = np.asarray(first_frame, dtype=np.float32)
        if raw.shape != (model.config.n_features,):
            raise MotionlangError(f"first_frame must be ({model.config.n_features},) model "
                                  f"features, got {raw.shape}")
        first = torch.from_numpy(_normalize(model.normalizer, raw[None])[0].astype(np.float32))
    if width < 1:
        raise MotionlangError(f"width must be >= 1, got {width}")
    if not temperature > 0:
        raise MotionlangError(f"temperature must be > 0, got {temperature}")
    model.eval()
    ids = encode_sentence(model.vocab, sentence)
    # a model told how far into its motion it is needs the length (also its cap)
    planned = _planned_length(model, sentence, n_frames, max_frames) \
        if model.config.progress_input else None
    state = model.encode(torch.tensor([ids]), torch.tensor([len(ids)]),
                         None if planned is None else torch.tensor([planned]))
    cap = planned or n_frames or max_frames or model.config.max_frames
    F = model.config.n_features
    if method == "mean":
        # a model trained on its own expected frames continues from those
        hyps = mean_decode(model.step, state, batch_size=1, max_frames=cap, dim=F,
                           min_frames=min_frames, first=first,
                           expected=model.config.rollout_input == "mean")
    elif method == "sample":
        hyps = sample_decode(model.step, state, width=width, max_frames=cap, dim=F,
                             min_frames=min_frames, length_norm=length_norm,
                             temperature=temperature, first=first,
                             generator=torch.Generator().manual_seed(seed))
    else:
        hyps = sampled_beam(model.step, state, batch_size=1, width=width, max_frames=cap,
                            samples=samples, dim=F, min_frames=min_frames,
                            length_norm=length_norm, temperature=temperature,
                            generator=torch.Generator().manual_seed(seed))[0]
    return [(_denormalize(model.normalizer, h.frames).astype(np.float32), h.score)
            for h in hyps]


def _features_of(model) -> Any:
    if model.features is None:
        raise MotionlangError("this model was saved without its feature set; "
                              "use describe_features / generate_features")
    return model.features


def describe(model: MotionToLanguage, motion, *, width: int = 5,
             max_len: int | None = None, length_penalty: float = 0.0,
             rank: str = "logp") -> list[tuple[str, float]]:
    """A :class:`Motion` -> W sentences with their total log probability, best first
    (``rank`` as for :func:`describe_features`)."""
    frames = motion_frames(_features_of(model), motion, 1)[0]
    return describe_features(model, frames, width=width, max_len=max_len,
                             length_penalty=length_penalty, rank=rank)


@torch.no_grad()
def embed_motion(model: MotionToLanguage, motion) -> np.ndarray:
    """A :class:`Motion` -> the M2L encoder's summary of it, its context (C,) float32 (the
    vector its decoder starts from; similar motions lie close)."""
    frames = motion_frames(_features_of(model), motion, 1)[0]
    x = torch.as_tensor(_normalize(model.normalizer, frames), dtype=torch.float32)[None]
    return model.eval().encode(x, torch.tensor([len(frames)]))["context"][0].numpy()


@torch.no_grad()
def embed_sentence(model: LanguageToMotion, sentence: str | Sequence[int]) -> np.ndarray:
    """A sentence -> the L2M encoder's summary of it, its context (C,) float32 (words the
    model does not know count as one unknown word)."""
    ids = encode_sentence(model.vocab, sentence)
    state = model.eval().encode(torch.tensor([ids]), torch.tensor([len(ids)]))
    return state["context"][0].numpy()


def generate(model: LanguageToMotion, sentence: str | Sequence[int], *, width: int = 5,
             max_frames: int | None = None, method: str = "beam", samples: int = 5,
             seed: int = 0, min_frames: int = 1, length_norm: bool = False,
             temperature: float = 1.0, skeleton=None, n_frames: int | None = None,
             reranker: MotionToLanguage | None = None, first_frame: np.ndarray | None = None
             ) -> list[tuple[Any, float]]:
    """Sentence -> W decoded motions with their log likelihood, best first.

    Each motion is what the feature set's ``decode`` returns: a :class:`Motion` for joint
    angles (on ``skeleton``, default the training subjects' mean build), joint positions
    (T, 21, 3) for position features.

    reranker: an M2L model with the same features; the motions then come ranked by its log
    P(sentence | motion) instead, and that is the number beside each (``models.seq2seq.decode.rerank``).

    first_frame: (F,) model features (``motion_frames(model.features, motion)[0][0]``):
    every motion starts with this frame ("mean" and "sample"; see ``generate_features``).
    """
    fs = _features_of(model)
    if reranker is not None:   # before the (slower) generation
        if not isinstance(sentence, str):
            raise MotionlangError("reranking needs the sentence as text (the two models have "
                                  "their own vocabularies)")
        check_same_features(model, reranker)
    out = generate_features(model, sentence, width=width, max_frames=max_frames,
                            method=method, samples=samples, seed=seed, min_frames=min_frames,
                            length_norm=length_norm, temperature=temperature,
                            n_frames=n_frames, first_frame=first_frame)
    if reranker is not None:
        out = [(f, m2l_score) for f, _, m2l_score in rerank(out, reranker, sentence)]
    kw = {} if skeleton is None else {"skeleton": skeleton}
    return [(fs.decode(frames_to_features(fs, f), **kw), score) for f, score in out]
