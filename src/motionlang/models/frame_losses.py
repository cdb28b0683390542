"""Masked loss terms over padded frame sequences, shared by the sequence models (the seq2seq
L2M and the two-stream model).

Sequences are (B, T, F) model features (normalised); masks are (B, T) with 1 on valid
frames. Every term is a mean over valid frames (or valid frame pairs).
"""
from __future__ import annotations

import torch
import torch.nn.functional as F

from motionlang.features.positions import local_joints, root_step, root_turn


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
    frame-to-frame change over a centred window of ``window`` frames (odd; 13 frames: about one
    gait cycle at the two-stream model's rate), over valid frame pairs only.

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


def foot_steps(raw: torch.Tensor, feet: tuple[int, ...]) -> torch.Tensor:
    """Horizontal steps of foot joints between consecutive frames of position features.

    raw: (B, T, F) *un-normalised* features of ``features.positions`` (21 local joints in
    the body's heading frame, then the root's ground step (sideways, forward; m/frame) in
    the previous frame's heading frame and its heading change (rad/frame)). feet: indices
    into the 21 joints. Returns (B, T-1, k, 2): each joint's move from frame t-1 to t, in
    metres, in the heading frame of t-1 (the frame that ``root.increments`` steps from):
    ``v_t + Ry(dyaw_t) local_t - local_{t-1}``, the same step the decoded global positions take.
    """
    local = local_joints(raw)[:, :, list(feet)]
    x, z = local[..., 0], local[..., 2]                       # (B, T, k)
    a = root_turn(raw)[:, 1:].unsqueeze(-1)
    c, s = torch.cos(a), torch.sin(a)
    step = root_step(raw)[:, 1:]
    dx = step[..., 0:1] + c * x[:, 1:] + s * z[:, 1:] - x[:, :-1]
    dz = step[..., 1:2] - s * x[:, 1:] + c * z[:, 1:] - z[:, :-1]
    return torch.stack([dx, dz], dim=-1)


def foot_contact_loss(pred_raw: torch.Tensor, target_raw: torch.Tensor, mask: torch.Tensor,
                      feet: tuple[int, ...], fps: float, height: float = 0.05,
                      speed: float = 1.0, down: str = "reference") -> torch.Tensor:
    """Mean horizontal speed (m/s) of the predicted ``feet`` over the frame steps where a foot
    is down: below ``height`` m (its local y, the floor being y = 0) at both frames and slower
    than ``speed`` m/s, the contact test of ``evaluation.metrics.physics.foot_skating``. Whose
    foot: the *reference's* (``down="reference"``), or the prediction's own (``"own"``, the
    test read from ``pred_raw`` without a gradient: the model's own steps need not fall
    when the reference's do once it runs on its own frames). Zero when no foot is down.

    pred_raw, target_raw: (B, T, F) un-normalised position features; mask: (B, T), 1 on
    valid frames. A planted foot should not move: this asks the model's frames to keep
    it where it was, which the frame NLL alone does not (small errors of the root's step and
    of the local foot position each look likely but add up to a slide).
    """
    if down not in ("reference", "own"):
        raise ValueError(f"down must be 'reference' or 'own', not {down!r}")
    if pred_raw.shape[1] < 2:
        return pred_raw.new_zeros(())
    with torch.no_grad():
        test = target_raw if down == "reference" else pred_raw.detach()
        ref = foot_steps(test, feet).norm(dim=-1) * fps                   # (B, T-1, k)
        y = local_joints(test)[:, :, list(feet), 1]
        low = y < height
        pair = (mask[:, 1:] * mask[:, :-1]).bool().unsqueeze(-1)
        contact = (low[:, 1:] & low[:, :-1] & (ref < speed) & pair).to(pred_raw.dtype)
    # sqrt(. + eps), not norm(): a finite gradient where a foot does not move at all
    moved = (foot_steps(pred_raw, feet).pow(2).sum(dim=-1) + 1e-10).sqrt() * fps
    return (moved * contact).sum() / contact.sum().clamp(min=1.0)
