"""Recurrent building blocks shared by the seq2seq models of Plappert et al. (2018).

- :class:`BiGRUEncoder`: stack of bidirectional GRUs over padded sequences; the context
  vector is the last output of the last layer in each direction, concatenated.
- :class:`StackedDecoder`: stack of GRUs where every layer sees the same input (context +
  previous token/frame) and the previous layer's output; used for teacher forcing (L steps)
  and for one decoding step (L = 1) by the same code.
- :class:`AdditiveAttention`: Bahdanau-style scores v^T tanh(W_q q + W_k k) over encoder
  outputs, the attention variant the paper proposes as future work.
- :func:`last_valid_output`: a one-way recurrent stack's state at each sequence's end,
  without packing (the two-stream model's encoders and discriminator).
"""
from __future__ import annotations

import torch
from torch import nn
from torch.nn.utils.rnn import pack_padded_sequence, pad_packed_sequence

from motionlang.features.collate import lengths_to_mask


def last_valid_output(rnn: nn.RNNBase, x: torch.Tensor, lengths: torch.Tensor | None
                      ) -> torch.Tensor:
    """A one-way, batch-first recurrent stack over a padded batch x (B, T, D) -> the last
    layer's output at each sequence's last valid step, (B, H): the last layer's final state
    that packing the batch would give (steps past a sequence's end are computed, then
    ignored: a recurrence only looks back). ``lengths`` None: every sequence is T long.

    Why not pack: on CPU the backward pass of a packed GRU zero-fills the whole
    (B*T, 3H) gate tensor once per time step; unpacked, the fused kernel runs once."""
    if rnn.bidirectional or not rnn.batch_first:
        raise ValueError("last_valid_output needs a one-way, batch-first recurrent module")
    if lengths is not None and len(lengths) and not (
            1 <= int(lengths.min()) and int(lengths.max()) <= x.shape[1]):
        raise ValueError(f"sequence lengths must be in 1..{x.shape[1]} (the padded length), "
                         f"got {int(lengths.min())}..{int(lengths.max())}")
    out, _ = rnn(x)
    if lengths is None:
        return out[:, -1]
    last = lengths.to(device=x.device, dtype=torch.long) - 1
    return out[torch.arange(len(x), device=x.device), last]


class BiGRUEncoder(nn.Module):
    """x (B, T, in_dim) with lengths (B,) -> context (B, 2H), outputs (B, T, 2H), mask (B, T)."""

    def __init__(self, in_dim: int, hidden: int, layers: int, dropout: float = 0.0):
        super().__init__()
        self.hidden = hidden
        self.gru = nn.GRU(in_dim, hidden, num_layers=layers, batch_first=True,
                          bidirectional=True, dropout=dropout if layers > 1 else 0.0)

    @property
    def out_dim(self) -> int:
        return 2 * self.hidden

    def forward(self, x: torch.Tensor, lengths: torch.Tensor):
        T = x.shape[1]
        lengths = lengths.cpu().long().clamp(min=1)
        packed = pack_padded_sequence(x, lengths, batch_first=True, enforce_sorted=False)
        out, h_n = self.gru(packed)
        out, _ = pad_packed_sequence(out, batch_first=True, total_length=T)
        # h_n: (layers * 2, B, H); the forward direction ends at the last valid step and the
        # backward one at step 0 -- packing makes both respect each sequence's length.
        context = torch.cat([h_n[-2], h_n[-1]], dim=-1)
        return context, out, lengths_to_mask(lengths, T)


class StackedDecoder(nn.Module):
    """GRU stack with input skip connections to every layer.

    forward(x (B, L, in_dim), h (B, layers, H) or None) ->
        outs (B, L, layers * H) every layer's output, concatenated (the output layer reads all),
        h (B, layers, H) final hidden states (batch-first so beam search can reorder them).
    """

    def __init__(self, in_dim: int, hidden: int, layers: int, dropout: float = 0.0,
                 layer_norm: bool = False):
        super().__init__()
        self.hidden, self.layers = hidden, layers
        self.grus = nn.ModuleList(
            nn.GRU(in_dim + (hidden if i else 0), hidden, batch_first=True)
            for i in range(layers))
        self.norms = nn.ModuleList(
            nn.LayerNorm(hidden) if layer_norm else nn.Identity() for _ in range(layers))
        self.drop = nn.Dropout(dropout)

    @property
    def out_dim(self) -> int:
        return self.layers * self.hidden

    def forward(self, x: torch.Tensor, h: torch.Tensor | None = None):
        B = x.shape[0]
        if h is None:
            h = x.new_zeros(B, self.layers, self.hidden)
        outs, hs = [], []
        below = None
        for i, (gru, norm) in enumerate(zip(self.grus, self.norms)):
            inp = x if below is None else torch.cat([x, below], dim=-1)
            out, h_i = gru(inp, h[:, i].unsqueeze(0).contiguous())
            hs.append(h_i[0])
            below = self.drop(norm(out))
            outs.append(below)
        return torch.cat(outs, dim=-1), torch.stack(hs, dim=1)


class AdditiveAttention(nn.Module):
    """q (B, L, Q), keys (B, T, K), mask (B, T) -> context (B, L, K), weights (B, L, T)."""

    def __init__(self, query_dim: int, key_dim: int, attn_dim: int):
        super().__init__()
        self.wq = nn.Linear(query_dim, attn_dim, bias=False)
        self.wk = nn.Linear(key_dim, attn_dim)
        self.v = nn.Linear(attn_dim, 1, bias=False)

    def forward(self, q: torch.Tensor, keys: torch.Tensor, mask: torch.Tensor):
        e = self.v(torch.tanh(self.wq(q).unsqueeze(2) + self.wk(keys).unsqueeze(1))).squeeze(-1)
        e = e.masked_fill(~mask.unsqueeze(1), float("-inf"))
        w = torch.softmax(e, dim=-1)
        return torch.bmm(w, keys), w
