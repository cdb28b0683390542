"""Padding and batching of (motion features, sentence) pairs for the seq2seq models.

An item is a dict with ``"motion"`` (T, F) float array/tensor of per-frame features and
``"tokens"`` a list/array of token ids SOS w1 .. wn EOS (``Vocabulary.encode``). The batch is
the dict both :class:`~motionlang.models.seq2seq.m2l.MotionToLanguage` and
:class:`~motionlang.models.seq2seq.l2m.LanguageToMotion` take in ``loss``.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import torch

from motionlang.features.collate import pad_batch


def pad_sequences(seqs: Sequence, pad: float = 0.0, dtype=torch.float32
                  ) -> tuple[torch.Tensor, torch.Tensor]:
    """List of (T_i, ...) arrays -> padded (B, max T_i, ...) tensor and lengths (B,) long."""
    tensors = [torch.as_tensor(np.asarray(s), dtype=dtype) for s in seqs]
    out, mask = pad_batch(tensors, value=pad)
    return out, mask.sum(1).long()


def collate_pairs(items: Sequence[dict], pad_id: int = 0) -> dict[str, torch.Tensor]:
    """items -> {"motion" (B, T, F) float32, "motion_lengths" (B,), "tokens" (B, L) long
    padded with ``pad_id``, "token_lengths" (B,)}."""
    motion, m_len = pad_sequences([it["motion"] for it in items])
    tokens, t_len = pad_sequences([it["tokens"] for it in items], pad=pad_id, dtype=torch.long)
    return {"motion": motion, "motion_lengths": m_len, "tokens": tokens, "token_lengths": t_len}
