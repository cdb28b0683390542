"""A one-way recurrent stack read at each padded sequence's end, shared by the seq2seq
models and the two-stream model's encoders and discriminator."""
from __future__ import annotations

import torch
from torch import nn


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
