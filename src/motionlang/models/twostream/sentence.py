"""Two-stream sentence encoder: frozen token features -> LSTM -> Z_ub^s, Z_lb^s."""
from __future__ import annotations

import torch
from torch import nn

from motionlang.models.recurrent import last_valid_output
from motionlang.models.twostream.config import TwoStreamConfig


class SentenceEncoder(nn.Module):
    """Token features (B, L, D), lengths (B,) -> {stream: (B, stream_size)}: a 2-layer
    LSTM to 2h whose last valid output is split into Z_ub^s and Z_lb^s (or kept whole)."""

    def __init__(self, config: TwoStreamConfig):
        super().__init__()
        self.config = config
        self.lstm = nn.LSTM(config.text_dim, 2 * config.h, num_layers=config.lstm_layers,
                            batch_first=True)

    def forward(self, tokens: torch.Tensor, lengths: torch.Tensor) -> dict[str, torch.Tensor]:
        z = last_valid_output(self.lstm, tokens, lengths)
        streams = list(self.config.streams())
        return dict(zip(streams, z.split(self.config.stream_size, dim=-1)))
