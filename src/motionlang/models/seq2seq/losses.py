"""The L2M's own foot terms (Plappert et al. 2018 and beyond), over the shared frame terms of
:mod:`motionlang.models.frame_losses`."""
from __future__ import annotations

import torch

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import TOES
from motionlang.models.frame_losses import foot_contact_loss


def fed_foot_contact_loss(fed_raw: torch.Tensor, pred_raw: torch.Tensor,
                          target_raw: torch.Tensor, mask: torch.Tensor,
                          feet: tuple[int, ...], fps: float, **contact) -> torch.Tensor:
    """:func:`foot_contact_loss` of the one-frame steps a decoder takes: from the frame it was
    fed at step t (``fed_raw`` (B, T, F); step 0's is a zero frame, left out) to the frame it
    gave (``pred_raw`` (B, T, F)), where the reference's toe is down over its own step from
    frame t-1 to t (``target_raw`` (B, T, F)); mask (B, T). ``contact``: ``height``, ``speed``.
    """
    B, T, F = pred_raw.shape
    prev = torch.cat([target_raw[:, :1], target_raw[:, :-1]], dim=1)
    pairs = torch.stack([fed_raw, pred_raw], dim=2).reshape(B * T, 2, F)
    true = torch.stack([prev, target_raw], dim=2).reshape(B * T, 2, F)
    m = mask.clone()
    m[:, 0] = 0.0
    return foot_contact_loss(pairs, true, m.reshape(B * T, 1).expand(-1, 2), feet, fps,
                             **contact)


def expected_foot_loss(expected: torch.Tensor, motion: torch.Tensor, valid: torch.Tensor,
                       fed: torch.Tensor | None, features, *, step: str = "expected",
                       down: str = "reference") -> torch.Tensor:
    """The L2M's foot term: :func:`foot_contact_loss` of its expected frames (B, T, F)
    against ``motion`` (B, T, F), both normalised model features, un-normalised with the
    position ``features``' normaliser; valid (B, T) bool. With ``step == "input"`` each step
    is from the frame fed (B, T, F) to the expected frame read from it (the step generation
    takes for a ``rollout_input "mean"`` model, fed its expected frames; with
    :func:`fed_foot_contact_loss`); else between consecutive expected frames, the toe down
    where ``down`` says (the reference's or the expected frames' own)."""
    norm = getattr(features, "normalizer", None)
    if norm is None or getattr(features, "kind", None) != "positions":
        raise MotionlangError("L2MConfig.foot_weight needs the model's position features "
                              "and their normaliser")
    mean = torch.as_tensor(norm.mean, dtype=motion.dtype, device=motion.device)
    std = torch.as_tensor(norm.std, dtype=motion.dtype, device=motion.device)
    pred = expected * std + mean
    target, mask = motion * std + mean, valid.to(motion.dtype)
    if step == "input":
        if fed is None:
            raise MotionlangError("foot_step 'input' needs the frames fed")
        return fed_foot_contact_loss(fed * std + mean, pred, target, mask, TOES, features.fps)
    return foot_contact_loss(pred, target, mask, TOES, features.fps, down=down)
