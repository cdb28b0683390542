"""A tiny two-stream model with deterministic fake token features (no language model)."""
from __future__ import annotations

import torch

from motionlang.models.text_tokens import CachedTokens
from motionlang.models.twostream.config import TwoStreamConfig
from motionlang.models.twostream.model import TwoStreamModel


class HashTokens(CachedTokens):
    """Deterministic fake token features (8 per word) so tests need no language model."""

    dim = 8

    def _compute(self, sentences):
        out = []
        for s in sentences:
            words = s.split() or [""]
            out.append(torch.stack([torch.randn(8, generator=torch.Generator().manual_seed(
                sum(ord(ch) * (i + 1) for i, ch in enumerate(w)))) for w in words]))
        return out


def tiny(**kw) -> TwoStreamModel:
    torch.manual_seed(0)
    cfg = TwoStreamConfig(h1=4, h2=8, h=16, disc_hidden=8, **kw)
    return TwoStreamModel(cfg, text_encoder=HashTokens())
