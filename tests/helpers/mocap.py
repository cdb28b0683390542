"""Small motions and motion files made by hand: the tiny 8-joint skeleton, an ASF/AMC pair,
a BVH with unusual channel orders, a smooth synthetic MMM motion, a walker, and a rigid turn."""
from __future__ import annotations

import numpy as np

from motionlang.features import root as rootlib
from motionlang.formats.mmm_model import mmm_skeleton
from motionlang.kinematics import Joint, Motion, Skeleton
from motionlang.kinematics.rotations import chain, matrix_to_chain


def tiny_skeleton() -> Skeleton:
    """Hips with two 2-link legs (1 m thigh along -y, knee about x) and a spine."""
    S = np.diag([-1.0, 1.0, 1.0])
    x, y, z = np.eye(3)
    joints = [
        Joint("Hips", -1, [0, 0, 0]),
        Joint("LeftUpLeg", 0, [0.1, 0, 0], axes=[z, x, y]),
        Joint("LeftLeg", 1, [0, -1.0, 0], axes=[x]),
        Joint("LeftFoot", 2, [0, -1.0, 0]),
        Joint("RightUpLeg", 0, [-0.1, 0, 0], axes=[z, x, y]),
        Joint("RightLeg", 4, [0, -1.0, 0], axes=[x]),
        Joint("RightFoot", 5, [0, -1.0, 0]),
        Joint("Spine", 0, [0, 0.5, 0], axes=[z, x, y]),
    ]
    return Skeleton(joints, name="tiny", mirror=S)


def walker(T=45, fps=30.0, speed=1.2) -> Motion:
    """Tiny skeleton swinging its legs while its root moves along +Z (its facing side)."""
    sk = tiny_skeleton()
    t = np.arange(T) / fps
    ph = 2 * np.pi * t
    ang = np.zeros((T, sk.ndof))
    ang[:, sk.dof_slice("LeftUpLeg").start + 1] = -0.4 * np.sin(ph)
    ang[:, sk.dof_slice("RightUpLeg").start + 1] = 0.4 * np.sin(ph)
    root = np.stack([np.zeros(T), 2.0 + 0.02 * np.cos(2 * ph), speed * t], axis=1)
    return Motion(sk, fps, root, np.zeros((T, 3)), ang, name="walker")


def synthetic_mmm(T=201, fps=100.0, seed=0, height=1.75) -> Motion:
    """A smooth MMM motion: the root walks a curve (Z-up source frame), joints swing."""
    sk = mmm_skeleton(height)
    rng = np.random.default_rng(seed)
    t = np.arange(T) / fps
    yaw = 0.3 + 0.4 * t                                       # turning left slowly
    step = 1.2 / fps * np.stack([np.cos(yaw), np.sin(yaw)], 1)  # source x/y ground plane
    xy = np.cumsum(step, 0) + [0.4, -0.7]
    trans = np.column_stack([xy, 0.95 + 0.02 * np.sin(2 * np.pi * 2 * t)])
    rot = np.column_stack([yaw, 0.05 * np.sin(2 * np.pi * t), 0.03 * np.cos(3 * t)])
    phase = rng.uniform(0, 2 * np.pi, sk.ndof)
    amp = rng.uniform(0.05, 0.4, sk.ndof)
    angles = amp * np.sin(2 * np.pi * 1.5 * t[:, None] + phase)
    return Motion(sk, fps, trans, rot, angles, name="synthetic", source_format="mmm",
                  meta={"height": height})


def turn(motion: Motion, theta: float, dx: float, dz: float) -> Motion:
    """The same motion rotated by ``theta`` about the vertical and shifted (dx, 0, dz) on the
    ground, as a rigid motion of the whole body (canonical frame)."""
    sk = motion.skeleton
    W, Ry = sk.world, rootlib.rot_y(theta)
    o = sk.joints[0].offset
    p = (motion.root_translation + o) @ W.T @ Ry.T + [dx, 0.0, dz]
    R = W.T @ Ry @ W @ chain(sk.root_axes, motion.root_rotation)
    return motion.replace(root_translation=p @ W - o,
                          root_rotation=matrix_to_chain(R, sk.root_axes))


TINY_ASF = """\
# a hand-made skeleton: two bones up the Y axis
:version 1.10
:name tiny
:units
  mass 1.0
  length 1.0
  angle deg
:root
   order TX TY TZ RX RY RZ
   axis XYZ
   position 0 0 0
   orientation 0 0 0
:bonedata
  begin
     id 1
     name chest
     direction 0 1 0
     length 10
     axis 0 0 0 XYZ
    dof rx ry rz
    limits (-180 180)
           (-180 180)
           (-180 180)
  end
  begin
     id 2
     name larm
     direction 1 0 0
     length 5
     axis 0 0 90 XYZ
    dof rx
    limits (-180 180)
  end
  begin
     id 3
     name rarm
     direction -1 0 0
     length 5
     axis 0 0 -90 XYZ
    dof rx
  end
:hierarchy
  begin
    root chest
    chest larm rarm
  end
"""


def tiny_amc(frames):
    """AMC text; frames = list of (root6, chest3, larm1, rarm1)."""
    out = [":FULLY-SPECIFIED", ":DEGREES"]
    for i, (root, chest, larm, rarm) in enumerate(frames, start=1):
        out += [str(i), "root " + " ".join(map(str, root)), "chest " + " ".join(map(str, chest)),
                f"larm {larm}", f"rarm {rarm}"]
    return "\n".join(out) + "\n"


# non-ZXY orders, an interleaved root, a 2-channel joint and End Sites; units: cm
HAND = """\
HIERARCHY
ROOT Hips
{
  OFFSET 0 90 0
  CHANNELS 6 Xposition Yposition Zposition Yrotation Xrotation Zrotation
  JOINT LeftUpLeg
  {
    OFFSET 10 0 0
    CHANNELS 3 Xrotation Yrotation Zrotation
    JOINT LeftLeg
    {
      OFFSET 0 -45 0
      CHANNELS 2 Xrotation Zrotation
      End Site
      {
        OFFSET 0 -45 0
      }
    }
  }
  JOINT RightUpLeg
  {
    OFFSET -10 0 0
    CHANNELS 3 Yrotation Zrotation Xrotation
    End Site
    {
      OFFSET 0 -90 0
    }
  }
  JOINT Chest
  {
    OFFSET 0 30 0
    CHANNELS 3 Zrotation Yrotation Xrotation
    End Site
    {
      OFFSET 0 50 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
1 2 3 90 0 0 0 0 0 90 0 0 0 0 0 0 0
1.5 2 3.25 10.5 -20 30 5 6 7 -80 15 1 2 3 4 5 6
2 2 3.5 -170 89 179 -5 -6 -7 100 -15 -1 -2 -3 -4 -5 -6
"""
