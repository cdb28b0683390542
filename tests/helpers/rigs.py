"""Hand-written rigs in the naming, unit and axis conventions of each built-in joint map,
posed standing and walking a few steps, written as small BVH files (or SMPL joint arrays).

A rig is a joint tree (``parse``) laid out standing, in the rig's own unit, in canonical
axes (x = the subject's left, y up, z forward); ``forward`` turns the whole rig to its own
facing axis. Offsets of the CMU conversions (cgspeed,
subjects 35 and 131) and of the DAZ-friendly rig are those of the public files; Bandai
Namco's are that rig's, rounded; SMPL's limbs are close to its template's joints; the others
are round human proportions in the vendor's naming and unit (Second Life: metres for its
own skeleton, inches for BVH uploads). ``along_x`` rigs (Bandai Namco; the LAFAN1-style
generic one) rest with every bone along its joint's local x axis (-x on the right side), so
their rest pose is not a standing pose at all. Bandai Namco's root stays on the floor and its
``Hips`` carry the walk in their position channels, as in the real files.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from motionlang.kinematics.rotations import AXES, axis_angle, matrix_to_chain

FORWARD = {"+z": np.eye(3), "-z": np.diag([-1.0, 1.0, -1.0]),
           "+x": np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])}


@dataclass
class Rig:
    map: str                        # the built-in map that should be chosen
    unit: float                     # metres per file unit
    tree: str                       # indented "name x y z" lines (see ``parse``)
    hips: tuple[str, str]           # left and right thigh joints (swung to walk)
    knees: tuple[str, str]
    arms: tuple[str, str]           # left and right upper-arm joints
    arms_down: float = 0.0          # degrees that lower T-pose arms (0: they hang at rest)
    legs_in: float = 0.0            # degrees that close a spread rest stance (CMU)
    forward: str = "+z"
    along_x: bool = False
    all_positions: bool = False     # position channels on every joint (Bandai Namco)
    root_on_floor: bool = False     # the root node is a floor node below the pelvis
    pelvis_moves: bool = False      # the root's child, not the root, carries the walk
    order: str = "ZXY"


def _side(name: str) -> float:
    """-1 for a right-side joint of the ``along_x`` rigs (their bones point along -x)."""
    return -1.0 if name.endswith("_R") or name.startswith("Right") else 1.0


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Smallest rotation taking unit a to unit b (a half turn about y if opposite)."""
    v, c = np.cross(a, b), float(a @ b)
    if np.linalg.norm(v) < 1e-9:
        return np.eye(3) if c > 0 else axis_angle(AXES["y"], np.pi)
    return axis_angle(v / np.linalg.norm(v), np.arctan2(np.linalg.norm(v), c))


SIDES = {"s": ("L", "R"), "side": ("Left", "Right"), "l": ("l", "r"),
         "lower": ("left", "right")}


def parse(tree: str) -> tuple[list[str], list[int], np.ndarray]:
    """Indented lines ``name x y z`` (two spaces per level; ``*`` an End Site) -> names,
    parent indices, offsets. A line whose name holds ``{s}``, ``{side}``, ``{l}`` or
    ``{lower}`` stands, with its subtree, for the left side as written and for the right
    side mirrored (x -> -x)."""
    rows = []
    for line in tree.strip("\n").splitlines():
        depth = (len(line) - len(line.lstrip())) // 2
        name, *xyz = line.split()
        rows.append((depth, name, np.array(xyz, dtype=float)))
    names, parents, offsets = [], [], []

    def add(i: int, parent: int, side: int | None) -> int:
        """Add row i (and its subtree) under ``parent``; -> index of the next sibling row."""
        depth, name, off = rows[i]
        end = next((k for k in range(i + 1, len(rows)) if rows[k][0] <= depth), len(rows))
        sides = [side] if side is not None or "{" not in name else [0, 1]
        for sd in sides:
            names.append(name.format(**{k: v[sd] for k, v in SIDES.items()})
                         if sd is not None else name)
            parents.append(parent)
            offsets.append(off * ([-1.0, 1.0, 1.0] if sd == 1 else 1.0))
            me, k = len(names) - 1, i + 1
            while k < end:
                k = add(k, me, sd)
        return end

    add(0, -1, None)
    return names, parents, np.array(offsets)


def _tree(rig: Rig):
    return parse(rig.tree)


def pose(rig: Rig, T: int, fps: float = 30.0, yaw0: float = 35.0, floor: float = 0.05):
    """World-aligned local rotations A (T, J, 3, 3) and root position (T, 3), canonical
    axes, rig units: a walk of T frames (one stride cycle), heading from ``yaw0`` degrees
    turning 10 degrees, floor ``floor`` metres above y = 0."""
    names, parents, off = _tree(rig)
    glob = off.copy()
    for j, p in enumerate(parents):
        glob[j] = off[j] + (glob[p] if p >= 0 else 0.0)
    ph = 2 * np.pi * np.arange(T) / T
    A = np.broadcast_to(np.eye(3), (T, len(names), 3, 3)).copy()
    x, z = AXES["x"], AXES["z"]
    for s, (hip, knee, arm) in enumerate(zip(rig.hips, rig.knees, rig.arms)):
        sign = 1.0 if s == 0 else -1.0          # left, right
        swing = np.deg2rad(25.0) * np.sin(ph) * sign
        A[:, names.index(hip)] = axis_angle(x, -swing) @ axis_angle(z, -sign * np.deg2rad(
            rig.legs_in))
        A[:, names.index(knee)] = axis_angle(x, np.deg2rad(30.0) * (1 - np.cos(ph + s * np.pi))
                                             / 2)
        A[:, names.index(arm)] = axis_angle(x, 0.6 * swing) @ axis_angle(
            z, -sign * np.deg2rad(rig.arms_down))
    yaw = np.deg2rad(yaw0 + 10.0 * np.arange(T) / T)
    A[:, 0] = axis_angle(AXES["y"], yaw)
    step = 1.2 / fps / rig.unit
    height = floor / rig.unit - (0.0 if rig.root_on_floor else glob[:, 1].min())
    root = np.stack([0.3 / rig.unit + step * np.cumsum(np.sin(yaw)),
                     np.full(T, height), -0.2 / rig.unit + step * np.cumsum(np.cos(yaw))], 1)
    return A, root


def positions(rig: Rig, T: int = 16, **kw) -> np.ndarray:
    """(T, J, 3) joint positions of the walk, rig units, in the rig's own axes."""
    names, parents, off = _tree(rig)
    A, root = pose(rig, T, **kw)
    W = np.empty_like(A)
    x = np.empty((T, len(names), 3))
    for j, p in enumerate(parents):
        W[:, j] = A[:, j] if p < 0 else W[:, p] @ A[:, j]
        x[:, j] = root if p < 0 else x[:, p] + W[:, p] @ off[j]
    return x @ FORWARD[rig.forward].T


def _fmt(v) -> str:
    return " ".join(f"{float(a):.6f}" for a in v)


def bvh_text(rig: Rig, T: int = 16, fps: float = 30.0, **kw) -> str:
    """The walk as BVH text in the rig's conventions."""
    names, parents, off = _tree(rig)
    M = FORWARD[rig.forward]
    A, root = pose(rig, T, fps=fps, **kw)
    kids = [[c for c, p in enumerate(parents) if p == j] for j in range(len(names))]
    Q = [np.eye(3)] * len(names)  # rest frame of each joint, in the rig's axes
    if rig.along_x:
        for j in range(1, len(names)):
            d = M @ off[kids[j][0]] if kids[j] else np.zeros(3)
            Q[j] = _align(_side(names[j]) * AXES["x"], d / np.linalg.norm(d)) \
                if np.linalg.norm(d) > 1e-9 else Q[parents[j]]
    axes = np.stack([AXES[c.lower()] for c in rig.order])
    rot = " ".join(f"{c}rotation" for c in rig.order)
    lines, cols = ["HIERARCHY"], []

    def emit(j: int, depth: int) -> None:
        ind, p = "  " * depth, parents[j]
        o = np.zeros(3) if p < 0 else Q[p].T @ M @ off[j]
        if names[j] == "*":
            lines.extend([f"{ind}End Site", f"{ind}{{", f"{ind}  OFFSET {_fmt(o)}",
                          f"{ind}}}"])
            return
        lines.extend([f"{ind}{'ROOT' if p < 0 else 'JOINT'} {names[j]}", f"{ind}{{",
                      f"{ind}  OFFSET {_fmt(o)}"])
        B = M @ A[:, j] @ M.T
        R = B @ Q[j] if p < 0 else Q[p].T @ B @ Q[j]
        pos = root @ M.T if p < 0 else np.broadcast_to(o, (T, 3))
        if rig.pelvis_moves and p < 0:  # a still root; its child takes the walk
            R, pos = np.broadcast_to(np.eye(3), R.shape), np.zeros((T, 3))
        elif rig.pelvis_moves and p == 0:
            B0 = M @ A[:, 0] @ M.T
            R, pos = B0 @ B @ Q[j], root @ M.T + np.einsum("tij,j->ti", B0, M @ off[j])
        if p < 0 or rig.all_positions:
            lines.append(f"{ind}  CHANNELS 6 Xposition Yposition Zposition {rot}")
            cols.append(pos)
        else:
            lines.append(f"{ind}  CHANNELS 3 {rot}")
        cols.append(np.rad2deg(matrix_to_chain(R, axes)))
        for c in kids[j]:
            emit(c, depth + 1)
        lines.append(f"{ind}}}")

    emit(0, 0)
    data = np.concatenate(cols, axis=1)
    lines += ["MOTION", f"Frames: {T}", f"Frame Time: {1.0 / fps:.8f}"]
    lines += [_fmt(row) for row in data]
    return "\n".join(lines) + "\n"


def write(rig: Rig, folder: Path, name: str | None = None, **kw) -> Path:
    path = Path(folder) / f"{name or rig.map}.bvh"
    path.write_text(bvh_text(rig, **kw))
    return path




RIGS: dict[str, Rig] = {r.map: r for r in [
    Rig("cmu-bvh", 0.0254 / 0.45, """
Hips 0 0 0
  {s}HipJoint 0 0 0
    {side}UpLeg 1.778 -1.890 0.483
      {side}Leg 2.534 -6.963 0
        {side}Foot 2.711 -7.448 0
          {side}ToeBase 0.180 -0.494 2.225
            * 0 0 1.147
  LowerBack 0 0 0
    Spine 0.034 2.016 -0.222
      Spine1 0.035 2.030 0.009
        Neck 0 0 0
          Neck1 -0.002 1.705 0.209
            Head 0.025 1.723 -0.222
              * 0.003 1.741 -0.098
        {side}Shoulder 0 0 0
          {side}Arm 3.364 1.005 -0.377
            {side}ForeArm 5.065 0 0
              {side}Hand 3.602 0 0
                * 0.8 0 0
""", ("LeftUpLeg", "RightUpLeg"), ("LeftLeg", "RightLeg"), ("LeftArm", "RightArm"),
        arms_down=75, legs_in=20, order="ZYX"),
    Rig("cmu-bvh-max", 0.0254 / 0.45, """
Hips 0 0 0
  {s}HipJoint 0 0 0
    {side}Hip 1.248 -1.643 0.717
      {side}Knee 2.493 -6.850 0
        {side}Ankle 2.368 -6.505 0
          {side}Toe 0.148 -0.407 2.214
            * 0 0 1.135
  lowerback 0 0 0
    Chest -0.023 1.987 0.003
      Chest2 -0.007 1.990 -0.005
        lowerneck 0 0 0
          Neck 0.001 1.610 0.107
            Head -0.011 1.599 0.013
              * -0.005 1.633 -0.006
        {side}Collar 0 0 0
          {side}Shoulder 3.054 1.471 -0.017
            {side}Elbow 0 -4.251 0
              {side}Wrist 0 -3.276 0
                {l}hand 0 0 0
                  * 0 -0.658 0
""", ("LeftHip", "RightHip"), ("LeftKnee", "RightKnee"), ("LeftShoulder", "RightShoulder"),
        legs_in=20, order="ZYX"),
    Rig("cmu-bvh-daz", 0.01, """
hip 0 0 0
  abdomen 0 20.69 -0.73
    chest 0 11.70 -0.49
      neck 0 22.19 -2.19
        head -0.24 7.07 1.22
          * 0 10 0
      {l}Collar 2.68 19.26 -4.88
        {l}Shldr 8.78 -1.95 1.46
          {l}ForeArm 28.17 -1.71 0.49
            {l}Hand 22.59 0.77 7.07
              * 8 0 0
  {l}Buttock 8.78 4.35 1.22
    {l}Thigh 0 -1.71 -2.19
      {l}Shin 0 -36.82 0.73
        {l}Foot -0.73 -45.11 -5.12
          * 1.12 -3.70 12.10
""", ("lThigh", "rThigh"), ("lShin", "rShin"), ("lShldr", "rShldr"), arms_down=75),
    Rig("bandai", 0.01, """
joint_Root 0 0 0
  Hips 0 94 0
    Spine 0 15.7 0
      Chest 0 9.0 0
        Neck 0 16.4 0
          Head 0 6.5 0
            * 0 0 0
        Shoulder_{s} 5.0 13.0 0
          UpperArm_{s} 5.3 0 0
            LowerArm_{s} 0 -24.3 0
              Hand_{s} 0 -22.3 0
                * 0 0 0
    UpperLeg_{s} 6.5 -2.2 0
      LowerLeg_{s} 0 -39.1 0
        Foot_{s} 0 -41.0 0
          Toes_{s} 0 -7.5 9.0
            * 0 0 0
""", ("UpperLeg_L", "UpperLeg_R"), ("LowerLeg_L", "LowerLeg_R"), ("UpperArm_L", "UpperArm_R"),
        along_x=True, all_positions=True, root_on_floor=True, pelvis_moves=True),
    Rig("cc", 0.01, """
CC_Base_BoneRoot 0 0 0
  CC_Base_Hip 0 97 0
    CC_Base_Pelvis 0 0 0
      CC_Base_{s}_Thigh 9.0 -4.0 0
        CC_Base_{s}_Calf 0 -43.5 0
          CC_Base_{s}_Foot 0 -42.0 0
            CC_Base_{s}_ToeBase 0 -6.5 12.5
              * 0 0 4
    CC_Base_Waist 0 6 0
      CC_Base_Spine01 0 9 0
        CC_Base_Spine02 0 13 0
          CC_Base_NeckTwist01 0 20 0
            CC_Base_NeckTwist02 0 4 0
              CC_Base_Head 0 5 0
                * 0 18 0
          CC_Base_{s}_Clavicle 3 16 0
            CC_Base_{s}_Upperarm 14 0 0
              CC_Base_{s}_Forearm 27 0 0
                CC_Base_{s}_Hand 24 0 0
                  * 8 0 0
""", ("CC_Base_L_Thigh", "CC_Base_R_Thigh"), ("CC_Base_L_Calf", "CC_Base_R_Calf"),
        ("CC_Base_L_Upperarm", "CC_Base_R_Upperarm"), arms_down=75, forward="-z",
        root_on_floor=True),
    Rig("second-life", 1.0, """
mPelvis 0 0 0
  mTorso 0 0.084 0
    mChest 0 0.205 -0.015
      mNeck 0 0.251 -0.010
        mHead 0 0.076 0
          * 0 0.1 0
      mCollar{side} 0.085 0.165 -0.021
        mShoulder{side} 0.079 0 0
          mElbow{side} 0.30 0 0
            mWrist{side} 0.25 0 0
              * 0.1 0 0
  mHip{side} 0.09 -0.041 0.034
    mKnee{side} 0 -0.44 0
      mAnkle{side} 0 -0.43 -0.03
        mFoot{side} 0 -0.07 0.13
          mToe{side} 0 0 0.06
            * 0 0 0.02
""", ("mHipLeft", "mHipRight"), ("mKneeLeft", "mKneeRight"),
        ("mShoulderLeft", "mShoulderRight"), arms_down=75, forward="+x"),
    Rig("poser", 0.0254, """
hip 0 0 0
  abdomen 0 3.3 0
    chest 0 8.1 -0.6
      neck 0 9.9 -0.4
        head 0 3.0 0
          * 0 4 0
      {l}Collar 3.3 6.5 -0.8
        {l}Shldr 3.1 0 0
          {l}ForeArm 11.8 0 0
            {l}Hand 9.8 0 0
              * 4 0 0
  {l}Thigh 3.5 -1.6 1.3
    {l}Shin 0 -17.3 0
      {l}Foot 0 -16.9 -1.1
        * 0 -2.8 5.1
""", ("lThigh", "rThigh"), ("lShin", "rShin"), ("lShldr", "rShldr"), arms_down=75),
    Rig("smpl", 1.0, """
pelvis 0 0 0
  {lower}_hip 0.0713 -0.0907 -0.0043
    {lower}_knee 0.0343 -0.3732 0.0079
      {lower}_ankle -0.0164 -0.4002 -0.0467
        {lower}_foot 0.0329 -0.0562 0.1363
          * 0 0 0.03
  spine1 0 0.114 -0.03
    spine2 0 0.138 0.015
      spine3 0 0.052 0.025
        neck 0 0.21 -0.05
          head 0 0.066 0.048
            * 0 0.1 0
        {lower}_collar 0.073 0.11 -0.04
          {lower}_shoulder 0.093 0.046 -0.014
            {lower}_elbow 0.261 -0.017 -0.025
              {lower}_wrist 0.259 0.012 -0.007
                * 0.08 0 0
""", ("left_hip", "right_hip"), ("left_knee", "right_knee"),
        ("left_shoulder", "right_shoulder"), arms_down=75),
    Rig("mixamo", 0.01, """
mixamorig:Hips 0 0 0
  mixamorig:Spine 0 9.9 1.0
    mixamorig:Spine1 0 11.7 0
      mixamorig:Spine2 0 13.4 0
        mixamorig:Neck 0 15.0 0
          mixamorig:Head 0 10.3 0
            mixamorig:HeadTop_End 0 18.5 0
              * 0 0 0
        mixamorig:{side}Shoulder 6.1 9.1 0
          mixamorig:{side}Arm 12.9 0 0
            mixamorig:{side}ForeArm 27.4 0 0
              mixamorig:{side}Hand 27.7 0 0
                * 8 0 0
  mixamorig:{side}UpLeg 9.1 -6.7 0
    mixamorig:{side}Leg 0 -44.5 0
      mixamorig:{side}Foot 0 -44.4 0
        mixamorig:{side}ToeBase 0 -8.7 10.6
          mixamorig:{side}Toe_End 0 0 8.0
            * 0 0 0
""", ("mixamorig:LeftUpLeg", "mixamorig:RightUpLeg"),
        ("mixamorig:LeftLeg", "mixamorig:RightLeg"), ("mixamorig:LeftArm", "mixamorig:RightArm"),
        arms_down=75),
    Rig("bvh", 0.01, """
Hips 0 0 0
  {side}UpLeg 10.5 -1.9 0
    {side}Leg 0 -43.5 0
      {side}Foot 0 -42.4 0
        {side}Toe 0 -7.0 12.0
          * 0 0 5
  Spine 0 6.9 -0.1
    Spine1 0 12.6 0
      Spine2 0 12.6 0
        Neck 0 16.8 0
          Head 0 9.6 0
            * 0 10 0
        {side}Shoulder 4.0 11.0 0
          {side}Arm 13.5 0 0
            {side}ForeArm 0 -28.4 0
              {side}Hand 0 -24.4 0
                * 0 -8 0
""", ("LeftUpLeg", "RightUpLeg"), ("LeftLeg", "RightLeg"), ("LeftArm", "RightArm"),
        along_x=True, order="ZYX"),
    Rig("biped", 0.01, """
Hips 0 0 0
  {side}Hip 9.5 0 0
    {side}Knee 0 -44 0
      {side}Ankle 0 -42 0
        {side}Toe 0 -6.5 13
          * 0 0 5
  Chest 0 10 0
    Chest2 0 11 0
      Chest3 0 10 0
        Chest4 0 10 0
          Neck 0 14 0
            Head 0 9.3 0
              * 0 17 0
          {side}Collar 3 9 0
            {side}Shoulder 14.5 0 0
              {side}Elbow 28 0 0
                {side}Wrist 24 0 0
                  * 8 0 0
""", ("LeftHip", "RightHip"), ("LeftKnee", "RightKnee"), ("LeftShoulder", "RightShoulder"),
        arms_down=75),
]}
