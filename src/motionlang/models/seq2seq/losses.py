"""Masked loss terms over padded frame sequences, shared by the sequence models.

Sequences are (B, T, F) model features (normalised); masks are (B, T) with 1 on valid
frames. Every term is a mean over valid frames (or valid frame pairs).
"""
from __future__ import annotations

import torch
import torch.nn.functional as F


def frame_mask(lengths: torch.Tensor | None, B: int, T: int) -> torch.Tensor:
    """(B, T) float mask, 1 where ``t < lengths[b]`` (all ones without lengths)."""
    if lengths is None:
        return torch.ones(B, T)
    return (torch.arange(T).unsqueeze(0) < lengths.unsqueeze(1)).float()


def masked_smooth_l1(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor
                     ) -> torch.Tensor:
    """Smooth-L1 of (B, T, F) sequences, averaged over features and valid frames."""
    per_frame = F.smooth_l1_loss(pred, target, reduction="none").mean(dim=-1)
    return (per_frame * mask).sum() / mask.sum().clamp(min=1.0)


def velocity_loss(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor
                  ) -> torch.Tensor:
    """Smooth-L1 between frame-to-frame differences (B, T-1, F) of both sequences."""
    if pred.shape[1] < 2:
        return pred.new_zeros(())
    m = mask[:, 1:] * mask[:, :-1]
    return masked_smooth_l1(pred[:, 1:] - pred[:, :-1], target[:, 1:] - target[:, :-1], m)


def energy_loss(pred: torch.Tensor, target: torch.Tensor, mask: torch.Tensor,
                window: int = 13) -> torch.Tensor:
    """Smooth-L1 between the local *speeds* of both sequences: per feature, the mean absolute
    frame-to-frame change over a centred window of ``window`` frames (odd; 13 = about 1 s at
    12.5 Hz, one gait cycle), over valid frame pairs only.

    Unlike :func:`velocity_loss` it does not care about phase: a step taken a little earlier
    or later costs nothing, but standing where the reference moves does. Beyond the paper.
    """
    if pred.shape[1] < 2:
        return pred.new_zeros(())
    m = (mask[:, 1:] * mask[:, :-1]).unsqueeze(1)                  # (B, 1, T-1)

    def local_speed(x):
        speed = (x[:, 1:] - x[:, :-1]).abs().transpose(1, 2) * m   # (B, F, T-1)
        num = F.avg_pool1d(speed, window, stride=1, padding=window // 2)
        den = F.avg_pool1d(m, window, stride=1, padding=window // 2)
        return (num / den.clamp(min=1e-6)).transpose(1, 2)         # (B, T-1, F)

    return masked_smooth_l1(local_speed(pred), local_speed(target), m[:, 0])
