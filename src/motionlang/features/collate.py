"""Padding and masks for batches of variable-length sequences — defined once, used everywhere.

Convention: ``mask[b, t]`` is True on real frames and False on padding; padding sits at the
end of each sequence. Functions accept numpy arrays or torch tensors and return the same kind.
"""
from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def _is_torch(x) -> bool:
    return type(x).__module__.startswith("torch")


def lengths_to_mask(lengths, max_len: int | None = None):
    """lengths (B,) ints -> mask (B, T) bool with T = max_len or max(lengths).

    Returns a torch tensor (on lengths' device) if ``lengths`` is a tensor, else numpy.
    """
    if _is_torch(lengths):
        import torch
        T = int(lengths.max().item()) if max_len is None else int(max_len)
        return torch.arange(T, device=lengths.device)[None, :] < lengths[:, None]
    lengths = np.asarray(lengths, dtype=np.int64)
    T = int(lengths.max(initial=0)) if max_len is None else int(max_len)
    return np.arange(T)[None, :] < lengths[:, None]


def pad_batch(seqs: Sequence, length: int | None = None, value: float = 0.0):
    """Stack sequences (T_i, D) into (B, T, D) plus a mask (B, T).

    Args:
        seqs: B arrays or tensors of shape (T_i, D) (or (T_i,) for token ids).
        length: batch length T; default max T_i. Longer sequences raise ValueError
            (cropping is the caller's decision, not padding's).
        value: fill value of the padding.

    Returns:
        (batch (B, T, ...), mask (B, T) bool) — torch if the inputs are tensors.
    """
    if len(seqs) == 0:
        raise ValueError("pad_batch needs at least one sequence")
    lens = [int(s.shape[0]) for s in seqs]
    T = max(lens) if length is None else int(length)
    if max(lens) > T:
        raise ValueError(f"sequence of length {max(lens)} does not fit batch length {T}")
    tail = tuple(seqs[0].shape[1:])
    for s in seqs:
        if tuple(s.shape[1:]) != tail:
            raise ValueError(f"pad_batch: trailing shapes differ: {tail} vs {tuple(s.shape[1:])}")
    if _is_torch(seqs[0]):
        import torch
        out = torch.full((len(seqs), T) + tail, value, dtype=seqs[0].dtype,
                         device=seqs[0].device)
        for b, s in enumerate(seqs):
            out[b, :lens[b]] = s
        return out, lengths_to_mask(torch.tensor(lens, device=out.device), T)
    first = np.asarray(seqs[0])
    out = np.full((len(seqs), T) + tail, value, dtype=first.dtype)
    for b, s in enumerate(seqs):
        out[b, :lens[b]] = np.asarray(s)
    return out, lengths_to_mask(np.array(lens), T)


def unpad(batch, mask) -> list:
    """Inverse of :func:`pad_batch`: (B, T, ...) and mask (B, T) -> list of (T_i, ...).

    Each sequence is cut at its number of True mask entries (padding is at the end).
    """
    lens = mask.sum(1)
    return [batch[b, :int(lens[b])] for b in range(len(batch))]
