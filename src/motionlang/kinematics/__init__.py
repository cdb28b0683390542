"""Skeletons, rotations and the ``Motion`` type (the bottom layer of motionlang)."""
from motionlang.kinematics.from_positions import motion_from_positions
from motionlang.kinematics.motion import Motion, concatenate
from motionlang.kinematics.retarget import retarget
from motionlang.kinematics.skeleton import Joint, Skeleton, detect_pairs

__all__ = ["Motion", "Joint", "Skeleton", "concatenate", "detect_pairs", "motion_from_positions",
           "retarget"]
