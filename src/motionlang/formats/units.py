"""Length units of motion files, decided from the body: measure the stature in file units,
then take the unit that makes it a human's.

How the stature is measured (:func:`estimate_stature`), and why that way. Both measures use
posed frames (an even sample of them), never the rest pose: a BVH rest pose need not be a
standing pose (Bandai Namco's bones all lie along their local X axis), and a rig may keep
a meaningless OFFSET where position channels override it.

1. From the legs: thigh + shank is 0.491 of the stature (Winter, *Biomechanics and Motor
   Control of Human Movement*, 2009, table 4.1: 0.245 + 0.246), and unlike the whole body
   it does not depend on where a rig ends (head joint or head top, ankle or sole). The leg
   is the chain of bones from the joint that is lowest in most frames (a toe or heel) up to
   the first branching joint (the pelvis); thigh + shank are its two longest consecutive
   bones. Bandai Namco's rig, whose head joint sits at the neck and whose feet float 4 cm,
   gets 1.63 m where the whole-body measures below get 1.2-1.7 m depending on the take.
2. The body's *diameter*: the largest distance between two joints of a frame, median over
   frames. It needs no up axis and no tree, and across standing, walking, T-pose, arms-up,
   sitting and lying poses stays between about 0.7 and 1.3 times the stature (toes to head,
   hand to foot, hand to hand). It checks the first measure, which a handstand, a kneeling
   take, a Z-up file or a rig with split thigh bones would fool: the leg estimate is kept
   only when the diameter is 0.6-1.4 times it; otherwise the diameter is the estimate.

Either way the error is far below the 2.54x between candidate units. (Not the vertical
extent: a crawl or a lying pose shrinks it to a fraction of the stature.) The unit is the
candidate (m, cm, mm, inch) nearest in log space to 1.7 m, kept when the stature then falls
in :data:`PLAUSIBLE_M`; otherwise the lengths are in "BVH units" and are scaled so that the
body is :data:`SCALED_STATURE_M` tall.
"""
from __future__ import annotations

import math

import numpy as np

from motionlang.kinematics.motion import Motion

UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "inch": 0.0254, "in": 0.0254}
CANDIDATES = ("m", "cm", "mm", "inch")
BVH_UNITS = "BVH units"
TYPICAL_STATURE_M = 1.7
PLAUSIBLE_M = (0.9, 2.5)   # children of ~1 m to the tallest adults, or tall ones arms up
SCALED_STATURE_M = 1.75
MAX_FRAMES = 64            # frames sampled for the stature: enough for a stable median
THIGH_SHANK = 0.491        # (hip-knee + knee-ankle) / stature, Winter 2009
AGREE = (0.6, 1.4)         # diameter / leg estimate for one human body in any pose

# 13 directions (axes, face and body diagonals): every direction lies within 27.6 degrees of
# one of them or its opposite, so the two joints extreme along it are at least cos(27.6) =
# 0.89 of the diameter apart (for an elongated body like a human's, almost exactly it).
_DIRS = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 1, 0], [1, -1, 0], [1, 0, 1],
                  [1, 0, -1], [0, 1, 1], [0, 1, -1], [1, 1, 1], [1, 1, -1], [1, -1, 1],
                  [-1, 1, 1]], dtype=float)
_DIRS /= np.linalg.norm(_DIRS, axis=1, keepdims=True)


def sample_frames(n_frames: int, max_frames: int = MAX_FRAMES) -> np.ndarray:
    """Up to ``max_frames`` evenly spaced frame indices of ``range(n_frames)``, first and
    last included."""
    return np.unique(np.linspace(0, n_frames - 1, min(n_frames, max_frames)).round()
                     ).astype(int)


def estimate_stature(positions: np.ndarray, parents: np.ndarray | None = None,
                     max_frames: int = MAX_FRAMES) -> float:
    """Stature from posed joint positions, in the positions' own unit (module docstring).

    Args:
        positions: (T, J, 3) or (J, 3) joint positions in any unit, Y up for the leg measure.
        parents: (J,) parent index of each joint (-1 for the root); without it only the
            diameter is used.
        max_frames: frames sampled evenly from ``positions``.

    Returns:
        the leg estimate when the diameter agrees with it, else the diameter; 0.0 for fewer
        than two joints or no finite frame.
    """
    p = np.asarray(positions, dtype=float)
    if p.ndim == 2:
        p = p[None]
    if p.ndim != 3 or p.shape[1] < 2 or p.shape[0] == 0:
        return 0.0
    p = p[sample_frames(len(p), max_frames)]
    p = p[np.all(np.isfinite(p), axis=(1, 2))]
    if not len(p):
        return 0.0
    diameter = _diameter(p)
    if parents is None or len(parents) != p.shape[1]:
        return diameter
    leg = _leg_stature(p, np.asarray(parents, dtype=int))
    return leg if leg > 0 and AGREE[0] <= diameter / leg <= AGREE[1] else diameter


def _diameter(p: np.ndarray) -> float:
    """Median over frames of the largest distance between two joints; p (F, J, 3)."""
    # candidates: the extreme joints along each direction, then exact distances among them
    proj = p @ _DIRS.T                                              # (F, J, 13)
    cand = np.concatenate([proj.argmin(axis=1), proj.argmax(axis=1)], axis=1)  # (F, 26)
    pts = np.take_along_axis(p, cand[:, :, None], axis=1)          # (F, 26, 3)
    d = np.linalg.norm(pts[:, :, None] - pts[:, None], axis=-1)     # (F, 26, 26)
    return float(np.median(d.max(axis=(1, 2))))


def _leg_stature(p: np.ndarray, parents: np.ndarray) -> float:
    """(thigh + shank) / 0.491 from the chain above the usually lowest joint; p (F, J, 3)
    Y up; 0.0 when that chain has fewer than two bones."""
    J = len(parents)
    if J < 3 or parents[0] != -1 or np.any(parents[1:] >= np.arange(1, J)) or \
            np.any(parents[1:] < 0):
        return 0.0
    height = p[:, :, 1] - p[:, :, 1].min(axis=1, keepdims=True)
    k = int(np.argmin(np.median(height, axis=0)))
    n_kids = np.bincount(parents[1:], minlength=J)
    bones = []
    while parents[k] >= 0:
        bones.append(float(np.median(np.linalg.norm(p[:, k] - p[:, parents[k]], axis=-1))))
        k = parents[k]
        if n_kids[k] != 1:  # the pelvis (or wherever the leg meets the body)
            break
    bones = [b for b in bones if b > 0]  # zero-length End Sites
    pairs = [a + b for a, b in zip(bones[:-1], bones[1:])]
    return max(pairs) / THIGH_SHANK if pairs else 0.0


def detect_unit(stature: float) -> tuple[str, float]:
    """The length unit that makes ``stature`` (in file units) a human's.

    Returns:
        (name, metres per file unit): a name of :data:`CANDIDATES`, or
        :data:`BVH_UNITS` with the scale that makes the body 1.75 m tall when no candidate
        gives a stature within :data:`PLAUSIBLE_M` (or ``1.0`` when the body has no size).
    """
    if not (math.isfinite(stature) and stature > 0):
        return BVH_UNITS, 1.0
    best = min(CANDIDATES, key=lambda n: abs(math.log(stature * UNITS[n] / TYPICAL_STATURE_M)))
    if PLAUSIBLE_M[0] <= stature * UNITS[best] <= PLAUSIBLE_M[1]:
        return best, UNITS[best]
    return BVH_UNITS, SCALED_STATURE_M / stature


def resolve_unit(unit: float | str) -> tuple[str, float]:
    """(name, metres per unit) of an explicit unit: a name of :data:`UNITS` or metres.

    Raises:
        ValueError: an unknown name or a number that is not a positive length.
    """
    if isinstance(unit, str):
        key = unit.lower()
        if key not in UNITS:
            raise ValueError(f"unknown unit {unit!r}; use one of {sorted(UNITS)} or metres")
        return ("inch" if key == "in" else key), UNITS[key]
    if not (isinstance(unit, (int, float, np.floating, np.integer)) and math.isfinite(unit)
            and unit > 0):
        raise ValueError(f"unit must be a positive number of metres, got {unit}")
    return unit_name(float(unit)), float(unit)


def unit_name(metres: float) -> str:
    """``"cm"`` for 0.01 and so on; ``"1/L inch"`` for an ASF ``:units length L`` other
    than 1; otherwise the metres per unit, e.g. ``"0.05 m"``."""
    for name in CANDIDATES:
        if math.isclose(metres, UNITS[name], rel_tol=1e-9):
            return name
    per_inch = UNITS["inch"] / metres  # ASF: one file unit is 1/L inch (CMU: L = 0.45)
    if 0.01 <= per_inch <= 100 and abs(per_inch - round(per_inch, 2)) < 1e-9 * per_inch:
        return f"1/{round(per_inch, 2):g} inch"
    return f"{metres:.6g} m"


def motion_stature(motion: Motion, max_frames: int = MAX_FRAMES) -> float:
    """Stature in metres of ``motion``'s body (:func:`estimate_stature` of its forward
    kinematics on up to ``max_frames`` evenly spaced frames)."""
    idx = sample_frames(motion.n_frames, max_frames)
    sub = motion.replace(root_translation=motion.root_translation[idx],
                         root_rotation=motion.root_rotation[idx],
                         joint_angles=motion.joint_angles[idx])
    return estimate_stature(sub.positions(), motion.skeleton.parents, max_frames)
