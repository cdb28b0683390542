"""A coarse plan of a motion: what it does in each of K equal parts of its duration.

The L2M's decoder drops the sentence once a motion is under way (it follows its previous
frames; ``experiments/probes/l2m_word_use.py``), although its context holds the direction
(``experiments/probes/l2m_context_probe.py``). A plan moves the sentence's say into every
frame: per part k of K (by the fraction of the motion done), the mean of each feature and
the mean absolute frame-to-frame change of each feature (how much it moves there). The root's mean
ground velocity per part is the path; a limb's change per part says when it acts.

While training, the decoder is fed the plan of the motion it is learning (so that it learns
to follow a plan, as FastSpeech 2 feeds the true pitch and energy); a :class:`Planner`
learns to predict the plan from the sentence, and generation feeds that prediction. The
planner has its own sentence encoder: fed the true plan, the decoder has no use for the
sentence, so its encoder learns little, and a head on its context learnt the plan too slowly
(after 3 epochs it planned forward walks for "backwards").
"""
from __future__ import annotations

import torch
from torch import nn

from motionlang.models.seq2seq.layers import BiGRUEncoder


def part_index(t: torch.Tensor, n_frames: torch.Tensor, parts: int) -> torch.Tensor:
    """Part of each frame: t (B, T) or (T,) frame indices, n_frames (B,) lengths ->
    (B, T) long in [0, parts - 1]: floor(t * parts / n_frames), clamped (frames past the
    end stay in the last part)."""
    n = n_frames.to(torch.float64).reshape(-1, 1).clamp(min=1)
    k = torch.floor(t.to(torch.float64).reshape(1, -1) * parts / n) if t.dim() == 1 \
        else torch.floor(t.to(torch.float64) * parts / n)
    return k.clamp(0, parts - 1).long()


def motion_plan(motion: torch.Tensor, lengths: torch.Tensor, parts: int,
                mean_mask: torch.Tensor | None = None) -> torch.Tensor:
    """motion (B, T, F) padded, lengths (B,) valid frames -> plan (B, parts, 2F).

    [..., :F]: mean of each feature over the part's frames (times ``mean_mask`` (F,), e.g.
    1 for the root's velocity and 0 for the posture, whose mean a planner can only guess
    as an average of different postures); [..., F:]: mean |x_t - x_{t-1}| over the part's
    frames t >= 1. A part without frames (a motion shorter than ``parts``) is 0.
    """
    B, T, F = motion.shape
    t = torch.arange(T)
    part = part_index(t, lengths, parts)                          # (B, T)
    valid = (t.view(1, T) < lengths.view(B, 1)).to(motion.dtype)  # (B, T)
    onehot = torch.nn.functional.one_hot(part, parts).to(motion.dtype) * valid.unsqueeze(-1)
    count = onehot.sum(1).clamp(min=1).unsqueeze(-1)              # (B, parts, 1)
    mean = torch.einsum("btk,btf->bkf", onehot, motion) / count
    if mean_mask is not None:
        mean = mean * mean_mask.to(mean)
    change = torch.zeros_like(motion)
    change[:, 1:] = (motion[:, 1:] - motion[:, :-1]).abs()
    moved = onehot.clone()
    moved[:, 0] = 0                                               # frame 0 has no change
    speed = torch.einsum("btk,btf->bkf", moved, change) / moved.sum(1).clamp(min=1).unsqueeze(-1)
    return torch.cat([mean, speed], dim=-1)


def plan_at(plan: torch.Tensor, t: torch.Tensor, n_frames: torch.Tensor) -> torch.Tensor:
    """plan (B, K, P), t (T,) frame indices, n_frames (B,) -> (B, T, P): each frame's part."""
    k = part_index(t, n_frames, plan.shape[1])                    # (B, T)
    return torch.gather(plan, 1, k.unsqueeze(-1).expand(-1, -1, plan.shape[2]))


class Planner(nn.Module):
    """Token ids (B, L), lengths (B,) -> plan (B, parts, 2F): word embeddings, a
    bidirectional GRU, and a two-layer perceptron on its context."""

    def __init__(self, vocab_size: int, n_features: int, parts: int, hidden: int = 128,
                 embed_dim: int = 64, pad_id: int = 0, dropout: float = 0.1):
        super().__init__()
        self.parts = parts
        self.embed = nn.Embedding(vocab_size, embed_dim, padding_idx=pad_id)
        self.encoder = BiGRUEncoder(embed_dim, hidden, 1)
        self.drop = nn.Dropout(dropout)
        self.head = nn.Sequential(nn.Linear(self.encoder.out_dim, 2 * hidden), nn.Tanh(),
                                  nn.Linear(2 * hidden, parts * 2 * n_features))

    @classmethod
    def for_config(cls, c) -> Planner:
        """The planner of an L2M config (``L2MConfig`` with ``plan_parts`` > 0)."""
        return cls(c.vocab_size, c.n_features, c.plan_parts, c.plan_hidden, c.embed_dim,
                   c.pad_id, c.dropout)

    def forward(self, tokens: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        context, _, _ = self.encoder(self.drop(self.embed(tokens)), lengths)
        return self.head(self.drop(context)).view(tokens.shape[0], self.parts, -1)
