"""Rank generated motions by how well a motion-to-language model explains the sentence.

The paper's sampled beam ranks an L2M's motions by their own likelihood, which on our corpus
prefers standing still (the likeliest frames move least). Here the candidates are ranked the
other way round, by log P(sentence | motion) under an M2L model: of several motions drawn for
"a person walks backwards", the one a describer finds likeliest to be called that comes
first. This is reranking with the reverse model (as in noisy-channel or maximum-mutual-
information decoding), beyond the paper.

An honest round trip must not rank with the model that then describes the motions: that
model would be graded on the choice it made. ``motionlang evaluate`` therefore refuses the
describer's own file as reranker (``--t2m l2m:rerank=M2L``; a copy of it is not detected).

Both models must read the same frames: :func:`check_same_features` compares their feature
sets (kind, names, fitted normaliser), since generated frames are in the L2M's feature units.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch
import torch.nn.functional as F

from motionlang.errors import MotionlangError
from motionlang.features.collate import pad_batch
from motionlang.models.seq2seq.decode.codec import encode_sentence, normalize
from motionlang.models.seq2seq.m2l import MotionToLanguage


def check_same_features(l2m, m2l: MotionToLanguage, what: str = "the reranker") -> None:
    """Raise :class:`MotionlangError` (naming ``what``) unless both models carry the same
    feature set: kind, feature names and fitted state (normaliser) must match."""
    fa, fb = getattr(l2m, "features", None), getattr(m2l, "features", None)
    if fa is None or fb is None:
        raise MotionlangError(f"{what}: both models need their feature sets to be compared")
    if fa.to_dict() != fb.to_dict():
        detail = (f"{fa.kind} vs {fb.kind}" if fa.kind != fb.kind else
                  "other feature names" if list(fa.names) != list(fb.names) else
                  "features fitted on other training motions")
        raise MotionlangError(f"{what}: its features differ from the L2M's ({detail}); rank "
                              "with an M2L trained on the same data and split")


@torch.no_grad()
def sentence_log_probs(m2l: MotionToLanguage, motions: Sequence[np.ndarray],
                       sentence: str | Sequence[int]) -> np.ndarray:
    """log P(sentence | motion) (nats, summed over the words and EOS) of each motion.

    motions: raw features (T_i, F) of the M2L's feature set (what ``generate_features``
    returns for an L2M with the same features). sentence: text (the M2L's vocabulary, unknown
    words as UNK) or token ids SOS .. EOS of the M2L's own vocabulary. Returns (N,) float64.
    """
    if not motions:
        return np.zeros(0)
    n_feat = m2l.config.n_features
    for k, m in enumerate(motions):
        if m.ndim != 2 or m.shape[1] != n_feat or len(m) == 0:
            raise MotionlangError(f"motion {k}: expected features of shape (T > 0, {n_feat}), "
                                  f"got {m.shape}")
    m2l.eval()
    ids = encode_sentence(m2l.vocab, sentence)
    x, mask = pad_batch([torch.as_tensor(normalize(m2l.normalizer, m), dtype=torch.float32)
                         for m in motions])
    lengths = mask.sum(1).long()
    tokens = torch.tensor([ids] * len(motions))
    logits = m2l(x, lengths, tokens[:, :-1])                      # (N, L - 1, V)
    logp = F.log_softmax(logits.float(), dim=-1)
    picked = logp.gather(-1, tokens[:, 1:].unsqueeze(-1)).squeeze(-1)   # (N, L - 1)
    return picked.sum(dim=1).double().numpy()


def rerank(candidates: Sequence[tuple[np.ndarray, float]], m2l: MotionToLanguage,
           sentence: str | Sequence[int]) -> list[tuple[np.ndarray, float, float]]:
    """(motion, L2M log likelihood) pairs -> (motion, L2M log likelihood, M2L log P(sentence |
    motion)) triples, the likeliest sentence first (ties keep the input order)."""
    scores = sentence_log_probs(m2l, [m for m, _ in candidates], sentence)
    order = sorted(range(len(candidates)), key=lambda k: -scores[k])
    return [(candidates[k][0], candidates[k][1], float(scores[k])) for k in order]
