"""One body for every rig: the 21 KIT joints standing on the floor, facing +Z, at a stature.

:func:`body21` maps any motion onto the 21-joint body (``joint_map.positions21``) and
normalises it (:func:`normalise21`): the floor at y = 0 (``positions.floor_height``: the
5th percentile over frames of the lowest foot joint), frame 0's root over the origin, frame
0 facing +Z (``positions.facing_yaw``, from the hips and shoulders), and optionally scaled
to a stature. Everything works on posed positions; no rig's rest pose is assumed to be a
T-pose (Bandai Namco's rest pose lays every bone along its local x axis).

:func:`stature21` estimates standing height from bone lengths, whatever the pose: legs
(hip-knee-ankle) plus the trunk chain (root-BP-BT-BLN-BUN) are 0.831 of stature in the MMM
reference model (thigh 0.245, shank 0.246, trunk 0.040 + 0.060 + 0.210 + 0.030), from which
KIT motion 00001 comes back at its subject's 1.82 m. Other rigs place their spine and head
nodes differently, which moves the estimate by a few per cent: CMU subject 35 comes out at
1.83 m, where its legs alone (86 cm, 0.491 of stature in MMM) would say 1.76 m.

:func:`uniform_bones21` lays a motion's bones again at given lengths, keeping every bone's
direction, and scales its root path by the ratio of the legs: the same motion on another
body (HumanML3D's "uniform skeleton" step does the same with joint angles). A classifier
that reads motions this way reads what the body does, not whose body it is.

:func:`centre_of_mass21` places the body's centre of mass from the 21 joints with Winter's
segment masses and centres (*Biomechanics and Motor Control of Human Movement*, table 4.1:
trunk with head and neck 0.578 of the body's mass, thigh 0.100, shank 0.0465, foot 0.0145,
upper arm 0.028, forearm 0.016, hand 0.006; a limb segment's centre 0.436/0.430/0.433 of
the way from its proximal joint): a body in flight moves it along a parabola, whatever its
limbs do.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from motionlang.errors import MotionlangError
from motionlang.features.joint_map import KIT21_NAMES, KIT21_PARENTS, bone_lengths21, positions21
from motionlang.features.positions import facing_yaw, floor_height
from motionlang.features.root import to_heading
from motionlang.kinematics.motion import Motion

#: (thigh + shank + trunk chain) / stature in the MMM reference model
LEGS_TRUNK_PER_STATURE = 0.831
_BONE = {KIT21_NAMES[i]: i - 1 for i in range(1, len(KIT21_NAMES))}  # child -> bone index
_LEGS = [(_BONE["LK"], _BONE["LA"]), (_BONE["RK"], _BONE["RA"])]
_TRUNK = [_BONE[n] for n in ("BP", "BT", "BLN", "BUN")]


def _check(p21) -> np.ndarray:
    p = np.asarray(p21, dtype=float)
    if p.ndim != 3 or p.shape[1:] != (len(KIT21_NAMES), 3) or not len(p):
        raise MotionlangError(f"21-joint positions must be (T, 21, 3) with T >= 1, got "
                              f"{p.shape}")
    return p


#: (share of the body's mass, proximal joint, distal joint, centre's share of the way)
_SEGMENTS = [(0.497, "root", "BLN", 0.5), (0.081, "BUN", "BUN", 0.0)] + [
    seg for s in "LR" for seg in (
        (0.028, f"{s}S", f"{s}E", 0.436), (0.016, f"{s}E", f"{s}W", 0.430),
        (0.006, f"{s}W", f"{s}W", 0.0), (0.100, f"{s}H", f"{s}K", 0.433),
        (0.0465, f"{s}K", f"{s}A", 0.433), (0.0145, f"{s}A", f"{s}F", 0.5))]
_J = {n: i for i, n in enumerate(KIT21_NAMES)}


def centre_of_mass21(p21) -> np.ndarray:
    """(T, 21, 3) positions -> (T, 3) the centre of mass, same unit (module docstring)."""
    p = _check(p21)
    out = np.zeros((len(p), 3))
    for mass, a, b, along in _SEGMENTS:
        out += mass * (p[:, _J[a]] + along * (p[:, _J[b]] - p[:, _J[a]]))
    return out


def stature21(p21) -> float:
    """Standing height (in the unit of ``p21`` (T, 21, 3)) from the median bone lengths."""
    lengths = np.median(bone_lengths21(_check(p21)), axis=0)
    legs = np.mean([lengths[list(leg)].sum() for leg in _LEGS])
    return float((legs + lengths[_TRUNK].sum()) / LEGS_TRUNK_PER_STATURE)


def normalise21(p21, *, stature: float | None = None) -> np.ndarray:
    """(T, 21, 3) Y-up positions -> the same motion with its feet on y = 0, frame 0's root
    over the origin and facing +Z, scaled to ``stature`` (same unit) if given."""
    p = _check(p21)
    p = p - np.array([0.0, floor_height(p), 0.0])
    origin = np.array([p[0, 0, 0], 0.0, p[0, 0, 2]])
    p = to_heading(p - origin, facing_yaw(p[:1])[0])
    if stature is not None:
        if not (np.isfinite(stature) and stature > 0):
            raise MotionlangError(f"stature must be a positive number, got {stature}")
        p = p * (stature / stature21(p))
    return p


def leg_length21(lengths) -> float:
    """Mean hip-knee-ankle length of the two legs, from bone lengths (..., 20) (median over
    any leading axes)."""
    lengths = np.asarray(lengths, dtype=float).reshape(-1, len(KIT21_NAMES) - 1)
    med = np.median(lengths, axis=0)
    return float(np.mean([med[list(leg)].sum() for leg in _LEGS]))


def median_bones21(motions) -> list[float]:
    """The 20 median bone lengths (``bone_lengths21`` order, the motions' unit) over every
    frame of ``motions`` (each (T, 21, 3)): one body to lay them all on."""
    return np.median(np.concatenate([bone_lengths21(_check(p)) for p in motions]),
                     axis=0).tolist()


def uniform_bones21(p21, lengths) -> np.ndarray:
    """(T, 21, 3) positions -> the same motion with bone i (child i + 1 to its parent,
    ``bone_lengths21``' order) ``lengths[i]`` long in every frame, its direction kept (a bone
    of zero length stays at its parent). The root keeps frame 0's position; its path from
    there is scaled by ``leg_length21(lengths)`` over the motion's own median legs, so
    strides fit the new legs; the feet may then leave the floor (readers put them back,
    ``positions.floor_height``). Same unit as ``lengths`` (20,)."""
    p = _check(p21)
    lengths = np.asarray(lengths, dtype=float)
    if lengths.shape != (len(KIT21_NAMES) - 1,) or not (np.isfinite(lengths).all()
                                                        and (lengths >= 0).all()):
        raise MotionlangError(f"uniform_bones21 needs 20 finite lengths >= 0, got "
                              f"{lengths.shape}")
    own_legs = leg_length21(bone_lengths21(p))
    scale = leg_length21(lengths) / own_legs if own_legs > 0 else 1.0
    out = np.empty_like(p)
    out[:, 0] = p[0, 0] + (p[:, 0] - p[0, 0]) * scale
    for j in range(1, len(KIT21_NAMES)):      # parents come before children
        par = KIT21_PARENTS[j]
        d = p[:, j] - p[:, par]
        n = np.linalg.norm(d, axis=-1, keepdims=True)
        unit = np.divide(d, n, out=np.zeros_like(d), where=n > 1e-12)
        out[:, j] = out[:, par] + unit * lengths[j - 1]
    return out


def body21(motion: Motion, *, map_name: str | None = None,
           joint_map: dict | str | Path | None = None,
           stature: float | None = None) -> np.ndarray:
    """Any motion -> (T, 21, 3) metres: the 21 KIT joints (``positions21``, same choice of
    map) on the floor, frame 0 at the origin facing +Z, scaled to ``stature`` m if given."""
    return normalise21(positions21(motion, map_name, joint_map), stature=stature)
