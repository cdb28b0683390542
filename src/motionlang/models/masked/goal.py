"""Where a gap must arrive: the goal that conditions in-betweening.

Tokens carry the root's motion as increments, never its place, so a generator that fills a
gap between kept frames does not know where the body has to be when the gap ends: a draft
may take the gap at another pace and arrive a stride off, and joining it to the kept frames
then slides the feet. A model with ``config.goal > 0`` is told, at every token of a gap,
the root's displacement and turn from the last kept frame before the gap to the first kept
frame after it, in the body's heading frame at the gap's start (:func:`gap_goal`), with the
gap's average velocity and the token's progress through the gap. Training draws such a gap
in a fraction ``config.goal`` of the motions (:func:`draw_gap`), masks only inside it and
gives its goal computed from the motion's own rows; in-betweening computes it from the
kept frames.

Goal features per token (:data:`GOAL_DIM`), zero outside a gap: displacement (sideways x,
forward z) / 2 m, average velocity (m/s), sin and cos - 1 of the turn, 1, progress in (0, 1).
"""
from __future__ import annotations

import numpy as np
import torch

from motionlang.features.positions import N_LOCAL
from motionlang.features.root import integrate, to_heading
from motionlang.kinematics.rotations import wrap_angle
from motionlang.models.masked.config import DOWN

GOAL_DIM = 8
#: the longest gap drawn in training, in tokens (about 10 s at 12.5 Hz)
MAX_GAP = 32


def root_track(raw: np.ndarray) -> np.ndarray:
    """Un-normalised position rows (T, 66) -> the root's ground position and heading
    (T, 3) as (x, z) metres and yaw radians, from (0, 0) facing +Z at frame 0."""
    raw = np.asarray(raw, dtype=np.float64)
    ground, yaw = integrate(raw[:, N_LOCAL:N_LOCAL + 2], raw[:, N_LOCAL + 2])
    return np.concatenate([ground, yaw[:, None]], 1).astype(np.float32)


def gap_goal(track: np.ndarray, a: int, b: int, n_tokens: int, fps: float) -> np.ndarray:
    """The goal features (n_tokens, GOAL_DIM) of a gap of tokens [a, b), kept tokens on both
    sides (1 <= a < b < n_tokens), from the root ``track`` (T, 3) of :func:`root_track`:
    rows a..b-1 filled, the others zero. The anchors are the gap's neighbouring frames:
    the last of token a - 1 and the first of token b."""
    track = np.asarray(track, dtype=np.float64)
    if not 1 <= a < b < n_tokens:
        raise ValueError(f"a gap [{a}, {b}) needs kept tokens on both sides of "
                         f"{n_tokens}")
    f0, f1 = DOWN * a - 1, min(DOWN * b, len(track) - 1)
    move = np.array([track[f1, 0] - track[f0, 0], 0.0, track[f1, 1] - track[f0, 1]])
    local = to_heading(move, track[f0, 2])[[0, 2]]
    turn = float(wrap_angle(track[f1, 2] - track[f0, 2]))
    seconds = max(f1 - f0, 1) / fps
    out = np.zeros((n_tokens, GOAL_DIM), dtype=np.float32)
    k = np.arange(a, b)
    out[a:b, 0:2] = local / 2.0
    out[a:b, 2:4] = local / seconds
    out[a:b, 4] = np.sin(turn)
    out[a:b, 5] = np.cos(turn) - 1.0
    out[a:b, 6] = 1.0
    out[a:b, 7] = (k - a + 0.5) / (b - a)
    return out


def kept_goal(track: np.ndarray, kept: np.ndarray, fps: float) -> np.ndarray:
    """Goal features (L, GOAL_DIM) of every gap in kept tokens (L,) bool that has kept
    tokens on both sides (a gap that reaches an end has no place to arrive at: zero)."""
    kept = np.asarray(kept, dtype=bool)
    out = np.zeros((len(kept), GOAL_DIM), dtype=np.float32)
    k = 0
    while k < len(kept):
        if kept[k]:
            k += 1
            continue
        end = k
        while end < len(kept) and not kept[end]:
            end += 1
        if k > 0 and end < len(kept):
            out += gap_goal(track, k, end, len(kept), fps)
        k = end
    return out


def draw_gap(n_tokens: int, generator: torch.Generator | None = None
             ) -> tuple[int, int] | None:
    """A training gap [a, b) of 1..MAX_GAP tokens with a kept token on each side, uniform
    in length then position (torch's generator); None when the motion is too short."""
    if n_tokens < 3:
        return None
    most = min(n_tokens - 2, MAX_GAP)
    length = int(torch.randint(1, most + 1, (), generator=generator))
    a = int(torch.randint(1, n_tokens - length, (), generator=generator))
    return a, a + length


def batch_goals(tracks: list[np.ndarray | None], n_tokens: list[int], length: int,
                prob: float, fps: float) -> tuple[torch.Tensor, torch.Tensor]:
    """A training batch's goals: each motion with a root ``track`` is, with probability
    ``prob`` (torch's generator), given a gap by :func:`draw_gap`. Returns the goal
    features (B, length, GOAL_DIM) and the gap positions (B, length) bool, all False for a
    motion without a gap (the whole motion is then open to masking)."""
    goal = torch.zeros(len(n_tokens), length, GOAL_DIM)
    gap = torch.zeros(len(n_tokens), length, dtype=torch.bool)
    for i, (track, n) in enumerate(zip(tracks, n_tokens, strict=True)):
        if track is None or prob <= 0 or float(torch.rand(())) >= prob:
            continue
        drawn = draw_gap(n)
        if drawn is None:
            continue
        a, b = drawn
        goal[i, :n] = torch.from_numpy(gap_goal(track, a, b, n, fps))
        gap[i, a:b] = True
    return goal, gap
