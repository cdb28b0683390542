"""The MMM reference model (KIT's Master Motor Map) as a motionlang :class:`Skeleton`.

The kinematic facts (node tree, segment transforms, joint axes and limits) live in
``motionlang/data/mmm_kinematics.json``, extracted once from the Simox robot file
``mmm.xml`` that KIT motions refer to (``tests/test_mmm.py`` checks every fact against the
original XML when it is available).

Facts worth knowing about that model:

* It is normalised to a subject 1 m tall with lengths in mm, i.e. a value of 245 means
  0.245 x subject height. The leg chain (hip 0 -> knee -245 -> ankle -246 -> sole -39)
  puts the hip at 0.530 H, Winter's anthropometric proportion.
* Every body segment is a *prismatic* node whose upper joint limit is the segment's length
  (Winter's table: trunk 40 + 60 + 188 = 288, neck 22 + 30, head 130, shoulder 87 + 23 ...);
  the translation in its ``Transform`` only gives the direction (for a few trunk nodes it
  is twice the length). With the limits the model stands exactly 1000 mm tall and its own
  markers land on Winter's landmarks (acromion 818, knee 287); with the translations it
  would be 1188 mm tall with shoulders 0.42 H wide. The prismatic DOFs themselves never
  move in recorded motions and are not DOFs here.
* Source frame: Z up, the body faces +Y, its left side is -X (so the sagittal mirror is
  ``diag(-1, 1, 1)``). ``world`` maps it to motionlang's canonical frame: Y up, facing +Z,
  left +X (the BVH/CMU habit).
* ``RootRotation`` in a motion file is roll, pitch, yaw about the source X, Y, Z axes,
  composed as ``Rz(yaw) @ Ry(pitch) @ Rx(roll)`` (Simox ``rpy``). The skeleton's root
  chain is therefore ``root_axes = [z, y, x]`` and ``Motion.root_rotation`` holds
  ``(yaw, pitch, roll)`` - the file's order reversed.
"""
from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np

from motionlang.errors import SkeletonError
from motionlang.kinematics.skeleton import Joint, Skeleton

KINEMATICS_FILE = Path(__file__).resolve().parents[1] / "data" / "mmm_kinematics.json"

#: The 44 joint DOFs of a KIT-ML motion file, in the files' ``<JointOrder>`` order.
MMM_DOF_ORDER: tuple[str, ...] = (
    "BLNx_joint", "BLNy_joint", "BLNz_joint", "BPx_joint", "BPy_joint", "BPz_joint",
    "BTx_joint", "BTy_joint", "BTz_joint", "BUNx_joint", "BUNy_joint", "BUNz_joint",
    "LAx_joint", "LAy_joint", "LAz_joint", "LEx_joint", "LEz_joint", "LHx_joint",
    "LHy_joint", "LHz_joint", "LKx_joint", "LSx_joint", "LSy_joint", "LSz_joint",
    "LWx_joint", "LWy_joint", "LFx_joint", "LMrot_joint",
    "RAx_joint", "RAy_joint", "RAz_joint", "REx_joint", "REz_joint", "RHx_joint",
    "RHy_joint", "RHz_joint", "RKx_joint", "RSx_joint", "RSy_joint", "RSz_joint",
    "RWx_joint", "RWy_joint", "RFx_joint", "RMrot_joint",
)

#: Model length (mm of a 1 m subject) of the thigh; used to recover a skeleton's height.
THIGH_MM = 245.0
#: Source frame (Z up, facing +Y, left -X) -> canonical (Y up, facing +Z, left +X).
MMM_WORLD = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, 1.0, 0.0]])
#: Root orientation chain: yaw about Z, then pitch about Y, then roll about X.
MMM_ROOT_AXES = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
MMM_MIRROR = np.diag([-1.0, 1.0, 1.0])


@functools.lru_cache(maxsize=1)
def mmm_kinematics() -> dict:
    """The project's copy of the model facts (parsed JSON; treat as read-only)."""
    with open(KINEMATICS_FILE, encoding="utf-8") as fh:
        return json.load(fh)


def _node_offset_mm(node: dict) -> np.ndarray:
    """(3,) offset of a node from its parent, mm of a 1 m subject (see module docstring)."""
    t = np.asarray(node.get("translation", (0.0, 0.0, 0.0)), dtype=float)
    if node["type"] == "prismatic" and np.linalg.norm(t) > 0:
        return t / np.linalg.norm(t) * float(node["limits"][1])
    return t


@functools.lru_cache(maxsize=64)
def _skeleton_parts(height_m: float) -> tuple:
    facts = mmm_kinematics()
    dofs = set(MMM_DOF_ORDER)
    scale = height_m / 1000.0  # mm of a 1 m model -> metres for this subject
    joints: list[Joint] = []
    index: dict[str, int] = {}
    for node in facts["nodes"]:
        name, parent = node["name"], node["parent"]
        has_dof = node["type"] == "revolute" and name in dofs
        fixed_identity = ("translation" not in node and "rotation" not in node)
        if parent is not None and not has_dof and fixed_identity:
            # A revolute node outside the 44 recorded DOFs (clavicles) with no transform
            # is the identity forever: fold it into its parent.
            index[name] = index[parent]
            continue
        joints.append(Joint(
            name=name,
            parent=-1 if parent is None else index[parent],
            offset=_node_offset_mm(node) * scale,
            axes=[node["axis"]] if has_dof else np.zeros((0, 3)),
            pre=node.get("rotation", np.eye(3)),
            dof_names=(name,) if has_dof else (),
        ))
        index[name] = len(joints) - 1
    return tuple(joints)


def mmm_skeleton(height_m: float = 1.75) -> Skeleton:
    """The MMM reference model scaled to a subject ``height_m`` metres tall.

    Joints: the root, every body segment (prismatic nodes, as fixed offsets) and every
    revolute node of the 44 recorded DOFs (``MMM_DOF_ORDER``, one axis each), in the
    model's tree order; fingers and the fixed clavicle rotations are left out.
    ``file_unit`` is 0.001 (motion files are in mm).
    """
    height_m = float(height_m)
    if not (np.isfinite(height_m) and height_m > 0):
        raise SkeletonError(f"MMM subject height must be positive, got {height_m}")
    joints = [Joint(j.name, j.parent, j.offset.copy(), j.axes.copy(), j.pre.copy(),
                    j.post.copy(), j.dof_names) for j in _skeleton_parts(height_m)]
    names = {j.name for j in joints}
    pairs = []
    for n in (j.name for j in joints):
        # "LKx_joint" <-> "RKx_joint", "LeftHandSegment_joint" <-> "RightHandSegment_joint"
        for left, right in (("Left", "Right"), ("L", "R")):
            rest = n[len(left):]
            if n.startswith(left) and rest[:1].isupper():
                if right + rest in names:
                    pairs.append((n, right + rest))
                break
    return Skeleton(joints, world=MMM_WORLD.copy(), root_axes=MMM_ROOT_AXES.copy(),
                    file_unit=0.001, name="mmm", mirror=MMM_MIRROR.copy(), pairs=pairs)


def mmm_height(skeleton: Skeleton) -> float:
    """Subject height (m) of an MMM skeleton, recovered from its thigh length."""
    if skeleton.name != "mmm" or "LKsegment_joint" not in skeleton:
        raise SkeletonError(f"skeleton {skeleton.name!r} is not an MMM skeleton")
    thigh = np.linalg.norm(skeleton.joints[skeleton.index("LKsegment_joint")].offset)
    return float(thigh / (THIGH_MM / 1000.0))
