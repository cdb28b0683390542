"""Physical plausibility of a motion as pure functions of its 21-joint positions.

Every function takes global positions (T, 21, 3) in metres, Y up, in the joint order of
``features.joint_map.KIT21_NAMES``, with the floor at y = 0 unless ``floor`` says
otherwise (``features.positions.floor_height`` estimates it for a captured motion), and
their frame rate ``fps`` in Hz where time matters.

* :func:`foot_skating`: mean horizontal speed (m/s) of a foot while it is in contact: its
  height below ``height`` and its horizontal speed below ``speed`` over a frame step
  (the speed bound leaves out a swinging foot that only passes low).
* :func:`floor_penetration`: how far the body goes below the floor (m), mean and max over
  frames of the lowest joint's depth (0 for a frame above the floor).
* :func:`root_jitter`: the largest one-frame move of the root (m). It grows with speed as
  well as with glitches: compare against ground truth at the same frame rate.
* :func:`root_kick`: the largest change of the root's one-frame move between two frame
  steps (m), the second difference: steady fast motion scores 0 there, a glitch (a jump
  out of a steady path) does not. At 12.5 Hz a real walk moves its root over 10 cm a
  frame; real Bandai takes change that move by at most 14 cm.
"""
from __future__ import annotations

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import TOES  # noqa: F401 (re-exported: the feet measured)


def _check(p21, name: str) -> np.ndarray:
    p = np.asarray(p21, dtype=float)
    if p.ndim != 3 or p.shape[1:] != (21, 3) or not len(p):
        raise MotionlangError(f"{name}: positions must be (T >= 1, 21, 3), got {p.shape}")
    return p


def foot_skating(p21, fps: float, *, feet=TOES, height: float = 0.05, speed: float = 1.0,
                 floor: float = 0.0) -> float:
    """Mean horizontal speed (m/s) of the ``feet`` joints over the frame steps (t, t + 1)
    where the foot is in contact: below ``height`` m above the floor at both frames and
    slower than ``speed`` m/s. NaN when no foot is ever in contact (nothing to measure).

    Example: a toe sliding 0.01 m per frame at 10 Hz on the floor skates at 0.1 m/s.
    """
    p = _check(p21, "foot_skating")
    if not fps > 0:
        raise MotionlangError(f"foot_skating: fps must be positive, got {fps}")
    f = p[:, list(feet)]                                             # (T, k, 3)
    v = np.linalg.norm(np.diff(f[..., [0, 2]], axis=0), axis=-1) * fps   # (T - 1, k)
    low = f[..., 1] - floor < height
    contact = low[:-1] & low[1:] & (v < speed)
    return float(v[contact].mean()) if contact.any() else float("nan")


def floor_penetration(p21, *, floor: float = 0.0) -> tuple[float, float]:
    """(mean, max) over frames of ``max(0, floor - lowest joint's y)``, metres."""
    p = _check(p21, "floor_penetration")
    depth = np.maximum(0.0, floor - p[..., 1].min(axis=1))
    return float(depth.mean()), float(depth.max())


def root_jitter(p21) -> float:
    """The largest distance (m) the root (joint 0) moves between two consecutive frames;
    0 for a single frame."""
    p = _check(p21, "root_jitter")
    if len(p) < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(p[:, 0], axis=0), axis=-1).max())


def root_kick(p21) -> float:
    """The largest distance (m) between two consecutive one-frame moves of the root
    (``|r[t+1] - 2 r[t] + r[t-1]|``); 0 for fewer than 3 frames."""
    p = _check(p21, "root_kick")
    if len(p) < 3:
        return 0.0
    return float(np.linalg.norm(np.diff(p[:, 0], n=2, axis=0), axis=-1).max())


def physics(p21, fps: float, **skating) -> dict[str, float]:
    """The measures of one motion: ``skating`` (m/s, NaN without contact), ``penetration``
    and ``penetration_max`` (m), ``root_jump`` and ``root_kick`` (m). ``skating``: options
    of :func:`foot_skating`."""
    mean, peak = floor_penetration(p21, floor=skating.get("floor", 0.0))
    return {"skating": foot_skating(p21, fps, **skating), "penetration": mean,
            "penetration_max": peak, "root_jump": root_jitter(p21),
            "root_kick": root_kick(p21)}
