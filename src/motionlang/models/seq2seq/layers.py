"""Recurrent building blocks shared by the seq2seq models of Plappert et al. (2018).

- :class:`BiGRUEncoder`: stack of bidirectional GRUs over padded sequences; the context
  vector is the last output of the last layer in each direction, concatenated. Runs
  unpacked (:func:`reverse_within_lengths` for the backward direction).
- :class:`StackedDecoder`: stack of GRUs where every layer sees the same input (context +
  previous token/frame) and the previous layer's output; used for teacher forcing (L steps)
  and for one decoding step (L = 1) by the same code.
- :class:`AdditiveAttention`: Bahdanau-style scores v^T tanh(W_q q + W_k k) over encoder
  outputs, the attention variant the paper proposes as future work.
"""
from __future__ import annotations

import torch
from torch import nn

from motionlang.features.collate import lengths_to_mask


def reverse_within_lengths(x: torch.Tensor, lengths: torch.Tensor) -> torch.Tensor:
    """x (B, T, D) -> each sequence's first lengths[b] steps in reverse order, the padding
    behind them left in place; its own inverse. lengths (B,) in 1..T, on any device."""
    T = x.shape[1]
    t = torch.arange(T, device=x.device)[None, :]
    n = lengths.to(device=x.device, dtype=torch.long)[:, None]
    idx = torch.where(t < n, n - 1 - t, t)                       # (B, T)
    return x.gather(1, idx[:, :, None].expand(-1, -1, x.shape[2]))


class BiGRUEncoder(nn.Module):
    """x (B, T, in_dim) with lengths (B,) -> context (B, 2H), outputs (B, T, 2H), mask (B, T).

    The same function as a bidirectional ``nn.GRU`` over the packed batch: each direction
    starts at its end of every sequence, outputs past a sequence's end are 0 and the context
    is the last layer's final state in each direction. It runs unpacked -- per layer, one
    one-way GRU over the batch and one over the batch reversed within each length -- because
    on CPU the backward pass of a packed GRU zero-fills its whole gate tensor once per time
    step (``benchmarks/bench_seq2seq.py`` measures the training speed). The parameters stay
    those of ``self.gru``, so checkpoints keep their layout."""

    def __init__(self, in_dim: int, hidden: int, layers: int, dropout: float = 0.0):
        super().__init__()
        self.hidden = hidden
        self.gru = nn.GRU(in_dim, hidden, num_layers=layers, batch_first=True,
                          bidirectional=True, dropout=dropout if layers > 1 else 0.0)

    @property
    def out_dim(self) -> int:
        return 2 * self.hidden

    def _direction(self, k: int, suffix: str, x: torch.Tensor) -> torch.Tensor:
        """Layer k's one direction ("" forward, "_reverse" backward) over x (B, T, D) from a
        zero state -> outputs (B, T, H). ``torch.gru`` is the stateless kernel ``nn.GRU``
        calls: no module whose weights would be swapped in and out (not thread-safe)."""
        weights = [getattr(self.gru, f"{n}{k}{suffix}")
                   for n in ("weight_ih_l", "weight_hh_l", "bias_ih_l", "bias_hh_l")]
        h0 = x.new_zeros(1, x.shape[0], self.hidden)
        # args: has_biases, num_layers, dropout, train, bidirectional, batch_first
        return torch.gru(x, h0, weights, True, 1, 0.0, False, False, True)[0]

    def forward(self, x: torch.Tensor, lengths: torch.Tensor):
        T = x.shape[1]
        lengths = lengths.cpu().long().clamp(min=1)
        if len(lengths) and int(lengths.max()) > T:
            raise ValueError(f"sequence lengths must be at most {T} (the padded length), "
                             f"got {int(lengths.max())}")
        lengths_x = lengths.to(x.device)
        mask = lengths_to_mask(lengths_x, T)                          # (B, T)
        inp = x.masked_fill(~mask[:, :, None], 0.0)   # NaN padding: 0 * NaN would be NaN
        for k in range(self.gru.num_layers):
            if k:                             # nn.GRU's dropout: between layers, not after
                inp = nn.functional.dropout(inp, self.gru.dropout, self.training)
            fwd = self._direction(k, "", inp)
            bwd_rev = self._direction(k, "_reverse", reverse_within_lengths(inp, lengths_x))
            # padded steps hold states run on past the end: zero them, as unpacking does
            inp = torch.cat([fwd, reverse_within_lengths(bwd_rev, lengths_x)], -1) \
                * mask[:, :, None]
        last = (lengths_x - 1)[:, None, None].expand(-1, 1, self.hidden)
        context = torch.cat([fwd.gather(1, last)[:, 0], bwd_rev.gather(1, last)[:, 0]], -1)
        return context, inp, mask


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
