"""The root's path, integrated in torch, for the tokenizer's path loss.

The position rows (``features.positions``) store the root's motion as per-frame increments:
a ground step in the previous frame's heading frame and a heading change. A tokenizer that
reconstructs each increment with a small error places a travelling body far off its path
once the errors add up, while a loss on the rows alone weighs those 3 of the 66 values like
any joint coordinate. :func:`global_joints` integrates the increments the way
``features.root.integrate`` does (differentiably) and places the local joints on the path,
so a loss can be taken on where the body ends up in metres.
"""
from __future__ import annotations

import torch

from motionlang.features.positions import N_LOCAL


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
