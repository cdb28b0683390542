"""motionlang: human whole-body motion and natural language.

Layers (a module imports from its own layer and those before it; ``tests/test_architecture``
checks ``docs/contributing.md``'s statement of it): utils, errors -> kinematics -> formats ->
features -> analysis -> rendering -> datasets -> models -> training -> evaluation -> recipes
-> library -> api -> web -> cli.
"""
from motionlang.errors import DatasetError, MotionFormatError, MotionlangError, SkeletonError
from motionlang.kinematics import Joint, Motion, Skeleton

__version__ = "0.1.0"

#: the Python API (:mod:`motionlang.api`), imported on first use so that ``import
#: motionlang`` stays light (no torch until a model is needed)
_API = ("read_motion", "write_motion", "load_model", "describe", "describe_many", "timeline",
        "generate", "read_words",
        "generate_hypotheses", "text_to_motion", "encode", "train", "fill_in", "body21",
        "retarget", "render", "write_result", "load_rig", "index", "search", "analyse",
        "check")


def __getattr__(name: str):
    if name in _API:
        from motionlang import api
        return getattr(api, name)
    raise AttributeError(f"module 'motionlang' has no attribute {name!r}")


__all__ = ["Motion", "Skeleton", "Joint", "MotionlangError", "MotionFormatError",
           "DatasetError", "SkeletonError", "__version__", *_API]
