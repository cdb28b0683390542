"""The three encoders of the public text-motion evaluator (Guo et al. 2022), with the
parameter names and shapes of its ``networks/modules.py`` (``MovementConvEncoder``,
``MotionEncoderBiGRUCo``, ``TextEncoderBiGRUCo``), so that its weights load unchanged.

Shapes (B batch, T frames, L words):

* :class:`MovementEncoder`: (B, T, F) -> (B, T // 4, latent). Two convolutions of kernel 4,
  stride 2, padding 1 (each halves T), dropout and LeakyReLU(0.2) after each, then a linear
  layer. Names ``main.0`` and ``main.3`` (the convolutions), ``out_net``.
* :class:`MotionEncoder`: movement codes (B, T', latent) and lengths -> (B, D). Linear
  ``input_emb``, a one-layer bidirectional GRU ``gru`` started from a learnt state
  ``hidden`` (2, 1, H), its two final states concatenated, then ``output_net``: Linear(2H,
  H), LayerNorm, LeakyReLU(0.2), Linear(H, D) (names ``output_net.0``, ``.1``, ``.3``).
* :class:`TextEncoder`: word vectors (B, L, W), POS one-hots (B, L, 15) and lengths ->
  (B, D): ``pos_emb`` (Linear 15 -> W) added to the word vectors, then as the motion
  encoder.

Padded steps are skipped (packed sequences; any order of lengths). Initialisation as the
public code: Xavier-normal weights and zero biases of the linear and convolution layers,
a standard-normal initial GRU state.
"""
from __future__ import annotations

import torch
from torch import nn
from torch.nn.utils.rnn import pack_padded_sequence


def _init(module: nn.Module) -> None:
    for m in module.modules():
        if isinstance(m, (nn.Linear, nn.Conv1d)):
            nn.init.xavier_normal_(m.weight)
            if m.bias is not None:
                nn.init.zeros_(m.bias)


def _head(hidden: int, out: int) -> nn.Sequential:
    return nn.Sequential(nn.Linear(2 * hidden, hidden), nn.LayerNorm(hidden),
                         nn.LeakyReLU(0.2), nn.Linear(hidden, out))


class MovementEncoder(nn.Module):
    """(B, T, F) -> (B, T // 4, latent) movement codes (T a multiple of 4)."""

    def __init__(self, in_dim: int, hidden: int, latent: int, dropout: float = 0.2):
        super().__init__()
        self.main = nn.Sequential(
            nn.Conv1d(in_dim, hidden, 4, 2, 1), nn.Dropout(dropout), nn.LeakyReLU(0.2),
            nn.Conv1d(hidden, latent, 4, 2, 1), nn.Dropout(dropout), nn.LeakyReLU(0.2))
        self.out_net = nn.Linear(latent, latent)
        _init(self)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return self.out_net(self.main(x.transpose(1, 2)).transpose(1, 2))


class _BiGRUEncoder(nn.Module):
    """Shared part of the motion and text encoders: ``input_emb``, ``gru``, ``hidden``,
    ``output_net``."""

    def __init__(self, in_dim: int, hidden: int, out: int):
        super().__init__()
        self.input_emb = nn.Linear(in_dim, hidden)
        self.gru = nn.GRU(hidden, hidden, batch_first=True, bidirectional=True)
        self.output_net = _head(hidden, out)
        self.hidden = nn.Parameter(torch.randn(2, 1, hidden))
        _init(self)

    def _encode(self, x: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        """(B, L, in_dim), (B,) -> (B, out): final forward and backward states."""
        h0 = self.hidden.expand(-1, x.shape[0], -1).contiguous()
        packed = pack_padded_sequence(self.input_emb(x), lengths.cpu().long(),
                                      batch_first=True, enforce_sorted=False)
        _, last = self.gru(packed, h0)   # (2, B, H), in the input's order
        return self.output_net(torch.cat([last[0], last[1]], dim=-1))


class MotionEncoder(_BiGRUEncoder):
    """Movement codes (B, T', latent), lengths (B,) in codes -> (B, D)."""

    def forward(self, codes: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
        return self._encode(codes, lengths)


class TextEncoder(_BiGRUEncoder):
    """Word vectors (B, L, W), POS one-hots (B, L, P), lengths (B,) -> (B, D)."""

    def __init__(self, word_dim: int, n_pos: int, hidden: int, out: int):
        super().__init__(word_dim, hidden, out)
        self.pos_emb = nn.Linear(n_pos, word_dim)
        _init(self.pos_emb)

    def forward(self, words: torch.Tensor, pos: torch.Tensor, lengths: torch.Tensor
                ) -> torch.Tensor:
        return self._encode(words + self.pos_emb(pos), lengths)
