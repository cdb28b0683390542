"""The token models of the masked family, all conditioned on a frozen sentence vector.

* :class:`MaskTransformer` — bidirectional transformer over the base tokens (codebook 0),
  some replaced by a mask token; predicts the base token at every position. With
  ``config.goal > 0`` it also reads per-token goal features (``goal.GOAL_DIM``, zero
  outside a gap), projected and added to the token embeddings. The sentence
  vector, projected, is the first element of the sequence; a learnt null vector takes its
  place when the condition is dropped (classifier-free guidance: ``cond_drop`` in training,
  the unconditioned pass in sampling).
* :class:`ResidualTransformer` — predicts the tokens of codebook j (1..Q-1) at every position
  from the sum of the embeddings of codebooks 0..j-1 there and an embedding of j (MoMask's
  residual transformer; no masking: the coarser codes are known).
* :class:`LengthEstimator` — the motion's length in tokens (a class in 1..max_tokens) from
  the sentence vector.
"""
from __future__ import annotations

import functools
import math

import torch
import torch.nn.functional as F
from torch import nn

from motionlang.models.masked.config import MaskedConfig
from motionlang.models.masked.goal import GOAL_DIM

#: the goal projection's output is scaled up: the token embeddings are about 1 a channel,
#: and a projection grown from zero by Adam's small steps (about the learning rate each)
#: would take thousands of steps to reach that size, so a model fine-tuned for goals
#: barely read them
GOAL_GAIN = 10.0


@functools.lru_cache(maxsize=64)
def sinusoid(T: int, dim: int, device: torch.device | None = None) -> torch.Tensor:
    """(T, dim) sinusoidal positions (Vaswani et al. 2017). Cached (every decoding step asks
    for the same): the tensor is shared, so callers must not change it in place."""
    pos = torch.arange(T, dtype=torch.float32, device=device)[:, None]
    rate = torch.exp(torch.arange(0, dim, 2, dtype=torch.float32, device=device)
                     * (-math.log(10000.0) / dim))
    out = torch.zeros(T, dim, device=device)
    out[:, 0::2] = torch.sin(pos * rate)
    out[:, 1::2] = torch.cos(pos * rate[:dim // 2])
    return out


class Conditioned(nn.Module):
    """Shared body: the condition as element 0, then the token embeddings, a pre-norm
    transformer encoder over both, the token positions' outputs (B, L, hidden)."""

    def __init__(self, c: MaskedConfig, layers: int):
        super().__init__()
        self.cond = nn.Linear(c.text_dim, c.hidden)
        self.null = nn.Parameter(torch.zeros(c.hidden))
        layer = nn.TransformerEncoderLayer(c.hidden, c.heads, 4 * c.hidden, c.dropout,
                                           activation="gelu", batch_first=True,
                                           norm_first=True)
        # nested tensors would make a motion's tokens depend on the batch's padding
        self.encoder = nn.TransformerEncoder(layer, layers, enable_nested_tensor=False)
        self.norm = nn.LayerNorm(c.hidden)

    def run(self, h: torch.Tensor, text: torch.Tensor, valid: torch.Tensor,
            drop: torch.Tensor | None) -> torch.Tensor:
        """Token inputs (B, L, H), sentence vectors (B, D), valid positions (B, L), drop
        (B,) bool (True: the null condition) -> (B, L, H)."""
        c = self.cond(text)
        if drop is not None:
            c = torch.where(drop[:, None], self.null.expand_as(c), c)
        x = torch.cat([c[:, None], h], 1)
        x = x + sinusoid(x.shape[1], x.shape[2], x.device)
        # no mask when nothing is padded (one motion at a time): the same result, and the
        # attention skips applying it
        pad = None if bool(valid.all()) else torch.cat([torch.zeros_like(valid[:, :1]),
                                                        ~valid], 1)
        return self.norm(self.encoder(x, src_key_padding_mask=pad))[:, 1:]


class MaskTransformer(Conditioned):
    """Base tokens (B, L) with ``mask_id`` where masked -> logits (B, L, codes)."""

    def __init__(self, c: MaskedConfig):
        super().__init__(c, c.layers)
        self.mask_id = c.codes
        self.embed = nn.Embedding(c.codes + 1, c.hidden)
        self.head = nn.Linear(c.hidden, c.codes)
        self.goal: nn.Linear | None = None
        if c.goal > 0:
            # from zero, no bias: a goal-less token (all zeros) reads as before, and a model
            # given goals starts as the model without them
            self.goal = nn.Linear(GOAL_DIM, c.hidden, bias=False)
            nn.init.zeros_(self.goal.weight)

    def forward(self, tokens: torch.Tensor, text: torch.Tensor, valid: torch.Tensor,
                drop: torch.Tensor | None = None, goal: torch.Tensor | None = None
                ) -> torch.Tensor:
        """Tokens (B, L), sentence vectors (B, D), valid (B, L), drop (B,) or None, goal
        features (B, L, GOAL_DIM) or None (ignored by a model without goals) -> logits
        (B, L, codes)."""
        h = self.embed(tokens)
        if self.goal is not None and goal is not None:
            h = h + GOAL_GAIN * self.goal(goal)
        return self.head(self.run(h, text, valid, drop))


class ResidualTransformer(Conditioned):
    """Tokens of codebooks 0..j-1 (B, L, j) and j -> logits of codebook j (B, L, codes)."""

    def __init__(self, c: MaskedConfig):
        super().__init__(c, c.res_layers)
        n = max(1, c.quantizers - 1)
        self.embed = nn.ModuleList(nn.Embedding(c.codes, c.hidden) for _ in range(n))
        self.level = nn.Embedding(n, c.hidden)
        self.heads = nn.ModuleList(nn.Linear(c.hidden, c.codes) for _ in range(n))

    def forward(self, tokens: torch.Tensor, j: int, text: torch.Tensor, valid: torch.Tensor,
                drop: torch.Tensor | None = None) -> torch.Tensor:
        h = sum(self.embed[q](tokens[..., q]) for q in range(j))
        h = h + self.level.weight[j - 1]
        return self.heads[j - 1](self.run(h, text, valid, drop))


class LengthEstimator(nn.Module):
    """Sentence vectors (B, D) -> logits (B, max_tokens) of the length 1..max_tokens."""

    def __init__(self, c: MaskedConfig):
        super().__init__()
        self.classes = c.max_tokens
        self.net = nn.Sequential(nn.Linear(c.text_dim, c.hidden), nn.GELU(),
                                 nn.Dropout(c.dropout), nn.Linear(c.hidden, c.max_tokens))

    def forward(self, text: torch.Tensor) -> torch.Tensor:
        return self.net(text)

    def loss(self, text: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """Cross-entropy of the true lengths (B,) in tokens (clipped to the classes)."""
        target = lengths.clamp(1, self.classes) - 1
        return F.cross_entropy(self(text), target)
