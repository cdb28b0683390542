"""CMU subject 35 walk/jog as the CRBM experiment reads it (Taylor, Hinton & Roweis 2006):
``cmu35WalkJog.mat`` (62 AMC channels per frame, degrees, 30 Hz: the 31 training trials and
the two test trials) with the normalisation ``cmu35TaylorScaleBias.mat``, and the per-frame
features the CRBM models (:func:`model_frames`).

The scoring protocol on this data is ``evaluation.crbm.fill``; ``datasets.named.cmu35_walkjog``
reads the same file as ``Motion`` objects. Pure numpy (scipy reads the files).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from motionlang.errors import DatasetError

# 0-based channels (of 62) kept as wrapped joint angles: 1-based 7-38, 41-47, 49-50, 53-59, 61-62.
JOINT_CHANNELS = np.r_[6:38, 40:47, 48:50, 52:59, 60:62]
JOG_TRIALS = set(range(17, 27))  # CMU 35_17 - 35_26 are jogs; the others walks
TRAIN_TRIALS = [f"35_{i:02d}" for i in [*range(1, 18), *range(19, 27), 28, *range(30, 35)]]


@dataclass
class Cmu35:
    """The 31 training trials and the two test trials, raw channels (T_i, 62) in degrees."""
    train: list[np.ndarray]
    train_names: list[str]
    test: dict[str, np.ndarray]          # "35_18" (jog), "35_29" (walk)
    scale: np.ndarray                    # (59,)
    bias: np.ndarray                     # (59,)
    fps: float = 30.0
    labels: dict[str, str] = field(default_factory=dict)   # trial -> "walk" / "jog"


def _split(Y: np.ndarray, lbls: np.ndarray) -> list[np.ndarray]:
    """Cut the concatenated frames into trials by their one-hot membership (columns in order)."""
    member = lbls.argmax(axis=1)
    if np.any(np.diff(member) < 0):
        raise DatasetError("cmu35WalkJog.mat: trial labels are not contiguous")
    return [Y[member == k] for k in range(lbls.shape[1]) if np.any(member == k)]


def load_cmu35(folder: str | Path) -> Cmu35:
    """Read ``cmu35WalkJog.mat`` and ``cmu35TaylorScaleBias.mat`` from ``folder``."""
    import scipy.io  # heavy; only needed here

    folder = Path(folder)
    try:
        d = scipy.io.loadmat(folder / "cmu35WalkJog.mat")
        sb = scipy.io.loadmat(folder / "cmu35TaylorScaleBias.mat")
        Y, lbls, Yt, lt = d["Y"], d["lbls"], d["Ytest"], d["lblstest"]
        scale, bias = sb["scale"].ravel(), sb["bias"].ravel()
    except (OSError, KeyError, ValueError) as exc:
        raise DatasetError(f"{folder}: cannot read the CMU subject 35 data: {exc}") from exc
    if Y.shape[1] != 62 or Yt.shape[1] != 62 or scale.shape != (59,):
        raise DatasetError(f"{folder}: expected 62 channels and a 59-value scale/bias")
    train = _split(Y.astype(np.float64), lbls)
    if len(train) != len(TRAIN_TRIALS):
        raise DatasetError(f"{folder}: expected {len(TRAIN_TRIALS)} training trials, got {len(train)}")
    test_jog, test_walk = _split(Yt.astype(np.float64), lt)
    labels = {n: ("jog" if int(n[3:]) in JOG_TRIALS else "walk") for n in TRAIN_TRIALS}
    labels.update({"35_18": "jog", "35_29": "walk"})
    return Cmu35(train, list(TRAIN_TRIALS), {"35_18": test_jog, "35_29": test_walk},
                 scale.astype(np.float64), bias.astype(np.float64), labels=labels)


def taylor59(channels: np.ndarray) -> np.ndarray:
    """(T, 62) degrees -> (T, 59): root xyz, sin(rot 3), cos(rot 3), wrapped joint angles (deg)."""
    r = np.deg2rad(channels[:, 3:6])
    joints = np.rad2deg(np.arcsin(np.sin(np.deg2rad(channels[:, JOINT_CHANNELS]))))
    return np.hstack([channels[:, :3], np.sin(r), np.cos(r), joints])


def unwrap_degrees(angles: np.ndarray) -> np.ndarray:
    """(T, K) degrees -> the same rotations without 360-degree jumps along T, the first
    frame brought into [-180, 180)."""
    a = np.rad2deg(np.unwrap(np.deg2rad(np.asarray(angles, dtype=np.float64)), axis=0))
    return a - 360.0 * np.floor((a[:1] + 180.0) / 360.0)


def world_to_body(step_xz: np.ndarray, sin_ry: np.ndarray, cos_ry: np.ndarray) -> np.ndarray:
    """Ground-plane steps (T, 2) as (x, z) in the world -> (side, forward) in the frame the
    root faces (facing direction (sin ry, cos ry), side (cos ry, -sin ry)): a rotation of
    the plane, undone by ``evaluation.crbm.reproduce.body_to_world``."""
    s, c = np.asarray(sin_ry), np.asarray(cos_ry)
    x, z = step_xz[:, 0], step_xz[:, 1]
    return np.stack([x * c - z * s, x * s + z * c], axis=1)


def model_frames(channels: np.ndarray) -> np.ndarray:
    """(T, 62) degrees -> (T, 59) model features: the protocol's 59 values with root x, z as
    the per-frame ground step *in the root's facing frame* (dim 0 sideways, dim 2 forward;
    the frame-to-frame step is stationary where the absolute position is not, and in the
    facing frame it no longer depends on where the subject happens to head - a walk is
    "1.2 m/s forward" whatever its direction, as in Taylor et al.'s body-centred root) and
    the 50 joint channels *unwrapped* instead of folded as asin(sin(x)): the jogs' knees
    bend past 90 degrees and several arm channels pass +-90 (14 % of the training frames),
    and a fold turns a smooth swing into a kink (110 -> 70 degrees) that the CRBM's
    dynamics cannot follow. ``evaluation.crbm.reproduce.to_protocol59`` folds back."""
    x = taylor59(channels)
    out = x.copy()
    out[:, 9:] = unwrap_degrees(channels[:, JOINT_CHANNELS])
    if len(x) > 1:
        step = np.diff(x[:, [0, 2]], axis=0)
        step = np.concatenate([step[:1], step])  # the first frame has no predecessor: copy the next step
        out[:, [0, 2]] = world_to_body(step, x[:, 4], x[:, 7])
    return out
