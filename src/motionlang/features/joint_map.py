"""The 21-joint KIT layout and named maps onto it from MMM, CMU-ASF and BVH skeletons.

The 21 joints are the ones the processed KIT-ML position data of later work (language2pose,
Ghosh et al. 2021, HumanML3D's ``kit``) uses, named after the MMM segments, in this order::

     0 root   MMM root (pelvis, at hip-joint height)       11 LH     left hip
     1 BP     pelvis/lumbar joint (BPSegment)              12 LK     left knee
     2 BT     thorax/lower-spine joint (BTSegment)         13 LA     left ankle
     3 BLN    lower neck (C7, BLNsegment)                  14 LMrot  left mid-foot (metatarsal)
     4 BUN    upper neck / head base (BUNsegment)          15 LF     left toe joint
     5 LS  6 LE  7 LW   left shoulder, elbow, wrist        16-20  RH RK RA RMrot RF (right leg)
     8 RS  9 RE 10 RW   right shoulder, elbow, wrist

Left means the subject's left (MMM's ``L*`` nodes, CMU's ``l*`` bones, BVH ``Left*``).
Tree: root-BP-BT-BLN-BUN; BLN-shoulders-elbows-wrists; root-hips-knees-ankles-midfoot-toes.

A map entry is a node name, ``("mid", a, b)`` (midpoint of two nodes) or
``("lerp", a, b, t)`` (``(1-t) a + t b``). Synthetic points are needed where the source
skeleton has no node: CMU and BVH roots sit above the hips, so ``root`` is the midpoint of
the two hip joints (the MMM root lies on that line); CMU has no mid-foot joint, so ``LMrot``
is put 40 % of the way from ankle to toe base (the MMM proportion, 31 of 82 mm/m). Names
are matched case-insensitively after dropping a ``namespace:`` prefix (``mixamorig:Hips``).

Limb bones of CMU subject 35 and KIT 00001 agree within 20 % after scaling by stature; the
four trunk bones do not, whatever CMU spine nodes are chosen (MMM puts the lumbar joint BP
0.04 H above the hip line, CMU's nearest spine nodes are at 0 and 0.066 H), so only the whole
root-to-head-base chain is comparable (``tests/test_joint_map.py`` checks both facts).
"""
from __future__ import annotations

from typing import Union

import numpy as np

from motionlang.errors import SkeletonError
from motionlang.kinematics.motion import Motion
from motionlang.kinematics.skeleton import Skeleton

KIT21_NAMES: tuple[str, ...] = (
    "root", "BP", "BT", "BLN", "BUN", "LS", "LE", "LW", "RS", "RE", "RW",
    "LH", "LK", "LA", "LMrot", "LF", "RH", "RK", "RA", "RMrot", "RF")
#: parent index of each of the 21 joints (-1 for the root); bones are (i, KIT21_PARENTS[i]).
KIT21_PARENTS: tuple[int, ...] = (
    -1, 0, 1, 2, 3, 3, 5, 6, 3, 8, 9, 0, 11, 12, 13, 14, 0, 16, 17, 18, 19)
#: left/right partner of each joint (itself on the midline), for mirroring positions.
KIT21_MIRROR: tuple[int, ...] = tuple(
    KIT21_NAMES.index(("R" + n[1:]) if n[0] == "L" else ("L" + n[1:]) if n[0] == "R" else n)
    for n in KIT21_NAMES)

Spec = Union[str, tuple]


def _sided(table: dict[str, Spec], left: str, right: str) -> dict[str, Spec]:
    """Expand entries written for the left side ("L*") into both sides."""
    out = {}
    for k, v in table.items():
        if not k.startswith("L"):
            out[k] = v
            continue
        for side, pre in (("L", left), ("R", right)):
            out[side + k[1:]] = (tuple(x.format(s=pre) if isinstance(x, str) else x for x in v)
                                 if isinstance(v, tuple) else v.format(s=pre))
    return out


_MMM = _sided({
    "root": "root_joint", "BP": "BPSegment_joint", "BT": "BTSegment_joint",
    "BLN": "BLNsegment_joint", "BUN": "BUNsegment_joint",
    "LS": "{s}Ssegment_joint", "LE": "{s}Esegment_joint", "LW": "{s}Wsegment_joint",
    "LH": "{s}Hsegment_joint", "LK": "{s}Ksegment_joint", "LA": "{s}Asegment_joint",
    "LMrot": "{s}Mrot_joint", "LF": "{s}Fx_joint"}, "L", "R")

# CMU ASF: a node sits at its bone's start, e.g. "ltibia" is the knee.
_CMU_ASF = _sided({
    "root": ("mid", "lfemur", "rfemur"), "BP": "lowerback", "BT": "upperback",
    "BLN": "lowerneck", "BUN": "head",
    "LS": "{s}humerus", "LE": "{s}radius", "LW": "{s}wrist",
    "LH": "{s}femur", "LK": "{s}tibia", "LA": "{s}foot",
    "LMrot": ("lerp", "{s}foot", "{s}toes", 0.4), "LF": "{s}toes"}, "l", "r")

_BVH_LIMBS = {
    "root": ("mid", "LeftUpLeg", "RightUpLeg"),
    "LS": "{s}Arm", "LE": "{s}ForeArm", "LW": "{s}Hand",
    "LH": "{s}UpLeg", "LK": "{s}Leg", "LA": "{s}Foot",
    "LMrot": ("lerp", "{s}Foot", "{s}ToeBase", 0.4), "LF": "{s}ToeBase"}
# CMU converted to BVH: Hips, LowerBack (= CMU lowerback), Spine (upperback), Spine1, Neck...
_CMU_BVH = _sided({**_BVH_LIMBS, "BP": "LowerBack", "BT": "Spine", "BLN": "Neck",
                   "BUN": "Head"}, "Left", "Right")
# Mixamo and similar: Hips, Spine, Spine1, Spine2, Neck, Head.
_MIXAMO_BVH = _sided({**_BVH_LIMBS, "BP": "Spine", "BT": "Spine1", "BLN": "Neck",
                      "BUN": "Head"}, "Left", "Right")

#: named maps, tried in this order.
JOINT_MAPS: dict[str, dict[str, Spec]] = {
    "mmm": _MMM, "cmu-asf": _CMU_ASF, "cmu-bvh": _CMU_BVH, "bvh": _MIXAMO_BVH}


def _key(name: str) -> str:
    return name.rsplit(":", 1)[-1].lower()


def _resolve(skeleton: Skeleton, table: dict[str, Spec]
             ) -> tuple[np.ndarray | None, list[str]]:
    """-> weight matrix (21, J) or None, and the list of missing source names."""
    index = {}
    for i, n in enumerate(skeleton.names):
        index.setdefault(_key(n), i)
    W = np.zeros((len(KIT21_NAMES), len(skeleton)))
    missing = []
    for k, name in enumerate(KIT21_NAMES):
        spec = table[name]
        if isinstance(spec, str):
            parts = [(spec, 1.0)]
        elif spec[0] == "mid":
            parts = [(spec[1], 0.5), (spec[2], 0.5)]
        else:  # ("lerp", a, b, t)
            parts = [(spec[1], 1.0 - spec[3]), (spec[2], spec[3])]
        for src, w in parts:
            j = index.get(_key(src))
            if j is None:
                missing.append(src)
            else:
                W[k, j] += w
    return (None if missing else W), missing


def kit21_weights(skeleton: Skeleton, map_name: str | None = None) -> tuple[str, np.ndarray]:
    """Pick the joint map for a skeleton.

    Returns:
        (map name, W (21, J)) with ``positions21 = W @ positions`` per frame.

    Raises:
        SkeletonError: no map fits; names the source joints the closest map misses.
    """
    names = [map_name] if map_name else list(JOINT_MAPS)
    best = None
    for name in names:
        if name not in JOINT_MAPS:
            raise SkeletonError(f"unknown joint map {name!r}; known: {sorted(JOINT_MAPS)}")
        W, missing = _resolve(skeleton, JOINT_MAPS[name])
        if W is not None:
            return name, W
        if best is None or len(missing) < len(best[1]):
            best = (name, missing)
    raise SkeletonError(f"skeleton {skeleton.name!r} cannot be mapped to the 21 KIT joints: "
                        f"closest map {best[0]!r} lacks joints {sorted(set(best[1]))}")


def positions21(motion: Motion, map_name: str | None = None) -> np.ndarray:
    """(T, 21, 3) metres, canonical frame (Y up), of the KIT joints ``KIT21_NAMES``.

    Works for MMM, CMU-ASF and BVH (CMU-converted or Mixamo naming) skeletons; the map is
    chosen from the joint names unless ``map_name`` (a key of ``JOINT_MAPS``) is given.

    Raises:
        SkeletonError: the skeleton lacks joints every map needs.
    """
    _, W = kit21_weights(motion.skeleton, map_name)
    return np.einsum("kj,tjc->tkc", W, motion.positions())


def bone_lengths21(pos21: np.ndarray) -> np.ndarray:
    """pos21 (..., 21, 3) -> (..., 20) lengths of the bones (i, parent(i)), i = 1..20."""
    child = np.arange(1, len(KIT21_NAMES))
    parent = np.array(KIT21_PARENTS[1:])
    return np.linalg.norm(pos21[..., child, :] - pos21[..., parent, :], axis=-1)
