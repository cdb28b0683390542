"""motionlang: human whole-body motion and natural language.

Layers (data flows downwards only): ``kinematics`` and ``formats`` -> ``datasets`` and
``features`` -> ``models`` -> ``decoding`` -> ``training`` -> ``evaluation`` ->
``render`` -> ``cli``.
"""
from motionlang.errors import DatasetError, MotionFormatError, MotionlangError, SkeletonError
from motionlang.kinematics import Joint, Motion, Skeleton

__version__ = "0.1.0"

__all__ = ["Motion", "Skeleton", "Joint", "MotionlangError", "MotionFormatError",
           "DatasetError", "SkeletonError", "__version__"]
