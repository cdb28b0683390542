"""Motions as the JSON the page's viewer draws: joint positions per frame, the tree, sides.

The viewer (``static/viewer.js``) draws lines between each joint and its parent, so any
skeleton works: the 21-joint body of a generated take or a described file, or a user's rig.
Positions are metres in the canonical Y-up frame (``Motion.positions``), rounded to the
millimetre; long takes are thinned to :data:`VIEW_FPS` and cut at :data:`MAX_VIEW_FRAMES`
so that a page never receives more than a few megabytes.
"""
from __future__ import annotations

import re
from collections.abc import Sequence
from typing import Any

import numpy as np

from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS
from motionlang.kinematics.motion import Motion

#: frames a second sent to the page at most (the viewer interpolates between frames)
VIEW_FPS = 30.0
#: frames sent at most (at VIEW_FPS: 10 minutes)
MAX_VIEW_FRAMES = 18_000
_TOKENS = re.compile(r"[A-Z]+(?![a-z])|[A-Z]?[a-z]+|\d+")
#: body words that follow a one-letter side in glued names (CMU's ``lfemur``, ``rhand``)
_PARTS = ("femur", "tibia", "foot", "toe", "humerus", "radius", "wrist", "hand", "clavicle",
          "hip", "shoulder", "finger", "thumb", "collar", "arm", "leg", "elbow", "knee",
          "ankle", "up", "low", "fore", "shin", "thigh", "eye", "ear")


def side(name: str) -> str:
    """"L", "R" or "" for a joint name in the common namings (``LK``, ``LeftUpLeg``,
    ``l_hip``, ``upperarm_l``, ``joint_LeftKnee``, ``lfemur``); the viewer colours by it."""
    tokens = _TOKENS.findall(name)
    for token in tokens:
        low = token.lower()
        if low in ("l", "left"):
            return "L"
        if low in ("r", "right"):
            return "R"
    first = tokens[0] if tokens else ""
    if first[:1] in "LR" and first.isupper() and len(first) in (2, 3):   # KIT's LK, RMrot
        return first[0]
    low = name.lower()
    if low[:1] in ("l", "r") and low[1:].startswith(_PARTS):
        return low[0].upper()
    return ""


def view_step(fps: float) -> int:
    """Every how many frames a take at ``fps`` Hz is shown: at most :data:`VIEW_FPS`."""
    return max(1, int(np.ceil(fps / VIEW_FPS - 1e-9)))


def positions_view(positions: np.ndarray, fps: float, names: Sequence[str],
                   parents: Sequence[int], **extra: Any) -> dict[str, Any]:
    """The viewer's JSON of ``positions`` (T, J, 3) metres, Y up, at ``fps`` Hz:
    ``{"fps", "n_frames", "n_joints", "names", "parents", "sides", "floor", "frames"}``,
    ``frames`` a flat list of T*J*3 numbers; ``floor`` the height of the ground (the lowest
    point any joint reaches); ``extra`` keys are added as they are."""
    p = np.asarray(positions, dtype=np.float64)
    step = view_step(fps)
    p = p[::step][:MAX_VIEW_FRAMES]
    return {"fps": fps / step, "n_frames": int(len(p)), "n_joints": int(p.shape[1]),
            "names": list(names), "parents": [int(q) for q in parents],
            "sides": [side(n) for n in names], "floor": round(float(p[..., 1].min()), 3),
            "frames": np.round(p, 3).ravel().tolist(), **extra}


def motion_view(motion: Motion, **extra: Any) -> dict[str, Any]:
    """The viewer's JSON of a Motion on its own skeleton (``positions_view``)."""
    joints = motion.skeleton.joints
    return positions_view(motion.positions(), motion.fps, [j.name for j in joints],
                          [j.parent for j in joints], **extra)


def body21_view(positions: np.ndarray, fps: float, **extra: Any) -> dict[str, Any]:
    """The viewer's JSON of positions on the 21-joint body (T, 21, 3)."""
    return positions_view(positions, fps, KIT21_NAMES, KIT21_PARENTS, **extra)
