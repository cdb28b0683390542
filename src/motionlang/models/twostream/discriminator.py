"""Pose discriminator of the adversarial loss (Ghosh et al. 2021): real vs generated
pose sequences."""
from __future__ import annotations

import torch
from torch import nn

from motionlang.models.recurrent import last_valid_output


class PoseDiscriminator(nn.Module):
    """poses (B, T, F), lengths (B,) -> logits (B,) that the sequence is real motion
    (a GRU over frames and an MLP on its last state)."""

    def __init__(self, n_features: int, hidden: int = 64):
        super().__init__()
        self.gru = nn.GRU(n_features, hidden, batch_first=True)
        self.head = nn.Sequential(nn.Linear(hidden, 2 * hidden), nn.LeakyReLU(0.2),
                                  nn.Linear(2 * hidden, hidden), nn.LeakyReLU(0.2),
                                  nn.Linear(hidden, 1))

    def forward(self, poses: torch.Tensor, lengths: torch.Tensor | None = None) -> torch.Tensor:
        return self.head(last_valid_output(self.gru, poses, lengths)).squeeze(-1)
