"""Loss terms of the two-stream model: the embedding and discriminator terms here; the
masked frame terms (pose, velocity, energy, foot contact) are :mod:`motionlang.models.frame_losses`',
re-exported.
"""
from __future__ import annotations

from typing import cast

import torch
import torch.nn.functional as F

from motionlang.models.frame_losses import (  # noqa: F401 (the model's terms, re-exported)
    energy_loss,
    foot_contact_loss,
    frame_mask,
    masked_smooth_l1,
    velocity_loss,
)


def embedding_loss(a: dict[str, torch.Tensor], b: dict[str, torch.Tensor]) -> torch.Tensor:
    """Sum over streams of the smooth-L1 between two embeddings (B, H)."""
    return cast(torch.Tensor, sum(F.smooth_l1_loss(a[s], b[s]) for s in a))   # >= 1 stream


def bce_logits(logits: torch.Tensor, real: bool) -> torch.Tensor:
    """Binary cross-entropy of discriminator logits (B,) against all-real or all-fake."""
    target = torch.ones_like(logits) if real else torch.zeros_like(logits)
    return F.binary_cross_entropy_with_logits(logits, target)
