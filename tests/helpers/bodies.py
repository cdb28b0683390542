"""Bodies the tests build joint by joint (21-joint KIT order, Y up, metres, facing +Z): a
standing pose, poses moved from it, and takes held and blended from them."""
from __future__ import annotations

import numpy as np

from motionlang.features.joint_map import KIT21_NAMES

FPS = 30.0
#: a standing body facing +Z (its left at +x), metres; leg length 0.84
STAND = {
    "root": (0, 0.95, 0), "BP": (0, 1.05, 0), "BT": (0, 1.25, 0), "BLN": (0, 1.45, 0),
    "BUN": (0, 1.6, 0), "LS": (0.18, 1.42, 0), "LE": (0.2, 1.14, 0), "LW": (0.2, 0.88, 0),
    "RS": (-0.18, 1.42, 0), "RE": (-0.2, 1.14, 0), "RW": (-0.2, 0.88, 0),
    "LH": (0.09, 0.92, 0), "LK": (0.09, 0.5, 0), "LA": (0.09, 0.08, 0),
    "LMrot": (0.09, 0.02, -0.05), "LF": (0.09, 0.02, 0.12), "RH": (-0.09, 0.92, 0),
    "RK": (-0.09, 0.5, 0), "RA": (-0.09, 0.08, 0), "RMrot": (-0.09, 0.02, -0.05),
    "RF": (-0.09, 0.02, 0.12)}
I = {n: i for i, n in enumerate(KIT21_NAMES)}


def pose(**moved) -> np.ndarray:
    """(21, 3) the standing body with some joints put elsewhere."""
    p = np.array([STAND[n] for n in KIT21_NAMES], dtype=float)
    for name, xyz in moved.items():
        p[I[name]] = xyz
    return p


def hold(p: np.ndarray, seconds: float) -> np.ndarray:
    return np.repeat(p[None], int(round(seconds * FPS)), axis=0)


def blend(a: np.ndarray, b: np.ndarray, seconds: float) -> np.ndarray:
    w = np.linspace(0, 1, int(round(seconds * FPS)))[:, None, None]
    return a[None] * (1 - w) + b[None] * w


def take(*parts: np.ndarray) -> np.ndarray:
    return np.concatenate(parts)


SIT = pose(root=(0, 0.5, 0), BP=(0, 0.6, 0), BT=(0, 0.8, 0), BLN=(0, 1.0, 0), BUN=(0, 1.15, 0),
           LS=(0.18, 0.97, 0), LE=(0.2, 0.7, 0.05), LW=(0.2, 0.6, 0.3), RS=(-0.18, 0.97, 0),
           RE=(-0.2, 0.7, 0.05), RW=(-0.2, 0.6, 0.3), LH=(0.09, 0.48, 0),
           LK=(0.09, 0.5, 0.42), LA=(0.09, 0.08, 0.45), LMrot=(0.09, 0.02, 0.4),
           LF=(0.09, 0.02, 0.57), RH=(-0.09, 0.48, 0), RK=(-0.09, 0.5, 0.42),
           RA=(-0.09, 0.08, 0.45), RMrot=(-0.09, 0.02, 0.4), RF=(-0.09, 0.02, 0.57))


def turned(p: np.ndarray, yaw: np.ndarray) -> np.ndarray:
    """(T, 21, 3) positions ``p`` turned about the vertical by ``yaw`` (T,) radians, frame by
    frame (positive: to the body's left)."""
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    out = p.copy()
    out[..., 0] = c * p[..., 0] + s * p[..., 2]
    out[..., 2] = -s * p[..., 0] + c * p[..., 2]
    return out
