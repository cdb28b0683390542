"""Physical plausibility checks for MMM motions: foot contacts, stance sliding, floor.

Measured from forward kinematics alone (no generator internals), so they apply to any
MMM motion, synthetic or recorded.
"""
from __future__ import annotations

import numpy as np

FOOT_JOINTS = {"L": ("LeftFootHeight_joint", "LAy_joint"),
               "R": ("RightFootHeight_joint", "RAy_joint")}


def foot_points(motion) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """{side: (heel (T, 3), ball (T, 3))} in metres, canonical frame (Y up).

    Heel = the sole point under the ankle; ball = the sole point 0.08 x height ahead of it.
    """
    from motionlang.formats.mmm_model import mmm_height

    sk = motion.skeleton
    rot, pos = motion.global_transforms()
    foot_len = 0.08 * mmm_height(sk)
    out = {}
    for s, (sole, ankle) in FOOT_JOINTS.items():
        heel = pos[:, sk.index(sole)]
        ball = heel + rot[:, sk.index(ankle)] @ np.array([0.0, foot_len, 0.0])
        out[s] = (heel @ sk.world.T, ball @ sk.world.T)
    return out


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) of the runs of True in a 1-D bool array."""
    d = np.diff(np.r_[0, mask.astype(int), 0])
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def stance_sliding(motion, height_tol: float = 0.02, min_frames: int = 5,
                   frames: slice | None = None) -> list[float]:
    """Horizontal slip (metres) of each foot contact.

    A contact is a run of >= ``min_frames`` frames in which the foot's lowest sole point
    (heel or ball) is within ``height_tol`` of the floor (the lowest point of the motion).
    Per frame the slip is the smaller horizontal move of heel and ball (a rolling foot
    keeps one of them fixed); a contact's slip is the sum over its frames.
    """
    pts = foot_points(motion)
    sl = frames or slice(None)
    floor = min(min(h[sl, 1].min(), b[sl, 1].min()) for h, b in pts.values())
    slips = []
    for heel, ball in pts.values():
        heel, ball = heel[sl], ball[sl]
        low = np.minimum(heel[:, 1], ball[:, 1]) - floor
        step = np.minimum(np.linalg.norm(np.diff(heel[:, [0, 2]], axis=0), axis=1),
                          np.linalg.norm(np.diff(ball[:, [0, 2]], axis=0), axis=1))
        for a, b in _runs(low < height_tol):
            if b - a >= min_frames:
                slips.append(float(step[a:b - 1].sum()))
    return slips


def lowest_point_height(motion) -> np.ndarray:
    """(T,) height (m) of the lowest sole point above the motion's global lowest point."""
    pts = foot_points(motion)
    low = np.min([np.minimum(h[:, 1], b[:, 1]) for h, b in pts.values()], axis=0)
    return low - low.min()
