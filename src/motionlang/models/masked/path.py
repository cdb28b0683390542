"""The root's path, integrated in torch, for the tokenizer's path loss.

The position rows (``features.positions``) store the root's motion as per-frame increments:
a ground step in the previous frame's heading frame and a heading change. A tokenizer that
reconstructs each increment with a small error places a travelling body far off its path
once the errors add up, while a loss on the rows alone weighs those 3 of the 66 values like
any joint coordinate. :func:`global_joints` integrates the increments the way
``features.root.integrate`` does (differentiably) and places the local joints on the path,
so a loss can be taken on where the body ends up in metres (:func:`global_errors`), and on
how fast the feet move over the floor (a decoder that gets the root's step and the legs'
swing each nearly right can still slide a planted foot).
"""
from __future__ import annotations

import torch

from motionlang.features.positions import FOOT, N_LOCAL


def root_path(raw: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
    """Un-normalised rows (B, T, 66) -> ground positions (B, T, 2) as (x, z) metres and
    headings (B, T) radians, from (0, 0) facing +Z at frame 0 (the step and turn of frame 0
    are ignored, as in ``features.root.integrate``)."""
    step, turn = raw[..., N_LOCAL:N_LOCAL + 2], raw[..., N_LOCAL + 2]
    yaw = torch.cat([torch.zeros_like(turn[:, :1]), torch.cumsum(turn[:, 1:], dim=1)], dim=1)
    prev = yaw[:, :-1]        # a step is taken in the previous frame's heading frame
    c, s = torch.cos(prev), torch.sin(prev)
    sx, sz = step[:, 1:, 0], step[:, 1:, 1]
    # R_y(yaw) applied to (sx, 0, sz): x' = c sx + s sz, z' = -s sx + c sz
    world = torch.stack([c * sx + s * sz, -s * sx + c * sz], dim=-1)
    ground = torch.cat([torch.zeros_like(world[:, :1]), torch.cumsum(world, dim=1)], dim=1)
    return ground, yaw


def global_joints(raw: torch.Tensor) -> torch.Tensor:
    """Un-normalised rows (B, T, 66) -> the 21 joints (B, T, 21, 3) in metres, placed along
    :func:`root_path` (frame 0 at the origin facing +Z)."""
    ground, yaw = root_path(raw)
    local = raw[..., :N_LOCAL].reshape(*raw.shape[:2], -1, 3)
    c, s = torch.cos(yaw)[..., None], torch.sin(yaw)[..., None]
    x, y, z = local[..., 0], local[..., 1], local[..., 2]
    return torch.stack([c * x + s * z + ground[..., :1], y, -s * x + c * z + ground[..., 1:]],
                       dim=-1)


def global_errors(recon: torch.Tensor, truth: torch.Tensor, frames: torch.Tensor,
                  fps: float) -> tuple[torch.Tensor, torch.Tensor]:
    """Un-normalised rows (B, T, 66) reconstructed and true, valid frames (B, T) bool ->
    (mean joint distance in metres along the integrated path, mean error of the six foot
    joints' ground-plane velocity in m/s over the valid frame steps). Integrated forwards,
    so the padding after a motion's end cannot move its frames."""
    got, want = global_joints(recon), global_joints(truth)
    w = frames.to(got.dtype)
    path = ((got - want).norm(dim=-1).mean(-1) * w).sum() / w.sum().clamp(min=1.0)
    feet = list(FOOT)
    step = (got[:, 1:, feet] - got[:, :-1, feet]) - (want[:, 1:, feet] - want[:, :-1, feet])
    both = w[:, 1:] * w[:, :-1]
    slide = (step[..., [0, 2]].norm(dim=-1).mean(-1) * both).sum() * fps
    return path, slide / both.sum().clamp(min=1.0)
